"""Grasp critic: the probability that a decoded grasp succeeds in physics, from what the extraction knows of it.

The decoder's own confidence (neighbour agreement x small offset, ``inference.decoder_grasps``) ranks grasps
usefully but says little about success: on the 1e-4 decoder of sessions 8-12 a score of 0.6 meant anything from
20 % to 90 % (``benchmarks/results/grasp_critic/``). The critic is a logistic regression over
:data:`GRASP_FEATURES` (each standardized), fitted to physics outcomes of the decoder's own grasps on objects it
was not trained on and that are not test objects (``benchmarks/grasp_critic.py``). Its probability becomes the
grasp's score and its ranking; the same features and outcomes give its calibration.

A critic belongs to one decoder: it is stored as JSON beside the checkpoint (:func:`critic_path`), with the
checkpoint's SHA-256, and read without running code; a critic of another checkpoint is refused.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from centerart.errors import CenterArtError
from centerart.models.checkpoint_files import file_sha256
from centerart.utils.json_schema import array, json_problem

FORMAT = "centerart-grasp-critic"
VERSION = 1

GRASP_FEATURES = (
    "offset_m",
    "tcp_sdf_m",
    "joint_sdf_change_m",
    "clearance_m",
    "between_pads_sdf_m",
    "approach_front",
    "joint",
)
"""What the extraction knows of each grasp (object frame, metres): |predicted offset|; predicted SDF at the TCP;
how much the SDF at the TCP changes when the joint moves by the extraction's ``moving_delta`` (large far from a
hinge, where a pull has leverage); the open gripper's least SDF (``inference.grasp_geometry.gripper_clearance``);
the least SDF where the closing pads sweep (negative: they close on decoded material;
``inference.grasp_geometry.material_between_pads``); the approach direction's component towards the front face
(-x of the object frame: 1 is straight at the front); the normalized joint code. None depends on how densely the
surface was sampled: the number of agreeing candidates, which does (the predictor's 48-cell lattice gives a
fraction of the 128-cell one's), is left out, so a critic fitted at 128 cells serves the predictor too."""


#: The anchored-grasp ranker's features (``inference.grasp_anchoring``): the critic's, then what the observation
#: says of a grasp checked against the depth: material proud of the front plane between the pads (0-1), leverage
#: about the predicted hinge (0-1), how far the approach points away from the camera (0-1), log(1 + observed points
#: between the pads), how far the snap moved it (m), and where it came from (one-hot: decoder, observed, handle).
ANCHOR_FEATURES = (
    *GRASP_FEATURES,
    "handle_cue",
    "leverage",
    "facing",
    "closing_points_log",
    "snap_shift_m",
    "from_decoder",
    "from_observed",
    "from_handle",
)
#: What a critic file beside a checkpoint is for: ``critic`` ranks the decoder's grasps (GRASP_FEATURES);
#: ``anchor_critic`` ranks grasps anchored in the observed depth (ANCHOR_FEATURES).
KINDS = {"critic": GRASP_FEATURES, "anchor_critic": ANCHOR_FEATURES}


def _schema(n: int) -> dict:
    return {"mean": array(n), "scale": array(n), "weights": array(n), "bias": float, "info?": dict}


@dataclass(frozen=True)
class GraspCritic:
    """p(success) = sigmoid(weights . (x - mean) / scale + bias) for features x in :data:`GRASP_FEATURES` order."""

    mean: np.ndarray
    scale: np.ndarray
    weights: np.ndarray
    bias: float
    info: dict = field(default_factory=dict)
    """How it was fitted: data, counts, penalty, the decoder checkpoint's SHA-256 (``decoder_sha256``)."""
    features: tuple[str, ...] = GRASP_FEATURES
    """The feature names, in order (:data:`KINDS`)."""

    def probability(self, features: np.ndarray) -> np.ndarray:
        """(K,) success probabilities of grasps with features (K, F)."""
        from scipy.special import expit

        z = (np.asarray(features, float) - self.mean) / self.scale
        return expit(z @ self.weights + self.bias)

    def to_dict(self) -> dict:
        return {
            "format": FORMAT,
            "version": VERSION,
            "features": list(self.features),
            "mean": self.mean.tolist(),
            "scale": self.scale.tolist(),
            "weights": self.weights.tolist(),
            "bias": float(self.bias),
            "info": self.info,
        }

    @classmethod
    def from_dict(cls, d: dict, source: str = "grasp critic", features=GRASP_FEATURES) -> GraspCritic:
        """The critic of :meth:`to_dict`; a wrong format, feature list (``features`` expected), field
        (``utils.json_schema``: finite numbers of the right shapes) or a scale that is not positive is one
        :class:`CenterArtError` naming ``source``."""
        if not isinstance(d, dict) or d.get("format") != FORMAT or d.get("version") != VERSION:
            raise CenterArtError(f"{source}: not a centerart grasp critic (expected format {FORMAT!r} v{VERSION})")
        if d.get("features") != list(features):
            raise CenterArtError(f"{source}: features {d.get('features')} differ from {list(features)}")
        problem = json_problem(d, _schema(len(features)))
        if problem:
            raise CenterArtError(f"{source}: damaged grasp critic ({problem})")
        mean, scale, weights = (np.asarray(d[k], float) for k in ("mean", "scale", "weights"))
        if (scale <= 0).any():
            raise CenterArtError(f"{source}: grasp critic scales must be positive")
        return cls(mean, scale, weights, float(d["bias"]), dict(d.get("info") or {}), tuple(features))


def fit_critic(
    features: np.ndarray, outcomes: np.ndarray, l2: float = 1.0, info: dict | None = None, names=GRASP_FEATURES
) -> GraspCritic:
    """Logistic regression of physics ``outcomes`` (K,) bool on ``features`` (K, F) named ``names``, each
    standardized, with the penalty ``l2 / 2 * |weights|^2`` (bias free), by L-BFGS. Scipy does the optimization;
    the model itself is these few lines rather than a new dependency (scikit-learn) for one linear classifier."""
    from scipy.optimize import minimize
    from scipy.special import expit, log_expit

    x, y = np.asarray(features, float), np.asarray(outcomes, bool).astype(float)
    if len(x) != len(y) or x.ndim != 2 or x.shape[1] != len(names) or len(set(y.tolist())) < 2:
        raise ValueError(f"fit_critic: need (K, {len(names)}) features and both outcomes, got {x.shape}")
    mean, scale = x.mean(0), np.maximum(x.std(0), 1e-9)
    z = (x - mean) / scale

    def loss(theta):
        w, b = theta[:-1], theta[-1]
        logit = z @ w + b
        nll = -(y * log_expit(logit) + (1 - y) * log_expit(-logit)).sum()
        residual = expit(logit) - y
        grad = np.append(z.T @ residual + l2 * w, residual.sum())
        return nll + 0.5 * l2 * (w @ w), grad

    theta = minimize(loss, np.zeros(z.shape[1] + 1), jac=True, method="L-BFGS-B").x
    return GraspCritic(mean, scale, theta[:-1], float(theta[-1]), dict(info or {}), tuple(names))


def critic_path(checkpoint: Path, kind: str = "critic") -> Path:
    """Where a critic of a decoder checkpoint lives: ``<checkpoint>.<kind>.json`` beside it (:data:`KINDS`)."""
    checkpoint = Path(checkpoint)
    return checkpoint.with_name(f"{checkpoint.name}.{kind}.json")


def critic_record(checkpoint: Path, kind: str = "critic") -> dict | None:
    """``{"path", "sha256"}`` of the critic beside ``checkpoint`` for reports and manifests (None: there is none)."""
    path = critic_path(checkpoint, kind)
    return {"path": str(path), "sha256": file_sha256(path)} if path.is_file() else None


def save_critic(critic: GraspCritic, checkpoint: Path, kind: str = "critic") -> Path:
    """Write ``critic`` beside ``checkpoint`` as ``kind`` (atomic), recording the checkpoint's SHA-256."""
    from centerart.utils.atomic import atomic_write_json

    if critic.features != KINDS[kind]:
        raise ValueError(f"save_critic: a {kind} has features {KINDS[kind]}, this one {critic.features}")
    d = critic.to_dict()
    d["info"] = {**d["info"], "decoder_sha256": file_sha256(checkpoint)}
    atomic_write_json(critic_path(checkpoint, kind), d)
    return critic_path(checkpoint, kind)


def load_critic(checkpoint: Path, kind: str = "critic") -> GraspCritic | None:
    """The critic of ``kind`` stored beside ``checkpoint``; None where there is none. A damaged one, or one fitted
    to another checkpoint (its recorded SHA-256 differs), is a :class:`CenterArtError` naming the file."""
    path = critic_path(checkpoint, kind)
    if not path.is_file():
        return None
    try:
        d = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise CenterArtError(f"{path}: unreadable grasp critic ({type(err).__name__})") from None
    critic = GraspCritic.from_dict(d, str(path), KINDS[kind])
    if critic.info.get("decoder_sha256") != file_sha256(checkpoint):
        raise CenterArtError(
            f"{path}: fitted to another decoder than {checkpoint} (SHA-256 differs); refit or delete it"
        )
    return critic
