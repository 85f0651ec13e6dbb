"""Acceptance checks that every generated object must pass before it is kept.

1. Every link's visual mesh is a closed manifold (watertight).
2. The moving part does not penetrate the rest of the object at any of ``n_states`` target states from closed
   to fully open (exact boolean intersection of the closed link solids, tolerance ``PENETRATION_TOL_M3``).
3. In pybullet, a position-controlled target joint reaches 90% of its range within 3 s under gravity
   (so masses, inertias, limits and damping are sane).
4. A gripper finger (1 cm x 2 cm cross-section, 4 cm long) fits behind every bar and U handle without touching it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from centerart.assets.articulated_object import ArticulatedObject
from centerart.assets.mesh_ops import intersection_volume, to_manifold, union
from centerart.geometry.transforms import make_pose

PENETRATION_TOL_M3 = 1e-8  # 10 mm^3: numerical noise of the boolean, far below any real overlap
REACH_FRACTION = 0.9
REACH_TOL_FRACTION = 0.03  # of the joint range
FINGER_SIZE = (0.01, 0.02, 0.04)  # m: thickness (towards the front), width (along the grip), length (across)


@dataclass
class CheckReport:
    ok: bool = True
    problems: list[str] = field(default_factory=list)
    max_penetration_m3: float = 0.0
    reached_fraction: float = 0.0

    def fail(self, problem: str) -> None:
        self.ok = False
        self.problems.append(problem)


def link_solids(obj: ArticulatedObject, q: float) -> dict:
    """Closed manifold per link (union of its visual parts), canonical frame, as manifold3d objects."""
    grouped: dict[str, list] = {}
    for part in obj.parts(q):
        grouped.setdefault(part.link, []).append(part.mesh)
    return {link: to_manifold(union(meshes)) for link, meshes in grouped.items()}


def check_penetration(obj: ArticulatedObject, n_states: int = 5) -> float:
    """Largest overlap volume (m^3) between the moving part and the rest over the target's range."""
    lo, hi = obj.joint_range
    worst = 0.0
    for q in np.linspace(lo, hi, n_states):
        solids = link_solids(obj, q)
        moving = [s for link, s in solids.items() if link in obj.moving_links]
        static = [s for link, s in solids.items() if link not in obj.moving_links]
        for m in moving:
            for s in static:
                worst = max(worst, intersection_volume(m, s))
    return worst


def check_reach(obj: ArticulatedObject, fraction: float = REACH_FRACTION, seconds: float = 3.0) -> float:
    """Drive the target joint to ``fraction`` of its range in pybullet; returns the fraction reached."""
    import pybullet as pb

    client = pb.connect(pb.DIRECT)
    try:
        pb.setGravity(0, 0, -9.81, physicsClientId=client)
        body = pb.loadURDF(
            str(obj.path / "mobility.urdf"),
            useFixedBase=True,
            globalScaling=obj.scale,
            flags=pb.URDF_USE_INERTIA_FROM_FILE,
            physicsClientId=client,
        )
        lo, hi = obj.joint_range
        goal = lo + fraction * (hi - lo)
        config = obj.configuration(goal)
        target_index = None
        for j in range(pb.getNumJoints(body, physicsClientId=client)):
            info = pb.getJointInfo(body, j, physicsClientId=client)
            name = info[1].decode()
            if info[2] == pb.JOINT_FIXED:
                continue
            if name == obj.target_joint:
                target_index = j
                pb.resetJointState(body, j, lo, physicsClientId=client)
            else:
                pb.resetJointState(body, j, config.get(name, 0.0), physicsClientId=client)
            pb.setJointMotorControl2(
                body,
                j,
                pb.POSITION_CONTROL,
                targetPosition=config.get(name, 0.0),
                force=info[10] or 100.0,
                maxVelocity=1.0,
                physicsClientId=client,
            )
        for _ in range(int(seconds * 240)):
            pb.stepSimulation(physicsClientId=client)
        q = pb.getJointState(body, target_index, physicsClientId=client)[0]
        return float((q - lo) / (hi - lo))
    finally:
        pb.disconnect(client)


def check_handle_clearance(obj: ArticulatedObject) -> list[str]:
    """Problems with bar/U handles that a finger cannot get behind (empty list when all fit)."""
    problems = []
    q0 = obj.joint_range[0]
    poses = obj.link_poses(q0)
    solids = link_solids(obj, q0)
    for h in obj.meta.get("handles", []):
        if h["type"] not in ("bar", "u"):
            continue
        if h["clearance"] < FINGER_SIZE[0] + 0.002:
            problems.append(f"{h['type']} handle on {h['link']} leaves {h['clearance'] * 1000:.1f} mm behind it")
            continue
        axis = np.asarray(h["axis"], float)
        across = np.cross([1.0, 0.0, 0.0], axis)
        rot = np.stack([np.array([1.0, 0.0, 0.0]), axis, across], axis=1)
        center = np.asarray(h["center"], float) - np.array([h["thickness"] / 2 + h["clearance"] / 2, 0.0, 0.0])
        import trimesh

        finger = trimesh.creation.box(extents=FINGER_SIZE)
        finger.apply_transform(poses[h["link"]] @ make_pose(rot, center))
        vol = intersection_volume(to_manifold(finger), solids[h["link"]])
        if vol > 0.0:
            problems.append(
                f"a finger behind the {h['type']} handle on {h['link']} overlaps it by {vol * 1e9:.0f} mm^3"
            )
    return problems


def check_object(folder: Path) -> CheckReport:
    """Run every check on a generated object folder."""
    report = CheckReport()
    obj = ArticulatedObject.load(folder)
    for part in obj.parts(obj.joint_range[0]):
        if not part.mesh.is_watertight:
            report.fail(f"visual mesh {part.name} is not watertight")
    if not report.ok:
        return report
    report.max_penetration_m3 = check_penetration(obj)
    if report.max_penetration_m3 > PENETRATION_TOL_M3:
        report.fail(f"moving part penetrates the body by {report.max_penetration_m3 * 1e6:.2f} cm^3")
    report.reached_fraction = check_reach(obj)
    if abs(report.reached_fraction - REACH_FRACTION) > REACH_TOL_FRACTION:
        report.fail(f"position control reached {report.reached_fraction:.2f} of the range, wanted {REACH_FRACTION}")
    for problem in check_handle_clearance(obj):
        report.fail(problem)
    return report
