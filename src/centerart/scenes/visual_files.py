"""Visual meshes of real objects whose material files name texture images that are not there.

Why: PartNet-Mobility copies often ship ``textured_objs/*.obj`` and their ``.mtl`` files without the ``images/``
folder the materials point into (``map_Kd ../images/texture_0.jpg``); 20 of the 21 objects of
``partnet-mobility-dev`` do. SAPIEN's mesh loader then stops the whole render with a filesystem error from deep
inside the library. Such a mesh is loaded from a copy instead: its material libraries rewritten without the maps
whose files are missing (the material keeps its diffuse colour) and with every other map named by its absolute
path, so that the copy, written elsewhere, still finds them. A mesh whose maps all exist is loaded as it is.
"""

from __future__ import annotations

import hashlib
import shutil
from pathlib import Path

MAP_KEYWORDS = ("map_", "bump", "disp", "decal", "refl", "norm")
"""Material statements that name an image file as their last word (``map_Kd``, ``map_Bump``, ``bump``, ...)."""


def _map_file(line: str, folder: Path) -> Path | None:
    """The image file a material statement names (relative to the material file's ``folder``), else None."""
    words = line.split()
    if len(words) < 2 or not words[0].lower().startswith(MAP_KEYWORDS):
        return None
    return (folder / words[-1]).resolve()


def _material_libraries(obj: Path) -> list[str]:
    """The names of the ``.mtl`` files an OBJ file names (``mtllib``), relative to its folder."""
    libraries = []
    with open(obj, errors="replace") as f:
        for line in f:
            if line.startswith("mtllib"):
                libraries += line.split()[1:]
    return libraries


def _rewritten(mtl: Path) -> tuple[str, bool]:
    """(the material file with absolute map paths and without missing maps, whether any map was missing)."""
    out, missing = [], False
    for line in mtl.read_text(errors="replace").splitlines():
        image = _map_file(line, mtl.parent)
        if image is None:
            out.append(line)
        elif image.is_file():
            out.append(" ".join([*line.split()[:-1], str(image)]))
        else:
            missing = True
    return "\n".join(out) + "\n", missing


def loadable_visual(obj: Path, cache: Path) -> Path:
    """``obj`` itself when every image its materials name exists; otherwise a copy under ``cache`` (one folder per
    source file, reused) whose material libraries drop the missing maps."""
    obj = Path(obj)
    # A library named with a folder (``mtllib ../x.mtl``) would not sit beside the copy: left as it is.
    libraries = [name for name in _material_libraries(obj) if "/" not in name and (obj.parent / name).is_file()]
    rewritten = {name: _rewritten(obj.parent / name) for name in libraries}
    if not any(missing for _, missing in rewritten.values()):
        return obj
    folder = Path(cache) / hashlib.sha256(str(obj.resolve()).encode()).hexdigest()[:16]
    copy = folder / obj.name
    if not copy.is_file():
        folder.mkdir(parents=True, exist_ok=True)
        for name, (text, _) in rewritten.items():
            (folder / name).write_text(text)
        shutil.copyfile(obj, folder / (obj.name + ".part"))
        (folder / (obj.name + ".part")).replace(copy)  # the mesh last, so a copy that exists is whole
    return copy
