"""Scene description: the single source of truth for a scene, as plain dataclasses serialised to JSON.

The renderer (:mod:`centerart.scenes.renderer`) and the physics evaluation both rebuild a scene from this file
alone, so it holds everything: the room and counter boxes with their materials, every object (asset folder,
pose, target joint and state, held states of its other joints, materials), lights, cameras and the stereo depth
sensor.

Frames and units: metres, radians. World frame z up; the kitchen's back wall is the plane x = 0 and objects face
+x (their canonical front). ``world_T_object`` places an object's **canonical frame** (x out of the front, z up,
origin at the centre of the closed bounding box with the other joints at their lower limits;
:mod:`centerart.assets.canonical_frame`); load objects with :func:`load_scene_object`. ``world_T_camera`` is
an OpenCV camera (x right, y down, z forward); ``K`` is its 3x3 intrinsic matrix with pixel centres at integer
coordinates (OpenCV convention). ``world_T_box`` is the centre of a box whose half extents are ``half_size``.
"""

from __future__ import annotations

import copy
import functools
import json
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from centerart.errors import CenterArtError
from centerart.utils.atomic import atomic_write_json
from centerart.utils.json_schema import ANY, array, json_problem, optional

SCENE_FORMAT_VERSION = 1


@dataclass
class MaterialSpec:
    """A surface: a procedural texture (see :mod:`centerart.scenes.textures`) and PBR parameters."""

    kind: str
    """wood, painted, metal, tile, stone, plain, or glass (dark, glossy, untextured)."""
    color: list[float]
    """Base RGBA in 0..1 (the texture is built around it)."""
    seed: int = 0
    """Texture noise seed."""
    roughness: float = 0.6
    metallic: float = 0.0
    specular: float = 0.3
    texture_scale_m: float = 0.5
    """Metres of surface covered by one repeat of the texture image."""
    texture: str | None = None
    """Texture image file, relative to the scene folder (written by the generator), or None: untextured for glass
    and plain, else made by the renderer from kind, colour and seed (``scenes generate --no-save-textures``)."""


@dataclass
class BoxSpec:
    """A static box of the room: floor, wall, counter top, plinth or backsplash."""

    name: str
    role: str
    world_T_box: list[list[float]]
    half_size: list[float]
    material: MaterialSpec


@dataclass
class ObjectSpec:
    """One articulated object instance."""

    name: str
    """Instance name in this scene (obj0, obj1, ...); instance index = position in ``SceneDescription.objects``."""
    object_id: str
    """Asset id (the asset folder's name)."""
    path: str
    """Asset folder (absolute when written; see :meth:`SceneDescription.load` to re-root it)."""
    category: str
    scale: float
    """URDF scale the asset is loaded with (``ArticulatedObject.scale``)."""
    world_T_object: list[list[float]]
    """World pose of the canonical object frame."""
    target_joint: str
    joint_type: str
    joint_state: float
    """Target joint state, metric (rad or m)."""
    joint_state_normalized: float
    held_states: dict[str, float]
    """Metric values of the other movable joints."""
    support: str = "floor"
    """floor or counter."""
    materials: dict[str, MaterialSpec] = field(default_factory=dict)
    """Material per part class of generated objects (metal, painted, plastic, wood, glass); empty keeps the asset's
    own look (real PartNet-Mobility textures)."""


@dataclass
class LightSpec:
    kind: str
    """point, directional or spot."""
    color: list[float]
    """RGB radiance (SAPIEN units: multiples of white)."""
    position: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    direction: list[float] = field(default_factory=lambda: [0.0, 0.0, -1.0])
    shadow: bool = False


@dataclass
class CameraSpec:
    name: str
    width: int
    height: int
    K: list[list[float]]
    world_T_camera: list[list[float]]
    """OpenCV camera frame (x right, y down, z forward) in the world."""
    near: float = 0.05
    far: float = 20.0


@dataclass
class StereoSpec:
    """Active stereo depth sensor rigidly attached to each RGB camera (RealSense-D415-like).

    Offsets are along the RGB camera's x axis (OpenCV, to the right). Both IR cameras share the RGB intrinsics and
    orientation (a rectified pair), the right IR camera sits ``baseline_m`` to the right of the left one.
    """

    left_offset_m: float = 0.015
    baseline_m: float = 0.055
    projector_offset_m: float = 0.030
    pattern_seed: int = 0
    pattern_dot_fraction: float = 0.12
    projector_intensity: float = 60.0
    projector_fov_deg: float = 90.0


@dataclass
class SceneDescription:
    scene_id: str
    seed: int
    layout: str
    boxes: list[BoxSpec]
    objects: list[ObjectSpec]
    lights: list[LightSpec]
    ambient: list[float]
    cameras: list[CameraSpec]
    stereo: StereoSpec = field(default_factory=StereoSpec)
    format_version: int = SCENE_FORMAT_VERSION

    # ----------------------------------------------------------- serialisation
    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    def save(self, path: Path) -> None:
        atomic_write_json(path, self.to_dict())

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> SceneDescription:
        return _build(cls, data)

    @classmethod
    def load(cls, path: Path, objects_root: Path | None = None) -> SceneDescription:
        """Read ``scene.json``. ``objects_root`` re-roots every object's asset folder (``root/<object_id>``)."""
        path = Path(path)
        try:
            data = json.loads(path.read_text())
        except FileNotFoundError:
            raise CenterArtError(f"{path}: no such scene file") from None
        except ValueError as err:  # JSONDecodeError, or UnicodeDecodeError for binary bytes
            raise CenterArtError(f"{path}: malformed JSON: {err}") from None
        if not isinstance(data, dict):
            raise CenterArtError(f"{path}: not a valid scene description (expected a JSON object)")
        if data.get("format_version") != SCENE_FORMAT_VERSION:
            raise CenterArtError(
                f"{path}: scene format version {data.get('format_version')!r}, this code reads {SCENE_FORMAT_VERSION}"
            )
        try:
            scene = cls.from_dict(data)
        except (KeyError, TypeError, ValueError) as err:
            raise CenterArtError(f"{path}: not a valid scene description ({err})") from None
        if objects_root is not None:
            for o in scene.objects:
                o.path = str(Path(objects_root) / o.object_id)
        return scene

    # ----------------------------------------------------------- helpers
    def object_pose(self, index: int) -> np.ndarray:
        return np.asarray(self.objects[index].world_T_object, dtype=float)

    def camera_pose(self, index: int) -> np.ndarray:
        return np.asarray(self.cameras[index].world_T_camera, dtype=float)


