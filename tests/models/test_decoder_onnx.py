"""The ONNX Runtime decoder gives the torch decoder's outputs (the predictor uses it on CPUs)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from centerart.models.checkpoint import load_decoder
from centerart.models.decoder_onnx import OnnxDecoder, onnxruntime_available

pytestmark = pytest.mark.skipif(not onnxruntime_available(), reason="onnx / onnxruntime not installed")


def test_onnx_decoder_matches_torch_on_the_shipped_weights():
    loaded = load_decoder()
    fast = OnnxDecoder(loaded.decoder, threads=1)
    rng = np.random.default_rng(0)
    n = 3000
    code = torch.as_tensor(np.repeat(next(iter(loaded.codes.values()))[None], n, 0))
    joint = torch.as_tensor(rng.uniform(0, 1, n), dtype=torch.float32)
    xyz = torch.as_tensor(rng.uniform(loaded.bounds[0], loaded.bounds[1], (n, 3)), dtype=torch.float32)
    with torch.no_grad():
        ref = loaded.decoder(code, joint, xyz)
    got = fast(code, joint, xyz)
    np.testing.assert_allclose(got.raw.numpy(), ref.raw.numpy(), atol=2e-4)
    np.testing.assert_allclose(got.rotation.numpy(), ref.rotation.numpy(), atol=2e-3)
    np.testing.assert_allclose(fast.sdf_only(code, joint[:, None], xyz).numpy(), ref.sdf.numpy(), atol=2e-4)
    assert len(fast(code[:0], joint[:0], xyz[:0]).sdf) == 0
