"""Execute one 6-DoF grasp on an articulated part in pybullet: approach, close, move the part along its joint.

This is the one executor shared by grasp-label generation and evaluation (success rate, SR-axis, the oracle),
so a label and an evaluated grasp are judged by the same physics.

Protocol (``execute``), all poses in the pybullet world frame (m, rad):

1. Spawn the floating gripper open, :data:`APPROACH_DISTANCE` back along its approach axis (TCP z). Touching or
   penetrating anything at spawn aborts (``collision_at_spawn``).
2. Approach along TCP +z to the grasp pose at :data:`APPROACH_SPEED`. If the TCP ends more than
   :data:`APPROACH_TOLERANCE` from its goal, the hand was blocked (``approach_blocked``).
3. Close both fingers with :data:`GRASP_FORCE` each. If no finger touches the moving part: ``no_contact``.
4. Move the hand along the joint's motion (revolute: rotate about the hinge line; prismatic: translate along the
   axis) in the commanded direction, up to :data:`PULL_ANGLE` / :data:`PULL_DISTANCE`, with the TCP moving at
   :data:`PULL_SPEED`.
5. Success: the joint moved at least :data:`SUCCESS_ANGLE` (revolute) / :data:`SUCCESS_DISTANCE` (prismatic) in
   the commanded direction, and both fingers still touch the moving part (``lost_grip`` otherwise). Any abort
   is a failure.

Direction (:func:`commanded_direction`): open when the remaining range allows (revolute: upper - q >=
:data:`OPEN_MARGIN_REVOLUTE`; prismatic: upper - q >= :data:`OPEN_MARGIN_PRISMATIC`), otherwise close.

The gripper is built from primitives (:mod:`centerart.grasps.gripper` dimensions): a palm box and two finger
boxes on prismatic joints, floating, driven by a fixed constraint whose pivot is moved every step
(:data:`HAND_MAX_FORCE`). Its base frame is the hand frame: the base inertial frame is put at the base origin,
because pybullet places a base at its inertial origin (reference/stack-measurements.md 2.2, gotcha 1).

Speed: the world is saved once (``saveState``) after the gripper is parked, and every trial starts from
``restoreState``, which also makes trials independent and deterministic.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from centerart.geometry.rotations import axis_angle_matrix, quat_from_matrix, quat_multiply
from centerart.geometry.transforms import invert_pose, make_pose
from centerart.grasps.gripper import (
    FINGER_LENGTH,
    FINGER_THICKNESS,
    FINGER_WIDTH,
    HAND_TO_TCP,
    MAX_OPENING,
    PALM_FACE_Z,
    PALM_SIZE,
    hand_pose,
)
from centerart.grasps.sim_world import GraspTarget

# --- the protocol's constants (printed in reports; EVALUATION.md) -------------------------------------------
SUCCESS_ANGLE = 0.17  # rad a revolute joint must move in the commanded direction
SUCCESS_DISTANCE = 0.05  # m a prismatic joint must move in the commanded direction
OPEN_MARGIN_REVOLUTE = 0.8  # rad of remaining range needed to command "open"
OPEN_MARGIN_PRISMATIC = 0.10  # m of remaining range needed to command "open"
APPROACH_DISTANCE = 0.10  # m, spawn offset behind the grasp along the approach axis
GRASP_FORCE = 70.0  # N per finger (Franka hand: 70 N continuous)
FINGER_FRICTION = 1.5  # lateral friction of the finger pads (pybullet multiplies it with the object's)
HAND_MAX_FORCE = 300.0  # N the floating hand's constraint may apply
APPROACH_SPEED = 0.5  # m/s
FINGER_SPEED = 0.3  # m/s per finger while closing
CLOSE_STEPS = 36  # steps of closing (0.15 s at 240 Hz: a full stroke at FINGER_SPEED plus settling)
PULL_SPEED = 0.4  # m/s of the TCP while moving the part
PULL_ANGLE = 0.40  # rad commanded for revolute joints (> SUCCESS_ANGLE, so a slipping grasp still fails)
PULL_DISTANCE = 0.10  # m commanded for prismatic joints
PULL_MIN_RADIUS = 0.05  # m, floor on the TCP-to-hinge distance when turning PULL_SPEED into an angular speed
APPROACH_TOLERANCE = 0.01  # m between the TCP and its goal after the approach
SPAWN_PENETRATION_TOL = 0.0005  # m of contact depth tolerated at spawn (numerical contact noise)
SETTLE_STEPS = 6  # steps after the approach for the constraint to settle on its goal
PARK_POSITION = (0.0, 0.0, -50.0)  # m, where the gripper waits between trials (far below everything)

ABORTS = ("collision_at_spawn", "approach_blocked", "no_contact", "lost_grip")


@dataclass(frozen=True)
class GraspResult:
    """Outcome of one executed grasp.

    ``displacement``: joint motion in the commanded direction (rad or m; negative = moved the wrong way).
    ``abort``: "" for a completed trial (success or not), else one of :data:`ABORTS`.
    """

    success: bool
    displacement: float
    abort: str
    direction: int
    q_start: float
    q_end: float
    steps: int


def commanded_direction(joint_type: str, q: float, upper: float) -> int:
    """+1 (open) when the remaining range allows, else -1 (close); see the module docstring."""
    margin = OPEN_MARGIN_REVOLUTE if joint_type == "revolute" else OPEN_MARGIN_PRISMATIC
    return 1 if upper - q >= margin else -1


def success_threshold(joint_type: str) -> float:
    return SUCCESS_ANGLE if joint_type == "revolute" else SUCCESS_DISTANCE


class PybulletGripper:
    """The floating two-finger gripper as a pybullet multibody. Base frame = hand frame (gripper.py)."""

    def __init__(self, client: int):
        import pybullet as pb

        self.client = client
        c = client
        palm = pb.createCollisionShape(
            pb.GEOM_BOX,
            halfExtents=[s / 2 for s in PALM_SIZE],
            collisionFramePosition=[0.0, 0.0, PALM_SIZE[2] / 2],
            physicsClientId=c,
        )
        finger_half = [FINGER_WIDTH / 2, FINGER_THICKNESS / 2, FINGER_LENGTH / 2]
        # Finger link frames sit on the palm face centre line; the joint value is the finger's inner-face offset
        # from the TCP plane (half the opening), so each collision box is shifted outwards by half its thickness.
        f_neg = pb.createCollisionShape(
            pb.GEOM_BOX,
            halfExtents=finger_half,
            collisionFramePosition=[0.0, -FINGER_THICKNESS / 2, 0.0],
            physicsClientId=c,
        )
        f_pos = pb.createCollisionShape(
            pb.GEOM_BOX,
            halfExtents=finger_half,
            collisionFramePosition=[0.0, FINGER_THICKNESS / 2, 0.0],
            physicsClientId=c,
        )
        z_f = PALM_FACE_Z + FINGER_LENGTH / 2
        self.body = pb.createMultiBody(
            baseMass=0.73,
            baseCollisionShapeIndex=palm,
            basePosition=PARK_POSITION,
            baseInertialFramePosition=[0.0, 0.0, 0.0],  # base frame == hand frame (gotcha 1)
            linkMasses=[0.1, 0.1],
            linkCollisionShapeIndices=[f_neg, f_pos],
            linkVisualShapeIndices=[-1, -1],
            linkPositions=[[0.0, 0.0, z_f], [0.0, 0.0, z_f]],
            linkOrientations=[[0, 0, 0, 1], [0, 0, 0, 1]],
            linkInertialFramePositions=[[0, 0, 0], [0, 0, 0]],
            linkInertialFrameOrientations=[[0, 0, 0, 1], [0, 0, 0, 1]],
            linkParentIndices=[0, 0],
            linkJointTypes=[pb.JOINT_PRISMATIC, pb.JOINT_PRISMATIC],
            linkJointAxis=[[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]],
            physicsClientId=c,
        )
        self.fingers = (0, 1)
        for link in (-1, *self.fingers):
            pb.changeDynamics(self.body, link, linearDamping=0.0, angularDamping=0.0, physicsClientId=c)
        for f in self.fingers:
            pb.changeDynamics(
                self.body,
                f,
                lateralFriction=FINGER_FRICTION,
                spinningFriction=0.01,
                frictionAnchor=True,
                physicsClientId=c,
            )
        self.constraint = pb.createConstraint(
            self.body,
            -1,
            -1,
            -1,
            pb.JOINT_FIXED,
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            PARK_POSITION,
            physicsClientId=c,
        )
        pb.changeConstraint(self.constraint, maxForce=HAND_MAX_FORCE, physicsClientId=c)
        self.place(make_pose(translation=PARK_POSITION), MAX_OPENING)

    def place(self, world_T_hand: np.ndarray, opening: float) -> None:
        """Teleport the hand (and its constraint goal) to ``world_T_hand`` with the given finger gap."""
        import pybullet as pb

        pos, orn = world_T_hand[:3, 3].tolist(), quat_from_matrix(world_T_hand[:3, :3])
        pb.resetBasePositionAndOrientation(self.body, pos, orn, physicsClientId=self.client)
        pb.resetBaseVelocity(self.body, [0, 0, 0], [0, 0, 0], physicsClientId=self.client)
        for f in self.fingers:
            pb.resetJointState(self.body, f, opening / 2, 0.0, physicsClientId=self.client)
        self.set_opening(opening)
        self.move(world_T_hand)

    def move(self, world_T_hand: np.ndarray) -> None:
        """Set the constraint goal: the hand is pulled towards ``world_T_hand`` with at most HAND_MAX_FORCE."""
        import pybullet as pb

        pos, orn = world_T_hand[:3, 3].tolist(), list(quat_from_matrix(world_T_hand[:3, :3]))
        pb.changeConstraint(
            self.constraint,
            jointChildPivot=pos,
            jointChildFrameOrientation=orn,
            maxForce=HAND_MAX_FORCE,
            physicsClientId=self.client,
        )

    def move_to(self, position, quat_xyzw) -> None:
        """:meth:`move` with a position (3,) and a quaternion (x, y, z, w): the per-step fast path."""
        import pybullet as pb

        pb.changeConstraint(
            self.constraint,
            jointChildPivot=list(position),
            jointChildFrameOrientation=list(quat_xyzw),
            maxForce=HAND_MAX_FORCE,
            physicsClientId=self.client,
        )

    def set_opening(self, opening: float, force: float = GRASP_FORCE) -> None:
        import pybullet as pb

        for f in self.fingers:
            pb.setJointMotorControl2(
                self.body,
                f,
                pb.POSITION_CONTROL,
                targetPosition=opening / 2,
                force=force,
                maxVelocity=FINGER_SPEED,
                physicsClientId=self.client,
            )

    def world_T_hand(self) -> np.ndarray:
        import pybullet as pb

        pos, orn = pb.getBasePositionAndOrientation(self.body, physicsClientId=self.client)
        return make_pose(np.reshape(pb.getMatrixFromQuaternion(orn), (3, 3)), pos)

    def opening(self) -> float:
        import pybullet as pb

        return sum(pb.getJointState(self.body, f, physicsClientId=self.client)[0] for f in self.fingers)


class GraspExecutor:
    """Runs grasps in one pybullet world. Build the world first (objects, room), then the executor: it adds the
    gripper and saves the world state that every trial starts from.

    Example (world = object canonical frame)::

        client = connect()
        target = spawn_object_in_pybullet(client, obj, q)
        executor = GraspExecutor(client)
        result = executor.execute(world_T_tcp, target)
    """

    def __init__(self, client: int):
        import pybullet as pb

        self.client = client
        self.gripper = PybulletGripper(client)
        self.dt = float(pb.getPhysicsEngineParameters(physicsClientId=client)["fixedTimeStep"])
        self.state_id = pb.saveState(physicsClientId=client)

    # ------------------------------------------------------------------ checks
    def hand_collides(self, world_T_tcp: np.ndarray, opening: float = MAX_OPENING, tol: float = 0.0) -> bool:
        """Whether the gripper at ``world_T_tcp`` (fingers at ``opening``) touches anything, penetration > tol (m).

        Used as the candidate pre-filter (pre-grasp and grasp poses) and for the spawn check. Restores the
        saved world state first, so it never disturbs a later trial.
        """
        import pybullet as pb

        pb.restoreState(self.state_id, physicsClientId=self.client)
        self.gripper.place(hand_pose(world_T_tcp), opening)
        pb.performCollisionDetection(physicsClientId=self.client)
        contacts = pb.getContactPoints(bodyA=self.gripper.body, physicsClientId=self.client)
        return any(c[8] < -tol for c in contacts)

    def min_distance(self, world_T_tcp: np.ndarray, body: int, opening: float = MAX_OPENING) -> float:
        """Signed distance (m, negative = penetration) between the gripper at ``world_T_tcp`` and ``body``."""
        import pybullet as pb

        pb.restoreState(self.state_id, physicsClientId=self.client)
        self.gripper.place(hand_pose(world_T_tcp), opening)
        pts = pb.getClosestPoints(self.gripper.body, body, 0.05, physicsClientId=self.client)
        return min((p[8] for p in pts), default=0.05)

    # ------------------------------------------------------------------ one trial
    def execute(
        self, world_T_tcp: np.ndarray, target: GraspTarget, direction: int | None = None, pull: float | None = None
    ) -> GraspResult:
        """Execute the grasp ``world_T_tcp`` (4x4, world frame) on ``target``; see the module docstring.

        ``direction``: +1 open / -1 close; default :func:`commanded_direction` at the joint's current state.
        The hand follows ``target.axis_*``/``target.joint_type``; success is measured on the true joint.
        ``pull``: commanded motion (rad or m, along ``target.joint_type``) instead of PULL_ANGLE / PULL_DISTANCE;
        the hand then keeps going past the success threshold and stops only when both fingers lose the part
        (the full-open variant of the evaluation).
        """
        import pybullet as pb

        pb.restoreState(self.state_id, physicsClientId=self.client)
        q_start = target.joint_state()
        if direction is None:
            direction = commanded_direction(target.joint_type, q_start, target.upper)

        def result(success: bool, abort: str, steps: int) -> GraspResult:
            q_end = target.joint_state()
            return GraspResult(success, direction * (q_end - q_start), abort, direction, q_start, q_end, steps)

        goal_hand = hand_pose(world_T_tcp)
        if self._spawn_collides(goal_hand):  # 1. spawn
            return result(False, "collision_at_spawn", 0)
        steps = self._approach(goal_hand)  # 2. approach
        reached = self.gripper.world_T_hand()
        if np.linalg.norm(reached[:3, 3] - goal_hand[:3, 3]) > APPROACH_TOLERANCE:
            return result(False, "approach_blocked", steps)
        steps += self._close()  # 3. close
        if not any(self._fingers_touching(target)):
            return result(False, "no_contact", steps)
        steps += self._pull(target, direction, q_start, pull)  # 4. move the part
        moved = direction * (target.joint_state() - q_start)
        if moved < success_threshold(target.joint_type):
            return result(False, "", steps)
        if not all(self._fingers_touching(target)):
            return result(False, "lost_grip", steps)
        return result(True, "", steps)

    def _spawn_collides(self, goal_hand: np.ndarray) -> bool:
        """Place the open hand APPROACH_DISTANCE behind ``goal_hand`` (world frame); whether it penetrates anything
        by more than SPAWN_PENETRATION_TOL there."""
        import pybullet as pb

        c = self.client
        start_hand = goal_hand @ make_pose(translation=[0.0, 0.0, -APPROACH_DISTANCE])
        self.gripper.place(start_hand, MAX_OPENING)
        pb.performCollisionDetection(physicsClientId=c)
        contacts = pb.getContactPoints(bodyA=self.gripper.body, physicsClientId=c)
        return any(p[8] < -SPAWN_PENETRATION_TOL for p in contacts)

    def _approach(self, goal_hand: np.ndarray) -> int:
        """Drive the hand along its own z to ``goal_hand`` (world frame), then let it settle; returns the steps."""
        import pybullet as pb

        c = self.client
        # Orientation fixed during the approach: one quaternion for all steps.
        n_approach = max(1, int(np.ceil(APPROACH_DISTANCE / APPROACH_SPEED / self.dt)))
        orn = quat_from_matrix(goal_hand[:3, :3])
        z_axis, goal_pos = goal_hand[:3, 2], goal_hand[:3, 3]
        for k in range(1, n_approach + 1):
            self.gripper.move_to(goal_pos - z_axis * (APPROACH_DISTANCE * (1 - k / n_approach)), orn)
            pb.stepSimulation(physicsClientId=c)
        for _ in range(SETTLE_STEPS):  # let the constraint settle on the goal
            pb.stepSimulation(physicsClientId=c)
        return n_approach + SETTLE_STEPS

    def _close(self) -> int:
        """Close both fingers with GRASP_FORCE for CLOSE_STEPS steps; returns the steps."""
        import pybullet as pb

        self.gripper.set_opening(0.0)
        for _ in range(CLOSE_STEPS):
            pb.stepSimulation(physicsClientId=self.client)
        return CLOSE_STEPS

    def _pull(self, target: GraspTarget, direction: int, q_start: float, pull: float | None = None) -> int:
        """Move the grasping hand along the (possibly predicted) joint motion of ``target``; returns the steps.

        Revolute: rotate the hand about the hinge line by up to PULL_ANGLE (rad); prismatic: translate it along the
        axis by up to PULL_DISTANCE (m); the TCP moves at PULL_SPEED (m/s). Stops early once the true joint is
        clearly past the success threshold. With ``pull`` (rad or m): move that far instead, stopping early only
        when no finger touches the moving part any more.
        """
        import pybullet as pb

        grasped_hand = self.gripper.world_T_hand()
        tcp = (grasped_hand @ make_pose(translation=[0.0, 0.0, HAND_TO_TCP]))[:3, 3]
        origin, axis = target.axis_origin, target.axis_direction
        if target.joint_type == "revolute":
            rel = tcp - origin
            radius = float(np.linalg.norm(rel - axis * (rel @ axis)))
            total = PULL_ANGLE if pull is None else pull
            rate = PULL_SPEED / max(radius, PULL_MIN_RADIUS)
        else:
            total, rate = (PULL_DISTANCE if pull is None else pull), PULL_SPEED
        n_pull = max(1, int(np.ceil(total / rate / self.dt)))
        needed = success_threshold(target.joint_type)
        hand_pos, hand_orn = grasped_hand[:3, 3], quat_from_matrix(grasped_hand[:3, :3])
        steps = 0
        for k in range(1, n_pull + 1):
            amount = direction * total * k / n_pull
            if target.joint_type == "revolute":
                half = amount / 2
                q_motion = (*(axis * np.sin(half)), np.cos(half))
                rot = axis_angle_matrix(axis, amount)
                pos = origin + rot @ (hand_pos - origin)
                orn = quat_multiply(q_motion, hand_orn)
            else:
                pos, orn = hand_pos + axis * amount, hand_orn
            self.gripper.move_to(pos, orn)
            pb.stepSimulation(physicsClientId=self.client)
            steps += 1
            if k % 8:
                continue
            if pull is None:  # stop once clearly past the threshold (saves time); the caller checks the grip
                if direction * (target.joint_state() - q_start) >= 1.25 * needed:
                    break
            elif not any(self._fingers_touching(target)):  # the grasp slipped off: nothing more will move
                break
        return steps

    def _fingers_touching(self, target: GraspTarget) -> tuple[bool, bool]:
        import pybullet as pb

        out = []
        for f in self.gripper.fingers:
            pts = pb.getContactPoints(
                bodyA=self.gripper.body, bodyB=target.body, linkIndexA=f, physicsClientId=self.client
            )
            out.append(any(p[4] in target.moving_links for p in pts))
        return out[0], out[1]


def world_T_tcp_from_hand(world_T_hand: np.ndarray) -> np.ndarray:
    """Inverse of :func:`~centerart.grasps.gripper.hand_pose`."""
    return world_T_hand @ invert_pose(make_pose(translation=[0.0, 0.0, -HAND_TO_TCP]))
