"""Image association beside the 3-D centre match in the scene evaluation (EVALUATION.md, "Matching predictions to
objects"), its reuse of executed trials, the published-protocol rate, and the report's columns for both.

Hand-made labels and predictions only: no rendering, no physics (the trials are stubbed and counted)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from centerart.evaluation import scene_rows
from centerart.evaluation.scene_report import all_thresholds, markdown
from centerart.evaluation.scene_rows import SceneContext, ViewInput, associate_by_image, learned_rows, peak_pixel
from centerart.evaluation.scene_summary import PUBLISHED_PROTOCOL_ABORTS, published_protocol, summarize_records
from centerart.grasps.executor import ABORTS

H, W = 20, 40  # wider than tall: a (u, v) read as (row, column) lands outside the image


def _pose(x: float, y: float = 0.0, z: float = 1.0) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = [x, y, z]
    return T


def _label(instance: int, x: float) -> dict:
    joint = {"type": "revolute", "state": 0.2, "range": [0.0, 1.5], "state_normalized": 0.13}
    return {"instance": instance, "object_id": f"obj{instance}", "category": "oven", "joint": joint,
            "visible_fraction": 0.9, "camera_T_object": _pose(x).tolist()}  # fmt: skip


def _view(n_objects: int = 2) -> ViewInput:
    """Object 0 (instance 1) fills rows 0-9 x columns 0-9, object 1 (instance 2) rows 0-9 x columns 20-39, and a
    third object (instance 3) rows 12-19 x columns 0-9; the rest is background (0). Centres 1 m apart."""
    inst = np.zeros((H, W), np.int32)
    inst[:10, :10], inst[:10, 20:] = 1, 2
    if n_objects > 2:
        inst[12:, :10] = 3
    labels = {"K": np.eye(3).tolist(), "world_T_camera": np.eye(4).tolist(),
              "objects": [_label(k + 1, float(k)) for k in range(n_objects)]}  # fmt: skip
    return ViewInput("s", 0, "true", np.zeros((H, W, 3), np.uint8), np.ones((H, W)), inst, labels)


def _pred(score: float, uv, centre_x: float, grasp_x: float = 0.0):
    """A prediction with its heatmap peak at pixel ``uv`` = (u, v), its centre at x = ``centre_x`` (camera frame,
    m) and one grasp whose x translation ``grasp_x`` tells the stubbed trials which prediction ran."""
    return SimpleNamespace(
        score=score, peak_uv=None if uv is None else np.array(uv, float), camera_T_object=_pose(centre_x),
        grasp_poses=_pose(grasp_x)[None], shape_code=np.zeros(4), joint_type="revolute",
        joint_type_probability=1.0, axis_direction=np.array([0.0, 0.0, 1.0]), axis_point=np.zeros(3), mask=None,
    )  # fmt: skip


def test_peak_pixel_reads_u_as_column_and_v_as_row():
    assert peak_pixel(np.array([25.4, 5.6]), (H, W)) == (6, 25)
    assert peak_pixel(np.array([5.0, 25.0]), (H, W)) is None  # row 25 of a 20-row image
    assert peak_pixel(None, (H, W)) is None


def test_image_association_on_two_masks():
    v = _view()
    preds = [
        _pred(0.6, (3, 3), 0.0),  # in object 0's mask, but a better one is there too
        _pred(0.9, (5, 5), 0.0),  # in object 0's mask, highest score there: taken
        _pred(0.5, (30, 2), 1.6),  # in object 1's mask with its centre 0.6 m off: still associated by image
        _pred(0.99, (15, 15), 1.0),  # highest score of all, on the background: nobody's
    ]
    assert associate_by_image(v, preds) == {0: 1, 1: 2}
    assert scene_rows.match_predictions(v, preds).get(1) == 3  # the 3-D match picks the background peak instead


def test_image_association_leaves_an_object_without_a_peak_in_its_mask_missed():
    v = _view()
    assert associate_by_image(v, [_pred(0.8, (25, 5), 1.0), _pred(0.7, (30, 8), 1.0)]) == {1: 0}
    assert associate_by_image(v, [_pred(0.8, None, 0.0), _pred(0.7, (15, 15), 0.0)]) == {}


@pytest.fixture
def stub_trials(monkeypatch):
    """Counted stand-ins for the physics: a trial succeeds when its grasp's x translation is 11 (prediction P1)."""
    calls = []

    def execute(phys, k, world_T_tcp, axis=None):
        x = round(float(world_T_tcp[0, 3]))
        calls.append((k, x, axis is not None))
        return {"success": x == 11, "abort": "" if x == 11 else "no_contact", "displacement": 0.0}

    monkeypatch.setattr(scene_rows, "execute_grasp", execute)
    monkeypatch.setattr(scene_rows, "any_of_top", lambda *a, **kw: False)
    monkeypatch.setattr(scene_rows, "full_open", lambda *a, **kw: None)
    monkeypatch.setattr(scene_rows, "relaxed_success", lambda world, labels: round(float(world[0, 3])) == 11)
    monkeypatch.setattr(scene_rows, "nearest_label_position_m", lambda world, labels: np.array([0.05]))
    monkeypatch.setattr(scene_rows, "object_errors", lambda pred, obj: {})
    monkeypatch.setattr(scene_rows, "view_metrics", lambda preds, labels: {"counts": {}})
    return calls


