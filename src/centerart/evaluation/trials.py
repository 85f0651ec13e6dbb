"""Grasp trials of the scene evaluation (EVALUATION.md): SR, SR-axis, full-open, any-of-top-k, and the oracle.

All poses are in the physics world frame (the scene's world, metres); ``k`` is the scene object index. The motion
direction (open or close) always comes from the true joint state by the protocol's rule
(:func:`~centerart.grasps.executor.commanded_direction`); success is always measured on the true joint.
"""

from __future__ import annotations

import numpy as np

from centerart.evaluation.physics_scene import PhysicsScene
from centerart.geometry.transforms import make_pose
from centerart.grasps.executor import APPROACH_DISTANCE, GraspResult, commanded_direction
from centerart.grasps.generate import PREFILTER_TOL

#: Full-open variant: drive the joint until this fraction of its range (from the lower limit) is reached.
FULL_OPEN_FRACTION = 0.9
#: ... and count it reached when the joint ends within this fraction of the range of that goal.
FULL_OPEN_TOLERANCE = 0.02
#: Commanded travel when the predicted joint type differs from the true one (units of the predicted type).
FULL_TRAVEL_BY_TYPE = {"revolute": 1.4, "prismatic": 0.35}
#: "Any of the top k" grasps of an object.
TOP_K_ANY = 5
#: The oracle tries labels in order and executes the first one clear of the scene (at most this many checked).
ORACLE_MAX_CHECKS = 50


def thresholds() -> dict:
    return {
        "full_open_fraction": FULL_OPEN_FRACTION,
        "full_open_tolerance": FULL_OPEN_TOLERANCE,
        "top_k_any": TOP_K_ANY,
        "oracle_max_checks": ORACLE_MAX_CHECKS,
    }


def _direction(phys: PhysicsScene, k: int) -> int:
    target = phys.targets[k]
    return commanded_direction(target.joint_type, phys.states[k], target.upper)


def _as_dict(result: GraspResult) -> dict:
    return {"success": bool(result.success), "abort": result.abort, "displacement": float(result.displacement)}


def execute_grasp(phys: PhysicsScene, k: int, world_T_tcp: np.ndarray, axis: dict | None = None) -> dict:
    """One trial of ``world_T_tcp`` on object ``k``. ``axis`` (world frame: ``origin``, ``direction``, ``type``)
    makes the hand follow a predicted joint (SR-axis); None follows the true joint (SR)."""
    target = phys.targets[k]
    direction = _direction(phys, k)
    if axis is not None:
        target = target.with_axis(axis["origin"], axis["direction"], axis["type"])
    return _as_dict(phys.executor.execute(np.asarray(world_T_tcp, float), target, direction))


def any_of_top(phys: PhysicsScene, k: int, grasps: np.ndarray, first: dict | None = None) -> bool:
    """Whether any of the first TOP_K_ANY grasps (world frame, ranked) succeeds (SR rules); ``first`` is the top
    grasp's already executed trial (saves re-running it)."""
    for i, pose in enumerate(np.asarray(grasps)[:TOP_K_ANY]):
        trial = first if (i == 0 and first is not None) else execute_grasp(phys, k, pose)
        if trial["success"]:
            return True
    return False


def full_open(phys: PhysicsScene, k: int, world_T_tcp: np.ndarray, axis: dict) -> dict | None:
    """Keep following the predicted ``axis`` until FULL_OPEN_FRACTION of the range is reached or the grasp slips.

    Only for objects the protocol opens (None when it closes them). Returns the fraction of the whole range the
    joint ends at, the share of the distance to the goal covered, and whether the goal was reached."""
    target = phys.targets[k]
    if _direction(phys, k) < 0:
        return None
    q0, lo, hi = phys.states[k], target.lower, target.upper
    goal = lo + FULL_OPEN_FRACTION * (hi - lo)
    pull = goal - q0 if axis["type"] == target.joint_type else FULL_TRAVEL_BY_TYPE[axis["type"]]
    moved = target.with_axis(axis["origin"], axis["direction"], axis["type"])
    result = phys.executor.execute(np.asarray(world_T_tcp, float), moved, +1, pull=max(pull, 1e-3))
    q1 = result.q_end
    return {
        "fraction_of_range": float((q1 - lo) / (hi - lo)),
        "covered": float(np.clip((q1 - q0) / max(goal - q0, 1e-9), -1.0, 1.0)),
        "reached": bool(q1 >= goal - FULL_OPEN_TOLERANCE * (hi - lo)),
        "abort": result.abort,
    }


def oracle_trial(phys: PhysicsScene, k: int, labels_world: np.ndarray) -> dict:
    """Execute the first ground-truth label of object ``k`` (world frame) whose gripper is clear of the scene at
    the grasp and pre-grasp poses (the label generator's own pre-filter, now with the room and the neighbours)."""
    back = make_pose(translation=[0.0, 0.0, -APPROACH_DISTANCE])
    ex = phys.executor
    for i, pose in enumerate(np.asarray(labels_world)[:ORACLE_MAX_CHECKS]):
        if ex.hand_collides(pose, tol=PREFILTER_TOL) or ex.hand_collides(pose @ back):
            continue
        return {**execute_grasp(phys, k, pose), "label_index": i, "grasp_world": pose.tolist()}
    abort = "no_labels" if len(labels_world) == 0 else "every_label_collides_in_scene"
    return {"success": False, "abort": abort, "displacement": 0.0, "label_index": -1, "grasp_world": None}
