"""ArticulatedObject on generated and real PartNet-Mobility objects: loading, canonical frame, kinematics."""

import numpy as np
import pytest

from centerart.assets.articulated_object import ArticulatedObject
from centerart.assets.categories import CATEGORIES
from centerart.geometry.transforms import apply_transform, transform_about_line


def test_every_category_generates_and_loads(generated_folders):
    cats = set()
    for folder in generated_folders:
        obj = ArticulatedObject.load(folder)
        cats.add(obj.category)
        assert obj.generated and obj.scale == 1.0
        assert obj.joint_type in ("revolute", "prismatic")
        lo, hi = obj.joint_range
        assert hi > lo
        # canonical frame: closed bounding box centred on the origin
        b = obj.bounds()
        np.testing.assert_allclose((b[0] + b[1]) / 2, 0.0, atol=1e-6)
    assert cats == set(CATEGORIES)


def test_generated_link_meshes_are_watertight(generated_folders):
    for folder in generated_folders:
        obj = ArticulatedObject.load(folder)
        for q in np.linspace(*obj.joint_range, 3):
            for part in obj.parts(q):
                assert part.mesh.is_watertight, f"{folder.name}: {part.name} at q={q}"
        whole = obj.watertight_mesh(np.mean(obj.joint_range))
        assert whole.is_watertight and whole.volume > 0


def test_every_partnet_sample_loads(partnet_folders):
    assert len(partnet_folders) >= 7
    for folder in partnet_folders:
        obj = ArticulatedObject.load(folder)
        assert not obj.generated
        b = obj.bounds()
        np.testing.assert_allclose((b[0] + b[1]) / 2, 0.0, atol=1e-6)
        assert 0.2 < obj.extents.max() < 2.5, f"{folder.name} not metric-sized: {obj.extents}"


@pytest.mark.parametrize("sample", ["7119", "11178", "11700", "40147"])
def test_partnet_front_faces_plus_x(partnet_dir, sample):
    """Doors of real objects lie on the canonical front (+x) side and open towards +x."""
    obj = ArticulatedObject.load(partnet_dir / sample)
    body_max_x = obj.bounds()[1][0]
    closed = obj.moving_mesh(obj.joint_range[0])
    assert closed.vertices[:, 0].max() > body_max_x - 0.05
    opened = obj.moving_mesh(obj.joint_range[0] + 0.5 * (obj.joint_range[1] - obj.joint_range[0]))
    assert opened.vertices[:, 0].max() > closed.vertices[:, 0].max() + 0.05


def test_partnet_soup_gets_a_watertight_mesh(partnet_dir):
    obj = ArticulatedObject.load(partnet_dir / "7119")
    assert not obj.mesh(0.0).is_watertight  # a real triangle soup
    closed = obj.watertight_mesh(0.0, pitch=0.01)
    assert closed.is_watertight and closed.volume > 0


def _check_motion(obj: ArticulatedObject, dq: float):
    q0 = obj.joint_range[0] + 0.1 * (obj.joint_range[1] - obj.joint_range[0])
    axis = obj.target_axis(q0)
    before = obj.moving_mesh(q0).vertices
    after = obj.moving_mesh(q0 + dq).vertices
    if obj.joint_type == "revolute":
        expected = apply_transform(transform_about_line(axis.origin, axis.direction, angle=dq), before)
    else:
        expected = before + dq * axis.direction
    np.testing.assert_allclose(after, expected, atol=1e-6)
    # and the body does not move
    still = [p.mesh.vertices for p in obj.parts(q0) if p.link not in obj.moving_links]
    moved = [p.mesh.vertices for p in obj.parts(q0 + dq) if p.link not in obj.moving_links]
    for a, b in zip(still, moved, strict=True):
        np.testing.assert_allclose(a, b, atol=1e-9)


def test_kinematics_generated(generated_folders):
    for folder in generated_folders:
        obj = ArticulatedObject.load(folder)
        _check_motion(obj, 0.3 if obj.joint_type == "revolute" else 0.1)


@pytest.mark.parametrize("sample", ["7119", "7179", "19179"])
def test_kinematics_partnet(partnet_dir, sample):
    obj = ArticulatedObject.load(partnet_dir / sample)
    _check_motion(obj, 0.4 if obj.joint_type == "revolute" else 0.05)


def test_held_joints_and_target_choice(partnet_dir):
    oven = ArticulatedObject.load(partnet_dir / "7179")
    assert oven.target_joint == "joint_3"  # a door by semantics.txt, not the first (tray) joint
    assert set(oven.held_states) == {"joint_0", "joint_1", "joint_2", "joint_4"}
    tray = ArticulatedObject.load(partnet_dir / "7179", target_joint="joint_0", held_states={"joint_3": 0.5})
    assert tray.joint_type == "prismatic" and tray.held_states["joint_3"] == 0.5
