"""``centerart scenes generate``: sample, check, render and label scenes; parallel over scenes, resumable.

On-disk layout (all images PNG; depth in millimetres as uint16, 0 = no measurement)::

    OUT/manifest.json                 config, seed, code version, counts, asset index, timing
    OUT/scene_000000/scene.json       SceneDescription: the single source of truth (see description.py)
    OUT/scene_000000/checks.json      exact interpenetration check of the layout (collisions.py)
    OUT/scene_000000/textures/*.png   procedural textures the scene uses (paths referenced by scene.json)
    OUT/scene_000000/views/00/
        rgb.png                       (H, W, 3) uint8
        depth_true.png                (H, W) uint16 mm, rasterised z-depth in the RGB camera frame
        depth_realistic.png           (H, W) uint16 mm, stereo (IR pair + SGBM), its error model, or analytic
                                      noise; 0 = hole
        ir_left.png, ir_right.png     (H, W) uint8 IR pair with the dot pattern (stereo only)
        instances.png                 (H, W) uint8: 0 room/background, k + 1 = scene object k
        links.png                     (H, W) uint16: link ids, see labels.json objects[*].links
        heatmap.png                   (H, W) uint16 = round(heatmap * 65535), the paper's centre heatmap
                                      (the three masks not with --no-save-masks; textures/ not with
                                      --no-save-textures)
        labels.json                   K, world_T_camera, per visible object: pose, joint, visibility, ...

A scene folder is written atomically (temporary folder, then rename), so a folder that exists is complete and a
rerun skips it. Scene i is drawn from a generator seeded by (seed, i, attempt) only: results do not depend on the
number of workers or on which scenes already exist. A layout that fails the exact collision check is redrawn with
the next attempt (counted in the manifest).
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Literal

import numpy as np
from PIL import Image

from centerart.assets.articulated_object import ArticulatedObject
from centerart.assets.dataset import list_objects
from centerart.errors import CenterArtError
from centerart.geometry.camera import Intrinsics
from centerart.scenes.cameras import ShellRanges, intrinsics
from centerart.scenes.collisions import check_scene
from centerart.scenes.description import SceneDescription
from centerart.scenes.layouts import AssetEntry, sample_scene
from centerart.scenes.textures import make_texture, write_texture
from centerart.utils.atomic import atomic_directory, atomic_write_json
from centerart.utils.checks import at_least, interval, workers
from centerart.utils.folders import check_output_folder, output_folder
from centerart.utils.json_schema import array, json_problem, optional
from centerart.utils.manifest import merge_manifest
from centerart.utils.parallel import parallel_map
from centerart.utils.seeding import item_rng

MAX_LAYOUT_ATTEMPTS = 10
DEPTH_SCALE_MM = 1000.0
HEATMAP_SCALE = 65535.0
#: zlib level of every PNG a scene writes: level 1 encodes 3x faster than PIL's default 6 for files about 20% larger
#: (measured on 640x480 views: 0.07 vs 0.20 CPU-s per view); PNG encoding was a sixth of the stereo pipeline's time.
PNG_COMPRESS_LEVEL = 1
DEFAULT_RADIUS_M = {"single": (1.0, 2.5), "kitchen": (1.5, 3.0)}


@dataclass
class GenerateScenesConfig:
    """Render scenes of articulated objects (RGB, true and realistic depth, masks, encoder labels)."""

    objects: Path
    """Folder of object folders (``centerart objects generate`` output or PartNet-Mobility folders)."""
    out: Path
    """Output folder (created). Complete scenes already there are kept and skipped (resume)."""
    layout: Literal["single", "kitchen"] = "kitchen"
    """single: one object in a room; kitchen: 2-5 objects along a wall under a counter."""
    count: int = 10
    """Number of scenes."""
    views_per_scene: int = 2
    """Camera views rendered per scene."""
    seed: int = 0
    depth: Literal["true", "stereo", "stereo-model", "analytic"] = "stereo"
    """Realistic depth: stereo (IR pair + SGBM), stereo-model (the full-size stereo sensor's measured errors drawn
    from the true depth, at any image size: :mod:`centerart.scenes.stereo_model`), analytic (noise model), or true
    (no realistic depth)."""
    intrinsics: Literal["d415", "d415-half", "paper", "tiny"] = "d415"
    """d415: 640x480 fx=fy=615; d415-half: the same camera at 320x240, f=307.5 (the small encoder's input);
    paper: 960x512 f=530; tiny: 320x240 (tests). Cheap encoder data: --intrinsics d415-half --depth stereo-model
    --no-save-ir --no-save-masks --no-save-textures (docs/scenes.md, Speed)."""
    shader: Literal["default", "rt"] = "default"
    """default: rasteriser; rt: path-traced RGB (slow on CPU, noisy without a GPU denoiser)."""
    rt_samples_per_pixel: int = 4
    radius_m: tuple[float, float] | None = None
    """Camera distance range (m) from the point of interest; default 1.0-2.5 (single), 1.5-3.0 (kitchen)."""
    elevation_deg: tuple[float, float] = (10.0, 40.0)
    azimuth_deg: tuple[float, float] = (-40.0, 40.0)
    """Azimuth measured from straight in front of the wall (+x) towards +y."""
    decoder_checkpoint: Path | None = None
    """Decoder checkpoint whose shape codes fill each object's ``shape_code`` label (else null)."""
    save_ir: bool = True
    """Keep the IR pair images of the stereo sensor."""
    save_masks: bool = True
    """Write instances.png, links.png and heatmap.png. The encoder's training reads none of them (it rebuilds its
    targets from labels.json); evaluation, ``scenes show`` and the encoder sheet need them."""
    save_textures: bool = True
    """Write the procedural textures into the scene folder. Without, scene.json names none and a renderer
    makes each texture again from its kind, colour and seed (the same image)."""
    ir_shading: Literal["fast", "full"] = "fast"
    """Stereo IR pair: fast (unlit raster shaded from geometry, :mod:`centerart.scenes.ir_synthesis`: half the
    CPU time of a stereo image, the same depth-error bands) or full (SAPIEN's lit render with the projector as a
    textured light, as scenes were made before)."""
    workers: int | None = None
    """Parallel worker processes (default: all cores). Each compiles SAPIEN's shaders once (a few seconds)."""
    ray_address: str | None = None
    """Ray cluster address (e.g. auto or ray://host:10001) to run scenes on a cluster instead of local processes."""

    def __post_init__(self):
        at_least("--count", self.count, 0)
        at_least("--views-per-scene", self.views_per_scene, 1)
        at_least("--rt-samples-per-pixel", self.rt_samples_per_pixel, 1)
        interval("--radius-m", self.radius_m, lo=0.0, strict_lo=True)
        interval("--elevation-deg", self.elevation_deg, lo=-90.0, hi=90.0)
        interval("--azimuth-deg", self.azimuth_deg, lo=-180.0, hi=180.0)
        workers("--workers", self.workers)


# ---------------------------------------------------------------------------- asset index
def asset_index(folder: Path) -> list[AssetEntry]:
    """Every usable object folder under ``folder`` with its category and closed height."""
    entries = []
    for path in list_objects(folder):
        obj = ArticulatedObject.load(path)
        lo, hi = obj.bounds()
        entries.append(AssetEntry(obj.object_id, str(path.resolve()), obj.category, float(hi[2] - lo[2])))
    return entries


# ---------------------------------------------------------------------------- per-process state
_RENDERERS: dict = {}
_SHAPE_CODES: dict = {}


def _renderer(shader: str, spp: int, ir_shading: str = "fast", ir_cameras: bool = True):
    from centerart.scenes.renderer import SceneRenderer

    key = (shader, spp, ir_shading, ir_cameras)
    if key not in _RENDERERS:
        _RENDERERS[key] = SceneRenderer(shader, spp, ir_shading, ir_cameras)
    return _RENDERERS[key]


def load_decoder_shape_codes(path: Path) -> dict[str, np.ndarray]:
    """Shape code per object id from a decoder checkpoint (``centerart.models.checkpoint.load_shape_codes``)."""
    key = str(path)
    if key not in _SHAPE_CODES:
        try:
            from centerart.models.checkpoint import load_shape_codes
        except ImportError as err:
            raise CenterArtError(
                f"--decoder-checkpoint {path}: this installation has no decoder checkpoint reader "
                f"(centerart.models.checkpoint.load_shape_codes: {err})"
            ) from None
        if not Path(path).is_file() and not Path(path).is_dir():
            raise CenterArtError(f"--decoder-checkpoint {path}: no such file")
        _SHAPE_CODES[key] = {str(k): np.asarray(v) for k, v in load_shape_codes(Path(path)).items()}
    return _SHAPE_CODES[key]


# ---------------------------------------------------------------------------- one scene
def sample_checked_scene(
    cfg: GenerateScenesConfig, index: int, entries: list[AssetEntry]
) -> tuple[SceneDescription, list[ArticulatedObject], dict]:
    """Draw scene ``index`` until its layout passes the exact collision check."""
    w, h, K = intrinsics(cfg.intrinsics)
    radius = cfg.radius_m or DEFAULT_RADIUS_M[cfg.layout]
    shell = ShellRanges(tuple(radius), tuple(cfg.elevation_deg), tuple(cfg.azimuth_deg))
    failures = []
    for attempt in range(MAX_LAYOUT_ATTEMPTS):
        rng = item_rng(cfg.seed, "scene", index, attempt)
        scene, objects = sample_scene(
            scene_id(index), cfg.seed, cfg.layout, entries, rng, cfg.views_per_scene, w, h, K, shell
        )
        report = check_scene(scene, objects)
        if report.ok:
            return scene, objects, {"attempt": attempt, "rejected": failures, "worst_overlap_m3": report.worst_m3}
        failures.append("; ".join(report.problems[:3]))
    raise CenterArtError(f"{scene_id(index)}: no layout out of {MAX_LAYOUT_ATTEMPTS} passed the collision check")


def scene_id(index: int) -> str:
    return f"scene_{index:06d}"


def _write_png(path: Path, array: np.ndarray) -> None:
    Image.fromarray(array).save(path, compress_level=PNG_COMPRESS_LEVEL)


def depth_to_png(depth: np.ndarray) -> np.ndarray:
    return np.clip(np.round(depth * DEPTH_SCALE_MM), 0, 65535).astype(np.uint16)


def render_scene_views(
    renderer,
    scene: SceneDescription,
    objects,
    scene_dir: Path,
    depth_mode: str,
    seed: int,
    index: int,
    shape_codes=None,
    save_ir: bool = True,
    save_masks: bool = True,
) -> list[dict]:
    """Render every view of a built scene into ``scene_dir/views``; returns per-view summaries."""
    from centerart.scenes.depth_noise import analytic_depth, stereo_depth, stereo_occlusion, to_ir_uint8
    from centerart.scenes.labels import view_labels
    from centerart.scenes.stereo_model import modelled_stereo_depth

    summaries, meshes = [], {}
    K = np.asarray(scene.cameras[0].K, float)
    for v in range(len(scene.cameras)):
        rng = item_rng(seed, "scene", index, "view", v, "sensor")
        images = renderer.render(v, ir=depth_mode == "stereo")
        view_dir = scene_dir / "views" / f"{v:02d}"
        view_dir.mkdir(parents=True)
        _write_png(view_dir / "rgb.png", images.rgb)
        _write_png(view_dir / "depth_true.png", depth_to_png(images.depth))
        if depth_mode == "stereo":
            left, right = to_ir_uint8(images.ir_left, rng), to_ir_uint8(images.ir_right, rng)
            st = scene.stereo
            occluded = stereo_occlusion(images.ir_left_depth, images.ir_right_depth, K, st.baseline_m)
            realistic = stereo_depth(left, right, K, st.baseline_m, st.left_offset_m, occluded=occluded)
            if save_ir:
                _write_png(view_dir / "ir_left.png", left)
                _write_png(view_dir / "ir_right.png", right)
        elif depth_mode == "stereo-model":
            st = scene.stereo
            realistic = modelled_stereo_depth(
                images.depth, K, rng, st.left_offset_m, st.baseline_m, st.projector_offset_m
            )
        elif depth_mode == "analytic":
            realistic = analytic_depth(images.depth, K, rng, baseline=scene.stereo.baseline_m)
        else:
            realistic = None
        if realistic is not None:
            _write_png(view_dir / "depth_realistic.png", depth_to_png(realistic))
        info, heat = view_labels(scene, objects, v, images.instances, renderer.link_ids, shape_codes, meshes)
        if save_masks:
            _write_png(view_dir / "instances.png", images.instances)
            _write_png(view_dir / "links.png", images.links)
            _write_png(view_dir / "heatmap.png", np.round(heat * HEATMAP_SCALE).astype(np.uint16))
        info["depth_realistic"] = depth_mode if realistic is not None else None
        atomic_write_json(view_dir / "labels.json", info)
        summaries.append({"view": v, "visible_objects": len(info["objects"])})
    return summaries


def write_textures(scene: SceneDescription, scene_dir: Path) -> None:
    """Write every textured material's image into ``scene_dir/textures`` and point the description at it."""
    materials = [b.material for b in scene.boxes] + [m for o in scene.objects for m in o.materials.values()]
    for m in materials:
        if m.kind in ("glass", "plain"):
            continue
        rel = f"textures/{m.kind}_{m.seed}.png"
        if not (scene_dir / rel).is_file():
            write_texture(scene_dir / rel, make_texture(m.kind, tuple(m.color), m.seed))
        m.texture = rel


def _generate_one(job: tuple) -> dict:
    cfg_dict, index, entries = job
    cfg = GenerateScenesConfig(**cfg_dict)
    final = Path(cfg.out) / scene_id(index)
    if (final / "scene.json").is_file():
        return {"scene": scene_id(index), "resumed": True, **json.loads((final / "checks.json").read_text())}
    started = time.perf_counter()
    scene, objects, check = sample_checked_scene(cfg, index, entries)
    codes = load_decoder_shape_codes(cfg.decoder_checkpoint) if cfg.decoder_checkpoint else None
    if cfg.workers is None or cfg.workers > 1:
        single_threaded_worker()
    renderer = _renderer(cfg.shader, cfg.rt_samples_per_pixel, cfg.ir_shading, ir_cameras=cfg.depth == "stereo")
    with atomic_directory(final) as tmp:
        if cfg.save_textures:
            write_textures(scene, tmp)
        renderer.build(scene, tmp)
        views = render_scene_views(
            renderer, scene, objects, tmp, cfg.depth, cfg.seed, index, codes, cfg.save_ir, cfg.save_masks
        )
        renderer.close()
        scene.save(tmp / "scene.json")
        record = {
            "scene": scene_id(index),
            "objects": [o.object_id for o in scene.objects],
            "views": views,
            **check,
            "seconds": round(time.perf_counter() - started, 3),
        }
        atomic_write_json(tmp / "checks.json", record)
    return record


def single_threaded_worker() -> None:
    """Thread settings of a scene worker when parallel workers already fill the cores (same pictures, less CPU):
    Mesa's lavapipe renders on the calling thread instead of spinning threads of its own (measured 1.71 against 1.47
    stereo images per CPU-second; takes effect only before the process's first renderer creates its Vulkan
    device, and a value the user set is kept), and OpenCV's semi-global matching (3-way mode) stops splitting each
    image over threads (81 against 72 CPU-ms per 640 x 480 pair, same disparities)."""
    import cv2

    os.environ.setdefault("LP_NUM_THREADS", "0")
    cv2.setNumThreads(1)


def generate_scenes(cfg: GenerateScenesConfig) -> dict:
    """Generate (or complete) the scene dataset described by ``cfg``; returns the manifest fields (counts and
    scene rows of every scene in the folder, earlier runs' included)."""
    check_output_folder(cfg.out)
    if cfg.decoder_checkpoint is not None:
        load_decoder_shape_codes(cfg.decoder_checkpoint)  # fail early, in the parent, with a clear message
    entries = asset_index(cfg.objects)
    out = output_folder(cfg.out)
    started = time.perf_counter()
    cfg_dict = {k: v for k, v in asdict(cfg).items()}
    jobs = [(cfg_dict, i, entries) for i in range(cfg.count)]
    records = parallel_map(_generate_one, jobs, cfg.workers, desc="scenes", ray_address=cfg.ray_address)
    return merge_manifest(
        out, "scenes", cfg, "scenes", list(records), key=lambda r: r["scene"],
        summarize=lambda rows: {"counts": _counts(rows, entries)},
        present=lambda r: (out / r["scene"] / "scene.json").is_file(),
        seed=cfg.seed, wall_seconds_this_run=round(time.perf_counter() - started, 1),
        assets=[asdict(e) for e in entries],
    )  # fmt: skip


def _counts(records: list[dict], entries: list[AssetEntry]) -> dict:
    return {
        "scenes": len(records),
        "images": sum(len(r.get("views", [])) for r in records),
        "rejected_layouts": int(sum(len(r.get("rejected", [])) for r in records)),
        "objects_available": len(entries),
    }


# ---------------------------------------------------------------------------- reading
@dataclass
class SceneView:
    """One rendered view read back from disk (depth in metres, 0 = no measurement)."""

    rgb: np.ndarray
    depth_true: np.ndarray
    depth_realistic: np.ndarray | None
    instances: np.ndarray
    links: np.ndarray
    heatmap: np.ndarray
    labels: dict

    def depth(self, kind: Literal["realistic", "true"]) -> tuple[np.ndarray, str]:
        """The ``kind`` depth image (m) and the kind returned: the true depth where the realistic one is asked for
        and the view was saved without it."""
        if kind == "realistic" and self.depth_realistic is not None:
            return self.depth_realistic, "realistic"
        return self.depth_true, "true"

    @property
    def camera(self) -> Intrinsics:
        """The view's pinhole camera (``labels.json``'s K and image size; OpenCV frame)."""
        return Intrinsics.from_matrix(self.labels["K"], self.labels["width"], self.labels["height"])


#: What readers of ``labels.json`` rely on (the file holds more); checked when a view is read.
JOINT_LABEL_SCHEMA = {"type": str, "state": float, "state_normalized": float, "range": array(2),
                      "axis_origin_camera": array(3), "axis_direction_camera": array(3)}  # fmt: skip
OBJECT_LABEL_SCHEMA = {"instance": int, "object_id": str, "category": str, "camera_T_object": array(4, 4),
                       "joint": JOINT_LABEL_SCHEMA, "visible_fraction": float, "bbox_xyxy": array(4),
                       "heatmap_gaussian": {"mean_uv": array(2), "cov_uv": array(2, 2)},
                       "shape_code?": optional(array(None))}  # fmt: skip
LABELS_SCHEMA = {"width": int, "height": int, "K": array(3, 3), "world_T_camera": array(4, 4),
                 "objects": [OBJECT_LABEL_SCHEMA]}  # fmt: skip


def read_view_labels(view_dir: Path) -> dict:
    """A view's ``labels.json``, checked against :data:`LABELS_SCHEMA` (one error naming the file and field)."""
    path = Path(view_dir) / "labels.json"
    try:
        labels = json.loads(path.read_text())
    except (OSError, ValueError) as err:  # ValueError: malformed JSON, or binary bytes
        raise CenterArtError(f"{path}: not a readable labels file ({str(err).splitlines()[0]})") from None
    problem = json_problem(labels, LABELS_SCHEMA)
    if problem:
        raise CenterArtError(f"{path}: not a valid labels file ({problem})")
    return labels


def read_png(path: Path) -> np.ndarray:
    """An image of a rendered view as an array; a damaged file is one error naming it."""
    try:
        with Image.open(path) as im:
            return np.asarray(im)
    except (OSError, ValueError, SyntaxError) as err:  # PIL: UnidentifiedImageError (OSError), truncated data
        raise CenterArtError(f"{path}: not a readable image ({str(err).splitlines()[0]})") from None


def check_view_files(view_dir: Path, images: tuple[str, ...] = ("rgb.png", "depth_true.png")) -> None:
    """Labels readable and images intact (PNG chunks and checksums verified, pixels not decoded): a dataset is
    checked before training starts instead of failing inside a data-loader worker."""
    read_view_labels(view_dir)
    for name in images:
        path = Path(view_dir) / name
        try:
            with Image.open(path) as im:
                im.verify()
        except (OSError, ValueError, SyntaxError) as err:
            raise CenterArtError(f"{path}: not a readable image ({str(err).splitlines()[0]})") from None


def load_view(view_dir: Path) -> SceneView:
    view_dir = Path(view_dir)
    if not (view_dir / "labels.json").is_file():
        raise CenterArtError(f"{view_dir}: not a rendered view (no labels.json)")
    labels = read_view_labels(view_dir)
    realistic = view_dir / "depth_realistic.png"
    return SceneView(
        rgb=read_png(view_dir / "rgb.png"),
        depth_true=read_png(view_dir / "depth_true.png").astype(np.float32) / DEPTH_SCALE_MM,
        depth_realistic=read_png(realistic).astype(np.float32) / DEPTH_SCALE_MM if realistic.is_file() else None,
        instances=read_png(view_dir / "instances.png"),
        links=read_png(view_dir / "links.png"),
        heatmap=read_png(view_dir / "heatmap.png").astype(np.float32) / HEATMAP_SCALE,
        labels=labels,
    )


def list_views(folder: Path) -> list[Path]:
    """Every view folder of a scene dataset (sorted)."""
    folder = Path(folder)
    if not folder.is_dir():
        raise CenterArtError(f"{folder}: no such folder")
    views = sorted(folder.glob("scene_*/views/*/labels.json"))
    if not views:
        raise CenterArtError(f"{folder}: no rendered views (expected scene_*/views/*/labels.json)")
    return [p.parent for p in views]
