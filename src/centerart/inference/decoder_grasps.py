"""Grasps from the decoder: candidates near the predicted surface of the moving part, scored, NMS'd and ranked.

All poses are TCP poses (``grasps/gripper.py``) in the object's canonical frame, metres.

1. Candidates: query points of the final reconstruction level (a thin shell around the predicted surface) and
   ``shell_points`` points drawn on the reconstructed surface and moved out along its normal by up to
   ``shell_distance``, with |sdf| < ``surface_band``, whose predicted grasp position is close to them
   (|offset| < ``max_offset``). Far from any label, the training target is the nearest label, so a large predicted
   offset means "the grasp is elsewhere": such points vote for a grasp but are not used as candidates. The shell
   points matter at closed states: a grasp's TCP sits between the fingers, 2-3 cm in front of a closed door at
   its handle, where the reconstruction's final level has few points or none (it refines only cells the surface
   crosses); without them a closed oven's handle got no candidate although the field predicts it well there.
2. Moving part: the candidate's grasp position must be on the part that moves with the joint. The decoder is
   queried there at the joint code +-``moving_delta``; if the SDF there does not change by ``moving_sdf_change``
   metres, the point is on a static part and is dropped (``require_moving``).
3. Consistency: the grasp predicted at a candidate is supported by the other candidates whose predicted grasp
   lies within ``agree_distance`` and ``agree_angle_deg`` of it (rotation counted with the finger-swapped
   gripper as equal). Confidence = support / (support + ``support_half``) * exp(-|offset| / ``offset_scale``),
   in [0, 1): many neighbours that agree and a small offset mean a grasp the network is sure about.
4. Non-maximum suppression (greedy by confidence; suppress within ``nms_distance`` and ``nms_angle_deg``) to
   ``check_pool`` x ``top_k`` grasps, which are checked on the decoded SDF (:mod:`~.grasp_geometry`: the open
   gripper must stay out of the predicted shape); the ``top_k`` best that pass, ranked by confidence.
5. With a grasp critic (``models/grasp_critic.py``, fitted per checkpoint to physics outcomes): the grasps that
   pass are ranked by its success probability instead, computed from what steps 1-4 know of each grasp
   (``GRASP_FEATURES``); the probability becomes the score.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import torch
from scipy.spatial import cKDTree

from centerart.grasps.gripper import FLIP_Z
from centerart.inference.grasp_geometry import (
    GeometryCheckConfig,
    clear_enough,
    gripper_clearance,
    material_between_pads,
)
from centerart.inference.reconstruction import Reconstruction, decoder_field
from centerart.models.decoder import SGDFDecoder, decode_outputs
from centerart.models.grasp_critic import GRASP_FEATURES, GraspCritic


@dataclass(frozen=True)
class GraspExtractionConfig:
    surface_band: float = 0.04
    max_offset: float = 0.02
    shell_points: int = 6000
    """Extra query points in front of the reconstructed surface (0: the reconstruction's own points only)."""
    shell_distance: float = 0.04
    """How far (m) along the outward surface normal the extra points go."""
    seed: int = 0
    agree_distance: float = 0.015
    agree_angle_deg: float = 20.0
    support_half: float = 5.0
    offset_scale: float = 0.01
    require_moving: bool = True
    moving_delta: float = 0.05
    moving_sdf_change: float = 0.002
    nms_distance: float = 0.02
    nms_angle_deg: float = 30.0
    top_k: int = 20
    max_candidates: int = 4000
    geometry: GeometryCheckConfig = field(default_factory=GeometryCheckConfig)
    check_pool: int = 3
    """Grasps kept by NMS per returned grasp, for the geometry check to choose from."""


def extraction_setting(name: str, **overrides) -> GraspExtractionConfig:
    """A named extraction setting, for A/B measurements: ``default`` (shell points and the clearance check),
    ``shell`` (no clearance check) or ``before`` (neither: the reconstruction's own points within 2 cm of the
    surface, the extraction before both were added)."""
    off = GeometryCheckConfig(enabled=False)
    settings = {
        "default": {},
        "shell": {"geometry": off},
        "before": {"surface_band": 0.02, "shell_points": 0, "geometry": off},
    }
    if name not in settings:
        raise ValueError(f"grasp extraction setting {name!r}: expected one of {sorted(settings)}")
    return GraspExtractionConfig(**(settings[name] | overrides))


@dataclass
class DecoderGrasps:
    poses: np.ndarray  # (K, 4, 4) TCP poses, object frame, ranked best first
    scores: np.ndarray  # (K,) confidence in [0, 1): the critic's success probability where one ranked them
    support: np.ndarray  # (K,) number of agreeing candidates
    features: np.ndarray | None = None  # (K, len(GRASP_FEATURES)): models.grasp_critic.GRASP_FEATURES

    def __len__(self) -> int:
        return len(self.poses)


def rotation_angle_symmetric(Ra: np.ndarray, Rb: np.ndarray) -> np.ndarray:
    """Angle (rad) between rotations (..., 3, 3), counting a 180-degree turn about the approach axis as equal."""

    def angle(A, B):
        tr = np.einsum("...ij,...ij->...", A, B)  # trace(A^T B)
        return np.arccos(np.clip((tr - 1.0) / 2.0, -1.0, 1.0))

    return np.minimum(angle(Ra, Rb), angle(Ra, Rb @ FLIP_Z[:3, :3]))


def _empty() -> DecoderGrasps:
    return DecoderGrasps(np.zeros((0, 4, 4)), np.zeros(0), np.zeros(0, int), np.zeros((0, len(GRASP_FEATURES))))


def extract_grasps(
    decoder: SGDFDecoder,
    code: np.ndarray,
    joint: float,
    recon: Reconstruction,
    cfg: GraspExtractionConfig = GraspExtractionConfig(),
    device: str | torch.device = "cpu",
    critic: GraspCritic | None = None,
) -> DecoderGrasps:
    """Ranked grasps on the moving part at normalized joint code ``joint`` (see module doc). With a ``critic``
    (:class:`~centerart.models.grasp_critic.GraspCritic`), the grasps that pass NMS and the clearance check are
    ranked by its success probability, which becomes their score, instead of by the agreement confidence."""
    if recon.raw is None or len(recon.points) == 0:
        return _empty()
    points, sdf, raw = _query_points(decoder, code, joint, recon, cfg, device)
    out = decode_outputs(raw)
    offset = out.offset.numpy()
    off_norm = np.linalg.norm(offset, axis=1)
    keep = (np.abs(sdf) < cfg.surface_band) & (off_norm < cfg.max_offset)
    if not keep.any():
        return _empty()
    idx = np.flatnonzero(keep)
    if len(idx) > cfg.max_candidates:  # the best-offset candidates; deterministic
        idx = idx[np.argsort(off_norm[idx], kind="stable")[: cfg.max_candidates]]
    pos, rot, off = points[idx] + offset[idx], out.rotation.numpy()[idx], off_norm[idx]
    tcp_sdf, change = joint_sdf_change(decoder, code, joint, pos, cfg.moving_delta, device)
    if cfg.require_moving:
        moving = change > cfg.moving_sdf_change
        pos, rot, off, tcp_sdf, change = pos[moving], rot[moving], off[moving], tcp_sdf[moving], change[moving]
        if len(pos) == 0:
            return _empty()
    support = grasp_support(pos, rot, cfg)
    score = support / (support + cfg.support_half) * np.exp(-off / cfg.offset_scale)
    c = nms_grasps(pos, rot, score, cfg, cfg.top_k * (cfg.check_pool if cfg.geometry.enabled else 1))
    poses = np.tile(np.eye(4), (len(c), 1, 1))
    poses[:, :3, :3] = rot[c]
    poses[:, :3, 3] = pos[c]
    features = grasp_features(decoder, code, joint, poses, off[c], tcp_sdf[c], change[c], device)
    ok = np.flatnonzero(clear_enough(features[:, GRASP_FEATURES.index("clearance_m")], cfg.geometry))
    scores = score[c]
    if critic is not None:
        scores = critic.probability(features)
        ok = ok[np.argsort(-scores[ok], kind="stable")]
    ok = ok[: cfg.top_k]
    return DecoderGrasps(poses[ok], scores[ok], support[c][ok], features[ok])


def grasp_features(decoder, code, joint: float, poses, offset, tcp_sdf, change, device) -> np.ndarray:
    """(K, len(GRASP_FEATURES)) what the grasp critic reads of TCP poses (K, 4, 4, object frame), given each
    grasp's |predicted offset|, SDF at the TCP and joint SDF change (m; :func:`joint_sdf_change`)."""
    sdf_fn = _sdf_fn(decoder, code, joint, device)
    clearance, between = gripper_clearance(sdf_fn, poses), material_between_pads(sdf_fn, poses)
    columns = [offset, tcp_sdf, change, clearance, between, -poses[:, 0, 2], np.full(len(poses), joint)]
    return np.stack([np.asarray(c, float) for c in columns], 1).reshape(len(poses), len(GRASP_FEATURES))


def grasp_support(pos: np.ndarray, rot: np.ndarray, cfg: GraspExtractionConfig) -> np.ndarray:
    """Per candidate: how many others predict a grasp within ``agree_distance`` whose rotation agrees."""
    tree = cKDTree(pos)
    support = np.zeros(len(pos), int)
    max_angle = np.deg2rad(cfg.agree_angle_deg)
    for i, nb in enumerate(tree.query_ball_point(pos, cfg.agree_distance)):
        nb = np.asarray(nb)
        nb = nb[nb != i]
        if len(nb):
            support[i] = int((rotation_angle_symmetric(rot[i][None], rot[nb]) < max_angle).sum())
    return support


def nms_grasps(
    pos: np.ndarray, rot: np.ndarray, score: np.ndarray, cfg: GraspExtractionConfig, limit: int
) -> np.ndarray:
    """Indices of up to ``limit`` grasps, best score first, none within ``nms_distance`` and ``nms_angle_deg`` of
    a better one."""
    chosen: list[int] = []
    nms_angle = np.deg2rad(cfg.nms_angle_deg)
    for i in np.argsort(-score, kind="stable"):
        if len(chosen) >= limit:
            break
        if chosen:
            c = np.asarray(chosen)
            close = np.linalg.norm(pos[c] - pos[i], axis=1) < cfg.nms_distance
            if close.any() and (rotation_angle_symmetric(rot[i][None], rot[c[close]]) < nms_angle).any():
                continue
        chosen.append(int(i))
    return np.asarray(chosen, int)


def _sdf_fn(decoder, code, joint: float, device):
    """The decoder's SDF at a fixed shape and joint code, object-frame points (N, 3) -> (N,)."""
    field_fn = decoder_field(decoder, code, joint, device=device)
    return lambda points: field_fn(points)[0]


def _query_points(decoder, code, joint, recon: Reconstruction, cfg: GraspExtractionConfig, device):
    """(points, sdf, raw outputs): the reconstruction's final level plus the seeded shell points (object frame)."""
    import trimesh

    if not cfg.shell_points or len(recon.mesh.faces) == 0:
        return recon.points, recon.sdf, recon.raw
    rng = np.random.default_rng(cfg.seed)
    on_surface, face = trimesh.sample.sample_surface(recon.mesh, cfg.shell_points, seed=rng)
    # Outward only: the reconstruction's own points already cover both sides within a cell of the surface.
    along = rng.uniform(0.0, cfg.shell_distance, size=(len(face), 1))
    shell = np.asarray(on_surface + along * recon.mesh.face_normals[face], np.float32)
    sdf, raw = decoder_field(decoder, code, joint, device=device)(shell)
    raw_all = np.concatenate([np.asarray(recon.raw, np.float32), raw])
    return np.concatenate([recon.points, shell]), np.concatenate([recon.sdf, sdf]), raw_all


def joint_sdf_change(decoder, code, joint, pos, moving_delta: float, device) -> tuple[np.ndarray, np.ndarray]:
    """(predicted SDF at ``pos`` (N, 3, object frame), how much it changes (m) when the joint code moves by
    +-``moving_delta``): a point on the moving part changes, one on a static part does not."""
    base = _sdf_fn(decoder, code, joint, device)(pos)
    change = np.zeros(len(pos))
    for j in (joint - moving_delta, joint + moving_delta):
        if 0.0 <= j <= 1.0:
            change = np.maximum(change, np.abs(_sdf_fn(decoder, code, j, device)(pos) - base))
    return np.asarray(base, float), change


def predict_shape_and_grasps(
    decoder: SGDFDecoder,
    code: np.ndarray,
    joint: float,
    bounds: np.ndarray,
    mesh_cfg=None,
    grasp_cfg: GraspExtractionConfig = GraspExtractionConfig(),
    device: str | torch.device = "cpu",
    critic: GraspCritic | None = None,
) -> tuple[Reconstruction, DecoderGrasps]:
    """Mesh (coarse-to-fine) and ranked grasps of one object at normalized joint code ``joint`` (object frame);
    ``critic`` as in :func:`extract_grasps`."""
    from centerart.inference.reconstruction import MeshConfig, reconstruct_object

    recon = reconstruct_object(decoder, code, joint, bounds, mesh_cfg or MeshConfig(), device)
    return recon, extract_grasps(decoder, code, joint, recon, grasp_cfg, device, critic)
