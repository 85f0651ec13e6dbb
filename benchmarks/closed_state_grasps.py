"""Why the decoder's grasps fail at closed states: how precise a grasp must be there, and what centring buys.

The held-out evaluation of a decoder run (``heldout_eval/physics_top1``) executes the top grasp at two states of
each held-out object: closed (commanded: open) and fully open (commanded: close, as no range is left to open).
This script splits that figure and asks where the closed states are lost (issue 29):

1. ``tolerance``: ground-truth labels at the closed state (the first ``--labels`` of each of the first ``--objects``
   held-out objects), shifted by 0, +-0.5, +-1, +-1.5 cm along each TCP axis (x: along the fingers' width, y: the
   closing axis, z: the approach), executed: the precision a grasp needs at a closed door or drawer.
2. ``centring``: each held-out object's top 5 decoded grasps at its closed state (the code fitted to its SDF samples,
   as ``centerart eval decoder`` does, no critic), executed as decoded, then shifted along their closing axis to
   centre the pads on the material between them (the extent of the surface points inside the pads' sweep: the pads'
   width along x, their length along z), once with the decoded surface and once with the object's true surface
   (an oracle: what a perfect observation of the handle would give). Also: each top grasp's offset from its nearest
   label, in that label's TCP frame.

Frames: object canonical frame = world frame (the object alone, as in ``evaluation.decoder_eval``); metres inside,
cm and degrees in the report. Run (2 cores, about 15 min for 18 objects)::

    PYTHONPATH=src:benchmarks python benchmarks/closed_state_grasps.py \\
        --decoder training_runs/decoder-small-102-paper-reg/decoder.pt --work WORK --out report.json

``WORK``: the decoder run's work folder (``centerart slices decoder --work``: ``objects/``, ``grasps/``, ``sdf/``).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

SHIFTS_M = (0.0, 0.005, 0.01, 0.015)
AXES = "xyz"


def centred_on_material(pose: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``pose`` shifted along its closing axis (TCP y) so that the pads straddle the surface points inside their
    sweep (|x| <= pad width / 2, |z| <= pad length / 2, |y| <= half the opening) symmetrically; unchanged when fewer
    than 5 points lie there. Points and pose in the same frame (m)."""
    from centerart.grasps.gripper import FINGER_PAD_LENGTH, FINGER_WIDTH, MAX_OPENING

    local = (points - pose[:3, 3]) @ pose[:3, :3]
    inside = (
        (np.abs(local[:, 0]) <= FINGER_WIDTH / 2)
        & (np.abs(local[:, 2]) <= FINGER_PAD_LENGTH / 2)
        & (np.abs(local[:, 1]) <= MAX_OPENING / 2)
    )
    if inside.sum() < 5:
        return pose
    y = local[inside, 1]
    out = pose.copy()
    out[:3, 3] = pose[:3, 3] + pose[:3, 1] * 0.5 * (y.min() + y.max())
    return out


def execute_all(obj, q: float, poses: list[np.ndarray]) -> list[str]:
    """Each pose executed on ``obj`` at joint state ``q`` (metric): "ok", "weak" (moved too little) or the abort."""
    from centerart.evaluation.decoder_eval import execute_grasp_results

    return [r.abort or ("ok" if r.success else "weak") for r in execute_grasp_results(obj, q, poses)]


def closed_state(states: list):
    """The object's closed state (lowest normalised joint value) among its SDF-sample states."""
    return min(states, key=lambda s: s.joint)


def tolerance(objects: dict, by_obj: dict, grasps: Path, n_objects: int, n_labels: int) -> dict:
    """Success rate of closed-state labels shifted along each TCP axis, averaged over objects."""
    from centerart.grasps.labels import StateLabels, state_path

    rates: dict[str, list[float]] = {}
    for oid in sorted(by_obj)[:n_objects]:
        st = closed_state(by_obj[oid])
        labels = StateLabels.load(state_path(grasps, oid, st.state_index)).poses.astype(np.float64)[:n_labels]
        poses, keys = [], []
        for axis in range(3):
            for shift in SHIFTS_M:
                for sign in (1,) if shift == 0 else (1, -1):
                    for p in labels:
                        moved = p.copy()
                        moved[:3, 3] += p[:3, axis] * shift * sign
                        poses.append(moved)
                        keys.append(f"{AXES[axis]} {sign * shift * 100:+.1f} cm")
        outcomes = execute_all(objects[oid], objects[oid].denormalize(st.joint), poses)
        for key in dict.fromkeys(keys):
            hits = [o == "ok" for k, o in zip(keys, outcomes, strict=True) if k == key]
            rates.setdefault(key, []).append(float(np.mean(hits)))
        print(f"tolerance: {oid}", file=sys.stderr, flush=True)
    return {k: round(float(np.mean(v)), 3) for k, v in rates.items()}


def label_offset(pose: np.ndarray, labels: np.ndarray) -> dict:
    """``pose``'s offset (cm) in the TCP frame of its nearest label (by position), and the angle between them."""
    from centerart.evaluation.metrics import grasp_distances

    pos, ang = grasp_distances(pose[None], labels)
    j = int(np.argmin(pos[0]))
    rel = np.linalg.inv(labels[j]) @ pose
    return {"x_cm": round(rel[0, 3] * 100, 2), "y_cm": round(rel[1, 3] * 100, 2), "z_cm": round(rel[2, 3] * 100, 2),
            "angle_deg": round(float(ang[0, j]), 1)}  # fmt: skip


