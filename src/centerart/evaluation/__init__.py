"""Evaluation: metrics on shapes and grasps, physics execution of predicted grasps, reports."""
