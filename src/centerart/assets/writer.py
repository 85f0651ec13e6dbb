"""Write an :class:`~centerart.assets.spec.ObjectSpec` as a PartNet-Mobility-layout folder.

Layout (the same that real PartNet-Mobility objects have, so one loader reads both)::

    <id>/mobility.urdf        links, joints, inertials, primitive collisions, mesh visuals with colours
    <id>/textured_objs/*.obj  one closed (watertight) mesh per visual group
    <id>/meta.json            model_cat, target_joint, handles, materials, sampled parameters, generator info
    <id>/semantics.txt        PartNet-style "link kind label" lines

Inertials: mass = density x volume of the link's solid, centre of mass at its centroid, inertia tensor of that
solid (trimesh mass properties). The fixed base gets its inertial frame at the link origin, because pybullet
puts a base's frame at its inertial origin (reference/stack-measurements.md 2.2, gotcha 1).
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path
from xml.dom import minidom
from xml.etree import ElementTree as ET

import numpy as np
from scipy.spatial.transform import Rotation

from centerart.assets.categories import MODEL_CAT
from centerart.assets.spec import JointSpec, LinkSpec, ObjectSpec, Primitive, VisualGroup


def _fmt(values) -> str:
    return " ".join(f"{float(v):.6g}" if abs(float(v)) >= 1e-12 else "0" for v in np.ravel(values))


def _origin(parent: ET.Element, pose: np.ndarray) -> None:
    with warnings.catch_warnings():  # cylinders along x are at pitch 90 deg; the angles are still exact
        warnings.simplefilter("ignore", UserWarning)
        rpy = Rotation.from_matrix(pose[:3, :3]).as_euler("xyz")
    ET.SubElement(parent, "origin", xyz=_fmt(pose[:3, 3]), rpy=_fmt(rpy))


def _geometry(parent: ET.Element, prim: Primitive) -> None:
    geom = ET.SubElement(parent, "geometry")
    if prim.kind == "box":
        ET.SubElement(geom, "box", size=_fmt(prim.size))
    else:
        ET.SubElement(geom, "cylinder", radius=_fmt([prim.size[0]]), length=_fmt([prim.size[1]]))


def write_object(spec: ObjectSpec, folder: Path, object_id: str, generator_info: dict) -> dict:
    """Write ``spec`` into ``folder`` (which must exist and be empty). Returns the meta dictionary.

    Geometry is written in each link's frame (metres); masses in kg (see the module docstring for inertials).
    """
    folder = Path(folder)
    (folder / "textured_objs").mkdir(parents=True, exist_ok=True)
    robot = ET.Element("robot", name=object_id)
    materials_meta: dict[str, list] = {}
    link_masses = {}
    for link in spec.links:
        el = ET.SubElement(robot, "link", name=link.name)
        link_masses[link.name] = round(_add_inertial(el, link), 4)
        for group in link.groups:
            materials_meta[f"{link.name}-{group.name}"] = _add_visual(el, link.name, group, folder)
        for prim in link.primitives():
            col = ET.SubElement(el, "collision")
            _origin(col, prim.pose)
            _geometry(col, prim)
    for j in spec.joints:
        _add_joint(robot, j)
    xml = minidom.parseString(ET.tostring(robot)).toprettyxml(indent="  ")
    (folder / "mobility.urdf").write_text(xml)

    semantics = ["base heavy body"]
    for j in spec.joints:
        semantics.append(f"{j.child} {'hinge' if j.type == 'revolute' else 'slider'} {j.role}")
    (folder / "semantics.txt").write_text("\n".join(semantics) + "\n")

    meta = _meta(spec, object_id, materials_meta, link_masses, generator_info)
    (folder / "meta.json").write_text(json.dumps(meta, indent=2) + "\n")
    return meta


def _add_inertial(el: ET.Element, link: LinkSpec) -> float:
    """Add the link's <inertial> (solid of its density; a fixed 50 kg for the base); returns its mass (kg)."""
    solid = link.mesh()
    if link.name == "base":
        mass, com, inertia = 50.0, np.zeros(3), np.eye(3) * 5.0
    else:
        solid.density = link.density
        mass, com, inertia = float(solid.mass), solid.center_mass, np.asarray(solid.moment_inertia)
    inertial = ET.SubElement(el, "inertial")
    ET.SubElement(inertial, "origin", xyz=_fmt(com), rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=f"{mass:.6g}")
    ET.SubElement(
        inertial,
        "inertia",
        ixx=f"{inertia[0, 0]:.6g}",
        ixy=f"{inertia[0, 1]:.6g}",
        ixz=f"{inertia[0, 2]:.6g}",
        iyy=f"{inertia[1, 1]:.6g}",
        iyz=f"{inertia[1, 2]:.6g}",
        izz=f"{inertia[2, 2]:.6g}",
    )
    return mass


