"""The shape-code stage of the stage analysis: a code fitted to the object's true surface at its test state.

The stage analysis first swaps the true pose and joint state into a failed prediction; what still fails was, until
this stage, all put on "shape and grasp decoding". That bucket mixes two models: the encoder, which regresses the
shape code from the image, and the decoder, which turns a code into a surface and grasps. Swapping in a code fitted
to the object's own surface (the decoder frozen, DeepSDF test-time optimisation, as ``centerart eval decoder`` does
for held-out objects) splits it: a grasp that succeeds with the fitted code lost to the encoder's shape code; one
that fails with it too lost to the decoder (and the grasp anchoring on the observed depth).

The fit uses SDF samples drawn the way the decoder's training samples are (``sdf.sampling``, canonical frame, m) at
the object's exact test state, and the decoder's own code prior. It is an upper bound for the encoder's code (the
object's full surface, which no camera sees), not a method.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from centerart.assets.articulated_object import ArticulatedObject
from centerart.evaluation.decoder_eval import fitted_code
from centerart.models.encoder.readout import Detection
from centerart.sdf.sampling import SamplingConfig, sample_points, signed_distance
from centerart.sdf.surface import object_surface

#: SDF samples drawn on the object's true surface at its test state, fit steps and points per step. 200 x 1024
#: reaches the data loss of 200 x 4096 (``centerart eval decoder``'s) within 1 % on generated test objects, in
#: 4 s instead of 17 s on one core.
ORACLE_CODE_FIT = {"samples": 20_000, "steps": 200, "points_per_step": 1024}


class _StateSamples(NamedTuple):
    joint: float  # normalized joint state in [0, 1]
    points: np.ndarray  # (N, 3) canonical frame, m
    sdf: np.ndarray  # (N,) m


def oracle_code(loaded, obj: ArticulatedObject, q: float, seed: int, dropout: bool = False) -> np.ndarray:
    """A shape code (code_dim,) fitted to ``obj``'s true surface at joint state ``q`` (m or rad), the decoder of
    ``loaded`` (a ``LoadedDecoder``) frozen (with ``dropout``: fitted under its dropout, ``CodeFitConfig.dropout``);
    deterministic given ``seed``."""
    rng = np.random.default_rng(seed)
    surface = object_surface(obj, q)
    sampling = SamplingConfig()
    points = sample_points(surface.mesh, ORACLE_CODE_FIT["samples"], sampling, rng)
    signed = signed_distance(surface, points, sampling, rng)
    state = _StateSamples(float(obj.normalize(q)), signed.points, signed.sdf)
    return fitted_code(loaded, [state], ORACLE_CODE_FIT["steps"], seed, ORACLE_CODE_FIT["points_per_step"], dropout)


def true_detection(obj: dict, instances: np.ndarray, shape_code: np.ndarray) -> Detection:
    """A detection of view label ``obj`` (``labels.json``, OpenCV camera frame, m, rad) with everything but the
    shape code true: pose, joint type, state and axis, and the object's visible mask from ``instances`` (H, W).
    Decoded with ``Predictor.predict_detection``, it measures a decoder (and the grasp anchoring) in closed loop
    with no encoder error."""
    joint = obj["joint"]
    return Detection(
        score=1.0, peak_uv=np.zeros(2), camera_T_object=np.asarray(obj["camera_T_object"], float),
        shape_code=np.asarray(shape_code, np.float32), joint_code=float(joint["state_normalized"]),
        joint_type=joint["type"], joint_type_probability=1.0,
        axis_direction=np.asarray(joint["axis_direction_camera"], float),
        axis_point=np.asarray(joint["axis_origin_camera"], float), joint_state=float(joint["state"]),
        mask=instances == obj["instance"],
    )  # fmt: skip
