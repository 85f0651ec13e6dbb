"""CPU settings for torch work: intra-op threads and denormal floats.

Why flush denormals: float32 values below 1.2e-38 (denormals) are computed by x86 cores in microcode, 10-100x
slower than normal numbers. Trained weights hold them: a weight-normalised decoder's direction vectors after
4,800 steps had 0.7-3 % denormal entries per layer, and a training step of it took 2-3x longer than with them read
as zero (``benchmarks/results/denormals/``). torch on the CPU keeps them unless told otherwise. Reading them as zero
moves no figure that is reported (they are below 1e-38, the weights around 1e-2; measured there).

The flag lives in each thread's floating-point control register. Linux threads copy it from the thread that
creates them, so it is set before torch starts its intra-op thread pool (the first parallel operation after
``torch.set_num_threads``); set later, it speeds up the calling thread only. The CLI sets it for every command,
once its arguments are parsed; the training, slice and evaluation functions set it again for API callers.
"""

from __future__ import annotations


def flush_denormals() -> bool:
    """Read and write denormal float32 values as zero on this thread and on the threads it starts from now on;
    False where the CPU cannot (no SSE3 or ARM FZ), which only costs speed."""
    import torch

    return torch.set_flush_denormal(True)


def use_cpu_threads(threads: int) -> None:
    """Flush denormal floats to zero, and use ``threads`` intra-op threads (0 keeps torch's default)."""
    import torch

    flush_denormals()
    if threads > 0:
        torch.set_num_threads(threads)
