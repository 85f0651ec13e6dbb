"""Encoder datasets: rendered views (``centerart scenes generate`` folders, layouts mixed) -> input tensors and
targets at the network's input size.

Each item is one view: RGB and depth letterboxed into the input (random scale and shift, colour jitter and a
depth kind chosen per sample when augmenting; a plain fit and the realistic depth otherwise), the input's K,
and the targets of :func:`centerart.training.encoder_targets.build_targets`. Items are drawn from a generator
seeded by (seed, epoch, index), so an epoch is reproducible whatever the number of loader workers.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import torch
from torch.utils.data import Dataset

from centerart.errors import CenterArtError
from centerart.models.encoder.config import EncoderConfig
from centerart.models.encoder.inputs import Letterbox, to_tensors
from centerart.scenes.dataset import (
    DEPTH_SCALE_MM,
    SceneView,
    check_view_files,
    list_views,
    read_png,
    read_view_labels,
)
from centerart.training.encoder_augment import AugmentConfig, choose_depth, jitter_colour, random_letterbox
from centerart.training.encoder_targets import build_targets

MAX_OBJECTS = 8


def collect_views(folders: list[Path]) -> list[Path]:
    """Every view folder of every scene folder given (a folder may also hold several scene folders)."""
    views: list[Path] = []
    for folder in folders:
        folder = Path(folder)
        if not folder.is_dir():
            raise CenterArtError(f"{folder}: scenes folder not found")
        if (folder / "manifest.json").is_file() or any(folder.glob("scene_*")):
            views += list_views(folder)
        else:
            subs = [p for p in sorted(folder.iterdir()) if p.is_dir() and any(p.glob("scene_*"))]
            if not subs:
                raise CenterArtError(f"{folder}: no rendered scenes (expected scene_*/views/*/labels.json)")
            for sub in subs:
                views += list_views(sub)
    return views


def checked_views(folders: list[Path]) -> list[Path]:
    """:func:`collect_views`, each view's labels and images checked (see
    :func:`~centerart.scenes.dataset.check_view_files`), so a damaged view stops training before it starts."""
    views = collect_views(folders)
    for view in views:
        check_view_files(view)
    return views


def load_view_for_encoder(view_dir: Path) -> SceneView:
    """The parts of a rendered view the encoder trains on (RGB, true and realistic depth in m, labels); the
    masks and the stored heatmap are skipped: targets are rebuilt from the labels at the input's scale."""
    view_dir = Path(view_dir)
    labels = read_view_labels(view_dir)
    rgb = read_png(view_dir / "rgb.png")
    rgb = rgb[..., :3] if rgb.ndim == 3 else np.repeat(rgb[..., None], 3, axis=2)
    depth_true = read_png(view_dir / "depth_true.png").astype(np.float32) / DEPTH_SCALE_MM
    realistic = view_dir / "depth_realistic.png"
    depth_real = read_png(realistic).astype(np.float32) / DEPTH_SCALE_MM if realistic.is_file() else None
    return SceneView(rgb, depth_true, depth_real, None, None, None, labels)


class EncoderViewDataset(Dataset):
    def __init__(
        self,
        views: list[Path],
        config: EncoderConfig,
        codes: dict[str, np.ndarray],
        augment: AugmentConfig | None = None,
        seed: int = 0,
        depth: str = "realistic",
    ):
        self.views, self.config, self.codes = list(views), config, codes
        self.augment = augment if augment is not None and augment.enabled else None
        self.seed, self.epoch, self.depth = seed, 0, depth

    def __len__(self) -> int:
        return len(self.views)

    def labels_of(self, view: str) -> dict:
        return json.loads((Path(view) / "labels.json").read_text())

    def set_epoch(self, epoch: int) -> None:
        self.epoch = epoch

    def __getitem__(self, index: int) -> dict:
        return self.item(index, self.epoch)

    def item(self, index: int, epoch: int) -> dict:
        """View ``index`` as drawn in ``epoch`` (its augmentation is seeded by (seed, epoch, index))."""
        view = load_view_for_encoder(self.views[index])
        labels, camera = view.labels, view.camera
        cfg = self.config
        if self.augment is not None:
            rng = np.random.default_rng([self.seed, epoch, index])
            depth, kind = choose_depth(view.depth_true, view.depth_realistic, camera.K, self.augment, rng)
            box = random_letterbox(camera.width, camera.height, cfg.input_width, cfg.input_height, self.augment, rng)
        else:
            depth, kind = view.depth(self.depth)
            box = Letterbox.fit(camera.width, camera.height, cfg.input_width, cfg.input_height)
        rgb_in, depth_in = box.warp(view.rgb[..., :3], depth)
        if self.augment is not None:
            rgb_in = jitter_colour(rgb_in, self.augment, rng)  # after the warp: 4x fewer pixels
        rgb_t, depth_t = to_tensors(rgb_in, depth_in)
        targets = build_targets(labels, box, self.codes, cfg.code_dim, cfg.head_stride, MAX_OBJECTS)
        item = {k: torch.from_numpy(np.asarray(v)) for k, v in targets.items()}
        item.update(rgb=rgb_t, depth=depth_t, index=torch.tensor(index))
        item["meta"] = {"view": str(self.views[index]), "depth_kind": kind, "scale": box.scale, "labels": labels}
        return item


def collate(items: list[dict]) -> dict:
    """Stack tensors; keep the per-item ``meta`` dicts as a list."""
    out = {k: torch.stack([it[k] for it in items]) for k in items[0] if k != "meta"}
    out["meta"] = [it["meta"] for it in items]
    return out
