"""``Predictor``: one RGB-D image and its intrinsics in; every articulated object's pose, joint, shape and ranked
grasps out, in the OpenCV camera frame (metres, radians).

Pipeline: letterbox and encode (:mod:`centerart.models.encoder.detect`) -> heatmap peaks -> per object: shape
code, joint code, pose, joint type / axis / state -> decoder: grasps on the moving part in the object frame (a
coarse reconstruction pass supplies the surface shell the grasps come from) -> optional refinement against the
observed depth -> grasps mapped to the camera frame, collision-checked against the observed point cloud,
ranked. Meshes are decoded only when asked for (:meth:`ObjectPrediction.mesh`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np
import torch
from scipy.spatial import cKDTree

from centerart.errors import CenterArtError
from centerart.geometry.camera import Intrinsics, backproject_depth
from centerart.inference.batched_decoder import run_batched
from centerart.inference.decoder_grasps import GraspExtractionConfig, predict_shape_and_grasps
from centerart.inference.grasp_anchoring import AnchoredGrasps, AnchoringConfig, ObjectView, anchor_grasps
from centerart.inference.grasp_filter import CollisionFilterConfig, collision_free
from centerart.inference.inputs import check_inputs
from centerart.inference.pose_from_depth import PoseFromDepthConfig, correct_pose
from centerart.inference.reconstruction import MeshConfig, reconstruct_object
from centerart.inference.refinement import RefineConfig, SdfRefineConfig, refine_pose_icp, refine_sdf
from centerart.inference.shape_prior import best_fit_code, nearest_code
from centerart.models.encoder.readout import PEAK_THRESHOLD, Detection


@dataclass(frozen=True)
class PredictorConfig:
    """How predictions are made (the CLI's ``centerart predict`` options generate from this)."""

    peak_threshold: float = PEAK_THRESHOLD
    """Heatmap peaks above this are objects."""
    top_k_grasps: int = 10
    grasp_resolution: int = 48
    """Lattice cells (longest side) of the pass that finds the surface shell the grasps are read from."""
    mesh_resolution: int = 128
    """Lattice cells (longest side) of meshes decoded on demand."""
    refine: RefineConfig = field(default_factory=RefineConfig)
    """ICP of the decoded surface to the observed points (pose only)."""
    refine_sdf: SdfRefineConfig = field(default_factory=SdfRefineConfig)
    """Pose, shape code and joint code fitted to the observed depth through the decoder (before grasps)."""
    collision: CollisionFilterConfig = field(default_factory=CollisionFilterConfig)
    """The proposal's own collision filter (used when anchoring is off)."""
    pose_from_depth: Literal["auto", "on", "off"] = "auto"
    """Correct each object's pose against its observed points before its grasps are placed (the decoded visible
    surface aligned by ICP; upright and yaw-only when gravity is known: :mod:`~.pose_from_depth`). ``auto``: when
    a gravity direction is known (given to :meth:`Predictor.predict`, or estimated with ``estimate_gravity``),
    which is where it was measured to pay (``benchmarks/results/anchoring_ladder/``); ``on``: always (a free 6-DoF
    alignment without gravity, not measured); ``off``: never."""
    pose_correction: PoseFromDepthConfig = field(default_factory=PoseFromDepthConfig)
    estimate_gravity: bool = False
    """Without a given gravity, estimate it from the image's largest low horizontal plane
    (:func:`centerart.geometry.gravity.estimate_gravity`; reliable on true depth, often off on stereo depth)."""
    anchoring: AnchoringConfig = field(default_factory=AnchoringConfig)
    """Grasps made on, snapped to, checked against and ranked on the object's observed points
    (:mod:`~centerart.inference.grasp_anchoring`); off: the decoder's grasps as they are (the proposal alone)."""
    shape_prior: Literal["regressed", "nearest", "best_fit"] = "regressed"
    """The shape code used: the encoder's regression as it is, or snapped to a training code of the decoder
    (nearest, or the nearby one whose surface fits the observed depth best; :mod:`~.shape_prior`)."""
    batch_objects: bool = True
    """Decode all objects of an image at once (their decoder calls merged into shared batches)."""
    grasp_critic: bool = True
    """Rank each object's grasps by the decoder's grasp critic (its physics success probability, which becomes the
    grasp score; :mod:`centerart.models.grasp_critic`) where the checkpoint has one; else by the decoder's
    agreement confidence."""
    runtime: Literal["auto", "torch", "onnxruntime"] = "auto"
    """What runs the decoder for grasps and meshes: onnxruntime (CPU only, about twice as fast as torch there),
    torch, or auto (onnxruntime on a CPU when installed, else torch). SDF refinement always uses torch."""


@dataclass
class ObjectPrediction:
    """One detected object; every pose and vector is in the OpenCV camera frame of the input image."""

    score: float
    camera_T_object: np.ndarray
    joint_type: str
    joint_type_probability: float
    axis_direction: np.ndarray
    axis_point: np.ndarray
    joint_state: float
    """Metric joint state (rad for revolute, m for prismatic), from the encoder's joint-state head."""
    joint_state_normalized: float
    """(q - lower) / (upper - lower) as the decoder reads it (the encoder's joint code)."""
    shape_code: np.ndarray
    grasp_poses: np.ndarray
    """(K, 4, 4) TCP poses (z approach, y finger closing), ranked best first."""
    grasp_scores: np.ndarray
    grasp_opening_directions: np.ndarray
    """(K, 3) unit vectors: the direction the grasped point moves when the joint opens (close: the opposite)."""
    mask: np.ndarray | None = field(default=None, repr=False)
    peak_uv: np.ndarray | None = None
    refinement: dict = field(default_factory=dict)
    """What refinement and anchoring did (``anchoring``: candidates per source and survivors of each check)."""
    grasp_sources: list[str] = field(default_factory=list)
    """Where each grasp came from: ``decoder``, ``observed`` or ``handle`` (:mod:`~.grasp_anchoring`); empty
    when anchoring is off (every grasp is the decoder's)."""
    grasp_closing_points: np.ndarray | None = None
    """(K,) observed points of the object between each grasp's pads (anchoring on), else None."""
    grasp_features: np.ndarray | None = field(default=None, repr=False)
    """(K, F) what the anchoring's ranking read of each grasp (``models.grasp_critic.ANCHOR_FEATURES``), else None."""
    rejected_grasps: np.ndarray | None = field(default=None, repr=False)
    """(R, 4, 4) candidates the anchoring rejected (camera frame), with ``rejected_reasons`` (R,)."""
    rejected_reasons: list[str] = field(default_factory=list)
    _mesher: object = field(default=None, repr=False)

    @property
    def joint_code(self) -> float:
        """The decoder's joint input (alias of ``joint_state_normalized``)."""
        return self.joint_state_normalized

    @property
    def joint_unit(self) -> str:
        return "rad" if self.joint_type == "revolute" else "m"

    def mesh(self, resolution: int | None = None):
        """The complete mesh (trimesh, camera frame) decoded at the predicted shape and joint codes."""
        return self._mesher(self, resolution)


def opening_directions(grasps_cam: np.ndarray, joint_type: str, axis_dir: np.ndarray, axis_pt: np.ndarray):
    """Where each grasp point moves when the joint state grows (opens): the tangent of the hinge circle
    (revolute, right-hand rule about the axis) or the axis itself (prismatic)."""
    if len(grasps_cam) == 0:
        return np.zeros((0, 3))
    if joint_type == "prismatic":
        return np.tile(axis_dir, (len(grasps_cam), 1))
    tangent = np.cross(axis_dir, grasps_cam[:, :3, 3] - axis_pt)
    return tangent / np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-9)


