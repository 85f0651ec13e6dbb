"""The object canonical frame, shared by generated and real PartNet-Mobility objects.

Every :class:`~centerart.assets.ArticulatedObject` reports geometry, joints and grasps in this frame:

- **origin**: the centre of the object's axis-aligned bounding box with the target joint at its lower limit
  (closed) and every other movable joint at its held value;
- **+x**: out of the front face, the side where doors and drawers open (the viewer stands at +x);
- **+z**: up (against gravity when the object stands on the floor);
- **+y** = z cross x: the viewer's right when looking at the front face.

Units are metres. Generated objects are written with their URDF base frame already equal to this frame.
PartNet-Mobility URDFs have z up and the front facing -x in their base frame (their root joint turns the
mesh's y-up axes into z-up), so the loader turns them 180 degrees about z, scales them to metres and moves the
origin to the bounding-box centre.
"""

from __future__ import annotations

import numpy as np

FRONT_AXIS = np.array([1.0, 0.0, 0.0])
UP_AXIS = np.array([0.0, 0.0, 1.0])
RIGHT_AXIS = np.cross(UP_AXIS, FRONT_AXIS)

#: Rotation that maps a URDF base frame whose front faces the given axis into the canonical frame (z up).
BASE_ROTATIONS: dict[str, np.ndarray] = {
    "+x": np.eye(3),
    "-x": np.diag([-1.0, -1.0, 1.0]),
    "+y": np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),
    "-y": np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),
}

#: Typical real heights (m) per category, used to bring PartNet-Mobility's unit-less models to metric size
#: when the caller gives no scale. Chosen from common appliance sizes (a countertop microwave is about 0.3 m
#: tall, a kitchen base unit about 0.85 m).
TYPICAL_HEIGHT_M: dict[str, float] = {
    "microwave": 0.32,
    "oven": 0.85,
    "refrigerator": 1.70,
    "dishwasher": 0.85,
    "storage_furniture": 0.90,
    "safe": 0.50,
    "table": 0.75,
}
