"""Checks of an object folder at load time, so damaged data is refused where it is read and never reaches a
physics engine, a renderer or a training set.

- every number of the URDF (origins, axes, limits, masses, inertias, geometry sizes, mesh scales, colours) parses
  to the right count of finite values of a plausible size and sign;
- every mesh file parses to a non-empty triangle mesh with finite vertices and valid face indices;
- ``meta.json`` is a JSON object whose known fields have the right types.

Errors are :class:`~centerart.errors.AssetError` naming the file, the element and the value. The URDF is checked
on the raw XML text (not on yourdfpy's matrices) so that the message shows the value exactly as written.
"""

from __future__ import annotations

import math

import numpy as np
import trimesh
from lxml import etree

from centerart.errors import AssetError

#: Largest plausible magnitude of a position or angle in a URDF (metres / radians; PartNet's raw units are
#: about 1): larger values are typing errors that make physics and rendering meaningless.
MAX_COORDINATE = 1e3
#: (element, attribute): (number of values, rule). Rules: "any" finite and |v| <= MAX_COORDINATE; "nonneg" >= 0;
#: "positive" > 0; "nonzero" some value != 0; "unit" in [0, 1].
URDF_NUMBERS: dict[tuple[str, str], tuple[int, str]] = {
    ("origin", "xyz"): (3, "any"),
    ("origin", "rpy"): (3, "any"),
    ("axis", "xyz"): (3, "nonzero"),
    ("limit", "lower"): (1, "any"),
    ("limit", "upper"): (1, "any"),
    ("limit", "effort"): (1, "nonneg"),
    ("limit", "velocity"): (1, "nonneg"),
    ("dynamics", "damping"): (1, "nonneg"),
    ("dynamics", "friction"): (1, "nonneg"),
    ("mass", "value"): (1, "nonneg"),
    ("inertia", "ixx"): (1, "nonneg"),
    ("inertia", "iyy"): (1, "nonneg"),
    ("inertia", "izz"): (1, "nonneg"),
    ("inertia", "ixy"): (1, "any"),
    ("inertia", "ixz"): (1, "any"),
    ("inertia", "iyz"): (1, "any"),
    ("box", "size"): (3, "positive"),
    ("cylinder", "radius"): (1, "positive"),
    ("cylinder", "length"): (1, "positive"),
    ("sphere", "radius"): (1, "positive"),
    ("mesh", "scale"): (3, "nonzero"),
    ("color", "rgba"): (4, "unit"),
}
_BY_TAG: dict[str, list[tuple[str, int, str]]] = {}
for (_tag, _attribute), (_count, _rule) in URDF_NUMBERS.items():
    _BY_TAG.setdefault(_tag, []).append((_attribute, _count, _rule))
_RULES = {
    "any": (lambda v: all(abs(x) <= MAX_COORDINATE for x in v), f"has a value beyond +-{MAX_COORDINATE:g}"),
    "nonneg": (lambda v: all(x >= 0 for x in v), "must not be negative"),
    "positive": (lambda v: all(x > 0 for x in v), "must be positive"),
    "nonzero": (lambda v: any(x != 0 for x in v), "must not be all zero"),
    "unit": (lambda v: all(0 <= x <= 1 for x in v), "must be within 0..1"),
}


def check_urdf_numbers(tree: etree._ElementTree, urdf_path) -> None:
    """Every numeric attribute of :data:`URDF_NUMBERS` in the parsed URDF, and each joint's limit order."""
    for el in tree.iter(*_BY_TAG):
        for attribute, count, rule in _BY_TAG[el.tag]:
            raw = el.get(attribute)
            if raw is not None:
                _check_number(el, attribute, raw, count, rule, urdf_path)
    for limit in tree.iter("limit"):
        lower, upper = limit.get("lower"), limit.get("upper")
        if lower is not None and upper is not None and float(lower) > float(upper):
            raise AssetError(urdf_path, f"{_where(limit)} <limit lower={lower!r} upper={upper!r}>: lower > upper")


def _check_number(el, attribute: str, raw: str, count: int, rule: str, urdf_path) -> None:
    where = f"{_where(el)} <{el.tag} {attribute}={raw!r}>"
    try:
        values = [float(x) for x in raw.split()]
    except ValueError:
        raise AssetError(urdf_path, f"{where}: not a number") from None
    # A mesh scale may be one number (uniform) in some exporters; everything else needs its full count.
    if len(values) != count and not (el.tag == "mesh" and len(values) == 1):
        raise AssetError(urdf_path, f"{where}: expected {count} numbers, got {len(values)}")
    if not all(math.isfinite(x) for x in values):
        raise AssetError(urdf_path, f"{where}: not finite")
    ok, problem = _RULES[rule]
    if not ok(values):
        raise AssetError(urdf_path, f"{where}: {problem}")


def _where(el) -> str:
    """The link or joint (and visual / collision / inertial element) that holds ``el``, for messages."""
    parts = []
    node = el.getparent()
    while node is not None and node.tag != "robot":
        if node.tag in ("link", "joint", "visual", "collision", "inertial"):
            name = node.get("name")
            parts.append(f"{node.tag} {name!r}" if name else node.tag)
        node = node.getparent()
    return ", ".join(reversed(parts)) or "robot"


def check_mesh(mesh: trimesh.Trimesh, mesh_path) -> trimesh.Trimesh:
    """A mesh read from ``mesh_path``: non-empty, finite vertices, face indices within the vertex list."""
    if len(mesh.faces) == 0 or len(mesh.vertices) == 0:
        raise AssetError(mesh_path, "mesh is empty (no triangles): the file is damaged or not a mesh")
    if not np.isfinite(mesh.vertices).all():
        raise AssetError(mesh_path, "mesh has non-finite (NaN or infinite) vertex coordinates")
    if mesh.faces.min() < 0 or mesh.faces.max() >= len(mesh.vertices):
        raise AssetError(mesh_path, f"mesh has face indices outside its {len(mesh.vertices)} vertices")
    if np.abs(mesh.vertices).max() > MAX_COORDINATE:
        raise AssetError(mesh_path, f"mesh has vertices beyond +-{MAX_COORDINATE:g} units")
    return mesh


#: Known meta.json fields and their JSON types (absent or null is always allowed).
META_TYPES = {"model_cat": str, "target_joint": str, "front_axis": str, "generator": dict, "joints": dict}


def check_meta(meta, meta_path) -> dict:
    """``meta.json``'s content: a JSON object whose known fields have the types :data:`META_TYPES` says."""
    if not isinstance(meta, dict):
        raise AssetError(meta_path, f"expected a JSON object, got {type(meta).__name__}")
    for key, kind in META_TYPES.items():
        value = meta.get(key)
        if value is not None and not isinstance(value, kind):
            raise AssetError(meta_path, f"field {key!r} must be a {kind.__name__}, got {value!r}")
    return meta
