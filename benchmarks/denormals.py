"""Training-step time of a decoder from a run's train state with denormal floats kept and read as zero.

Each setting runs in its own process, because the flush flag is per thread and torch's intra-op threads copy it
when they start (``centerart.utils.torch_cpu``). Prints JSON: the state's denormal counts per tensor, then per
setting the median seconds of a forward and backward pass over ``--points`` random query points.

    python benchmarks/denormals.py --state training_runs/decoder-small-102-paper-reg/state.pt --threads 2
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

from bench_report import run_main


def load_decoder(state_path: Path):
    import torch

    from centerart.models.decoder import DecoderConfig, SGDFDecoder

    state = torch.load(state_path, map_location="cpu", weights_only=True)
    model = SGDFDecoder(DecoderConfig.from_dict(state["decoder_config"]))
    prefix = "decoder."
    model.load_state_dict({k[len(prefix) :]: v for k, v in state["state_dict"].items() if k.startswith(prefix)})
    return model, state


def denormal_counts(state: dict) -> dict:
    """Per floating-point tensor of the weights and the optimizer state: (denormal entries, entries)."""

    import torch

    tiny = torch.finfo(torch.float32).tiny  # the smallest normal float32, 1.18e-38

    def count(t):
        return int(((t != 0) & (t.abs() < tiny)).sum())

    out = {k: [count(v), v.numel()] for k, v in state["state_dict"].items() if v.is_floating_point()}
    for i, s in state.get("optimizer", {}).get("state", {}).items():
        for k, v in s.items():
            if hasattr(v, "is_floating_point") and v.is_floating_point() and v.dim() > 0:
                out[f"optimizer.{i}.{k}"] = [count(v), v.numel()]
    return {k: v for k, v in out.items() if v[0] > 0}


def time_steps(state_path: Path, flush: bool, threads: int, points: int, steps: int) -> dict:
    """Median seconds of one forward + backward pass (train mode), in this process."""
    import torch

    torch.set_flush_denormal(flush)  # before the intra-op pool starts, so that its threads copy the flag
    torch.set_num_threads(threads)
    model, _ = load_decoder(state_path)
    return {
        "flush_denormals": flush,
        "threads": threads,
        "points": points,
        "step_s": median_pass_s(model, points, steps),
    }


def median_pass_s(model, points: int, steps: int) -> float:
    """Median seconds of one forward + backward pass of decoder ``model`` in train mode over ``points`` random query
    points, of ``steps`` passes after one warm-up."""
    import torch

    model.train()
    gen = torch.Generator().manual_seed(0)
    code = 0.3 * torch.randn(points, model.config.code_dim, generator=gen)
    joint, xyz = torch.rand(points, generator=gen), 0.3 * torch.randn(points, 3, generator=gen)
    times = []
    for _ in range(steps + 1):  # the first is a warm-up
        t0 = time.perf_counter()
        out = model(code, joint, xyz)
        model.zero_grad()
        (out.sdf.abs().mean() + out.offset.abs().mean()).backward()
        times.append(time.perf_counter() - t0)
    times = sorted(times[1:])
    return times[len(times) // 2]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--state", type=Path, required=True, help="a decoder run's state.pt (or a slice's)")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--points", type=int, default=8 * 2048, help="query points a step (8 items x 2,048)")
    parser.add_argument("--steps", type=int, default=8)
    parser.add_argument("--one", choices=["kept", "flushed"], help=argparse.SUPPRESS)  # the child process
    args = parser.parse_args(argv)
    if not args.state.is_file():
        print(f"error: --state {args.state}: no such file", file=sys.stderr)
        return 2
    if args.one:
        print(json.dumps(time_steps(args.state, args.one == "flushed", args.threads, args.points, args.steps)))
        return 0
    _, state = load_decoder(args.state)
    rows = []
    for one in ("kept", "flushed", "kept", "flushed"):  # alternated, so that a load change hits both
        cmd = [sys.executable, __file__, *(argv if argv is not None else sys.argv[1:]), "--one", one]
        rows.append(json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout))
    print(json.dumps({"state": str(args.state), "step": state.get("step"), "denormals": denormal_counts(state),
                      "runs": rows}, indent=1))  # fmt: skip
    return 0


if __name__ == "__main__":
    run_main(main)
