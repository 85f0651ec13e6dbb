"""Encoder overfit check: train a fresh encoder on N views (no augmentation) and measure it on the same views.
Prints JSON: recall, median rotation / translation errors over matched objects, the same fields read at the
true object cells (diagnostic), per category, the learning curve, and the Chamfer-L1 of the shape decoded from
the regressed code (with the target code's as the ceiling).

    PYTHONPATH=src python benchmarks/overfit_encoder.py --scenes /work/data/fit/single \
        --objects /work/data/fit/objects --views 50 --steps 800 --threads 1 \
        --out benchmarks/results/overfit_encoder/baseline.json

Views must be of the decoder's training objects (their codes are the targets); views of objects without a code
train pose and joint only and are left out of the Chamfer. Variants: ``--loss.FIELD VALUE`` and
``--encoder.FIELD VALUE`` (repeatable ``--set`` style, e.g. ``--loss shape_whiten=true``).
"""

from __future__ import annotations

import argparse
import json
from dataclasses import fields, replace
from pathlib import Path

import torch

from bench_report import emit, run_main
from centerart.evaluation.encoder_overfit import OverfitConfig, overfit_encoder
from centerart.models.checkpoint import load_decoder
from centerart.models.encoder.config import EncoderConfig
from centerart.models.encoder.losses import EncoderLossConfig


def parse_overrides(pairs: list[str], cls) -> dict:
    """``name=value`` pairs -> typed fields of dataclass ``cls`` (values parsed as JSON, else kept as text)."""
    known = {f.name for f in fields(cls)}
    out = {}
    for pair in pairs:
        name, _, text = pair.partition("=")
        if name not in known:
            raise SystemExit(f"unknown {cls.__name__} field {name!r}; known: {sorted(known)}")
        try:
            out[name] = json.loads(text)
        except json.JSONDecodeError:
            out[name] = text
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=Path, nargs="+", required=True)
    ap.add_argument("--objects", type=Path, default=None, help="objects root for the Chamfer metric (skip if absent)")
    ap.add_argument("--decoder", type=Path, default=None, help="decoder checkpoint (default: the shipped one)")
    ap.add_argument("--views", type=int, default=50)
    ap.add_argument("--preset", default="small")
    ap.add_argument("--steps", type=int, default=800, help="training steps (0: measure --load-model only)")
    ap.add_argument("--batch-size", type=int, default=8)
    ap.add_argument("--lr", type=float, default=1e-3)
    ap.add_argument("--eval-every", type=int, default=100)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--shape-objects", type=int, default=50)
    ap.add_argument("--mesh-resolution", type=int, default=96)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--loss", nargs="*", default=[], help="EncoderLossConfig overrides, name=value")
    ap.add_argument("--encoder", nargs="*", default=[], help="EncoderConfig overrides, name=value")
    ap.add_argument("--save-model", type=Path, default=None, help="write the trained state_dict here")
    ap.add_argument("--load-model", type=Path, default=None, help="start from a --save-model file (--steps 0: measure)")
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    decoder = load_decoder(args.decoder)
    cfg = OverfitConfig(
        scenes=tuple(args.scenes), views=args.views, preset=args.preset, steps=args.steps,
        batch_size=args.batch_size, lr=args.lr, seed=args.seed, eval_every=args.eval_every,
        loss=replace(EncoderLossConfig(), **parse_overrides(args.loss, EncoderLossConfig)),
        encoder_overrides=parse_overrides(args.encoder, EncoderConfig),
        shape_objects=args.shape_objects, mesh_resolution=args.mesh_resolution,
    )  # fmt: skip
    init = torch.load(args.load_model, weights_only=True)["state_dict"] if args.load_model else None
    report, model = overfit_encoder(
        cfg, decoder.codes, decoder, args.objects, log=lambda p: print(p, flush=True), init_state=init
    )
    report["threads"] = args.threads
    if args.save_model:
        torch.save({"config": model.config.to_dict(), "state_dict": model.state_dict()}, args.save_model)
    emit(report, args.out)


if __name__ == "__main__":
    run_main(main)
