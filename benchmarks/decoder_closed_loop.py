"""Closed-loop SR of decoders with no encoder: true pose, joint and mask, a code fitted to the true surface.

Every object of the scenes is given with its true pose, joint and visible mask and a shape code fitted to its true
surface; each decoder decodes, anchors and ranks its grasps, the top one is executed, and every decoder is paired
against the first.

Which decoder should an encoder be trained against? An encoder run costs several sessions, and an encoder's codes
belong to one decoder, so ``centerart eval scenes`` cannot compare decoders before that is paid. This runs the code
oracle of the stage analysis (``evaluation/code_oracle.py``: the decoder frozen, a code fitted to the object's
surface at its scene state) through the predictor's own decoding, anchoring and ranking
(``Predictor.without_encoder``, ``predict_detection``), executes the top grasp in the scene's physics, and pairs
the decoders' outcomes object by object (``centerart.evaluation.paired``: sign test on views and on distinct
objects). It is an upper bound for what an encoder could get from each decoder, not a method. Prints JSON:

    PYTHONPATH=src:benchmarks python benchmarks/decoder_closed_loop.py --scenes DEV/single --out OUT \\
        --decoders shipped=src/centerart/weights/sgdf_small.pt \\
        reg=training_runs/decoder-small-102-paper-reg/decoder.pt \\
        [--labels-from EVAL_OUT] [--grasps pose] [--depth realistic] [--max-scenes N] [--workers 2] \\
        [--oracle-fit-dropout NAME...] [--critic NAME...]
    # DEV/single: scenes of objects no decoder trained on (refused otherwise); EVAL_OUT: a `centerart eval scenes`
    # output on the same scenes whose cached ground-truth labels are reused (else they are generated into OUT);
    # OUT/records/<set>/<scene>.json: one record per scene (a rerun skips it: resumable)
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import time
from collections import Counter, defaultdict
from pathlib import Path

from bench_report import emit, run_main
from centerart.inference.grasp_anchoring import LADDER
from centerart.models.grasp_critic import critic_path

_PREDICTORS: dict = {}


def predictor(decoder: str, grasps: str, critic: bool = False):
    """The encoder-less predictor of one decoder and grasp setting, cached; ``critic``: ranking with the grasp
    critic beside the checkpoint (``--critic``), else without one."""
    from centerart.inference.grasp_anchoring import ladder_predictor_settings
    from centerart.inference.predictor import Predictor, PredictorConfig

    if (decoder, grasps, critic) not in _PREDICTORS:
        config = PredictorConfig(grasp_critic=critic, **ladder_predictor_settings(grasps))
        _PREDICTORS[(decoder, grasps, critic)] = Predictor.without_encoder(decoder, config=config)
    return _PREDICTORS[(decoder, grasps, critic)]


def reference_outcomes(ctx, v, seed: int) -> dict[int, dict]:
    """Scene object -> the outcomes of the scene evaluation's reference rows on view ``v``: the geometric
    ``baseline`` (handles in the depth points inside the true mask) and a ground-truth ``label`` executed."""
    from centerart.evaluation.scene_rows import baseline_rows, oracle_rows

    out: dict[int, dict] = defaultdict(dict)
    for method, rows in (("baseline", baseline_rows(ctx, v, seed)), ("label", oracle_rows(ctx, v))):
        for r in rows:
            out[r["instance"]][method] = {"sr": bool(r["sr"]), "abort": r["sr_abort"], "rsr": bool(r["rsr"])}
    return out


def object_rows(ctx, v, decoders: list[tuple[str, str]], cfg: dict, codes: dict) -> list[dict]:
    """One row per visible object of view ``v``: each decoder's top-grasp outcome (SR, abort word, RSR), and the
    reference rows' with ``cfg["references"]``."""
    from centerart.evaluation.code_oracle import oracle_code, true_detection
    from centerart.evaluation.scene_rows import top_grasp_trial
    from centerart.geometry.gravity import gravity_from_world_T_camera

    rows, refs = [], reference_outcomes(ctx, v, cfg["seed"]) if cfg["references"] else {}
    gravity = gravity_from_world_T_camera(v.world_T_camera)  # as the scene evaluation gives it (TF)
    for _, obj in v.ground_truth():
        k = obj["instance"] - 1
        row = {"scene": v.scene, "view": v.view, "depth": v.depth_mode, "instance": k, "object_id": obj["object_id"],
               "category": obj["category"], "state_normalized": obj["joint"]["state_normalized"]}  # fmt: skip
        for name, path in decoders:
            p = predictor(path, cfg["grasps"], name in cfg["critic"])
            p.gravity = gravity
            dropout = name in cfg["fit_dropout"]
            key = (path, dropout, k)  # one fit per decoder file and fit: --critic pairs share it
            if key not in codes:
                codes[key] = oracle_code(p.decoder, ctx.phys.objects[k], ctx.phys.states[k], k, dropout)
            pred = p.predict_detection(true_detection(obj, v.instances, codes[key]), v.rgb, v.depth, v.K)
            trial = top_grasp_trial(ctx, v, k, pred.grasp_poses)
            row[name] = {"sr": bool(trial["sr"]), "abort": trial["sr_abort"], "rsr": bool(trial["rsr"])}
        rows.append(row | refs.get(k, {}))
    return rows


