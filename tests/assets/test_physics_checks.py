"""The acceptance checks pass on generated objects and catch broken ones."""

import json
import shutil

import numpy as np

from centerart.assets.articulated_object import ArticulatedObject
from centerart.assets.physics_checks import (
    FINGER_SIZE,
    PENETRATION_TOL_M3,
    check_handle_clearance,
    check_object,
    check_penetration,
    check_reach,
)


def test_generated_objects_pass_all_checks(generated_folders):
    for folder in generated_folders:
        report = check_object(folder)
        assert report.ok, f"{folder.name}: {report.problems}"
        assert abs(report.reached_fraction - 0.9) < 0.03


def test_pybullet_reaches_90_percent(generated_folders):
    for folder in generated_folders:
        obj = ArticulatedObject.load(folder)
        assert abs(check_reach(obj) - 0.9) < 0.03, folder.name


def _door_object(generated_folders):
    for folder in generated_folders:
        obj = ArticulatedObject.load(folder)
        if obj.joint_type == "revolute" and any(h["type"] in ("bar", "u") for h in obj.meta["handles"]):
            return folder
    raise AssertionError("no door with a bar/U handle among the generated objects")


def test_penetration_check_catches_a_hinge_moved_into_the_body(generated_folders, tmp_path):
    folder = _door_object(generated_folders)
    broken = tmp_path / folder.name
    shutil.copytree(folder, broken)
    obj = ArticulatedObject.load(broken)
    urdf = (broken / "mobility.urdf").read_text()
    # Move the hinge 8 cm back into the carcass: the door now sweeps through the body when it opens.
    origin = obj.joints[obj.target_joint].origin[:3, 3]
    old = f'origin xyz="{" ".join(f"{v:.6g}" if abs(v) >= 1e-12 else "0" for v in origin)}"'
    assert old in urdf
    moved = origin - np.array([0.08, 0, 0])
    urdf = urdf.replace(old, f'origin xyz="{moved[0]:.6g} {moved[1]:.6g} {moved[2]:.6g}"')
    (broken / "mobility.urdf").write_text(urdf)
    assert check_penetration(ArticulatedObject.load(folder)) <= PENETRATION_TOL_M3
    assert check_penetration(ArticulatedObject.load(broken)) > PENETRATION_TOL_M3


def test_finger_fits_behind_bar_handles_and_check_catches_a_tight_one(generated_folders, tmp_path):
    folder = _door_object(generated_folders)
    obj = ArticulatedObject.load(folder)
    assert check_handle_clearance(obj) == []
    handle = next(h for h in obj.meta["handles"] if h["type"] in ("bar", "u"))
    assert handle["clearance"] >= FINGER_SIZE[0] + 0.002
    # Claim the grip sits 5 mm from the door: the finger box now hits the door.
    broken = tmp_path / folder.name
    shutil.copytree(folder, broken)
    meta = json.loads((broken / "meta.json").read_text())
    for h in meta["handles"]:
        if h["type"] in ("bar", "u"):
            h["center"][0] -= h["clearance"] - 0.004
            h["clearance"] = 0.015
    (broken / "meta.json").write_text(json.dumps(meta))
    assert check_handle_clearance(ArticulatedObject.load(broken))
