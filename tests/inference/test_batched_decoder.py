"""Lockstep batching of several objects' decoder calls: same answers as one object at a time, fewer calls."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from centerart.inference.batched_decoder import run_batched
from centerart.models.checkpoint import load_decoder
from centerart.models.decoder import decode_outputs


class CountingDecoder:
    """sdf = code[0] * |xyz| + joint; counts calls and points."""

    config = None

    def __init__(self):
        self.calls, self.points = 0, 0

    def __call__(self, code, joint, xyz):
        self.calls += 1
        self.points += len(xyz)
        raw = torch.zeros(len(xyz), 10)
        raw[:, 0] = code[:, 0] * xyz.norm(dim=1) + joint.reshape(-1)
        return decode_outputs(raw)


def task(k: int, sizes: list[int]):
    def run(decoder):
        out = []
        for i, n in enumerate(sizes):  # each call depends on the previous answer, as in the mesher
            xyz = torch.full((n, 3), float(i + 1))
            code = torch.full((n, 4), float(k + 1))
            joint = torch.full((n,), 0.1 * k)
            out.append(decoder(code, joint, xyz).sdf.numpy().copy())
        return out

    return run


def test_merged_calls_answer_each_task_as_alone():
    sizes = {0: [5, 7, 3], 1: [2, 9], 2: [4, 4, 4, 4]}
    tasks = [task(k, s) for k, s in sizes.items()]
    alone = [t(CountingDecoder()) for t in tasks]
    counting = CountingDecoder()
    merged = run_batched(counting, tasks)
    for a, b in zip(alone, merged, strict=True):
        for x, y in zip(a, b, strict=True):
            np.testing.assert_array_equal(x, y)
    assert counting.calls == max(len(s) for s in sizes.values())  # 4 merged calls instead of 9
    assert counting.points == sum(sum(s) for s in sizes.values())


def test_a_failing_task_raises_without_hanging_the_others():
    def bad(decoder):
        decoder(torch.zeros(2, 4), torch.zeros(2), torch.zeros(2, 3))
        raise ValueError("object 1 failed")

    with pytest.raises(ValueError, match="object 1 failed"):
        run_batched(CountingDecoder(), [task(0, [3, 3, 3]), bad, task(2, [1])])


def test_batched_meshes_and_grasps_match_one_at_a_time():
    from centerart.inference.decoder_grasps import predict_shape_and_grasps
    from centerart.inference.reconstruction import MeshConfig

    loaded = load_decoder()
    codes = list(loaded.codes.values())[:3]
    cfg = MeshConfig(resolution=32)

    def make(code, joint):
        return lambda dec: predict_shape_and_grasps(dec, code, joint, loaded.bounds, cfg)

    tasks = [make(c, j) for c, j in zip(codes, (0.0, 0.5, 1.0), strict=True)]
    alone = [t(loaded.decoder) for t in tasks]
    merged = run_batched(loaded.decoder, tasks)
    for (ra, ga), (rb, gb) in zip(alone, merged, strict=True):
        np.testing.assert_allclose(rb.mesh.vertices, ra.mesh.vertices, atol=1e-5)
        np.testing.assert_allclose(gb.poses, ga.poses, atol=1e-4)