class _Predictor:
    def __init__(self, preds):
        self.preds, self.timing = preds, {}

    def predict(self, rgb, depth, K, encoded=None, gravity=None):
        return self.preds

    def predict_detection(self, det, rgb, depth, K):  # the true pose swapped in: grasp x = 99 (fails)
        return SimpleNamespace(grasp_poses=_pose(99.0)[None])


def test_learned_rows_reuse_the_3d_trial_and_execute_only_where_the_associations_differ(stub_trials):
    v = _view(3)
    preds = [
        _pred(0.9, (5, 5), 0.0, grasp_x=10),  # P0: object 0 by both associations
        _pred(0.8, (30, 5), 1.6, grasp_x=11),  # P1: object 1 by image only (centre 0.6 m off)
        _pred(0.7, (15, 15), 1.0, grasp_x=12),  # P2: object 1 by 3-D centre only (peak on the background)
    ]
    ctx = SceneContext(phys=None, labels_world=[np.zeros((0, 4, 4))] * 3)
    rows, _ = learned_rows(ctx, v, _Predictor(preds), "centerart", shape=False, ablation=True)
    r0, r1, r2 = rows
    assert r0["image_matched"] and r0["image_same_as_3d"] and r0["sr_image"] == r0["sr"] is False
    assert r0["sr_image_abort"] == r0["sr_abort"] == "no_contact"
    assert r1["matched"] and not r1["sr"] and r1["sr_abort"] == "no_contact"  # P2's grasp
    assert r1["image_matched"] and r1["image_same_as_3d"] is False
    assert r1["sr_image"] is True and r1["rsr_image"] is True and r1["sr_image_abort"] == ""  # P1's grasp
    assert r2["matched"] is False and r2["image_matched"] is False and r2["sr_image_abort"] == "missed"
    assert r2["sr_image_gt_pose"] is None and r0["sr_image_gt_pose"] == r0["sr_gt_pose"] is False

    true_joint_trials = [(k, x) for k, x, follows_prediction in stub_trials if not follows_prediction]
    assert true_joint_trials.count((0, 10)) == 1, "the image association re-ran the 3-D match's trial"
    assert true_joint_trials.count((1, 11)) == 1 and true_joint_trials.count((1, 12)) == 1
    # true-pose swaps: object 0 once (reused for the image association), object 1 once per association
    assert true_joint_trials.count((0, 99)) == 1 and true_joint_trials.count((1, 99)) == 2
    assert not any(k == 2 for k, _ in true_joint_trials)


def _row(**kw) -> dict:
    row = {"scene": "s", "view": 0, "instance": 0, "category": "oven", "matched": True, "sr": False,
           "sr_abort": "", "sr_axis": False, "top5_any": False, "rsr": False, "nearest_label_m": None,
           "image_matched": True, "sr_image": False, "sr_image_abort": "too_little_motion",
           "rsr_image": False}  # fmt: skip
    return {**row, **kw}


