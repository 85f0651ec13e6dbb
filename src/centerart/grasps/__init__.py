"""Grasp stage: the floating gripper, candidate grasps, the pybullet physics check and the label files."""
