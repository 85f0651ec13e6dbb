"""The grasp critic: a logistic regression that recovers a known success model, is calibrated on its own kind of
data, round-trips through JSON beside its checkpoint and refuses a critic of another checkpoint."""

import json

import numpy as np
import pytest

from centerart.errors import CenterArtError
from centerart.evaluation.metrics import score_calibration
from centerart.models.grasp_critic import (
    GRASP_FEATURES,
    GraspCritic,
    critic_path,
    fit_critic,
    load_critic,
    save_critic,
)

F = len(GRASP_FEATURES)


def _data(n: int, seed: int):
    """Features with the scales of real ones; success drawn from a known logistic model on two of them."""
    rng = np.random.default_rng(seed)
    x = rng.normal(0.0, 1.0, (n, F)) * np.array([0.005, 0.01, 0.01, 0.01, 0.01, 0.5, 0.4]) + 0.1
    logit = 3.0 * (x[:, 2] - 0.1) / 0.01 - 2.0 * (x[:, 5] - 0.1) / 0.5
    return x, rng.random(n) < 1.0 / (1.0 + np.exp(-logit))


def test_fit_recovers_the_success_model_and_is_calibrated_on_new_data():
    critic = fit_critic(*_data(4000, 0), l2=1.0)
    w = critic.weights  # per standard deviation of each feature
    assert w[2] == pytest.approx(3.0, abs=0.4) and w[5] == pytest.approx(-2.0, abs=0.4)
    assert np.abs(np.delete(w, [2, 5])).max() < 0.3
    x, y = _data(4000, 1)
    cal = score_calibration(critic.probability(x), y)
    assert cal["ece"] < 0.04 and cal["auroc"] > 0.85


def test_penalty_shrinks_the_weights():
    x, y = _data(500, 2)
    assert np.abs(fit_critic(x, y, l2=1000.0).weights).sum() < 0.5 * np.abs(fit_critic(x, y, l2=0.1).weights).sum()


def test_fit_needs_both_outcomes():
    x, _ = _data(50, 3)
    with pytest.raises(ValueError, match="both outcomes"):
        fit_critic(x, np.ones(50, bool))


def test_saved_beside_its_checkpoint_and_refused_for_another(tmp_path):
    ckpt = tmp_path / "decoder.pt"
    ckpt.write_bytes(b"weights")
    assert load_critic(ckpt) is None  # none stored: the decoder's own ranking
    critic = fit_critic(*_data(300, 4), info={"objects": 3})
    path = save_critic(critic, ckpt)
    assert path == critic_path(ckpt) == tmp_path / "decoder.pt.critic.json"
    back = load_critic(ckpt)
    x, _ = _data(20, 5)
    assert np.allclose(back.probability(x), critic.probability(x)) and back.info["objects"] == 3
    ckpt.write_bytes(b"other weights")
    with pytest.raises(CenterArtError, match=r"decoder\.pt\.critic\.json: fitted to another decoder"):
        load_critic(ckpt)


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda d: d.update(format="x"), "not a centerart grasp critic"),
        (lambda d: d.update(features=d["features"][:-1]), "features"),
        (lambda d: d.update(weights=[float("nan")] * F), "weights: holds NaN"),
        (lambda d: d.update(mean=[0.0] * (F - 1)), "mean: expected a 7 array"),
        (lambda d: d.update(scale=[0.0] * F), "positive"),
        (lambda d: d.pop("bias"), "damaged grasp critic \\(bias: missing"),
    ],
)
def test_damaged_critic_is_one_clear_error(change, message):
    d = fit_critic(*_data(300, 6)).to_dict()
    change(d)
    with pytest.raises(CenterArtError, match=message):
        GraspCritic.from_dict(json.loads(json.dumps(d)), "c.json")


def test_anchor_ranker_is_its_own_kind_beside_the_checkpoint(tmp_path):
    """The anchored-grasp ranker: ANCHOR_FEATURES, its own file; a grasp critic is not taken for one."""
    from centerart.models.grasp_critic import ANCHOR_FEATURES

    ckpt = tmp_path / "decoder.pt"
    ckpt.write_bytes(b"weights")
    rng = np.random.default_rng(7)
    x = rng.normal(size=(400, len(ANCHOR_FEATURES)))
    y = rng.random(400) < 1.0 / (1.0 + np.exp(-2.0 * x[:, ANCHOR_FEATURES.index("handle_cue")]))
    ranker = fit_critic(x, y, names=ANCHOR_FEATURES)
    assert ranker.weights[ANCHOR_FEATURES.index("handle_cue")] > 1.0
    with pytest.raises(ValueError, match="anchor_critic"):
        save_critic(fit_critic(*_data(300, 8)), ckpt, "anchor_critic")
    path = save_critic(ranker, ckpt, "anchor_critic")
    assert path.name == "decoder.pt.anchor_critic.json" and load_critic(ckpt) is None
    assert np.allclose(load_critic(ckpt, "anchor_critic").probability(x[:5]), ranker.probability(x[:5]))
    path.write_text(path.read_text().replace('"handle_cue"', '"other"'))
    with pytest.raises(CenterArtError, match=r"anchor_critic\.json: features"):
        load_critic(ckpt, "anchor_critic")
