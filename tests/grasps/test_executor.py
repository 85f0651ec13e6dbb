"""The shared grasp executor on hand-built grasps with known outcomes."""

from __future__ import annotations

import numpy as np
import pytest

from centerart.assets.articulated_object import ArticulatedObject
from centerart.geometry.transforms import make_pose
from centerart.grasps import executor as ex
from centerart.grasps.sim_world import connect, spawn_object_in_pybullet


def _handle_grasp(obj: ArticulatedObject, q: float) -> np.ndarray:
    """TCP across the first bar/U handle of the moving part: x along the bar, approach towards the front."""
    h = next(h for h in obj.meta["handles"] if h["link"] in obj.moving_links and h["type"] in ("bar", "u"))
    link = obj.link_poses(q)[h["link"]]
    center = (link @ np.r_[h["center"], 1.0])[:3]
    x = link[:3, :3] @ np.asarray(h["axis"], float)
    z = -link[:3, 0]
    return make_pose(np.stack([x, np.cross(z, x), z], axis=1), center)


def _world(obj, q):
    import pybullet as pb

    client = connect()
    target = spawn_object_in_pybullet(client, obj, q)
    return client, target, ex.GraspExecutor(client), pb


@pytest.mark.parametrize("which", ["door_bar", "door_u"])
def test_handle_grasp_opens_door_and_air_grasp_does_not(objects_dir, known_ids, which):
    obj = ArticulatedObject.load(objects_dir / known_ids[which])
    q = obj.joint_range[0]
    client, target, executor, pb = _world(obj, q)
    grasp = _handle_grasp(obj, q)
    result = executor.execute(grasp, target)
    assert result.direction == 1
    assert result.success, result
    assert result.displacement >= ex.SUCCESS_ANGLE
    # The same grasp 0.3 m out in front of the door, in free air: nothing moves.
    air = grasp.copy()
    air[:3, 3] -= air[:3, 2] * 0.3
    missed = executor.execute(air, target)
    assert not missed.success
    assert missed.abort == "no_contact"
    assert abs(missed.displacement) < 1e-4
    pb.disconnect(client)


def test_drawer_pulled_by_handle_opens(objects_dir, known_ids):
    obj = ArticulatedObject.load(objects_dir / known_ids["drawer_bar"])
    assert obj.joint_type == "prismatic"
    q = obj.joint_range[0]
    client, target, executor, pb = _world(obj, q)
    result = executor.execute(_handle_grasp(obj, q), target)
    assert result.success, result
    assert result.displacement >= ex.SUCCESS_DISTANCE
    pb.disconnect(client)


def test_pushing_closed_door_further_closed_fails(objects_dir, known_ids):
    obj = ArticulatedObject.load(objects_dir / known_ids["door_bar"])
    q = obj.joint_range[0]
    client, target, executor, pb = _world(obj, q)
    result = executor.execute(_handle_grasp(obj, q), target, direction=-1)
    assert not result.success
    assert result.displacement < ex.SUCCESS_ANGLE
    pb.disconnect(client)


def test_wrong_motion_axis_fails(objects_dir, known_ids):
    """SR-axis variant: following a wrong (predicted) axis cannot open the door."""
    obj = ArticulatedObject.load(objects_dir / known_ids["door_bar"])
    q = obj.joint_range[0]
    client, target, executor, pb = _world(obj, q)
    grasp = _handle_grasp(obj, q)
    assert executor.execute(grasp, target).success
    # Pull straight up along world z instead of swinging the bottom-hinged door down/out.
    wrong = target.with_axis(target.axis_origin, [0.0, 0.0, 1.0], "prismatic")
    assert not executor.execute(grasp, wrong).success
    pb.disconnect(client)


def test_spawn_collision_aborts(objects_dir, known_ids):
    obj = ArticulatedObject.load(objects_dir / known_ids["door_bar"])
    q = obj.joint_range[0]
    client, target, executor, pb = _world(obj, q)
    # Approach straight down: the spawn pose (0.1 m back) puts the TCP 5 mm, the fingertips 10 mm into the top.
    top = obj.bounds(q)[1, 2]
    down = np.array([[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]]).T
    grasp = make_pose(down, [-0.1, 0.0, top - 0.105])
    result = executor.execute(grasp, target)
    assert not result.success
    assert result.abort == "collision_at_spawn"
    pb.disconnect(client)


def test_commanded_direction_rule():
    assert ex.commanded_direction("revolute", 0.0, 1.57) == 1
    assert ex.commanded_direction("revolute", 0.8, 1.57) == -1
    assert ex.commanded_direction("prismatic", 0.0, 0.3) == 1
    assert ex.commanded_direction("prismatic", 0.25, 0.3) == -1


def test_trials_are_deterministic(objects_dir, known_ids):
    obj = ArticulatedObject.load(objects_dir / known_ids["door_u"])
    q = 0.5 * sum(obj.joint_range)
    client, target, executor, pb = _world(obj, q)
    grasp = _handle_grasp(obj, q)
    a, b = executor.execute(grasp, target), executor.execute(grasp, target)
    assert a == b
    pb.disconnect(client)


def test_pybullet_gripper_matches_the_gripper_geometry():
    """The simulated fingers sit where gripper.gripper_boxes says (guards the base-at-inertial-origin gotcha)."""
    import pybullet as pb

    from centerart.geometry.transforms import rotation_about_axis
    from centerart.grasps.gripper import gripper_boxes, hand_pose

    client = connect()
    executor = ex.GraspExecutor(client)
    tcp = make_pose(rotation_about_axis([0.3, -0.5, 0.8], 1.1), [0.2, -0.1, 0.4])
    for opening in (0.08, 0.03):
        executor.gripper.place(hand_pose(tcp), opening)
        base = pb.getBasePositionAndOrientation(executor.gripper.body, physicsClientId=client)[0]
        np.testing.assert_allclose(base, hand_pose(tcp)[:3, 3], atol=1e-6)
        for finger, (_, tcp_T_box) in zip(executor.gripper.fingers, gripper_boxes(opening)[1:], strict=True):
            state = pb.getLinkState(executor.gripper.body, finger, physicsClientId=client)
            aabb_lo, aabb_hi = pb.getAABB(executor.gripper.body, finger, physicsClientId=client)
            centre = (np.asarray(aabb_lo) + np.asarray(aabb_hi)) / 2
            np.testing.assert_allclose(centre, (tcp @ tcp_T_box)[:3, 3], atol=2e-3)
            assert state is not None
    pb.disconnect(client)


@pytest.mark.parametrize("which", ["door_bar", "drawer_bar"])
def test_commanded_pull_carries_the_part_past_the_success_threshold(objects_dir, known_ids, which):
    """The full-open variant: with ``pull`` the hand keeps going (no early stop at the threshold) and the joint
    follows close to the commanded travel; without it the trial stops soon after the threshold."""
    obj = ArticulatedObject.load(objects_dir / known_ids[which])
    lo, hi = obj.joint_range
    client, target, executor, pb = _world(obj, lo)
    grasp = _handle_grasp(obj, lo)
    travel = 0.8 * (hi - lo)
    full = executor.execute(grasp, target, direction=1, pull=travel)
    short = executor.execute(grasp, target, direction=1)
    pb.disconnect(client)
    assert full.success and short.success, (full, short)
    assert full.displacement > 0.8 * travel, (full.displacement, travel)
    assert short.displacement < 0.6 * travel
