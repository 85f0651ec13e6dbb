"""The encoder's overfit check: train on a few views, no augmentation, and measure on the *same* views.

A model that cannot fit its own training views has a problem that more data will not fix (its readout, targets,
loss weights or capacity). :func:`overfit_encoder` trains a fresh encoder for a fixed number of steps on the first
``views`` views of some scene folders (items built once and kept in memory: without augmentation an item never
changes), then reads the objects out of the same views as inference does
(:func:`~centerart.models.encoder.readout.read_objects`) and reports, over matched objects
(:mod:`centerart.training.encoder_metrics`): recall, median rotation (deg) and translation (cm) errors and, with a
decoder, the Chamfer-L1 (mm) of the mesh decoded from the regressed shape code against the true mesh (object
frame, joint at its labelled state).

Besides the read-out, a diagnostic ``at_true_cells`` reads the same fields at the *target* cells of every
labelled object (the cells the loss trains, weighted by their target heatmap): when that is much better than the
read-out, the error is in finding and reading the peak; when it is as bad, the fields themselves do not fit.

Every quantity is in the OpenCV camera frame of the view (m, rad); errors are reported in cm / deg / mm.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np
import torch

from centerart.errors import CenterArtError
from centerart.geometry.transforms import rotation_angle_between
from centerart.models.encoder.config import PRESETS
from centerart.models.encoder.decoded_shape import DecodedShape
from centerart.models.encoder.losses import EncoderLossConfig, code_scale, encoder_loss
from centerart.models.encoder.network import RGBDEncoder, cell_centers, object_translation, rotation_from_raw
from centerart.training.encoder_data import EncoderViewDataset, collate, collect_views
from centerart.training.encoder_metrics import batch_detections, summarize, summarize_by_category, view_metrics
from centerart.training.schedules import lr_factor


@dataclass
class OverfitConfig:
    scenes: tuple[Path, ...]
    """Scene folders (``centerart scenes generate`` outputs); the first ``views`` views are used."""
    views: int = 50
    preset: str = "small"
    steps: int = 600
    batch_size: int = 8
    lr: float = 1e-3
    seed: int = 0
    eval_every: int = 100
    """Measure the views every this many steps (the learning curve); always at the end."""
    depth: str = "realistic"
    loss: EncoderLossConfig = field(default_factory=EncoderLossConfig)
    encoder_overrides: dict = field(default_factory=dict)
    """EncoderConfig fields over the preset (e.g. a readout option)."""
    shape_objects: int = 50
    """Decode at most this many matched objects for the Chamfer (0: none)."""
    mesh_resolution: int = 96


def overfit_encoder(
    cfg: OverfitConfig,
    codes: dict[str, np.ndarray],
    decoder=None,
    objects_root: Path | None = None,
    log=print,
    init_state: dict | None = None,
) -> tuple[dict, RGBDEncoder]:
    """Train on the views and measure on them; ``decoder`` (a LoadedDecoder) enables the Chamfer metric. Returns
    the report and the trained encoder. ``init_state``: start from these weights (with ``steps`` 0: measure a
    trained encoder, e.g. under another readout)."""
    torch.manual_seed(cfg.seed)
    code_dim = len(next(iter(codes.values()))) if codes else PRESETS[cfg.preset].code_dim
    enc_cfg = replace(PRESETS[cfg.preset], **{**cfg.encoder_overrides, "code_dim": code_dim})
    views = collect_views(list(cfg.scenes))[: cfg.views]
    ds = EncoderViewDataset(views, enc_cfg, codes, augment=None, depth=cfg.depth)
    items = [ds[i] for i in range(len(ds))]
    model = RGBDEncoder(enc_cfg)
    if init_state is not None:
        model.load_state_dict(init_state)
    opt = torch.optim.Adam(model.parameters(), lr=cfg.lr)
    steps_per_epoch = max(1, len(items) // cfg.batch_size)
    sched = torch.optim.lr_scheduler.LambdaLR(opt, lambda s: lr_factor(s, steps_per_epoch, cfg.steps))
    code_std = code_scale(codes) if codes else None
    decoded = decoded_shape(cfg.loss, decoder, codes)
    gen = torch.Generator().manual_seed(cfg.seed)
    curve, order, train_seconds = [], [], 0.0
    for step in range(1, cfg.steps + 1):
        t0 = time.perf_counter()
        if len(order) < cfg.batch_size:  # epochs of shuffled views, as a loader with drop_last would draw them
            order += torch.randperm(len(items), generator=gen).tolist()
        batch = collate([items[i] for i in order[: cfg.batch_size]])
        del order[: cfg.batch_size]
        model.train()
        loss, terms, _ = _loss(model, batch, cfg.loss, code_std, decoded)
        opt.zero_grad()
        loss.backward()
        opt.step()
        sched.step()
        train_seconds += time.perf_counter() - t0  # the measurements below are not training time
        if step % cfg.eval_every == 0 or step == cfg.steps:
            point = {"step": step, "seconds": train_seconds, "train_loss": float(loss.detach())}
            point.update({f"train_{k}": float(v) for k, v in terms.items()})
            point.update(measure(model, items, codes)["overall"])
            curve.append(point)
            log({k: round(v, 4) if isinstance(v, float) else v for k, v in point.items()})
    final = measure(model, items, codes)
    report = {
        "config": _jsonable(asdict(cfg)),
        "encoder": enc_cfg.to_dict(),
        "views": len(items),
        "train_seconds": train_seconds,
        "curve": curve,
        **final,
    }
    if decoder is not None and objects_root is not None and cfg.shape_objects > 0:
        report["shape_from_regressed_code"] = shape_errors(
            final["matched"][: cfg.shape_objects], decoder, objects_root, cfg.mesh_resolution
        )
    report.pop("matched")
    return report, model


def _loss(model, batch, loss_cfg, code_std, decoded=None):
    out = model(batch["rgb"], batch["depth"])
    loss, terms = encoder_loss(out, batch, loss_cfg, code_std, decoded)
    return loss, terms, out


def decoded_shape(loss: EncoderLossConfig, loaded, codes: dict) -> DecodedShape | None:
    """The decoded-shape term's frozen decoder and query points when ``loss.shape_sdf`` asks for it (else None);
    ``loaded``: the LoadedDecoder whose ``codes`` are the targets."""
    if loss.shape_sdf <= 0:
        return None
    if loaded is None or not codes:
        raise CenterArtError("--loss shape_sdf needs the decoder whose codes are the targets (--decoder)")
    return DecodedShape.build(loaded.decoder, codes, loaded.bounds)


@torch.no_grad()
def measure(model: RGBDEncoder, items: list[dict], codes: dict, chunk: int = 10) -> dict:
    """Read-out metrics over the items (as inference reads them), per category, and the true-cell diagnostic."""
    model.eval()
    results, matched, true_cells = [], [], []
    for start in range(0, len(items), chunk):
        batch = collate(items[start : start + chunk])
        out = model(batch["rgb"], batch["depth"])
        for dets, meta in zip(batch_detections(out, batch, model.config), batch["meta"], strict=True):
            labels = meta["labels"]
            res = view_metrics(dets, labels, codes)
            results.append(res)
            matched += [
                (meta["view"], dets[r["prediction"]], labels["objects"][r["label"]], labels) for r in res["rows"]
            ]
        true_cells += true_cell_errors(out, batch)
    overall = summarize(results)
    tilt = [upright_errors(det, label, meta) for _, det, label, meta in matched]
    overall["tilt_deg_median"] = _median(tilt, "tilt_deg")
    overall["rotation_deg_median_upright"] = _median(tilt, "rotation_deg_upright")
    overall["rotation_deg_median_at_true_cells"] = _median(true_cells, "rotation_deg")
    overall["translation_cm_median_at_true_cells"] = _median(true_cells, "translation_cm")
    overall["rotation_deg_median_at_true_peak_cell"] = _median(true_cells, "rotation_deg_peak")
    overall["translation_cm_median_at_true_peak_cell"] = _median(true_cells, "translation_cm_peak")
    rows = [row for r in results for row in r["rows"]]
    return {
        "overall": overall,
        "per_category": summarize_by_category(results),
        "worst_rotations": sorted(
            ({k: row[k] for k in ("object_id", "category", "rotation_deg", "translation_cm")} for row in rows),
            key=lambda r: -r["rotation_deg"],
        )[:10],
        "matched": [m[:3] for m in matched],
    }


def upright_errors(det, label: dict, labels: dict) -> dict:
    """How far the predicted object +z leans from true up (deg), and the rotation error once the prediction is
    turned upright with the true gravity (what inference does with an estimated gravity): the yaw error."""
    from centerart.geometry.gravity import gravity_from_world_T_camera
    from centerart.inference.pose_from_depth import upright

    gravity = gravity_from_world_T_camera(np.asarray(labels["world_T_camera"]))
    pose, truth = det.camera_T_object, np.asarray(label["camera_T_object"], float)
    tilt = float(np.degrees(np.arccos(np.clip(-pose[:3, 2] @ gravity, -1.0, 1.0))))
    turned = upright(pose, gravity)
    return {
        "tilt_deg": tilt,
        "rotation_deg_upright": float(np.degrees(rotation_angle_between(turned[:3, :3], truth[:3, :3]))),
    }


def _median(rows: list[dict], key: str) -> float:
    return float(np.median([r[key] for r in rows])) if rows else float("nan")


def true_cell_errors(out, batch: dict) -> list[dict]:
    """Per labelled object: pose errors of the fields averaged over its target cells (weights: target heatmap)
    and at its single highest-weight target cell."""
    rows = []
    obj, weight = batch["cell_object"], batch["cell_weight"]
    h, w = obj.shape[-2:]
    centers = cell_centers(h, w, out.stride)
    for b in range(obj.shape[0]):
        for k in range(int(batch["present"][b].sum())):
            sel = (obj[b] == k) & (weight[b] > 0.25)
            if not bool(sel.any()):
                continue
            ii, jj = torch.nonzero(sel, as_tuple=True)
            wts = weight[b, ii, jj]
            raw = out.dense["rotation"][b][:, ii, jj].T
            t = object_translation(
                centers[ii, jj], out.dense["center_offset"][b][:, ii, jj].T, out.dense["center_depth"][b][0, ii, jj],
                batch["K"][b].expand(len(ii), 3, 3),
            )  # fmt: skip
            rot_true, t_true = batch["rotation"][b, k].numpy(), batch["translation"][b, k].numpy()
            mean_rot = rotation_from_raw((raw * wts[:, None]).sum(0, keepdim=True) / wts.sum())[0].numpy()
            mean_t = ((t * wts[:, None]).sum(0) / wts.sum()).numpy()
            top = int(wts.argmax())
            rows.append({
                "rotation_deg": float(np.degrees(rotation_angle_between(mean_rot, rot_true))),
                "translation_cm": 100.0 * float(np.linalg.norm(mean_t - t_true)),
                "rotation_deg_peak": float(np.degrees(rotation_angle_between(
                    rotation_from_raw(raw[top : top + 1])[0].numpy(), rot_true))),
                "translation_cm_peak": 100.0 * float(np.linalg.norm(t[top].numpy() - t_true)),
            })  # fmt: skip
    return rows


def shape_errors(matched: list, decoder, objects_root: Path, resolution: int) -> dict:
    """Chamfer-L1 (mm) and F-score of meshes decoded from the regressed codes (at the regressed joint code, as
    inference decodes them) against the true meshes (object frame, labelled joint state); also from the target
    code at the true joint code: the decoder's own error, the floor the regressed code can reach."""
    from centerart.evaluation.metrics import shape_metrics
    from centerart.inference.reconstruction import MeshConfig, reconstruct_object
    from centerart.scenes.description import SceneDescription, load_scene_object

    rows = []
    for view_dir, det, label in matched:
        desc = SceneDescription.load(Path(view_dir).parent.parent / "scene.json", objects_root=objects_root)
        spec = next(o for o in desc.objects if o.name == label["name"])
        truth = load_scene_object(spec).mesh(spec.joint_state)
        code = decoder.codes.get(label["object_id"])
        if code is None:
            continue
        row = {"object_id": label["object_id"], "category": label["category"]}
        true_joint = label["joint"]["state_normalized"]
        for name, c, q in (("regressed", det.shape_code, det.joint_code), ("target", code, true_joint)):
            rec = reconstruct_object(decoder.decoder, np.asarray(c, np.float32), q, decoder.bounds,
                                     MeshConfig(resolution=resolution))  # fmt: skip
            m = shape_metrics(rec.mesh, truth)
            row[f"{name}_chamfer_l1_mm"], row[f"{name}_fscore"] = m.chamfer_l1_mm, m.fscore
        rows.append(row)
    if not rows:
        return {}
    col = lambda key: np.array([r[key] for r in rows])  # noqa: E731
    return {
        "objects": len(rows),
        "mesh_resolution": resolution,
        "chamfer_l1_mm_median": float(np.median(col("regressed_chamfer_l1_mm"))),
        "chamfer_l1_mm_mean": float(np.mean(col("regressed_chamfer_l1_mm"))),
        "fscore_1cm_mean": float(np.mean(col("regressed_fscore"))),
        "target_code_chamfer_l1_mm_median": float(np.median(col("target_chamfer_l1_mm"))),
        "target_code_chamfer_l1_mm_mean": float(np.mean(col("target_chamfer_l1_mm"))),
        "rows": rows,
    }


def _jsonable(value):
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    return str(value) if isinstance(value, Path) else value
