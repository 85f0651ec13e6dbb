"""Encoder training throughput on this machine: images/s of the training step (forward, loss, backward, Adam) of a
preset at batch B, in each memory layout / precision variant, and of the whole loop with data loading.

    python benchmarks/encoder_train_speed.py --scenes /work/data/dev/kitchen /work/data/dev/single \
        --threads 2 --out benchmarks/results/encoder_train_speed/result.json

Variants: ``default`` (NCHW fp32, how the encoder trained before issue 29), ``channels_last`` (NHWC fp32, the
default since), ``bf16`` (channels-last under CPU bf16 autocast), ``compile`` (channels-last + torch.compile;
``--compile`` only: it compiles for minutes). ``loop``: the slice training loop (``run_steps``) with the default
layout and ``--loader-workers`` loader processes, items decoded and augmented from the scene files.
Prints JSON; measure on an idle machine.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import torch

from bench_report import run_main
from centerart.models.checkpoint import default_checkpoint, load_shape_codes
from centerart.models.encoder.config import preset
from centerart.models.encoder.losses import EncoderLossConfig, encoder_loss
from centerart.models.encoder.network import EncoderOutput, RGBDEncoder
from centerart.training.encoder_augment import AugmentConfig
from centerart.training.encoder_data import EncoderViewDataset, checked_views, collate
from centerart.training.slice_training import SliceSchedule, StepLoop, new_state, run_steps, slice_batches


def step_rate(encoder, batch, variant: str, steps: int) -> float:
    """Images/s of ``steps`` training steps on one fixed batch (after two warm-up steps)."""
    layout = torch.contiguous_format if variant == "default" else torch.channels_last
    encoder = encoder.to(memory_format=layout)
    batch = {**batch, **{k: batch[k].contiguous(memory_format=layout) for k in ("rgb", "depth")}}
    model = torch.compile(encoder) if variant == "compile" else encoder
    opt = torch.optim.Adam(encoder.parameters(), lr=1e-4)
    loss_cfg = EncoderLossConfig()

    def step():
        with torch.autocast("cpu", dtype=torch.bfloat16, enabled=variant == "bf16"):
            out = model(batch["rgb"], batch["depth"])
        # The loss in fp32 (its SVD has no bf16 kernel on the CPU), as autocast would run it.
        out = EncoderOutput(out.heatmap.float(), {k: v.float() for k, v in out.dense.items()}, out.stride)
        loss, _ = encoder_loss(out, batch, loss_cfg)
        opt.zero_grad()
        loss.backward()
        opt.step()

    for _ in range(2):
        step()
    t0 = time.perf_counter()
    for _ in range(steps):
        step()
    return steps * batch["rgb"].shape[0] / (time.perf_counter() - t0)


def loop_rate(views, cfg, codes, batch_size: int, steps: int, workers: int) -> float:
    ds = EncoderViewDataset(views, cfg, codes, AugmentConfig(), seed=0)
    state = new_state(cfg, seed=0)
    batches = slice_batches(len(views), batch_size, steps + 2, seed=0, slice_index=1)
    run_steps(state, ds, StepLoop(batches[:2], SliceSchedule(), EncoderLossConfig(), workers))
    t0 = time.perf_counter()
    run_steps(state, ds, StepLoop(batches, SliceSchedule(), EncoderLossConfig(), workers), start=2)
    return steps * batch_size / (time.perf_counter() - t0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scenes", type=Path, nargs="+", required=True, help="rendered scene folders")
    parser.add_argument("--preset", default="small")
    parser.add_argument("--batch-size", type=int, default=8)
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--loader-workers", type=int, default=1)
    parser.add_argument(
        "--variants",
        nargs="+",
        default=["default", "channels_last", "bf16"],
        choices=["default", "channels_last", "bf16"],
        help="timed in this order (repeats allowed)",
    )
    parser.add_argument("--compile", action="store_true", help="also time torch.compile (minutes to compile)")
    parser.add_argument("--out", type=Path, default=None, help="also write the JSON here")
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    codes = load_shape_codes(default_checkpoint())
    cfg = preset(args.preset, code_dim=len(next(iter(codes.values()))))
    views = checked_views(args.scenes)
    ds = EncoderViewDataset(views, cfg, codes, AugmentConfig(), seed=0)
    batch = collate([ds[i] for i in range(args.batch_size)])
    variants = args.variants + (["compile"] if args.compile else [])
    result = {"preset": args.preset, "batch_size": args.batch_size, "threads": args.threads, "steps": args.steps,
              "cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(), "torch": torch.__version__,
              "step_images_per_s": {}}  # fmt: skip
    for variant in variants:
        torch.manual_seed(0)
        rate = step_rate(RGBDEncoder(cfg), batch, variant, args.steps)
        result["step_images_per_s"].setdefault(variant, []).append(round(rate, 2))
    loop = loop_rate(views, cfg, codes, args.batch_size, args.steps, args.loader_workers)
    result["loop_images_per_s"] = round(loop, 2)
    result["loader_workers"] = args.loader_workers
    text = json.dumps(result, indent=2)
    print(text)
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text + "\n")


if __name__ == "__main__":
    run_main(main)