def _build(cls, data, where: str = ""):
    """Construct nested dataclasses from a dictionary made by ``asdict``, checking every value's type (numbers
    finite, poses and matrices rectangular); a wrong one is a ValueError naming the field."""
    if not isinstance(data, dict):
        raise ValueError(f"{where or cls.__name__}: expected an object, got {type(data).__name__}")
    kwargs = {}
    for f in fields(cls):
        if f.name not in data:
            continue
        kwargs[f.name] = _convert(f.type, data[f.name], f"{where}.{f.name}" if where else f.name)
    return cls(**kwargs)


_NESTED = {
    "MaterialSpec": MaterialSpec,
    "BoxSpec": BoxSpec,
    "ObjectSpec": ObjectSpec,
    "LightSpec": LightSpec,
    "CameraSpec": CameraSpec,
    "StereoSpec": StereoSpec,
}
#: Schemas (utils/json_schema.py) of the plain field types used in the description.
_PLAIN = {
    "str": str,
    "int": int,
    "float": float,
    "bool": bool,
    "list[float]": array(None),
    "list[list[float]]": array(None, None),
    "str | None": optional(str),
}


def _convert(type_name: str, value, where: str):
    t = str(type_name)
    for name, klass in _NESTED.items():
        if t == name:
            return _build(klass, value, where)
        if t == f"list[{name}]":
            if not isinstance(value, list):
                raise ValueError(f"{where}: expected a list, got {type(value).__name__}")
            return [_build(klass, v, f"{where}[{i}]") for i, v in enumerate(value)]
        if t == f"dict[str, {name}]":
            if not isinstance(value, dict):
                raise ValueError(f"{where}: expected an object, got {type(value).__name__}")
            return {k: _build(klass, v, f"{where}.{k}") for k, v in value.items()}
    if t == "dict[str, float]":
        problem = json_problem(value, dict, where) or next(
            (p for k, v in value.items() if (p := json_problem(v, float, f"{where}.{k}"))), None
        )
    else:
        problem = json_problem(value, _PLAIN.get(t, ANY), where)
    if problem:
        raise ValueError(problem)
    return value


def load_object_in_default_frame(
    path: str | Path, target_joint: str | None = None, scale: float | None = None, held_states: dict | None = None
):
    """Load an asset for a scene, in the frame that ``world_T_object`` places.

    That frame is the canonical frame of the asset with its other joints at their *default* held values (lower
    limits): ``ArticulatedObject.load`` would otherwise centre the frame on the bounding box with the scene's held
    states, so an opened non-target drawer would shift the object's origin. Pinning the frame keeps poses of the same
    asset comparable across scenes (and with the decoder's object frame).
    """
    obj = cached_object(path, target_joint, scale)
    if held_states and any(abs(obj.held_states[k] - v) > 0 for k, v in held_states.items() if k in obj.held_states):
        obj = obj.with_held_states(held_states)
    return obj


#: Assets memoised per process (a generated object holds about 3 MB of meshes, so at most ~200 MB per worker): the
#: small recipe's 41 objects fit; a cache of 32 kept evicting them.
OBJECT_CACHE_SIZE = 64


def cached_object(path: str | Path, target_joint: str | None = None, scale: float | None = None):
    """``ArticulatedObject.load``, memoised per process: scene generation loads every asset several times for each
    scene it appears in (state sampling, swept bounds, collision check, rendering, labels), which was half of a
    kitchen's layout time. Returns a shallow copy, so a caller may rebind its fields (``canonical_T_base``); the
    key holds the URDF's and meta.json's modification times, so an object rewritten on disk is loaded again. Held
    joints are applied to the cached object (``ArticulatedObject.with_held_states``), not loaded again."""
    folder = Path(path).parent if Path(path).suffix == ".urdf" else Path(path)
    stamps = tuple(f.stat().st_mtime_ns if f.is_file() else 0 for f in (folder / "mobility.urdf", folder / "meta.json"))
    return copy.copy(_load_object(str(folder.resolve()), stamps, target_joint, scale))


@functools.lru_cache(maxsize=OBJECT_CACHE_SIZE)
def _load_object(folder: str, stamps: tuple, target_joint: str | None, scale: float | None):
    from centerart.assets.articulated_object import ArticulatedObject

    return ArticulatedObject.load(folder, target_joint=target_joint, scale=scale)


def load_scene_object(spec: ObjectSpec):
    """The :class:`~centerart.assets.ArticulatedObject` of a scene object (see :func:`load_object_in_default_frame`)."""
    return load_object_in_default_frame(spec.path, spec.target_joint, spec.scale, spec.held_states)


def pose_list(pose: np.ndarray) -> list[list[float]]:
    return [[float(x) for x in row] for row in np.asarray(pose, float)]
