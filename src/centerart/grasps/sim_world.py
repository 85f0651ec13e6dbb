"""Articulated objects in a pybullet world, and the description of the joint a grasp must move.

Frames: the pybullet world frame ("world", z up, metres). An object is placed by ``world_T_object`` (the pose of
its canonical frame, :mod:`centerart.assets.canonical_frame`); its URDF root goes to
``world_T_object @ obj.canonical_T_base`` with ``globalScaling = obj.scale``, so every geometry query of
:class:`~centerart.assets.ArticulatedObject` maps into the world by ``world_T_object``.

Label generation loads one object at the origin (``world_T_object = I``, so world = canonical frame); evaluation
loads several objects plus room geometry into one world and reuses the same :class:`GraspTarget` and executor.
"""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from centerart.assets.articulated_object import ArticulatedObject
from centerart.errors import AssetError
from centerart.geometry.transforms import apply_transform

#: Torque (N m) / force (N) of the velocity motor that acts as friction on the target joint: enough that a
#: door does not drift after a bump, small next to what a gripper applies (a real hinge needs 0.5-2 N m).
TARGET_JOINT_FRICTION = {"revolute": 0.5, "prismatic": 2.0}
#: Force/torque that holds the object's other movable joints at their held values.
HELD_JOINT_FORCE = 1000.0


@dataclass(frozen=True)
class GraspTarget:
    """The joint a grasp acts on, in the pybullet world.

    ``axis_origin``/``axis_direction`` (world frame, m) and ``joint_type`` define the motion the hand follows
    (revolute: rotation by the right-hand rule about the line; prismatic: translation along it). They are the
    true joint for label generation and SR, or a predicted axis for the SR-axis variant (see
    :meth:`with_axis`). ``body``/``joint_index``/``moving_links`` always name the true joint, which decides
    success. ``lower``/``upper`` are its metric limits.
    """

    client: int
    body: int
    joint_index: int
    moving_links: tuple[int, ...]
    joint_type: str
    axis_origin: np.ndarray
    axis_direction: np.ndarray
    lower: float
    upper: float

    def joint_state(self) -> float:
        import pybullet as pb

        return float(pb.getJointState(self.body, self.joint_index, physicsClientId=self.client)[0])

    def with_axis(self, origin: np.ndarray, direction: np.ndarray, joint_type: str) -> GraspTarget:
        """The same joint, but the hand follows another (e.g. predicted) axis and joint type (world frame)."""
        d = np.asarray(direction, float)
        return GraspTarget(
            self.client,
            self.body,
            self.joint_index,
            self.moving_links,
            joint_type,
            np.asarray(origin, float),
            d / np.linalg.norm(d),
            self.lower,
            self.upper,
        )


def pose_to_pb(pose: np.ndarray) -> tuple[list[float], list[float]]:
    """(position, quaternion xyzw) of a 4x4 pose."""
    return pose[:3, 3].tolist(), Rotation.from_matrix(pose[:3, :3]).as_quat().tolist()


def spawn_object_in_pybullet(
    client: int,
    obj: ArticulatedObject,
    q: float,
    world_T_object: np.ndarray | None = None,
) -> GraspTarget:
    """Load ``obj`` (fixed base) into the pybullet world ``client`` with its target joint at ``q`` (metric).

    Other movable joints are set to and held at ``obj.held_states``. The target joint gets a weak velocity
    motor (:data:`TARGET_JOINT_FRICTION`) as friction. Returns the :class:`GraspTarget` of its true joint.
    """
    import pybullet as pb

    world_T_object = np.eye(4) if world_T_object is None else np.asarray(world_T_object, float)
    pos, orn = pose_to_pb(world_T_object @ obj.canonical_T_base)
    urdf = obj.path / "mobility.urdf"
    try:
        with quiet_native_output():  # PartNet URDFs without inertials make pybullet print a warning per link
            body = pb.loadURDF(
                str(urdf),
                basePosition=pos,
                baseOrientation=orn,
                useFixedBase=True,
                globalScaling=obj.scale,
                flags=pb.URDF_USE_INERTIA_FROM_FILE if obj.generated else 0,
                physicsClientId=client,
            )
    except pb.error as err:
        raise AssetError(urdf, f"pybullet cannot load it ({err})") from None
    config = obj.configuration(q)
    target_index, moving = None, []
    for j in range(pb.getNumJoints(body, physicsClientId=client)):
        info = pb.getJointInfo(body, j, physicsClientId=client)
        name, jtype, child = info[1].decode(), info[2], info[12].decode()
        if child in obj.moving_links:
            moving.append(j)
        if jtype == pb.JOINT_FIXED:
            continue
        value = config.get(name, 0.0)
        pb.resetJointState(body, j, value, physicsClientId=client)
        if name == obj.target_joint:
            target_index = j
            pb.setJointMotorControl2(
                body,
                j,
                pb.VELOCITY_CONTROL,
                targetVelocity=0.0,
                force=TARGET_JOINT_FRICTION[obj.joint_type],
                physicsClientId=client,
            )
        else:
            pb.setJointMotorControl2(
                body, j, pb.POSITION_CONTROL, targetPosition=value, force=HELD_JOINT_FORCE, physicsClientId=client
            )
    if target_index is None:
        raise AssetError(urdf, f"pybullet found no joint named {obj.target_joint!r}")
    axis = obj.target_axis(q)
    lo, hi = obj.joint_range
    return GraspTarget(
        client=client,
        body=body,
        joint_index=target_index,
        moving_links=tuple(moving),
        joint_type=obj.joint_type,
        axis_origin=apply_transform(world_T_object, axis.origin),
        axis_direction=world_T_object[:3, :3] @ axis.direction,
        lower=lo,
        upper=hi,
    )


@contextlib.contextmanager
def quiet_native_output() -> Iterator[None]:
    """Silence what native code writes to the process's stdout (file descriptor 1) inside the block."""
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 1)
        yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


def connect(gravity: float = 0.0, timestep: float = 1.0 / 240.0) -> int:
    """A new headless pybullet world (DIRECT). ``gravity`` in m/s^2 along -z.

    Label generation uses no gravity: a grasp is judged on whether it can move the part, not on whether gravity
    moves it (a bottom-hinged oven door would fall open by itself and count as a success).
    """
    with quiet_native_output():  # the first import prints the build time
        import pybullet as pb

        client = pb.connect(pb.DIRECT)
    pb.setGravity(0.0, 0.0, -gravity, physicsClientId=client)
    pb.setTimeStep(timestep, physicsClientId=client)
    return client