def _add_visual(el: ET.Element, link_name: str, group: VisualGroup, folder: Path) -> list:
    """Write the group's coloured OBJ and add its <visual>; returns its meta entry [material, rgba]."""
    fname = f"textured_objs/{link_name}-{group.name}.obj"
    _write_obj_with_colour(folder / fname, group.mesh(), group.rgba, f"{link_name}-{group.name}")
    vis = ET.SubElement(el, "visual", name=f"{link_name}-{group.name}")
    ET.SubElement(vis, "origin", xyz="0 0 0", rpy="0 0 0")
    ET.SubElement(ET.SubElement(vis, "geometry"), "mesh", filename=fname)
    mat = ET.SubElement(vis, "material", name=f"{link_name}-{group.name}-{group.material}")
    ET.SubElement(mat, "color", rgba=_fmt(group.rgba))
    return [group.material, list(group.rgba)]


def _add_joint(robot: ET.Element, j: JointSpec) -> None:
    """Add the <joint> of ``j`` (origin in the parent link's frame, m; limits in rad or m)."""
    el = ET.SubElement(robot, "joint", name=j.name, type=j.type)
    ET.SubElement(el, "origin", xyz=_fmt(j.origin), rpy="0 0 0")
    ET.SubElement(el, "axis", xyz=_fmt(j.axis))
    ET.SubElement(el, "parent", link=j.parent)
    ET.SubElement(el, "child", link=j.child)
    effort = 200.0 if j.type == "revolute" else 500.0
    ET.SubElement(el, "limit", lower=_fmt([j.lower]), upper=_fmt([j.upper]), effort=f"{effort:g}", velocity="2")
    ET.SubElement(el, "dynamics", damping=f"{j.damping:g}", friction=f"{j.friction:g}")


def _meta(spec: ObjectSpec, object_id: str, materials: dict, link_masses: dict, generator_info: dict) -> dict:
    """The meta.json dictionary (handle positions in their link's frame, m)."""
    return {
        "model_cat": MODEL_CAT[spec.category],
        "anno_id": object_id,
        "front_axis": "+x",
        "units": "m",
        "target_joint": spec.target_joint,
        "joints": {
            j.name: {"type": j.type, "role": j.role, "child": j.child, "lower": j.lower, "upper": j.upper}
            for j in spec.joints
        },
        "handles": [
            {
                "type": h.type,
                "link": h.link,
                "center": np.round(h.center, 6).tolist(),
                "axis": np.round(h.axis, 6).tolist(),
                "length": round(h.length, 6),
                "thickness": round(h.thickness, 6),
                "clearance": round(h.clearance, 6),
            }
            for h in spec.handles
        ],
        "materials": materials,
        "link_masses_kg": link_masses,
        "params": _jsonable(spec.params),
        "generator": generator_info,
    }


def _write_obj_with_colour(path: Path, mesh, rgba, material: str) -> None:
    """OBJ plus a one-material MTL (diffuse colour), so renderers that ignore URDF colours still show it."""
    r, g, b, a = (float(c) for c in rgba)
    path.with_suffix(".mtl").write_text(
        f"newmtl {material}\nKa 0 0 0\nKd {r:.4f} {g:.4f} {b:.4f}\nKs 0.1 0.1 0.1\nNs 20\nd {a:.4f}\nillum 2\n"
    )
    body = mesh.export(file_type="obj", include_normals=False, include_texture=False)
    path.write_text(f"mtllib {path.with_suffix('.mtl').name}\nusemtl {material}\n{body}")


def _jsonable(obj):
    if isinstance(obj, dict):
        return {k: _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        return round(float(obj), 6)
    if isinstance(obj, (np.integer, np.bool_)):
        return obj.item()
    return obj