def _anchoring_fields(anchored: AnchoredGrasps | None) -> dict:
    """The ObjectPrediction fields that anchoring fills (none when it is off)."""
    if anchored is None:
        return {}
    return {
        "grasp_sources": anchored.sources,
        "grasp_closing_points": anchored.closing_points,
        "grasp_features": anchored.features,
        "rejected_grasps": anchored.rejected_poses,
        "rejected_reasons": anchored.rejected_reasons,
    }


class Predictor:
    """Encoder + decoder. ``Predictor()`` loads the shipped weights; pass checkpoint paths to use your own."""

    def __init__(self, encoder_ckpt=None, decoder_ckpt=None, device: str = "cpu", config=None, *, encoder=True):
        """``encoder=False``: no encoder is loaded (see :meth:`without_encoder`)."""
        from centerart.models.checkpoint import default_checkpoint, load_decoder
        from centerart.models.encoder.checkpoint import load_encoder

        self.device = torch.device(device)
        decoder_ckpt = Path(decoder_ckpt) if decoder_ckpt is not None else default_checkpoint()
        self.encoder = load_encoder(encoder_ckpt, decoder_path=decoder_ckpt, device=self.device) if encoder else None
        self.decoder = load_decoder(decoder_ckpt, device=self.device)
        self.config = config or PredictorConfig()
        self.timing: dict[str, float] = {}
        self.gravity: np.ndarray | None = None
        self.fast_decoder = self._inference_decoder(self.config.runtime)

    def _inference_decoder(self, runtime: str):
        """The decoder that grasp extraction and meshing call (see ``PredictorConfig.runtime``)."""
        from centerart.models.decoder_onnx import OnnxDecoder, onnxruntime_available

        on_cpu, available = self.device.type == "cpu", onnxruntime_available()
        if runtime == "onnxruntime" and not (on_cpu and available):
            raise CenterArtError(
                "runtime onnxruntime: needs device cpu and the onnx and onnxruntime packages "
                f"(device {self.device}, packages {'found' if available else 'missing'})"
            )
        if runtime == "onnxruntime" or (runtime == "auto" and on_cpu and available):
            return OnnxDecoder(self.decoder.decoder)
        return self.decoder.decoder

    @classmethod
    def from_pretrained(cls, device: str = "cpu", config: PredictorConfig | None = None) -> Predictor:
        return cls(None, None, device, config)

    @classmethod
    def without_encoder(cls, decoder_ckpt=None, device: str = "cpu", config: PredictorConfig | None = None):
        """A predictor that only decodes given detections (:meth:`predict_detection`): e.g. a detection with the
        true pose and joint and a code fitted to the object, to measure a decoder in closed loop before any
        encoder is trained against its codes. :meth:`predict` and :meth:`encode` refuse."""
        return cls(None, decoder_ckpt, device, config, encoder=False)

    def predict(self, rgb: np.ndarray, depth: np.ndarray, K, encoded=None, gravity=None) -> list[ObjectPrediction]:
        """Objects in one RGB (H, W, 3) uint8 image with depth (H, W) in metres (holes 0 / NaN) and 3x3 ``K``.
        ``encoded``: this image's :meth:`encode` result, to reuse one encoder pass across predictor settings.
        ``gravity``: the downward direction in the camera frame (3,), e.g. from TF or the camera's IMU; used by
        the pose correction (``config.pose_from_depth``)."""
        camera, depth = self._checked(rgb, depth, K)
        encoded = self.encode(rgb, depth, K) if encoded is None else encoded
        t0 = time.perf_counter()
        self.timing = {"encoder_s": encoded.seconds, "grasps_s": 0.0, "refine_s": 0.0, "filter_s": 0.0}
        self.last_heatmap = encoded.heatmap
        self.gravity = self._gravity(gravity, depth, camera)
        preds = self._predict_objects(encoded.detections, depth, camera, self._scene_tree(depth, camera))
        self.timing["total_s"] = time.perf_counter() - t0 + encoded.seconds
        return preds

    def encode(self, rgb: np.ndarray, depth: np.ndarray, K):
        """The encoder's pass over one image (detections with masks, heatmap; ``seconds`` it took), which
        :meth:`predict` decodes; same inputs as :meth:`predict`."""
        from centerart.models.encoder.detect import detect_objects

        if self.encoder is None:
            raise CenterArtError("this Predictor has no encoder (Predictor.without_encoder): use predict_detection")
        camera, depth = self._checked(rgb, depth, K)
        t0 = time.perf_counter()
        encoded = detect_objects(self.encoder.encoder, rgb, depth, camera, self.config.peak_threshold)
        encoded.seconds = time.perf_counter() - t0
        return encoded

    def predict_detection(self, det: Detection, rgb: np.ndarray, depth: np.ndarray, K) -> ObjectPrediction:
        """Decode, refine, filter and rank grasps for one given detection (e.g. one with ground-truth pose and
        joint state swapped in, to measure what each stage loses); same inputs and frames as :meth:`predict`."""
        camera, depth = self._checked(rgb, depth, K)
        self.timing = {"grasps_s": 0.0, "refine_s": 0.0, "filter_s": 0.0}
        # self.gravity stays the last predict()'s: predict_detection re-runs one object of that image
        return self._predict_objects([det], depth, camera, self._scene_tree(depth, camera))[0]

    @staticmethod
    def _checked(rgb: np.ndarray, depth: np.ndarray, K) -> tuple[Intrinsics, np.ndarray]:
        """The intrinsics of the image and its checked depth (holes as 0; errors name the input)."""
        h, w = np.asarray(depth).shape[:2]
        camera = K if isinstance(K, Intrinsics) else Intrinsics.from_matrix(K, w, h)
        return camera, check_inputs(np.asarray(rgb), np.asarray(depth), camera)

    def _scene_tree(self, depth: np.ndarray, camera: Intrinsics) -> cKDTree | None:
        """One search tree of the observed points for every object's grasp collision check (None: no check on)."""
        checks = self.config.collision.enabled or self.config.anchoring.enabled
        return cKDTree(backproject_depth(depth, camera.K)) if checks else None

    def _gravity(self, gravity, depth: np.ndarray, camera: Intrinsics) -> np.ndarray | None:
        """The unit downward direction (camera frame) the pose correction uses: the given one, else the estimate
        (``config.estimate_gravity``), else None (a free 6-DoF correction)."""
        if gravity is not None:
            g = np.asarray(gravity, float).reshape(-1)
            if g.shape != (3,) or not np.all(np.isfinite(g)) or np.linalg.norm(g) < 1e-9:
                raise CenterArtError(f"gravity: expected a non-zero direction (3 numbers), got {gravity!r}")
            return g / np.linalg.norm(g)
        if self.config.pose_from_depth != "off" and self.config.estimate_gravity:
            from centerart.geometry.gravity import estimate_gravity

            return estimate_gravity(backproject_depth(depth[::2, ::2], camera.scaled(
                depth[::2, ::2].shape[1], depth[::2, ::2].shape[0]).K))  # fmt: skip
        return None

    def _tick(self, key: str, since: float) -> float:
        now = time.perf_counter()
        self.timing[key] += now - since
        return now

    def _predict_objects(self, dets: list[Detection], depth, camera: Intrinsics, scene) -> list[ObjectPrediction]:
        """Refine (SDF fit), decode grasps of all objects at once (:mod:`~centerart.inference.batched_decoder`),
        then per object: ICP, grasps to the camera frame, collision filter, ranking."""
        t = time.perf_counter()
        starts = [self._refine_start(det, depth, camera) for det in dets]
        t = self._tick("refine_s", t)
        mesh_cfg = MeshConfig(resolution=self.config.grasp_resolution)
        grasp_cfg = GraspExtractionConfig(top_k=self.config.top_k_grasps * 3)
        bounds, device = self.decoder.bounds, self.device
        critic = self.decoder.critic if self.config.grasp_critic else None

        def task(code, joint):
            return lambda dec: predict_shape_and_grasps(dec, code, joint, bounds, mesh_cfg, grasp_cfg, device, critic)

        tasks = [task(code, joint) for _, code, joint, _, _ in starts]
        decoded = (
            run_batched(self.fast_decoder, tasks)
            if self.config.batch_objects
            else [f(self.fast_decoder) for f in tasks]
        )
        self._tick("grasps_s", t)
        return [
            self._finish_object(det, start, recon, grasps, scene)
            for det, start, (recon, grasps) in zip(dets, starts, decoded, strict=True)
        ]

    def _refine_start(self, det: Detection, depth, camera: Intrinsics) -> tuple:
        """(pose, shape code, joint code, refinement info, observed points or None) of one detection, after the
        SDF fit when it is on."""
        cfg = self.config
        code, joint, pose, info = det.shape_code.astype(np.float32), det.joint_code, det.camera_T_object, {}
        uses = cfg.refine_sdf.enabled or cfg.refine.icp or cfg.shape_prior == "best_fit" or cfg.anchoring.enabled
        observed = backproject_depth(depth, camera.K, mask=det.mask) if uses and det.mask is not None else None
        code = self._prior_code(code, joint, pose, observed, info)
        if cfg.refine_sdf.enabled and observed is not None:
            pose, code, joint, info["sdf"] = refine_sdf(
                self.decoder.decoder, code, joint, pose, observed, cfg.refine_sdf
            )
        return pose, code, joint, info, observed

    def _prior_code(self, code: np.ndarray, joint: float, pose: np.ndarray, observed, info: dict) -> np.ndarray:
        """The shape code after ``config.shape_prior`` (regressed codes pass through)."""
        prior = self.config.shape_prior
        if prior == "regressed":
            return code
        ids = sorted(self.decoder.codes)
        codes = np.stack([self.decoder.codes[i] for i in ids]).astype(np.float32)
        if prior == "best_fit" and observed is not None:
            k, info["shape_prior"] = best_fit_code(self.fast_decoder, code, joint, codes, observed, pose)
        else:
            k = nearest_code(code, codes)
        info.setdefault("shape_prior", {})["object_id"] = ids[k]
        return codes[k].copy()

    def _finish_object(self, det: Detection, start: tuple, recon, grasps, scene) -> ObjectPrediction:
        cfg = self.config
        pose, code, joint, info, observed = start
        t = time.perf_counter()
        if cfg.refine.icp and observed is not None:
            pose, info["icp"] = refine_pose_icp(recon.mesh, pose, observed, cfg.refine)
        correcting = cfg.pose_from_depth == "on" or (cfg.pose_from_depth == "auto" and self.gravity is not None)
        if correcting and observed is not None and len(recon.mesh.faces):
            surface = recon.mesh.sample(4000, seed=0)
            pose, info["pose_from_depth"] = correct_pose(surface, pose, observed, self.gravity, cfg.pose_correction)
        t = self._tick("refine_s", t)
        # The axis moves with the refined pose (it was predicted relative to the object).
        delta = pose @ np.linalg.inv(det.camera_T_object)
        axis_point = delta[:3, :3] @ det.axis_point + delta[:3, 3]
        axis_direction = delta[:3, :3] @ det.axis_direction
        grasps_cam = pose @ grasps.poses if len(grasps) else np.zeros((0, 4, 4))
        anchored = None
        if cfg.anchoring.enabled and observed is not None:
            view = ObjectView(self.fast_decoder, code, joint, pose, observed, det.joint_type, axis_point,
                              axis_direction, self.device)  # fmt: skip
            critics = (self.decoder.critic, self.decoder.anchor_critic) if cfg.grasp_critic else None
            anchored = anchor_grasps(view, grasps_cam, scene, critics, cfg.anchoring, cfg.top_k_grasps)
            grasps_cam, scores, info["anchoring"] = anchored.poses, anchored.scores, anchored.counts
        else:
            grasps_cam, scores = self._proposal_grasps(grasps_cam, grasps.scores, scene)
        self._tick("filter_s", t)
        return ObjectPrediction(
            score=det.score,
            camera_T_object=pose,
            joint_type=det.joint_type,
            joint_type_probability=det.joint_type_probability,
            axis_direction=axis_direction,
            axis_point=axis_point,
            joint_state=det.joint_state,
            joint_state_normalized=joint,
            shape_code=code,
            grasp_poses=grasps_cam,
            grasp_scores=np.asarray(scores, float),
            grasp_opening_directions=opening_directions(grasps_cam, det.joint_type, axis_direction, axis_point),
            mask=det.mask,
            peak_uv=det.peak_uv,
            refinement=info,
            _mesher=self._mesh,
            **_anchoring_fields(anchored),
        )

    def _proposal_grasps(self, grasps_cam: np.ndarray, scores: np.ndarray, scene) -> tuple[np.ndarray, np.ndarray]:
        """The decoder's grasps (camera frame) through the proposal's collision filter, cut to ``top_k_grasps``."""
        cfg = self.config
        if cfg.collision.enabled and len(grasps_cam):
            keep = collision_free(grasps_cam, scene, cfg.collision)
            grasps_cam, scores = grasps_cam[keep], scores[keep]
        return grasps_cam[: cfg.top_k_grasps], scores[: cfg.top_k_grasps]

    def meshes(self, preds: list[ObjectPrediction], resolution: int | None = None) -> list:
        """The complete mesh of every prediction (trimesh, camera frame), all objects decoded at once."""
        tasks = [(lambda dec, p=p: self._mesh(p, resolution, dec)) for p in preds]
        return (
            run_batched(self.fast_decoder, tasks)
            if self.config.batch_objects
            else [f(self.fast_decoder) for f in tasks]
        )

    def _mesh(self, pred: ObjectPrediction, resolution: int | None, decoder=None):
        res = resolution or self.config.mesh_resolution
        recon = reconstruct_object(
            decoder or self.fast_decoder, pred.shape_code, pred.joint_state_normalized, self.decoder.bounds,
            MeshConfig(resolution=res), self.device,
        )  # fmt: skip
        mesh = recon.mesh.copy()
        mesh.apply_transform(pred.camera_T_object)
        return mesh