def test_published_protocol_leaves_out_misses_and_aborted_runs_only():
    rows = [
        _row(sr_image=True, sr_image_abort=""),
        _row(sr_image=True, sr_image_abort=""),
        _row(sr_image_abort="no_contact"),  # the hand closed on nothing: a failure that counts
        _row(sr_image_abort="lost_grip"),  # counts too
        _row(sr_image_abort="collision_at_spawn"),  # never ran: left out
        _row(sr_image_abort="approach_blocked"),  # never ran: left out
        _row(image_matched=False, sr_image_abort="missed"),  # no associated prediction: left out
    ]
    p = published_protocol(rows)
    assert p == {"objects": 7, "left_out_missed": 1, "left_out_aborted": 2, "counted": 4, "sr": 0.5}
    assert published_protocol([{k: v for k, v in r.items() if "image" not in k} for r in rows]) is None


def test_published_protocol_aborts_are_executor_aborts_before_the_grasp():
    assert set(PUBLISHED_PROTOCOL_ABORTS) <= set(ABORTS)
    assert "no_contact" not in PUBLISHED_PROTOCOL_ABORTS and "lost_grip" not in PUBLISHED_PROTOCOL_ABORTS


def _report(records: list[dict]) -> dict:
    sha = "0" * 64
    return {
        "code_version": "test", "checkpoints": {"encoder": {"path": "e.pt", "sha256": sha},
                                                "decoder": {"path": "d.pt", "sha256": sha}, "grasp_critic": None},
        "held_out": True, "training_overlap": [], "thresholds": all_thresholds(), "scenes_evaluated": len(records),
        "scenes_missing": [], "images": 1, "sets": {"new": {"label": "new", "layout": "single"},
                                                    "old": {"label": "old", "layout": "single"}},
        **summarize_records(records),
    }  # fmt: skip


def test_report_shows_both_associations_and_dashes_for_old_records():
    new = [_row(method="centerart", depth="true", sr=False, sr_image=True, sr_image_abort="", sr_gt_pose=False,
                sr_image_gt_pose=True, image_same_as_3d=i == 0, instance=i) for i in range(2)]  # fmt: skip
    new.append(_row(method="oracle", depth="true", sr=True, sr_image=True, sr_image_abort=""))
    old = [{k: v for k, v in r.items() if "image" not in k} for r in new]
    records = [{"set": "new", "rows": new, "images": []}, {"set": "old", "rows": old, "images": []}]
    report = _report(records)
    md = markdown(report)
    assert "SR img true | SR 3-D true | RSR img true | RSR 3-D true | SR img realistic" in md
    assert "| new | single | centerart | 1.00 | 0.00 | 0.00 | 0.00 | - | - | - | - | 2 |" in md
    assert "| old | single | centerart | - | 0.00 | - | 0.00 | - | - | - | - | 2 |" in md
    assert "## Published protocol, for comparison only" in md
    assert "| new / centerart / true | 2 | 0 | 0 | 2 | 1.00 | 1.00 |" in md
    assert "| old / centerart / true | 2 | - | - | - | - | - |" in md
    published_section = md.split("## Published protocol")[1].split("\n## ")[0]
    assert "new / centerart / true" in published_section and "oracle" not in published_section
    # stage analysis: SR 3-D, its true-pose swap, SR img, its true-pose swap
    assert "| new / centerart / true | 2 | 0.00 | 0.00 | 1.00 | 1.00 |" in md
    assert "| old / centerart / true | 2 | 0.00 | 0.00 | - | - |" in md
    # variants: matched (3-D), associated (img), img = 3-D (the outcome reused for one of the two objects)
    assert "| new / centerart / true | 2 | 1.00 | 1.00 | 0.50 | 0.00 |" in md
    assert "collision_at_spawn, approach_blocked" in md and "within 0.1 m" in md and "visible instance mask" in md
    assert report["thresholds"]["matching"]["published_protocol_aborts"] == list(PUBLISHED_PROTOCOL_ABORTS)
