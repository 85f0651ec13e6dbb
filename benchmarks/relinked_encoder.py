"""A copy of an encoder checkpoint whose decoder link names another decoder: an experiment, never a product file.

An encoder regresses the shape codes of the decoder it was trained against, and ``load_encoder`` refuses any
other decoder (the codes of two decoders mean different shapes). A decoder run continued by a slice at a low rate
keeps its training objects' codes close to where they were, so how far the continued decoder's codes have drifted
can be measured in closed loop without training an encoder against them: relink the encoder, run
``closed_loop_selection.py`` with the new decoder, and pair the outcomes with the same encoder on its own decoder
(``benchmarks/results/decoder_slices/slice4_closed_loop/``). The copy records the link it replaced
(``decoder.relinked_from``) so that it cannot pass for a trained pair.

    python benchmarks/relinked_encoder.py --encoder ENC.pt --decoder NEW_DECODER.pt --out RELINKED.pt
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from bench_report import run_main
from centerart.errors import CenterArtError
from centerart.models.checkpoint_files import file_sha256, read_blob, write_blob
from centerart.models.encoder.checkpoint import FORMAT, VERSION


def relink(encoder: Path, decoder: Path, out: Path) -> Path:
    """Write ``out``: ``encoder``'s weights and metadata, its decoder link set to ``decoder``'s file hash."""
    if not decoder.is_file():
        raise CenterArtError(f"{decoder}: no such decoder checkpoint")
    if not out.parent.is_dir():
        raise CenterArtError(f"--out {out}: folder {out.parent} does not exist")
    blob = read_blob(encoder, FORMAT, VERSION, "encoder")
    old = dict(blob.get("decoder") or {})
    blob["decoder"] = {**old, "file": decoder.name, "sha256": file_sha256(decoder), "relinked_from": old.get("sha256")}
    return write_blob(out, blob)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--encoder", type=Path, required=True)
    parser.add_argument("--decoder", type=Path, required=True)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    try:
        print(relink(args.encoder, args.decoder, args.out))
    except CenterArtError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    run_main(main)
