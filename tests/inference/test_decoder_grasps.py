"""Grasp extraction on an exact "decoder" of an analytic cabinet (exact SDF and nearest-label grasps)."""

import numpy as np
import torch
import trimesh
from torch import nn

from centerart.evaluation.decoder_eval import grasp_matches
from centerart.inference.decoder_grasps import GraspExtractionConfig, extract_grasps, rotation_angle_symmetric
from centerart.inference.grasp_geometry import GeometryCheckConfig
from centerart.inference.reconstruction import MeshConfig, reconstruct_object
from centerart.models.decoder import DecoderConfig, decode_outputs
from centerart.training.synthetic import BoxCabinet

BOUNDS = np.array([[-0.2, -0.25, -0.2], [0.55, 0.3, 0.2]])


class ExactCabinetDecoder(nn.Module):
    """Outputs what a perfectly trained decoder would: the SDF and, per point, the nearest label's TCP pose
    (as offset + the two rotation columns). ``labels_on_body`` puts the labels on the static body instead."""

    def __init__(self, cabinet: BoxCabinet, labels_on_body: bool = False):
        super().__init__()
        self.cab = cabinet
        self.labels_on_body = labels_on_body
        self.config = DecoderConfig(code_dim=2, width=8, depth=2, skip_layers=(1,))

    def _labels(self, u):
        g = self.cab.grasps(u)
        if self.labels_on_body:
            g = self.cab.grasps(0.0)
            g[:, 0, 3] -= 0.05  # behind the closed door: on the body's top edge region
            g[:, :3, 3] = [[0.0, 0.0, self.cab.half_body[2]]] * len(g)
        return g

    def sdf_only(self, code, joint, xyz):
        return torch.as_tensor(self.cab.sdf(xyz.numpy().astype(np.float64), float(joint[0])), dtype=torch.float32)

    def forward(self, code, joint, xyz):
        u = float(joint[0])
        p = xyz.numpy().astype(np.float64)
        labels = self._labels(u)
        nearest = np.linalg.norm(p[:, None] - labels[None, :, :3, 3], axis=-1).argmin(1)
        L = labels[nearest]
        raw = np.concatenate([self.cab.sdf(p, u)[:, None], L[:, :3, 3] - p, L[:, :3, 0], L[:, :3, 1]], 1)
        return decode_outputs(torch.as_tensor(raw, dtype=torch.float32))


def _run(dec, u, cfg=None):
    cfg = cfg or GraspExtractionConfig()
    code = np.zeros(2, np.float32)
    rec = reconstruct_object(dec, code, u, BOUNDS, MeshConfig(resolution=96))
    return rec, extract_grasps(dec, code, u, rec, cfg)


def test_grasps_on_moving_part_ranked_and_matching_labels():
    cab = BoxCabinet()
    for u in (0.0, 0.6):
        _, g = _run(ExactCabinetDecoder(cab), u, GraspExtractionConfig(geometry=GeometryCheckConfig(enabled=False)))
        assert len(g) >= 3
        assert np.all(np.diff(g.scores) <= 1e-12)  # ranked best first
        assert 0.0 < g.scores[0] < 1.0
        door_dist = np.abs(trimesh.proximity.signed_distance(cab.door_mesh(u), g.poses[:, :3, 3]))
        assert (door_dist < 0.02).all()  # on the moving part
        assert grasp_matches(g.poses[:3], cab.grasps(u)).any(1).all()  # the top 3 are true labels
        dets = np.linalg.det(g.poses[:, :3, :3])
        assert np.allclose(dets, 1.0, atol=1e-4)


def test_nms_keeps_distinct_grasps():
    _, g = _run(ExactCabinetDecoder(BoxCabinet()), 0.3)
    d = np.linalg.norm(g.poses[:, None, :3, 3] - g.poses[None, :, :3, 3], axis=-1)
    ang = rotation_angle_symmetric(g.poses[:, None, :3, :3], g.poses[None, :, :3, :3])
    close = (d < 0.02) & (ang < np.deg2rad(30))
    assert close.sum() == len(g)  # only the diagonal


