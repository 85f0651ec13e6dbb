"""Export a decoder training run's Lightning checkpoint (an intermediate epoch) as a ``decoder.pt`` checkpoint, so
two runs can be compared at the same number of optimizer steps before either finishes (issue 15's levers).

    PYTHONPATH=src python benchmarks/decoder_snapshot.py --run runs/small/decoder \
        --ckpt runs/small/decoder/lightning/epoch=49-step=1600.ckpt --out snapshots/classic_e49.pt

The run's ``config.json`` rebuilds the module and its data split (the SDF samples must still be where it names);
the result loads with ``centerart.models.checkpoint.load_decoder`` like a finished run's export. Prints one JSON line.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path

import torch

from bench_report import run_main


def main() -> None:
    from centerart.training.train_decoder import TrainDecoderConfig, build_module, export_decoder, load_split_data

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--run", type=Path, required=True, help="the training run's output folder")
    parser.add_argument("--ckpt", type=Path, required=True, help="a Lightning checkpoint of that run")
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    saved = json.loads((args.run / "config.json").read_text())
    names = {f.name for f in dataclasses.fields(TrainDecoderConfig)}
    cfg = TrainDecoderConfig(**{k: v for k, v in saved.items() if k in names})
    cfg = dataclasses.replace(cfg, data=Path(cfg.data), out=Path(cfg.out), progress=False)
    data = load_split_data(cfg)
    module = build_module(cfg, data)
    blob = torch.load(args.ckpt, map_location="cpu", weights_only=False)  # our own training output
    module.load_state_dict(blob["state_dict"])
    args.out.parent.mkdir(parents=True, exist_ok=True)
    step = {"epoch": blob.get("epoch"), "global_step": blob.get("global_step")}
    export_decoder(args.out, cfg, module, data, {**dataclasses.asdict(cfg), "snapshot_of": str(args.ckpt)}, step)
    print(json.dumps({"out": str(args.out), **step}))


if __name__ == "__main__":
    run_main(main)
