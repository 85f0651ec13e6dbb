"""What the paper's regularisation costs a decoder training step on CPU: dropout and weight norm, apart and together.

``decoder-small-102-paper-reg`` steps at 2.6 steps/s against the unregularised run's 5.1 once denormals are read as
zero (``benchmarks/results/denormals/``). This splits that gap: a freshly initialised decoder of one preset (no
denormals), each setting timed in its own process, a forward and backward pass over ``--points`` random query points
in train mode, the median of ``--steps`` passes after one warm-up. Prints JSON:

    python benchmarks/decoder_reg_cost.py --preset small --threads 2
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys

from bench_report import run_main

SETTINGS = {"none": (0.0, False), "dropout": (0.2, False), "weight_norm": (0.0, True), "both": (0.2, True)}


def time_setting(preset: str, setting: str, threads: int, points: int, steps: int) -> dict:
    """Median seconds of one forward + backward pass of the preset with one regularisation setting."""
    import torch

    from centerart.models.decoder import SGDFDecoder
    from centerart.models.decoder import preset as decoder_preset
    from centerart.utils.torch_cpu import use_cpu_threads
    from denormals import median_pass_s  # benchmarks/ (this script's folder)

    use_cpu_threads(threads)  # denormals read as zero too
    dropout, weight_norm = SETTINGS[setting]
    torch.manual_seed(0)
    model = SGDFDecoder(decoder_preset(preset, dropout=dropout, weight_norm=weight_norm))
    step_s = median_pass_s(model, points, steps)
    return {"setting": setting, "dropout": dropout, "weight_norm": weight_norm, "step_s": round(step_s, 4)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default="small", choices=["tiny", "small", "paper"])
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--points", type=int, default=8 * 2048, help="query points a step (8 items x 2,048)")
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--one", choices=list(SETTINGS), help=argparse.SUPPRESS)  # the child process
    args = parser.parse_args(argv)
    if args.one:
        print(json.dumps(time_setting(args.preset, args.one, args.threads, args.points, args.steps)))
        return 0
    rows = []
    for setting in [*SETTINGS, *SETTINGS]:  # twice, alternated, so that a load change hits every setting
        cmd = [sys.executable, __file__, *(argv if argv is not None else sys.argv[1:]), "--one", setting]
        rows.append(json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout))
    best = {s: min(r["step_s"] for r in rows if r["setting"] == s) for s in SETTINGS}
    print(json.dumps({"preset": args.preset, "threads": args.threads, "points": args.points, "runs": rows,
                      "best_step_s": best}, indent=1))  # fmt: skip
    return 0


if __name__ == "__main__":
    run_main(main)
