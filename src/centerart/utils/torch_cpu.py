"""CPU settings for torch work: intra-op threads and denormal floats.

Why flush denormals: float32 values below 1.2e-38 (denormals) are computed by x86 cores in microcode, 10-100x
slower than normal numbers. Trained weights hold them: a weight-normalised decoder's direction vectors after
4,800 steps had 1-3 % denormal entries per layer, and one training step of it took 3x longer than with them read
as zero (2.0 s against 0.65 s on one thread, ``benchmarks/results/denormals/``). GPUs flush them by default; torch
on the CPU does not. Reading them as zero changes no result that matters (they are 1e-38 of the weights' scale).

The flag lives in each thread's floating-point control register. Linux threads copy it from the thread that
creates them, so it is set before torch starts its intra-op thread pool (the first parallel operation after
``torch.set_num_threads``); set later, it speeds up the calling thread only.
"""

from __future__ import annotations


def use_cpu_threads(threads: int) -> None:
    """Flush denormal floats to zero, and use ``threads`` intra-op threads (0 keeps torch's default)."""
    import torch

    torch.set_flush_denormal(True)
    if threads > 0:
        torch.set_num_threads(threads)
