"""Aggregate scene-evaluation rows into the report's numbers: per test set x method x depth mode, per category,
errors, detection, latency, and where the failures come from.

Every rate counts every ground-truth object of its group in its denominator (misses and aborts are failures);
a rate is None only where a method does not define it (SR-axis of the oracle and the baseline) or where the
records predate it (the image-association rates of records written before rows held ``sr_image``). The one
exception, labelled as such, is the published protocol's rate (:func:`published_protocol`), for comparison only.
"""

from __future__ import annotations

from collections import Counter, defaultdict

import numpy as np

from centerart.evaluation.metrics import distance_distribution

#: Outcomes the published protocol leaves out of its denominator as "aborted runs" (reference/
#: published-implementation.md 5.3: a hand that could not be placed or could not approach; the run never
#: happened). Their counterparts in the executor: the hand collides where it spawns, or is blocked on the way in.
#: ``no_contact``, ``lost_grip`` and too little motion happen after the hand closed at the grasp: the run took
#: place and failed, so they stay failures; so does ``no_grasp`` (the prediction decoded no grasp: the method's
#: failure, not the run's).
PUBLISHED_PROTOCOL_ABORTS = ("collision_at_spawn", "approach_blocked")


def rate(rows: list[dict], key: str) -> float | None:
    vals = [bool(r[key]) for r in rows if r.get(key) is not None]
    return float(np.mean(vals)) if vals else None


def rate_if_recorded(rows: list[dict], key: str) -> float | None:
    """``rate`` over every row, or None when some row lacks ``key`` (records written before the key existed):
    a rate over only the newer rows would silently be over another set of objects."""
    return rate(rows, key) if rows and all(key in r for r in rows) else None


def published_protocol(rows: list[dict]) -> dict | None:
    """The published protocol's SR, for comparison only: the hand follows the true hinge (our SR already does),
    objects without an image-associated prediction (misses) and aborted runs (:data:`PUBLISHED_PROTOCOL_ABORTS`)
    leave the denominator; the image-associated prediction's top grasp is executed. None for old records."""
    if not rows or not all("image_matched" in r for r in rows):
        return None
    missed = sum(not r["image_matched"] for r in rows)
    aborted = sum(bool(r["image_matched"] and r["sr_image_abort"] in PUBLISHED_PROTOCOL_ABORTS) for r in rows)
    kept = [r for r in rows if r["image_matched"] and r["sr_image_abort"] not in PUBLISHED_PROTOCOL_ABORTS]
    return {
        "objects": len(rows),
        "left_out_missed": missed,
        "left_out_aborted": aborted,
        "counted": len(kept),
        "sr": float(np.mean([bool(r["sr_image"]) for r in kept])) if kept else None,
    }


def _median(values) -> float | None:
    values = [v for v in values if v is not None and np.isfinite(v)]
    return float(np.median(values)) if values else None


def _mean(values) -> float | None:
    values = [v for v in values if v is not None and np.isfinite(v)]
    return float(np.mean(values)) if values else None


def full_open_summary(rows: list[dict]) -> dict | None:
    """Full-open variant over the objects the protocol opens, for methods that predict an axis; an object whose
    grasp never ran (missed, no grasp) counts as not reached."""
    applicable = [r for r in rows if r.get("opens") and r.get("sr_axis") is not None]
    if not applicable:
        return None
    runs = [r["full_open"] for r in applicable if r.get("full_open")]
    return {
        "objects": len(applicable),
        "reached_share": float(np.mean([bool(r.get("full_open") and r["full_open"]["reached"]) for r in applicable])),
        "fraction_of_range_mean": _mean([x["fraction_of_range"] for x in runs]),
        "covered_mean": _mean([x["covered"] for x in runs]),
    }


def error_summary(rows: list[dict]) -> dict | None:
    errs = [r["errors"] for r in rows if r.get("errors")]
    if not errs:
        return None
    rev = [e for e in errs if e["joint_type"] == "revolute"]
    pri = [e for e in errs if e["joint_type"] == "prismatic"]
    shapes = [r["shape"] for r in rows if r.get("shape")]
    return {
        "matched": len(errs),
        "translation_cm_median": _median(e["translation_cm"] for e in errs),
        "rotation_deg_median": _median(e["rotation_deg"] for e in errs),
        "joint_type_accuracy": float(np.mean([e["joint_type_correct"] for e in errs])),
        "axis_deg_median": _median(e["axis_deg"] for e in errs),
        "joint_state_deg_median": _median(e["joint_state_error"] for e in rev),
        "joint_state_cm_median": _median(e["joint_state_error"] for e in pri),
        "chamfer_mm_mean": _mean(s["chamfer_l1_mm"] for s in shapes),
        "chamfer_mm_median": _median(s["chamfer_l1_mm"] for s in shapes),
        "fscore_mean": _mean(s["fscore"] for s in shapes),
        "shapes": len(shapes),
    }


def category_summary(rows: list[dict]) -> dict:
    return {
        "objects": len(rows),
        "sr": rate(rows, "sr"),
        "sr_image": rate_if_recorded(rows, "sr_image"),
        "sr_axis": rate(rows, "sr_axis"),
        "rsr": rate(rows, "rsr"),
    }


