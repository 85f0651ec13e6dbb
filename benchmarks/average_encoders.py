"""The weight average of encoder checkpoints of one sliced run (a "soup" of its slices), as an encoder checkpoint.

Every slice of a run continues the one before from its weights, so the slices lie along one training trajectory and
their floating-point weights can be averaged (as stochastic weight averaging does along one run); integer buffers are
the last file's. The files must share the encoder config and the decoder whose codes they regress; the average keeps
the last file's metadata and names its members (path and sha256) under ``train_config["weight_average_of"]``. Prints
JSON:

    git show f6b0a94:training_runs/encoder-small-102/encoder.pt > slice1.pt   # (and each other slice's commit)
    PYTHONPATH=src:benchmarks python benchmarks/average_encoders.py --out soup.pt --encoders slice1.pt ... slice5.pt
"""

from __future__ import annotations

import argparse
from pathlib import Path

import torch

from bench_report import emit, run_main


def average_encoders(paths: list[Path], out: Path) -> dict:
    """Write the uniform weight average of the encoder checkpoints ``paths`` to ``out``; its report."""
    from centerart.errors import CenterArtError
    from centerart.models.checkpoint_files import file_sha256, read_blob, write_blob
    from centerart.models.encoder.checkpoint import FORMAT, VERSION, load_encoder

    blobs = [read_blob(p, FORMAT, VERSION, "encoder") for p in paths]
    for path, blob in zip(paths[1:], blobs[1:], strict=True):
        if blob["encoder_config"] != blobs[0]["encoder_config"] or blob["decoder"] != blobs[0]["decoder"]:
            raise CenterArtError(f"{path}: another encoder config or decoder than {paths[0]}; nothing to average")
    states = [b["state_dict"] for b in blobs]
    average = {k: torch.stack([s[k] for s in states]).mean(0) if v.is_floating_point() else v
               for k, v in states[-1].items()}  # fmt: skip
    members = [{"file": str(p), "sha256": file_sha256(p)} for p in paths]
    write_blob(out, {**blobs[-1], "state_dict": average,
                     "train_config": {**blobs[-1]["train_config"], "weight_average_of": members}})  # fmt: skip
    load_encoder(out)  # the average loads like any encoder checkpoint
    return {"out": str(out), "sha256": file_sha256(out), "members": members}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--encoders", type=Path, nargs="+", required=True, help="encoder checkpoints of one run")
    p.add_argument("--out", type=Path, required=True)
    args = p.parse_args()
    emit(average_encoders(args.encoders, args.out), None)


if __name__ == "__main__":
    run_main(main)