def test_static_part_grasps_are_dropped():
    dec = ExactCabinetDecoder(BoxCabinet(), labels_on_body=True)
    _, g = _run(dec, 0.5)
    assert len(g) == 0
    _, g = _run(dec, 0.5, GraspExtractionConfig(require_moving=False, geometry=GeometryCheckConfig(enabled=False)))
    assert len(g) > 0


def test_clearance_check_drops_edge_pinches_of_a_closed_door():
    """The exact cabinet's labels pinch the door's free edge across its thickness: ajar, both fingers are in free
    space; shut, the inner finger would be inside the body, so the clearance check must drop every one of them."""
    cab = BoxCabinet()
    _, shut = _run(ExactCabinetDecoder(cab), 0.0)
    assert len(shut) == 0
    _, ajar = _run(ExactCabinetDecoder(cab), 0.6)
    assert len(ajar) >= 3 and grasp_matches(ajar.poses[:3], cab.grasps(0.6)).any(1).all()


def test_shell_points_find_grasps_whose_tcp_is_off_the_surface():
    """Labels 4 cm in front of the door (a handle's TCP): no point of the reconstruction's own (within 2 cm of
    the surface) is within 2 cm of one; the shell points (up to 4 cm either side of the surface) are."""

    class HandleDecoder(ExactCabinetDecoder):
        def _labels(self, u):
            g = self.cab.grasps(u)
            g[:, :3, 3] += 0.04 * self.cab.door_T(u)[:3, 0]  # the door's outward normal (+x when closed)
            return g

    dec = HandleDecoder(BoxCabinet())
    no_check = GeometryCheckConfig(enabled=False)
    _, without = _run(dec, 0.6, GraspExtractionConfig(shell_points=0, surface_band=0.02, geometry=no_check))
    _, with_shell = _run(dec, 0.6, GraspExtractionConfig(geometry=no_check))
    assert len(with_shell) >= 3 and grasp_matches(with_shell.poses[:3], dec._labels(0.6)).any(1).all()
    assert len(without) == 0


def test_features_describe_each_grasp_and_a_critic_ranks_by_them():
    """Every returned grasp carries its features (joint code, clearance within the check's margin, a positive joint
    SDF change on the moving door, its approach); a critic that only rewards approaching the front face reorders
    the same grasps by that feature, and its probabilities become the scores."""
    from centerart.models.grasp_critic import GRASP_FEATURES, GraspCritic

    dec, cfg, u = ExactCabinetDecoder(BoxCabinet()), GraspExtractionConfig(), 0.6
    _, plain = _run(dec, u, cfg)
    assert len(plain) >= 3 and plain.features.shape == (len(plain), len(GRASP_FEATURES))
    col = {name: plain.features[:, i] for i, name in enumerate(GRASP_FEATURES)}
    assert np.allclose(col["joint"], u) and (col["clearance_m"] > -cfg.geometry.clearance_m).all()
    assert (col["joint_sdf_change_m"] > cfg.moving_sdf_change).all()
    assert np.allclose(col["approach_front"], -plain.poses[:, 0, 2])
    w = np.zeros(len(GRASP_FEATURES))
    w[GRASP_FEATURES.index("approach_front")] = 5.0
    critic = GraspCritic(np.zeros_like(w), np.ones_like(w), w, 0.0)
    rec = reconstruct_object(dec, np.zeros(2, np.float32), u, BOUNDS, MeshConfig(resolution=96))
    ranked = extract_grasps(dec, np.zeros(2, np.float32), u, rec, cfg, critic=critic)
    front = ranked.features[:, GRASP_FEATURES.index("approach_front")]
    assert np.all(np.diff(front) <= 1e-12) and np.allclose(ranked.scores, critic.probability(ranked.features))
    assert front[0] >= col["approach_front"].max() - 1e-12
