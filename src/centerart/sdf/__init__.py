"""SDF stage: signed-distance samples with nearest-grasp targets per (object, joint state)."""
