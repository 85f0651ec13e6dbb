"""Do the decoder's grasps survive a shape code fitted to the object's surface?

The held-out evaluation of a decoder run fits each object's shape code to its SDF samples (the decoder frozen), as
inference does with a perfect observation of the object. At closed states the top grasp then misses the handle by
1-2 cm (``benchmarks/results/closed_state_grasps/``). This script asks whether the code, not the decoder, is at
fault: for the first ``--per-category`` training objects of each category at their closed state, the top 5 grasps
decoded with the object's trained code and with a code fitted to its SDF samples (200 steps, as
``centerart eval decoder`` fits them) are executed in physics
(``evaluation.decoder_eval.execute_grasp_results``), with each top grasp's offset from its nearest label.

Frames: object canonical frame = world frame; metres inside, cm and degrees in the report. Run (one core, about
10 min for 15 objects)::

    PYTHONPATH=src:benchmarks python benchmarks/fitted_code_grasps.py \\
        --decoder training_runs/decoder-small-102-paper-reg/decoder.pt --work WORK --out report.json

``WORK``: the decoder run's work folder (``centerart slices decoder --work``: ``objects/``, ``grasps/``, ``sdf/``).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

CODE_FIT_STEPS = 200  # as centerart eval decoder fits held-out objects


def chosen_objects(training: list[str], per_category: int) -> list[str]:
    by_cat: dict[str, list[str]] = {}
    for oid in sorted(training):
        by_cat.setdefault(oid.rsplit("_", 1)[0], []).append(oid)
    return [o for c in sorted(by_cat) for o in by_cat[c][:per_category]]


def closed_row(loaded, work: Path, oid: str, states: list, seed: int, fit_dropout: bool = False) -> dict:
    """Top-5 outcomes at the object's closed state with its trained code and with a code fitted to its SDF (and,
    with ``fit_dropout``, one fitted under the decoder's dropout)."""
    from centerart.assets.articulated_object import ArticulatedObject
    from centerart.evaluation.decoder_eval import fitted_code
    from centerart.grasps.labels import StateLabels, state_path
    from centerart.inference.decoder_grasps import extraction_setting, predict_shape_and_grasps
    from centerart.inference.reconstruction import MeshConfig
    from closed_state_grasps import closed_state, execute_all, label_offset

    obj, st = ArticulatedObject.load(work / "objects" / oid), closed_state(states)
    q = obj.denormalize(st.joint)
    labels = StateLabels.load(state_path(work / "grasps", oid, st.state_index)).poses.astype(np.float64)
    row = {"object": oid}
    codes = {"trained": loaded.codes[oid], "fitted": fitted_code(loaded, states, CODE_FIT_STEPS, seed)}
    if fit_dropout:
        codes["fitted_dropout"] = fitted_code(loaded, states, CODE_FIT_STEPS, seed, dropout=True)
    mesh_cfg, grasp_cfg = MeshConfig(resolution=128), extraction_setting("default", top_k=20)
    for name, code in codes.items():
        _, found = predict_shape_and_grasps(loaded.decoder, code, st.joint, loaded.bounds, mesh_cfg, grasp_cfg)
        top = list(found.poses[:5])
        row[name] = execute_all(obj, q, top)
        row[f"{name}_top_offset"] = label_offset(top[0], labels) if top and len(labels) else None
        row[f"{name}_code_distance"] = round(float(np.linalg.norm(code - codes["trained"])), 4)
    return row


def main(argv=None) -> int:
    from closed_state_grasps import object_states, parse_run_args, run_parser

    p = run_parser(__doc__.split("\n\n")[0])
    p.add_argument("--per-category", type=int, default=3, help="training objects per category")
    p.add_argument("--fit-dropout", action="store_true", help="also fit a code under the decoder's dropout")
    args = parse_run_args(p, argv)

    from centerart.models.checkpoint import load_decoder
    from centerart.utils.atomic import atomic_write_json
    from centerart.utils.torch_cpu import use_cpu_threads

    use_cpu_threads(1)
    loaded = load_decoder(args.decoder)
    oids = chosen_objects(list(loaded.codes), args.per_category)
    states = object_states(args.work / "sdf", oids, args.seed)
    rows = []
    for oid in oids:
        rows.append(closed_row(loaded, args.work, oid, states[oid], args.seed, args.fit_dropout))
        print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
    summary = {k: {"top1": sum(r[k][:1] == ["ok"] for r in rows), "any5": sum("ok" in r[k] for r in rows),
                   "states": len(rows)} for k in rows[0] if k in ("trained", "fitted", "fitted_dropout")}  # fmt: skip
    report = {"decoder": str(args.decoder), "state": "closed (commanded: open)", "objects": "training",
              "code_fit_steps": CODE_FIT_STEPS, "fit_dropout": args.fit_dropout,
              "summary": summary, "rows": rows}  # fmt: skip
    atomic_write_json(args.out, report)
    print(json.dumps(summary, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
