"""A scene description rebuilt in pybullet for grasp execution: room boxes, counters, every object at its state.

Frames: the scene's world frame (z up, metres), the same frame as ``SceneDescription`` (objects placed by
``world_T_object``, boxes by ``world_T_box``). The executor is the grasp-label generator's
(:class:`~centerart.grasps.executor.GraspExecutor`): a predicted grasp and a label are judged by the same physics.
No gravity, as for the labels: a grasp is judged on whether it moves the part, not on whether gravity does.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from centerart.assets.articulated_object import ArticulatedObject
from centerart.grasps.executor import GraspExecutor
from centerart.grasps.sim_world import GraspTarget, connect, pose_to_pb, spawn_object_in_pybullet
from centerart.scenes.description import SceneDescription, load_scene_object


@dataclass
class PhysicsScene:
    """One pybullet world of a scene. ``targets[k]`` / ``objects[k]`` / ``states[k]``: scene object k (instance
    k + 1) and its true target-joint state (metric; what the saved world holds, exactly)."""

    client: int
    executor: GraspExecutor
    targets: list[GraspTarget]
    objects: list[ArticulatedObject]
    states: list[float]
    boxes: list[int] = field(default_factory=list)

    def close(self) -> None:
        import pybullet as pb

        pb.disconnect(self.client)

    def __enter__(self) -> PhysicsScene:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def add_box(client: int, world_T_box: np.ndarray, half_size) -> int:
    """A static collision box (pybullet body id) centred at ``world_T_box`` with ``half_size`` (m)."""
    import pybullet as pb

    shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=list(map(float, half_size)), physicsClientId=client)
    pos, orn = pose_to_pb(np.asarray(world_T_box, float))
    return pb.createMultiBody(0.0, shape, -1, pos, orn, physicsClientId=client)


def build_physics_scene(scene: SceneDescription, objects: list[ArticulatedObject] | None = None) -> PhysicsScene:
    """Rebuild ``scene`` in a new headless pybullet world; ``objects`` (loaded with
    :func:`~centerart.scenes.description.load_scene_object`) may be passed to avoid loading them twice."""
    client = connect()
    try:
        boxes = [add_box(client, b.world_T_box, b.half_size) for b in scene.boxes]
        objects = objects if objects is not None else [load_scene_object(spec) for spec in scene.objects]
        targets = [
            spawn_object_in_pybullet(client, obj, spec.joint_state, scene.object_pose(k))
            for k, (spec, obj) in enumerate(zip(scene.objects, objects, strict=True))
        ]
        executor = GraspExecutor(client)  # last: it saves the world every trial starts from
    except BaseException:
        import pybullet as pb

        pb.disconnect(client)
        raise
    return PhysicsScene(client, executor, targets, list(objects), [s.joint_state for s in scene.objects], boxes)