def scene_job(job: tuple) -> dict:
    """Every row of one scene into OUT/records/<set>/<scene>.json (skipped when it is there: resume)."""
    from centerart.evaluation.scene_eval import scene_context, view_inputs
    from centerart.utils.atomic import atomic_write_json
    from centerart.utils.torch_cpu import use_cpu_threads

    set_name, scene_dir, out, decoders, args = job
    use_cpu_threads(1)  # denormals read as zero too
    record = Path(out) / "records" / set_name / f"{Path(scene_dir).name}.json"
    if record.is_file():
        return {"skipped": True}
    started = time.perf_counter()
    _, ctx = scene_context(Path(scene_dir), Path(out) / "labels" / set_name, args)
    try:
        rows, codes = [], {}
        for v in view_inputs(Path(scene_dir), args["depth"]):
            rows += object_rows(ctx, v, decoders, args, codes)
    finally:
        ctx.phys.close()
    atomic_write_json(record, {"scene": Path(scene_dir).name, "set": set_name, "rows": rows,
                               "seconds": round(time.perf_counter() - started, 2)})  # fmt: skip
    return {"skipped": False}


def check_held_out(folders: list[Path], sets: dict, decoders: list[tuple[str, str]]) -> None:
    """Refuse scenes that show an object any of the decoders trained on."""
    from centerart.evaluation.heldout import check_held_out as check
    from centerart.evaluation.heldout import checkpoint_training_objects
    from centerart.evaluation.testset import describe_set

    trained = [checkpoint_training_objects(Path(path), "decoder") for _, path in decoders]
    for folder, dirs in zip(folders, sets.values(), strict=True):
        info = describe_set(folder, dirs)
        check({o["object_id"]: o["fingerprint"] for o in info["objects"].values()}, trained, str(folder))


def read_rows(out: Path) -> list[dict]:
    """Every row of OUT's records, each with its set's name (``set``)."""
    rows = []
    for path in sorted((out / "records").glob("*/*.json")):
        rec = json.loads(path.read_text())
        rows += [{**r, "set": rec["set"]} for r in rec["rows"]]
    return rows


def outcomes(rows: list[dict], name: str) -> dict:
    """(set, scene, view, depth, method, instance, object) -> SR of decoder ``name``, as ``evaluation.paired``
    keys its rows."""
    keys = ("set", "scene", "view", "depth")
    return {(*(r[k] for k in keys), "oracle-code", r["instance"], r["object_id"]): r[name]["sr"] for r in rows}


