"""Closed-loop SR of several encoders on the same scenes, each paired against the first (views and objects).

For choosing between checkpoints without the test scenes: each encoder is run through ``centerart eval scenes`` on
the given scenes (stereo depth, ``centerart[pose]``, or ``centerart`` without the pose correction with ``--grasps
full``; the headline SR only: no stage analysis, shapes, oracle or baseline, which makes a run about 0.4 s per
single-object view on 2 cores once the labels exist), the first run's ground-truth labels copied into the others so
that only the encoders differ; then every encoder's SR by image association per set, and its pairing with the first
(``centerart.evaluation.paired``: the sign test on views and on distinct objects). Prints JSON:

    PYTHONPATH=src:benchmarks python benchmarks/closed_loop_selection.py --scenes DEV/single --out OUT \
        --decoder training_runs/encoder-small-102/decoder.pt --encoders slice1=S1.pt slice4=S4.pt [--workers 2]
    # DEV/single: scenes of objects no model trained on and no test scene shows (benchmarks/results/
    # eval_scenes_s24/README.md makes 400 of 200 new objects); OUT/<name>/ holds each evaluation (resumable)
    PYTHONPATH=src:benchmarks python benchmarks/closed_loop_selection.py --make-sets SETS --out OUT --decoder D \
        --encoders ...   # instead of --scenes: the two selection sets of sessions 24-31, made in SETS if missing
    ... --encoders plain=E.pt critic=E.pt --row-decoders critic=C/decoder.pt   # one encoder, two decoders (C:
    # a copy of the decoder with its grasp critic beside it, DECODER.critic.json)
    ... --against benchmarks/results/decoder_closed_loop/rows.jsonl --against-columns shipped shippedc
    # each encoder paired with those decoders given the true detection on the same views: what the encoder costs
"""

from __future__ import annotations

import argparse
import shutil
from collections import Counter
from pathlib import Path

from bench_report import emit, run_main

#: The selection sets used since session 24 (``benchmarks/results/eval_scenes_s24/``): scene folder -> (object
#: seed, scene seed). 200 objects (40 per category) and 400 single-object views each; no training or test set
#: uses these seeds, and the folder names are the set names in every selection report.
SELECTION_SETS = {"d_single": (6000, 6100), "d2_single": (6500, 6600)}


def make_selection_sets(folder: Path, workers: int) -> list[Path]:
    """The two selection sets under ``folder`` (``<set>_objects/``, ``<set>/``); both stages skip finished items."""
    from centerart.assets.dataset import GenerateObjectsConfig, generate_objects
    from centerart.scenes.dataset import GenerateScenesConfig, generate_scenes

    scenes = []
    for name, (object_seed, scene_seed) in SELECTION_SETS.items():
        objects = folder / f"{name}_objects"
        generate_objects(GenerateObjectsConfig(out=objects, count=40, seed=object_seed, workers=workers))
        generate_scenes(
            GenerateScenesConfig(
                objects=objects, out=folder / name, layout="single", count=400, views_per_scene=1,
                seed=scene_seed, save_ir=False, workers=workers,
            )
        )  # fmt: skip
        scenes.append(folder / name)
    return scenes


def evaluate(name: str, encoder: Path, decoder: Path | None, args, first: Path | None) -> Path:
    """``centerart eval scenes`` of one encoder and decoder into ``OUT/name`` (the first evaluation's labels copied
    in). A grasp critic beside the decoder file (``DECODER.critic.json``) ranks its grasps, as in the predictor."""
    from centerart.evaluation.scene_eval import EvalScenesConfig, evaluate_scenes

    out = args.out / name
    if first is not None and (first / "labels").is_dir() and not (out / "labels").exists():
        shutil.copytree(first / "labels", out / "labels")
    evaluate_scenes(EvalScenesConfig(
        scenes=tuple(args.scenes), out=out, encoder=encoder, decoder=decoder, depth=("realistic",),
        grasps=(args.grasps,), oracle=False, baseline=False, shape=False, ablation=False,
        workers=args.workers,
    ))  # fmt: skip
    return out


def success_rates(outcomes: dict) -> dict:
    """Per set: successes, object views, SR."""
    views, wins = Counter(k[0] for k in outcomes), Counter(k[0] for k, ok in outcomes.items() if ok)
    return {s: {"successes": wins[s], "views": n, "sr_image": round(wins[s] / n, 4)} for s, n in sorted(views.items())}


def main() -> None:
    from centerart.evaluation.paired import paired_table, read_outcomes
    from decoder_closed_loop import against_rows, bare_key

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    where = p.add_mutually_exclusive_group(required=True)
    where.add_argument("--scenes", type=Path, nargs="+", help="scene folders (objects no model saw)")
    where.add_argument("--make-sets", type=Path, help="make (or resume) the two selection sets here and use them")
    p.add_argument("--encoders", nargs="+", required=True, help="NAME=ENCODER.pt; the first is the reference")
    p.add_argument("--decoder", type=Path, default=None, help="the decoder all encoders regress codes of")
    p.add_argument("--row-decoders", nargs="+", default=[], metavar="NAME=DECODER.pt",
                   help="a decoder for one row instead of --decoder (e.g. a copy with a grasp critic beside it), so "
                   "that one encoder can be paired with two decoders")  # fmt: skip
    p.add_argument("--against", type=Path, default=None, metavar="ROWS.jsonl",
                   help="a decoder_closed_loop.py rows file of the same scenes (decoders given the true detection): "
                   "each encoder paired with its --against-columns, which is what the encoder costs")  # fmt: skip
    p.add_argument("--against-columns", nargs="*", default=[], help="columns of --against, e.g. shipped shippedc")
    p.add_argument("--out", type=Path, required=True)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--grasps", default="pose", choices=["pose", "full"],
                   help="pose: centerart[pose] (the pose corrected from the depth first; the selections so far); "
                   "full: without that correction")  # fmt: skip
    args = p.parse_args()
    if args.against is not None and not args.against.is_file():
        p.error(f"--against: {args.against}: no such rows file")
    if args.make_sets is not None:
        args.scenes = make_selection_sets(args.make_sets, args.workers)
    named = [e.partition("=")[::2] for e in args.encoders]
    row_decoders = dict(d.partition("=")[::2] for d in args.row_decoders)
    if unknown := sorted(set(row_decoders) - {name for name, _ in named}):
        p.error(f"--row-decoders: {unknown} are not rows of --encoders")
    if empty := sorted(name for name, path in row_decoders.items() if not path):
        p.error(f"--row-decoders: {empty} name no file (NAME=DECODER.pt)")
    report: dict = {"scenes": [str(s) for s in args.scenes], "decoder": str(args.decoder), "encoders": {}}
    first, reference = None, None  # the first evaluation's folder (its labels) and outcomes, read once
    mine: dict[str, dict] = {}  # name -> outcomes keyed as decoder_closed_loop's rows (for --against)
    for name, path in named:
        decoder = Path(row_decoders[name]) if name in row_decoders else args.decoder
        out = evaluate(name, Path(path), decoder, args, first)
        outcomes = read_outcomes(out)
        entry = {"file": path, "decoder": str(decoder), "sets": success_rates(outcomes)}
        if reference is not None:
            entry["paired_with_first"] = paired_table(reference, outcomes)["sets"]
        else:
            first, reference = out, outcomes
        report["encoders"][name] = entry
        mine[name] = {bare_key(k): v for k, v in outcomes.items()}
    if args.against is not None:
        report["against"] = against_rows(mine, args.against, args.against_columns)
    emit(report, args.out / "selection.json")


if __name__ == "__main__":
    run_main(main)
