"""Scene layouts: ``single`` (one object in a room) and ``kitchen`` (2-5 objects along a wall under a counter).

World frame: z up, the back wall's face is the plane x = 0, objects stand with their canonical front (+x) facing
the room. Placement works on each object's *swept* bounding box: the union of its axis-aligned bounds over the
states in :func:`centerart.scenes.collisions.check_states` (closed to fully open, plus the scene's state). Boxes
of neighbours are separated by a random gap, the wall gap and floor clearance are measured on the swept box, so a
door opened fully cannot reach a neighbour, the wall, the floor or the counter. The exact mesh check in
:mod:`centerart.scenes.collisions` verifies the result.

Kitchen rules: 2-5 objects; at most one microwave, which stands on the counter; tall objects (over
:data:`TALL_M`, fridges and tall storage units) only at the ends of the row; the rest stand under one counter top
that spans them. If the only objects are a microwave and tall ones, a plain base cabinet carries the counter.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from centerart.assets.articulated_object import ArticulatedObject
from centerart.errors import CenterArtError
from centerart.geometry.transforms import make_pose
from centerart.scenes.cameras import ShellRanges, sample_shell_pose
from centerart.scenes.collisions import check_states
from centerart.scenes.description import (
    BoxSpec,
    CameraSpec,
    LightSpec,
    MaterialSpec,
    ObjectSpec,
    SceneDescription,
    StereoSpec,
    cached_object,
    load_object_in_default_frame,
    pose_list,
)

TALL_M = 1.15
WALL_GAP_M = (0.01, 0.04)
NEIGHBOUR_GAP_M = (0.02, 0.10)
COUNTER_THICKNESS_M = (0.03, 0.05)
COUNTER_OVERHANG_M = (0.02, 0.04)
FLOOR_CLEARANCE_M = 0.002
CLOSED_PROBABILITY = 0.2
HELD_RANDOM_PROBABILITY = 0.3


@dataclass(frozen=True)
class AssetEntry:
    """One usable asset: where it is, its category and its closed height (m)."""

    object_id: str
    path: str
    category: str
    height: float

    @property
    def tall(self) -> bool:
        return self.height > TALL_M


# ------------------------------------------------------------------ materials and colours
def _paint_color(rng) -> list[float]:
    palette = [
        (0.93, 0.93, 0.91),  # white
        (0.96, 0.95, 0.9),  # cream
        (0.12, 0.12, 0.13),  # black
        (0.55, 0.57, 0.6),  # grey
        (0.24, 0.3, 0.4),  # navy
        (0.4, 0.48, 0.38),  # sage
        (0.6, 0.25, 0.2),  # red
        (0.75, 0.68, 0.55),  # beige
    ]
    c = np.asarray(palette[rng.integers(len(palette))]) * rng.uniform(0.92, 1.05) + rng.normal(0, 0.015, 3)
    return [*np.clip(c, 0, 1).tolist(), 1.0]


def _wood_color(rng) -> list[float]:
    base = np.array([[0.62, 0.44, 0.27], [0.45, 0.3, 0.18], [0.78, 0.64, 0.45], [0.33, 0.22, 0.14]])
    c = base[rng.integers(len(base))] * rng.uniform(0.9, 1.1)
    return [*np.clip(c, 0, 1).tolist(), 1.0]


def _metal_color(rng) -> list[float]:
    g = rng.uniform(0.6, 0.82)
    tint = rng.normal(0, 0.01, 3)
    return [*np.clip(g + tint + np.array([0.0, 0.005, 0.015]), 0, 1).tolist(), 1.0]


def _seed(rng) -> int:
    return int(rng.integers(2**31))


def object_materials(rng: np.random.Generator) -> dict[str, MaterialSpec]:
    """One finish per object, by part class of generated objects (metal, painted, plastic, wood, glass)."""
    dark_metal = rng.random() < 0.25
    metal_color = [0.18, 0.18, 0.19, 1.0] if dark_metal else _metal_color(rng)
    return {
        "metal": MaterialSpec(
            "metal",
            metal_color,
            _seed(rng),
            roughness=rng.uniform(0.25, 0.45),
            metallic=0.8,
            specular=0.5,
            texture_scale_m=0.4,
        ),
        "painted": MaterialSpec(
            "painted",
            _paint_color(rng),
            _seed(rng),
            roughness=rng.uniform(0.35, 0.6),
            specular=0.4,
            texture_scale_m=0.8,
        ),
        "plastic": MaterialSpec(
            "painted",
            _paint_color(rng) if rng.random() < 0.3 else [0.1, 0.1, 0.11, 1.0],
            _seed(rng),
            roughness=0.5,
            specular=0.3,
            texture_scale_m=0.5,
        ),
        "wood": MaterialSpec(
            "wood",
            _wood_color(rng),
            _seed(rng),
            roughness=rng.uniform(0.45, 0.7),
            specular=0.25,
            texture_scale_m=rng.uniform(0.5, 0.9),
        ),
        "glass": MaterialSpec(
            "glass", [0.05, 0.06, 0.07, 1.0], 0, roughness=0.08, metallic=0.0, specular=0.9, texture_scale_m=1.0
        ),
    }


def room_materials(rng: np.random.Generator) -> dict[str, MaterialSpec]:
    floor_kind = ["wood", "tile", "stone"][rng.integers(3)]
    floor_color = {
        "wood": _wood_color(rng),
        "tile": [*np.clip(rng.uniform(0.45, 0.9) + rng.normal(0, 0.03, 3), 0, 1).tolist(), 1.0],
        "stone": [*np.clip(rng.uniform(0.35, 0.7) + rng.normal(0, 0.03, 3), 0, 1).tolist(), 1.0],
    }[floor_kind]
    wall = [*np.clip(rng.uniform(0.7, 0.95) + rng.normal(0, 0.03, 3), 0, 1).tolist(), 1.0]
    counter_kind = ["stone", "wood", "painted"][rng.integers(3)]
    counter_color = {
        "stone": [*np.clip(rng.uniform(0.2, 0.85) + rng.normal(0, 0.02, 3), 0, 1).tolist(), 1.0],
        "wood": _wood_color(rng),
        "painted": _paint_color(rng),
    }[counter_kind]
    splash = [*np.clip(rng.uniform(0.6, 0.95) + rng.normal(0, 0.04, 3), 0, 1).tolist(), 1.0]
    return {
        "floor": MaterialSpec(
            floor_kind,
            floor_color,
            _seed(rng),
            roughness=rng.uniform(0.4, 0.8),
            specular=0.3,
            texture_scale_m=rng.uniform(0.6, 1.2),
        ),
        "wall": MaterialSpec("painted", wall, _seed(rng), roughness=0.9, specular=0.1, texture_scale_m=2.0),
        "counter": MaterialSpec(
            counter_kind,
            counter_color,
            _seed(rng),
            roughness=rng.uniform(0.2, 0.6),
            specular=0.5,
            texture_scale_m=rng.uniform(0.6, 1.0),
        ),
        "backsplash": MaterialSpec(
            "tile", splash, _seed(rng), roughness=0.25, specular=0.6, texture_scale_m=rng.uniform(0.2, 0.4)
        ),
        "cabinet": MaterialSpec(
            "painted", _paint_color(rng), _seed(rng), roughness=0.5, specular=0.3, texture_scale_m=0.8
        ),
    }


def sample_lights(rng: np.random.Generator, center: np.ndarray, width: float) -> tuple[list[float], list[LightSpec]]:
    """Ambient level plus 1-2 ceiling point lights and one window-like directional light, random colour temperature
    and intensity."""
    ambient = float(rng.uniform(0.25, 0.45))
    warm = rng.uniform(-0.08, 0.08)
    ambient_rgb = [ambient * (1 + warm), ambient, ambient * (1 - warm)]
    lights = []
    for _ in range(int(rng.integers(1, 3))):
        tint = rng.uniform(-0.12, 0.12)
        power = rng.uniform(2.0, 6.0)
        pos = [rng.uniform(0.6, 2.2), center[1] + rng.uniform(-0.6, 0.6) * max(width, 1.0), rng.uniform(2.2, 2.8)]
        lights.append(LightSpec("point", [power * (1 + tint), power, power * (1 - tint)], position=pos, shadow=True))
    d = np.array([-rng.uniform(0.2, 1.0), rng.uniform(-0.8, 0.8), -rng.uniform(0.4, 1.0)])
    strength = rng.uniform(0.4, 1.4)
    lights.append(LightSpec("directional", [strength] * 3, direction=(d / np.linalg.norm(d)).tolist(), shadow=True))
    return ambient_rgb, lights


# ------------------------------------------------------------------ joint states
def sample_states(obj: ArticulatedObject, rng: np.random.Generator) -> tuple[float, dict[str, float]]:
    """Random target state (closed with probability 0.2, else uniform) and held states of the other joints."""
    lo, hi = obj.joint_range
    q = lo if rng.random() < CLOSED_PROBABILITY else float(rng.uniform(lo, hi))
    held = {}
    for name, value in obj.held_states.items():
        j = obj.joints[name]
        if j.lower is not None and j.upper is not None and rng.random() < HELD_RANDOM_PROBABILITY:
            held[name] = float(rng.uniform(j.lower, j.upper))
        else:
            held[name] = float(value)
    return float(q), held


def swept_bounds(obj: ArticulatedObject, q: float) -> np.ndarray:
    """Axis-aligned bounds (2, 3) of the object over every checked state, canonical frame."""
    b = np.stack([obj.bounds(s) for s in check_states(obj, q)])
    return np.stack([b[:, 0].min(0), b[:, 1].max(0)])


@dataclass
class _Placed:
    entry: AssetEntry
    obj: ArticulatedObject
    q: float
    held: dict[str, float]
    swept: np.ndarray
    world_T_object: np.ndarray
    support: str


def _load(entry: AssetEntry, rng) -> tuple[ArticulatedObject, float, dict[str, float]]:
    obj = cached_object(entry.path)
    q, held = sample_states(obj, rng)
    return load_object_in_default_frame(entry.path, obj.target_joint, obj.scale, held), q, held


def _translation(x, y, z) -> np.ndarray:
    return make_pose(translation=np.array([x, y, z], float))


def _stand(obj, q, held, entry, rng, y_left: float, z_floor: float, support: str) -> _Placed:
    """Place the object with its swept box starting at ``y_left``, back to the wall, bottom on ``z_floor``."""
    swept = swept_bounds(obj, q)
    x = rng.uniform(*WALL_GAP_M) - swept[0, 0]
    y = y_left - swept[0, 1]
    z = z_floor + FLOOR_CLEARANCE_M - swept[0, 2]
    return _Placed(entry, obj, q, held, swept, _translation(x, y, z), support)


def _world_swept(p: _Placed) -> np.ndarray:
    return p.swept + p.world_T_object[:3, 3]


# ------------------------------------------------------------------ layouts
def sample_kitchen(entries: list[AssetEntry], rng: np.random.Generator) -> tuple[list[_Placed], list[BoxSpec]]:
    """A kitchen row along the wall (world frame, metres; module docstring rules): objects and static boxes.

    Row order along +y: a tall object (left end), the under-counter objects, a base cabinet where the counter
    would otherwise be too short, a tall object (right end); the microwave stands on the counter.
    """
    micro, use_micro, chosen_under, chosen_tall = _choose_kitchen_entries(entries, rng)
    mats = room_materials(rng)
    row: list[_Placed] = []
    y = _stand_in_row(row, chosen_tall[:1], 0.0, rng)
    under_start = y
    y = _stand_in_row(row, chosen_under, y, rng)
    under_rows = [p for p in row if p.support == "floor" and not p.entry.tall]
    micro_placed = None
    if use_micro:
        entry = micro[int(rng.integers(len(micro)))]
        obj, q, held = _load(entry, rng)
        micro_placed = (entry, obj, q, held, swept_bounds(obj, q))
    micro_width = None if micro_placed is None else micro_placed[4][1, 1] - micro_placed[4][0, 1]
    cabinet, y = _base_cabinet(micro_width, under_rows, under_start, y, rng)
    _stand_in_row(row, chosen_tall[1:2], y, rng, gap_after=False)
    boxes, y0, y1, counter_top = _counter_boxes(under_rows, cabinet, mats, rng)
    if micro_placed is not None:
        entry, obj, q, held, swept = micro_placed
        free = (y1 - y0) - (swept[1, 1] - swept[0, 1])
        y_left = y0 + 0.01 + rng.uniform(0, max(free - 0.02, 0.0))
        row.append(_stand(obj, q, held, entry, rng, y_left, counter_top, "counter"))
    _center_row(row, boxes)
    boxes.extend(_room(rng, row, boxes, mats))
    return row, boxes


def _choose_kitchen_entries(
    entries: list[AssetEntry], rng: np.random.Generator
) -> tuple[list[AssetEntry], bool, list[AssetEntry], list[AssetEntry]]:
    """(all microwaves, whether the kitchen gets one, the chosen under-counter entries, the chosen tall entries)."""
    micro = [e for e in entries if e.category == "microwave"]
    tall = [e for e in entries if e.tall and e.category != "microwave"]
    under = [e for e in entries if not e.tall and e.category != "microwave"]
    if not under and not tall:
        raise CenterArtError("kitchen layout needs at least one non-microwave object in --objects")
    n = int(rng.integers(2, 6))
    use_micro = bool(micro) and rng.random() < 0.6
    n_tall = min(len(tall) and int(rng.choice([0, 1, 1, 2])), n - int(use_micro))
    n_under = n - int(use_micro) - n_tall
    if not under:
        n_tall, n_under = n - int(use_micro), 0
    if n_under == 0 and not use_micro and n_tall < 2:
        n_under = 1 if under else 0
    chosen_under = [under[i] for i in rng.choice(len(under), n_under, replace=True)] if n_under else []
    chosen_tall = [tall[i] for i in rng.choice(len(tall), n_tall, replace=True)] if n_tall else []
    return micro, use_micro, chosen_under, chosen_tall


def _stand_in_row(
    row: list[_Placed], entries: list[AssetEntry], y: float, rng: np.random.Generator, gap_after: bool = True
) -> float:
    """Load each entry and stand it on the floor from ``y`` (m) along +y, appending to ``row``; returns the next y.

    ``gap_after``: leave a random neighbour gap after each object (the row's last object needs none, and drawing
    it would shift the random stream).
    """
    for entry in entries:
        obj, q, held = _load(entry, rng)
        row.append(_stand(obj, q, held, entry, rng, y, 0.0, "floor"))
        y = _world_swept(row[-1])[1, 1] + (rng.uniform(*NEIGHBOUR_GAP_M) if gap_after else 0.0)
    return y


def _base_cabinet(
    micro_width: float | None, under_rows: list[_Placed], under_start: float, y: float, rng: np.random.Generator
) -> tuple[tuple[float, float, float, float] | None, float]:
    """The plain base cabinet (y0, y1, depth, height) in m, or None, and the next free y along the row.

    The microwave (swept width ``micro_width``, None without one) needs a counter at least as long as itself; the
    cabinet extends the under-counter segment (or stands in for it) when that is too short.
    """
    needed = 0.0 if micro_width is None else micro_width + 0.04
    if not under_rows:
        needed = max(needed, rng.uniform(0.6, 0.9))
    span = (max(_world_swept(p)[1, 1] for p in under_rows) - under_start) if under_rows else 0.0
    if span >= needed:
        return None, y
    c0 = y if under_rows else under_start
    width = max(needed - span, 0.3)
    depth, height = rng.uniform(0.55, 0.62), rng.uniform(0.84, 0.88)
    return (c0, c0 + width, depth, height), c0 + width + rng.uniform(*NEIGHBOUR_GAP_M)


def _counter_boxes(
    under_rows: list[_Placed], cabinet: tuple | None, mats: dict, rng: np.random.Generator
) -> tuple[list[BoxSpec], float, float, float]:
    """Counter top, base cabinet and backsplash boxes; also the counter's y extent (y0, y1) and top height (m).

    The counter spans the under-counter objects (or the cabinet), flush with their swept boxes' y extent.
    """
    heights = [_world_swept(p)[1, 2] for p in under_rows] + ([cabinet[3]] if cabinet else [])
    # The counter's depth follows the closed fronts: open doors and drawers swing out below it.
    depths = [p.obj.bounds()[1, 0] + p.world_T_object[0, 3] for p in under_rows] + ([cabinet[2]] if cabinet else [])
    gap_below = rng.uniform(0.005, 0.02)
    thickness = rng.uniform(*COUNTER_THICKNESS_M)
    bottom = max(max(heights) + gap_below, 0.86)
    front = max(max(depths), 0.5) + rng.uniform(*COUNTER_OVERHANG_M)
    spans = [_world_swept(p)[:, 1] for p in under_rows] + ([np.array(cabinet[:2])] if cabinet else [])
    y0 = min(float(sp[0]) for sp in spans)
    y1 = max(float(sp[1]) for sp in spans)
    counter_top = bottom + thickness
    boxes = [
        _box(
            "counter",
            "counter",
            [front / 2, (y0 + y1) / 2, bottom + thickness / 2],
            [front / 2, (y1 - y0) / 2, thickness / 2],
            mats["counter"],
        )
    ]
    if cabinet is not None:
        c0, c1, depth, _height = cabinet
        boxes.append(
            _box(
                "base_cabinet",
                "cabinet",
                [depth / 2, (c0 + c1) / 2, (bottom - 0.002) / 2],
                [depth / 2 - 0.005, (c1 - c0) / 2, (bottom - 0.002) / 2],
                mats["cabinet"],
            )
        )
    splash_h = rng.uniform(0.45, 0.6)
    boxes.append(
        _box(
            "backsplash",
            "backsplash",
            [-0.005, (y0 + y1) / 2, counter_top + splash_h / 2],
            [0.005, (y1 - y0) / 2, splash_h / 2],
            mats["backsplash"],
        )
    )
    return boxes, y0, y1, counter_top


def sample_single(entries: list[AssetEntry], rng: np.random.Generator) -> tuple[list[_Placed], list[BoxSpec]]:
    entry = entries[int(rng.integers(len(entries)))]
    mats = room_materials(rng)
    obj, q, held = _load(entry, rng)
    boxes: list[BoxSpec] = []
    if entry.category == "microwave":
        # A microwave stands on a base cabinet with a counter top, as in a kitchen.
        swept = swept_bounds(obj, q)
        width = swept[1, 1] - swept[0, 1] + rng.uniform(0.3, 0.8)
        depth, height, thickness = rng.uniform(0.55, 0.62), rng.uniform(0.84, 0.88), rng.uniform(0.03, 0.05)
        closed = obj.bounds()
        front = max(depth, closed[1, 0] - closed[0, 0] + WALL_GAP_M[1]) + 0.03
        y0 = -width / 2
        boxes.append(
            _box(
                "base_cabinet",
                "cabinet",
                [depth / 2, 0.0, height / 2],
                [depth / 2 - 0.005, width / 2, height / 2 - 0.001],
                mats["cabinet"],
            )
        )
        boxes.append(
            _box(
                "counter",
                "counter",
                [front / 2, 0.0, height + thickness / 2],
                [front / 2, width / 2, thickness / 2],
                mats["counter"],
            )
        )
        placed = _stand(
            obj,
            q,
            held,
            entry,
            rng,
            y0 + rng.uniform(0.05, width - (swept[1, 1] - swept[0, 1]) - 0.05),
            height + thickness,
            "counter",
        )
    else:
        placed = _stand(obj, q, held, entry, rng, 0.0, 0.0, "floor")
    row = [placed]
    _center_row(row, boxes)
    boxes.extend(_room(rng, row, boxes, mats))
    return row, boxes


def _center_row(row: list[_Placed], boxes: list[BoxSpec]) -> None:
    """Shift everything along y so the row is centred on y = 0."""
    ys = [_world_swept(p)[:, 1] for p in row] + [
        np.asarray(b.world_T_box)[1, 3] + np.array([-1, 1]) * b.half_size[1] for b in boxes
    ]
    ys = np.concatenate(ys)
    shift = -(ys.min() + ys.max()) / 2
    for p in row:
        p.world_T_object[1, 3] += shift
    for b in boxes:
        b.world_T_box[1][3] += shift


def _room(rng, row: list[_Placed], boxes: list[BoxSpec], mats) -> list[BoxSpec]:
    """Floor, back wall and two side walls around the row (walls are 0.1 m thick, faces at x=0 and y=+-half)."""
    half = max(2.5, max(abs(_world_swept(p)[:, 1]).max() for p in row) + rng.uniform(1.5, 2.5))
    depth = 6.0
    return [
        _box("floor", "floor", [depth / 2 - 0.1, 0.0, -0.05], [depth / 2 + 0.1, half + 0.1, 0.05], mats["floor"]),
        _box("back_wall", "wall", [-0.05 - 0.01, 0.0, 1.5], [0.05, half + 0.1, 1.5], mats["wall"]),
        _box("left_wall", "wall", [depth / 2, -half - 0.05, 1.5], [depth / 2, 0.05, 1.5], mats["wall"]),
        _box("right_wall", "wall", [depth / 2, half + 0.05, 1.5], [depth / 2, 0.05, 1.5], mats["wall"]),
    ]


def _box(name, role, center, half, material) -> BoxSpec:
    return BoxSpec(name, role, pose_list(_translation(*center)), [float(h) for h in half], material)


# ------------------------------------------------------------------ whole scene
def sample_scene(
    scene_id: str,
    seed: int,
    layout: str,
    entries: list[AssetEntry],
    rng: np.random.Generator,
    views: int,
    width: int,
    height: int,
    K: np.ndarray,
    shell: ShellRanges,
    stereo: StereoSpec | None = None,
) -> tuple[SceneDescription, list[ArticulatedObject]]:
    """Sample a complete scene description (and the loaded objects, for checks and labels)."""
    if not entries:
        raise CenterArtError("no objects to place")
    if layout == "kitchen":
        row, boxes = sample_kitchen(entries, rng)
    elif layout == "single":
        row, boxes = sample_single(entries, rng)
    else:
        raise CenterArtError(f"unknown layout {layout!r}; choose single or kitchen")
    objects = []
    for k, p in enumerate(row):
        objects.append(
            ObjectSpec(
                name=f"obj{k}",
                object_id=p.entry.object_id,
                path=str(p.entry.path),
                category=p.obj.category,
                scale=float(p.obj.scale),
                world_T_object=pose_list(p.world_T_object),
                target_joint=p.obj.target_joint,
                joint_type=p.obj.joint_type,
                joint_state=float(p.q),
                joint_state_normalized=float(p.obj.normalize(p.q)),
                held_states={k2: float(v) for k2, v in p.held.items()},
                support=p.support,
                materials=object_materials(rng) if p.obj.generated else {},
            )
        )
    all_b = np.concatenate([_world_swept(p) for p in row])
    center = (all_b.min(0) + all_b.max(0)) / 2
    row_width = all_b[:, 1].max() - all_b[:, 1].min()
    ambient, lights = sample_lights(rng, center, row_width)
    cameras = []
    for v in range(views):
        # Look at one object of the row (or the row centre), at about counter height.
        if rng.random() < 0.4 or len(row) == 1:
            target = center.copy() if len(row) > 1 else (_world_swept(row[0]).mean(0))
        else:
            target = _world_swept(row[int(rng.integers(len(row)))]).mean(0)
        target[2] = min(target[2], 1.0)
        pose = sample_shell_pose(rng, target, shell)
        cameras.append(CameraSpec(f"view{v:02d}", int(width), int(height), K.tolist(), pose_list(pose)))
    stereo = stereo or StereoSpec()
    stereo = StereoSpec(**{**stereo.__dict__, "pattern_seed": int(rng.integers(2**31))})
    scene = SceneDescription(
        scene_id=scene_id,
        seed=int(seed),
        layout=layout,
        boxes=boxes,
        objects=objects,
        lights=lights,
        ambient=ambient,
        cameras=cameras,
        stereo=stereo,
    )
    return scene, [p.obj for p in row]