def group_summary(rows: list[dict]) -> dict:
    nearest = np.array([np.inf if r.get("nearest_label_m") is None else r["nearest_label_m"] for r in rows])
    by_cat = defaultdict(list)
    for r in rows:
        by_cat[r["category"]].append(r)
    return {
        "objects": len(rows),
        "sr": rate(rows, "sr"),
        "sr_axis": rate(rows, "sr_axis"),
        "rsr": rate(rows, "rsr"),
        "sr_image": rate_if_recorded(rows, "sr_image"),
        "rsr_image": rate_if_recorded(rows, "rsr_image"),
        "top5_any": rate(rows, "top5_any"),
        "matched_share": rate(rows, "matched"),
        "image_matched_share": rate_if_recorded(rows, "image_matched"),
        # of the objects with an image-associated prediction: how often it is the 3-D matched one (outcome reused)
        "image_same_as_3d_share": rate(rows, "image_same_as_3d"),
        "published_protocol": published_protocol(rows),
        "full_open": full_open_summary(rows),
        "aborts": dict(sorted(Counter(r["sr_abort"] or "success" for r in rows).items())),
        "nearest_label": distance_distribution(nearest),
        "errors": error_summary(rows),
        "by_category": {c: category_summary(rs) for c, rs in sorted(by_cat.items())},
    }


def image_summary(images: list[dict]) -> dict:
    """Detection precision / recall (3-D centre match) and latency per image of one group."""
    c = Counter()
    for im in images:
        c.update({k: v for k, v in im["counts"].items() if isinstance(v, int)})
    totals = [im["timing_s"].get("total_s") for im in images]
    return {
        "images": len(images),
        "precision": c["true_positives"] / c["predictions"] if c["predictions"] else None,
        "recall": c["found"] / c["true_objects"] if c["true_objects"] else None,
        "latency_s_median": _median(totals),
        "latency_s_mean": _mean(totals),
    }


STAGES = ("detection", "pose_and_joint", "shape_code", "shape_and_grasp_decoding", "execution")
"""``shape_code`` counts only in records with the code oracle (``sr_gt_pose_code``); there
``shape_and_grasp_decoding`` is what fails even with a shape code fitted to the object: the decoder's grasps."""


def stage_losses(rows: list[dict], oracle_rows: list[dict]) -> dict | None:
    """Where the learned method's failures come from, by swapping in ground truth one stage at a time:
    detection (missed), pose and joint (the true pose and state make the grasp succeed), shape code (a code fitted
    to the object's true surface makes it succeed too, where the records hold that swap), shape and grasp
    decoding (still failing with them, while a ground-truth label succeeds), execution (the label fails too).
    The failures are those of the 3-D match; the image association's SR and its swaps stand beside it (None for
    records without them)."""
    if not rows or not any("sr_gt_pose" in r for r in rows):
        return None
    oracle = {(r["scene"], r["view"], r["instance"]): r["sr"] for r in oracle_rows}
    out = Counter()
    for r in rows:
        if r["sr"]:
            continue
        if not r["matched"]:
            out["detection"] += 1
        elif r.get("sr_gt_pose"):
            out["pose_and_joint"] += 1
        elif r.get("sr_gt_pose_code"):
            out["shape_code"] += 1
        elif oracle.get((r["scene"], r["view"], r["instance"]), True):
            out["shape_and_grasp_decoding"] += 1
        else:
            out["execution"] += 1
    n = len(rows)
    with_code = any("sr_gt_pose_code" in r for r in rows)  # misses hold no swap
    return {
        "objects": n,
        "sr": rate(rows, "sr"),
        "sr_with_true_pose_and_joint": float(np.mean([bool(r["sr"] or r.get("sr_gt_pose")) for r in rows])),
        "sr_with_true_pose_joint_and_code": _any_rate(rows, ("sr", "sr_gt_pose", "sr_gt_pose_code"))
        if with_code
        else None,
        "sr_image": rate_if_recorded(rows, "sr_image"),
        "sr_image_with_true_pose_and_joint": _swap_rate(rows, "sr_image", ("sr_image_gt_pose",)),
        "sr_image_with_true_pose_joint_and_code": _swap_rate(
            rows, "sr_image", ("sr_image_gt_pose", "sr_image_gt_pose_code")
        ),
        "failures_by_stage": {k: out[k] for k in STAGES if k != "shape_code" or with_code},
        "failure_share_by_stage": {k: out[k] / n for k in out},
    }


def _swap_rate(rows: list[dict], sr_key: str, swap_keys: tuple[str, ...]) -> float | None:
    """Share of rows that succeed as they are or with any of the swaps (None where a record lacks one)."""
    if not all(sr_key in r and all(k in r for k in swap_keys) for r in rows):
        return None
    return _any_rate(rows, (sr_key, *swap_keys))


def _any_rate(rows: list[dict], keys: tuple[str, ...]) -> float:
    """Share of rows where any of ``keys`` is true (a missing or None value counts as false)."""
    return float(np.mean([any(bool(r.get(k)) for k in keys) for r in rows]))


def summarize_records(records: list[dict]) -> dict:
    """Groups keyed ``set|method|depth`` with their summaries, plus the stage analysis per ``set|depth``."""
    rows_by, images_by = defaultdict(list), defaultdict(list)
    for rec in records:
        for r in rec["rows"]:
            rows_by[(rec["set"], r["method"], r["depth"])].append(r)
        for im in rec["images"]:
            images_by[(rec["set"], im["method"], im["depth"])].append(im)
    groups = {}
    for key, rows in sorted(rows_by.items()):
        g = group_summary(rows)
        if key in images_by:
            g["detection"] = image_summary(images_by[key])
        groups["|".join(key)] = g
    stages = {}
    for (s, method, depth), rows in sorted(rows_by.items()):
        loss = stage_losses(rows, rows_by.get((s, "oracle", depth), []))
        if loss is not None:
            stages[f"{s}|{method}|{depth}"] = loss
    return {"groups": groups, "stages": stages}