def summary(out: Path, named: list[tuple[str, str]]) -> dict:
    """Each decoder's (and reference's) SR, overall and per category, and its pairing with the first."""
    from centerart.evaluation.paired import paired_table

    rows = read_rows(out)
    first = outcomes(rows, named[0][0])
    report = {}
    for name, path in named:
        wins = Counter(r["category"] for r in rows if r[name]["sr"])
        views = Counter(r["category"] for r in rows)
        aborts = Counter(r[name]["abort"] or "success" for r in rows)
        report[name] = {
            "decoder": path, "object_views": len(rows), "sr": round(sum(wins.values()) / max(1, len(rows)), 4),
            "rsr": round(sum(r[name]["rsr"] for r in rows) / max(1, len(rows)), 4),
            "sr_by_category": {c: f"{wins[c]}/{n}" for c, n in sorted(views.items())}, "outcomes": dict(aborts),
        }  # fmt: skip
        if name != named[0][0]:
            report[name]["paired_with_first"] = paired_table(first, outcomes(rows, name))
    return report


def parse(argv=None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenes", type=Path, nargs="+", required=True, help="scene folders (objects no decoder saw)")
    p.add_argument("--decoders", nargs="*", default=[], help="NAME=DECODER.pt; the first is the reference")
    p.add_argument("--oracle-fit-dropout", nargs="*", default=[], metavar="NAME",
                   help="decoders whose oracle codes are fitted under dropout (CodeFitConfig.dropout)")  # fmt: skip
    p.add_argument("--critic", nargs="*", default=[], metavar="NAME",
                   help="decoders ranked by the critic beside their checkpoint (CHECKPOINT.critic.json)")  # fmt: skip
    p.add_argument("--references", action="store_true", help="also the baseline and a label executed, per view")
    p.add_argument("--out", type=Path, required=True, help="records (resumable) and report.json")
    p.add_argument("--labels-from", type=Path, default=None, help="an eval-scenes output whose labels/ are reused")
    p.add_argument("--grasps", default="pose", choices=LADDER, help="grasp setting (inference.grasp_anchoring.LADDER)")
    p.add_argument("--depth", nargs="+", default=["realistic"], choices=["true", "realistic"])
    p.add_argument("--max-scenes", type=int, default=None, help="the first N scenes of each folder")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--against", type=Path, default=None,
                   help="an earlier run's rows.jsonl (same scenes), paired with each decoder")  # fmt: skip
    p.add_argument("--against-columns", nargs="*", default=[], help="columns of --against, e.g. shipped reg4")
    p.add_argument("--summary-only", action="store_true", help="no new scenes: summarise OUT's records as they are")
    args = p.parse_args(argv)
    if args.against is not None and not args.against.is_file():
        p.error(f"--against: {args.against}: no such rows file")
    for folder in args.scenes:
        if not (folder / "manifest.json").is_file():
            p.error(f"--scenes: {folder}: not a scenes folder (no manifest.json)")
    if args.labels_from and not (args.labels_from / "labels").is_dir():
        p.error(f"--labels-from: {args.labels_from}: holds no labels/ folder")
    if not args.decoders and not args.references:
        p.error("--decoders: give at least one decoder (or --references)")
    args.decoders = [tuple(d.partition("=")[::2]) for d in args.decoders]
    for name, path in args.decoders:
        if not name or not Path(path).is_file():
            p.error(f"--decoders: {name}={path}: expected NAME=FILE with an existing decoder checkpoint")
    paths = dict(args.decoders)
    for flag, names in (("--oracle-fit-dropout", args.oracle_fit_dropout), ("--critic", args.critic)):
        unknown = sorted(set(names) - set(paths))
        if unknown:
            p.error(f"{flag}: {', '.join(unknown)}: not a NAME of --decoders")
    for name in args.critic:
        if not critic_path(Path(paths[name])).is_file():
            p.error(f"--critic: {name}: no grasp critic beside {paths[name]} ({critic_path(Path(paths[name]))})")
    return args


def bare_key(key: tuple) -> tuple:
    """A row key without its method, and with its set's name stripped of the folder hash (``set_key``): (set, scene,
    view, depth, instance, object id), so that the same scenes generated in another folder or on another machine
    pair up, and a decoder given the detection pairs with an encoder's predictions (``closed_loop_selection.py``)."""
    return (key[0].rsplit("-", 1)[0], *key[1:4], *key[5:])


