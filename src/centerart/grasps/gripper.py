"""The parallel-jaw gripper: a Franka-hand-like floating hand, its TCP convention and control points.

TCP (tool centre point) frame, used by every API that takes or returns a grasp:

- origin: between the two finger pads, at the pads' centre (where a thin part is pinched);
- +z: approach direction (from the palm towards the fingertips);
- +y: finger closing direction (the fingers move along +-y);
- +x = y cross z.

The hand base (the frame at the back of the palm) sits ``HAND_TO_TCP`` metres behind the TCP along -z:
``hand_T_tcp = make_pose(translation=[0, 0, HAND_TO_TCP])``. A grasp is always a 4x4 pose of the TCP frame; each
API says in which frame (object canonical, camera, world) it is expressed.
"""

from __future__ import annotations

import numpy as np

from centerart.geometry.transforms import make_pose

HAND_TO_TCP = 0.1034  # m, Franka hand base to the centre of the finger pads
MAX_OPENING = 0.08  # m, full stroke of the two fingers together
FINGER_PAD_LENGTH = 0.02  # m along z (pad centre is the TCP)
FINGER_WIDTH = 0.02  # m along x
FINGER_THICKNESS = 0.01  # m along y
FINGER_LENGTH = 0.05  # m from the palm face to the fingertip
PALM_TO_TCP = 0.045  # m, palm face (finger roots) to the TCP along z

#: Five control points of the gripper in the TCP frame (m): wrist centre, left/right finger roots, left/right
#: pad centres. Used for the grasp loss and grasp distances; swapping rows 1<->2 and 3<->4 gives the same
#: physical gripper turned 180 degrees about z.
CONTROL_POINTS_TCP = np.array(
    [
        [0.0, 0.0, -PALM_TO_TCP - 0.06],
        [0.0, -MAX_OPENING / 2, -PALM_TO_TCP],
        [0.0, MAX_OPENING / 2, -PALM_TO_TCP],
        [0.0, -MAX_OPENING / 2, 0.0],
        [0.0, MAX_OPENING / 2, 0.0],
    ]
)
FINGER_SWAP = np.array([0, 2, 1, 4, 3])

#: The same gripper turned 180 degrees about its approach axis.
FLIP_Z = make_pose(np.diag([-1.0, -1.0, 1.0]))


def hand_pose(tcp_pose: np.ndarray) -> np.ndarray:
    """``F_T_hand`` from ``F_T_tcp`` (any frame F)."""
    return tcp_pose @ make_pose(translation=[0.0, 0.0, -HAND_TO_TCP])


def control_points(tcp_poses: np.ndarray) -> np.ndarray:
    """Control points (..., 5, 3) of TCP poses (..., 4, 4), in the poses' frame."""
    rot, t = tcp_poses[..., :3, :3], tcp_poses[..., :3, 3]
    return np.einsum("...ij,kj->...ki", rot, CONTROL_POINTS_TCP) + t[..., None, :]


# ---------------------------------------------------------------------------------------------------------------
# Body geometry (used by the pybullet gripper and by pictures). Hand frame: origin at the back of the palm,
# z towards the fingers, y along the finger stroke; the TCP is at z = HAND_TO_TCP.
PALM_SIZE = (0.06, 0.204, HAND_TO_TCP - PALM_TO_TCP)  # m (x, y, z): Franka-hand-like palm block
PALM_FACE_Z = HAND_TO_TCP - PALM_TO_TCP  # m, where the fingers leave the palm (hand frame z)
FINGERTIP_BEYOND_TCP = FINGER_LENGTH - PALM_TO_TCP  # m the fingertips reach past the TCP along +z


def gripper_boxes(opening: float = MAX_OPENING) -> list[tuple[np.ndarray, np.ndarray]]:
    """The gripper's three boxes as (extents (3,), ``tcp_T_box`` 4x4) for a finger gap of ``opening`` m.

    Order: palm, finger on -y, finger on +y. Frames: TCP frame, metres.
    """
    half = float(np.clip(opening, 0.0, MAX_OPENING)) / 2
    palm_c = [0.0, 0.0, -PALM_TO_TCP - PALM_SIZE[2] / 2]
    finger_z = -PALM_TO_TCP + FINGER_LENGTH / 2
    finger_ext = np.array([FINGER_WIDTH, FINGER_THICKNESS, FINGER_LENGTH])
    return [
        (np.array(PALM_SIZE), make_pose(translation=palm_c)),
        (finger_ext, make_pose(translation=[0.0, -half - FINGER_THICKNESS / 2, finger_z])),
        (finger_ext, make_pose(translation=[0.0, half + FINGER_THICKNESS / 2, finger_z])),
    ]


def gripper_mesh(tcp_pose: np.ndarray, opening: float = MAX_OPENING):
    """A trimesh of the gripper boxes at ``F_T_tcp`` (any frame F), for pictures and collision checks."""
    import trimesh

    meshes = []
    for extents, tcp_T_box in gripper_boxes(opening):
        box = trimesh.creation.box(extents=extents)
        box.apply_transform(tcp_pose @ tcp_T_box)
        meshes.append(box)
    return trimesh.util.concatenate(meshes)
