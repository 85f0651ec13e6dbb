"""Content fingerprints of object folders: which object a folder holds, whatever it is called.

Object ids are not identities: generated objects are named ``<category>_<index>`` whatever their seed, so
``cabinet_0003`` of seed 0 and of seed 9000 are different objects, and a user may rename a PartNet-Mobility
folder. The fingerprint hashes what defines the object's geometry and joints: ``mobility.urdf``, ``meta.json``
(when present) and every mesh file under ``textured_objs/``. Checkpoints record their training objects'
fingerprints, and the scene evaluation refuses a test set that shares one (:mod:`centerart.evaluation.heldout`).
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from centerart.errors import AssetError

MESH_SUFFIXES = (".obj", ".stl", ".ply", ".dae")


def object_fingerprint(folder: str | Path) -> str:
    """sha256 (hex) over the URDF, ``meta.json`` and the mesh files of one object folder (names and bytes)."""
    folder = Path(folder)
    urdf = folder / "mobility.urdf"
    if not urdf.is_file():
        raise AssetError(folder, "no mobility.urdf: not an object folder")
    files = [urdf] + ([folder / "meta.json"] if (folder / "meta.json").is_file() else [])
    meshes = folder / "textured_objs"
    if meshes.is_dir():
        files += sorted(p for p in meshes.rglob("*") if p.suffix.lower() in MESH_SUFFIXES and p.is_file())
    digest = hashlib.sha256()
    for path in files:
        digest.update(path.relative_to(folder).as_posix().encode() + b"\0")
        digest.update(hashlib.sha256(path.read_bytes()).digest())
    return digest.hexdigest()


def fingerprint_folders(folders: dict[str, str | Path]) -> dict[str, str | None]:
    """Fingerprint of each object folder by object id; None where the folder is gone (recorded, not guessed)."""
    out: dict[str, str | None] = {}
    for object_id, folder in sorted(folders.items()):
        out[object_id] = object_fingerprint(folder) if (Path(folder) / "mobility.urdf").is_file() else None
    return out
