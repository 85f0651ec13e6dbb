"""Ways to damage an input file: truncate it, replace it with random bytes, edit one XML attribute or JSON field,
rewrite one array of an ``.npz`` record. Each returns the damaged path so a case can name it."""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np
from lxml import etree

RANDOM = np.random.default_rng(1234).integers(0, 256, 4096, dtype=np.uint8).tobytes()


def truncate(path: Path, fraction: float = 0.5) -> Path:
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * fraction)])
    return path


def random_bytes(path: Path) -> Path:
    path.write_bytes(RANDOM)
    return path


def empty(path: Path) -> Path:
    path.write_bytes(b"")
    return path


def set_xml(urdf: Path, xpath: str, attribute: str, value: str) -> Path:
    """Set ``attribute`` of the first element matching ``xpath`` (e.g. ``//joint/origin``) to ``value``."""
    tree = etree.parse(str(urdf))
    tree.xpath(xpath)[0].set(attribute, value)
    tree.write(str(urdf))
    return urdf


def set_json(path: Path, keys: list, value) -> Path:
    """Set the field at ``keys`` (a path of dict keys / list indices) of a JSON file; ``keys=[]``: the whole file."""
    if not keys:
        path.write_text(json.dumps(value))
        return path
    data = json.loads(path.read_text())
    node = data
    for k in keys[:-1]:
        node = node[k]
    node[keys[-1]] = value
    path.write_text(json.dumps(data))
    return path


def set_npz(path: Path, key: str, value) -> Path:
    """Rewrite one array of an ``.npz`` (``value=None`` removes the key)."""
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    if value is None:
        arrays.pop(key)
    else:
        arrays[key] = np.asarray(value)
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    path.write_bytes(buf.getvalue())
    return path


def target_mesh(object_dir: Path) -> Path:
    """The first visual mesh of the link that the object's target joint moves (the door or drawer)."""
    meta = json.loads((object_dir / "meta.json").read_text())
    tree = etree.parse(str(object_dir / "mobility.urdf"))
    child = tree.xpath(f"//joint[@name='{meta['target_joint']}']/child/@link")[0]
    return object_dir / tree.xpath(f"//link[@name='{child}']/visual/geometry/mesh/@filename")[0]