def column_outcomes(earlier: list[dict], column: str) -> dict[tuple, bool]:
    """One column of an earlier run's ``rows.jsonl`` rows (those that hold it): :func:`bare_key` -> "success"."""
    keys = ("set", "scene", "view", "depth")
    return {
        bare_key((*(r.get(k, "realistic") for k in keys), "", r["instance"], r["object_id"])): r[column] == "success"
        for r in earlier
        if column in r
    }


def read_jsonl(rows_file: Path) -> list[dict]:
    """The rows of a ``rows.jsonl`` file."""
    return [json.loads(line) for line in rows_file.read_text().splitlines() if line.strip()]


def against_rows(mine: dict[str, dict], rows_file: Path, columns: list[str]) -> dict:
    """Each of ``mine`` (name -> outcomes keyed by :func:`bare_key`) paired with each column of an earlier run's
    ``rows.jsonl`` on the views both hold (same scenes, outcomes by name: "success" counts), plus each side's
    successes on those views."""
    from centerart.evaluation.paired import paired_table

    earlier = read_jsonl(rows_file)
    report = {}
    for col in columns:
        theirs = column_outcomes(earlier, col)
        for n, outcome in mine.items():
            common = set(outcome) & set(theirs)
            mine_name = n if n != col else f"{n} (this run)"  # an encoder row named as the decoder column
            report[f"{col} / {n}"] = {"views": len(common), col: sum(theirs[k] for k in common),
                                      mine_name: sum(outcome[k] for k in common),
                                      "paired": paired_table(theirs, outcome)}  # fmt: skip
    return report


def against(out: Path, names: list[str], rows_file: Path, columns: list[str]) -> dict:
    """This run's decoders (:func:`against_rows`) against the columns of an earlier run's ``rows.jsonl``."""
    rows = read_rows(out)
    mine = {n: {bare_key(k): v for k, v in outcomes(rows, n).items()} for n in names}
    return against_rows(mine, rows_file, columns)


def main(argv=None) -> int:
    from centerart.errors import CenterArtError
    from centerart.evaluation.scene_eval import EvalScenesConfig, list_scene_dirs, set_key
    from centerart.models.checkpoint import load_decoder
    from centerart.utils.parallel import parallel_map

    args = parse(argv)
    decoders = args.decoders
    try:  # bad input (not a decoder, a scene of a training object): one line, before any work
        for _, path in decoders:
            load_decoder(Path(path))
        sets = {set_key(f): list_scene_dirs(f, args.max_scenes) for f in args.scenes}
        check_held_out(args.scenes, sets, decoders)
    except CenterArtError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    if args.labels_from and not (args.out / "labels").exists():
        shutil.copytree(args.labels_from / "labels", args.out / "labels")
    defaults = EvalScenesConfig(scenes=(), out=args.out)
    cfg = {"depth": tuple(args.depth), "grasps": args.grasps, "ablation": False, "seed": defaults.seed,
           "references": args.references, "fit_dropout": tuple(args.oracle_fit_dropout), "critic": tuple(args.critic),
           "labels_per_state": defaults.labels_per_state, "label_max_trials": defaults.label_max_trials}  # fmt: skip
    jobs = [(name, str(d), str(args.out), decoders, cfg) for name, dirs in sets.items() for d in dirs]
    started = time.perf_counter()
    if not args.summary_only:
        list(parallel_map(scene_job, jobs, args.workers, "scenes"))
    wall_s = round(time.perf_counter() - started, 1)
    named = decoders + ([(r, "reference") for r in ("baseline", "label")] if args.references else [])
    report = {"scenes": [str(s) for s in args.scenes], "grasps": args.grasps, "depth": args.depth,
              "oracle_fit_dropout": args.oracle_fit_dropout, "critic": args.critic, "wall_s_this_run": wall_s,
              "decoders": summary(args.out, named)}  # fmt: skip
    if args.against is not None:
        report["against"] = against(args.out, [n for n, _ in decoders], args.against, args.against_columns)
    emit(report, args.out / "report.json")
    return 0


if __name__ == "__main__":
    run_main(main)