def centring(loaded, objects: dict, by_obj: dict, grasps: Path, seed: int) -> list[dict]:
    """Per held-out object at its closed state: the top 5 decoded grasps executed as decoded and centred on the
    decoded and on the true surface, with the top grasp's offset from its nearest label."""
    import trimesh

    from centerart.evaluation.decoder_eval import fitted_code
    from centerart.grasps.labels import StateLabels, state_path
    from centerart.inference.decoder_grasps import extraction_setting, predict_shape_and_grasps
    from centerart.inference.reconstruction import MeshConfig

    rows, mesh_cfg, grasp_cfg = [], MeshConfig(resolution=128), extraction_setting("default", top_k=20)
    for oid in sorted(by_obj):
        obj, st = objects[oid], closed_state(by_obj[oid])
        q = obj.denormalize(st.joint)
        code = fitted_code(loaded, by_obj[oid], 200, seed)
        recon, found = predict_shape_and_grasps(loaded.decoder, code, st.joint, loaded.bounds, mesh_cfg, grasp_cfg)
        top = list(found.poses[:5])
        decoded_pts = np.asarray(trimesh.sample.sample_surface(recon.mesh, 30000, seed=seed)[0])
        true_pts = np.asarray(trimesh.sample.sample_surface(obj.watertight_mesh(q), 30000, seed=seed)[0])
        labels = StateLabels.load(state_path(grasps, oid, st.state_index)).poses.astype(np.float64)
        row = {"object": oid, "category": obj.category, "grasps": len(top)}
        row["decoded"] = execute_all(obj, q, top)
        row["centred_on_decoded"] = execute_all(obj, q, [centred_on_material(p, decoded_pts) for p in top])
        row["centred_on_true"] = execute_all(obj, q, [centred_on_material(p, true_pts) for p in top])
        row["top_offset_from_label"] = label_offset(top[0], labels) if len(top) and len(labels) else None
        rows.append(row)
        print(f"centring: {json.dumps(row)}", file=sys.stderr, flush=True)
    return rows


def summarise(rows: list[dict]) -> dict:
    out = {}
    for key in ("decoded", "centred_on_decoded", "centred_on_true"):
        out[key] = {"top1": sum(r[key][:1] == ["ok"] for r in rows), "any5": sum("ok" in r[key] for r in rows),
                    "states": len(rows)}  # fmt: skip
    offsets = [r["top_offset_from_label"] for r in rows if r["top_offset_from_label"]]
    out["top_grasp_abs_offset_cm_median"] = {
        a: round(float(np.median([abs(o[f"{a}_cm"]) for o in offsets])), 2) for a in AXES
    }
    return out


def run_parser(description: str) -> argparse.ArgumentParser:
    """The arguments every decoder-run benchmark here takes: --decoder, --work, --out, --seed."""
    p = argparse.ArgumentParser(description=description)
    p.add_argument("--decoder", type=Path, required=True, help="a decoder checkpoint of the run")
    p.add_argument("--work", type=Path, required=True, help="the run's WORK folder (objects/, grasps/, sdf/)")
    p.add_argument("--out", type=Path, required=True, help="report JSON")
    p.add_argument("--seed", type=int, default=0)
    return p


def parse_run_args(p: argparse.ArgumentParser, argv) -> argparse.Namespace:
    args = p.parse_args(argv)
    for sub in ("objects", "grasps", "sdf"):
        if not (args.work / sub).is_dir():
            p.error(f"--work: {args.work} has no {sub}/ folder (a decoder run's WORK is expected)")
    return args


def object_states(sdf: Path, oids: list[str], seed: int) -> dict[str, list]:
    """Each object's SDF-sample states (``sdf.samples.StateData``, 30,000 points each) from the run's ``sdf/``."""
    from centerart.sdf.samples import load_states

    by_obj: dict[str, list] = {}
    with tempfile.TemporaryDirectory() as tmp:  # load_states reads a folder of object folders: the chosen ones
        for oid in oids:
            (Path(tmp) / oid).symlink_to((sdf / oid).resolve())
        for st in load_states(Path(tmp), 30000, seed, progress=False):
            by_obj.setdefault(st.object_id, []).append(st)
    return by_obj


def main(argv=None) -> int:
    p = run_parser(__doc__.split("\n\n")[0])
    p.add_argument("--objects", type=int, default=4, help="held-out objects in the tolerance part")
    p.add_argument("--labels", type=int, default=8, help="labels per object in the tolerance part")
    args = parse_run_args(p, argv)

    from centerart.assets.articulated_object import ArticulatedObject
    from centerart.models.checkpoint import load_decoder
    from centerart.training.decoder_data import DecoderSplit
    from centerart.utils.atomic import atomic_write_json
    from centerart.utils.torch_cpu import use_cpu_threads

    use_cpu_threads(1)
    loaded = load_decoder(args.decoder)
    heldout = DecoderSplit.from_dict(loaded.meta["split"]).heldout_objects
    by_obj = object_states(args.work / "sdf", heldout, args.seed)
    objects = {oid: ArticulatedObject.load(args.work / "objects" / oid) for oid in heldout}
    rows = centring(loaded, objects, by_obj, args.work / "grasps", args.seed)
    report = {
        "decoder": str(args.decoder), "heldout_objects": len(heldout), "state": "closed (commanded: open)",
        "tolerance_success_rate": tolerance(objects, by_obj, args.work / "grasps", args.objects, args.labels),
        "centring": summarise(rows), "rows": rows,
    }  # fmt: skip
    atomic_write_json(args.out, report)
    print(json.dumps({k: v for k, v in report.items() if k != "rows"}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
