"""The SGDF decoder run by ONNX Runtime on the CPU: the same call and outputs as ``SGDFDecoder.forward``, no
gradients, about twice as fast on two cores (``benchmarks/onnx_bench.py``: 378 ms against 702 ms for 65,536
query points, outputs within 5e-4).

Inference calls the decoder on hundreds of thousands of points per image (the grasp pass and meshes), and eager
torch runs a small MLP poorly on few threads; ONNX Runtime fuses the layers. The graph is exported from the loaded
weights when the predictor starts (about a second; kept in memory, nothing written), so any checkpoint works.
Refinement that needs gradients (``refine_sdf``) keeps the torch decoder.
"""

from __future__ import annotations

import io
import warnings

import numpy as np
import torch

from centerart.models.decoder import DecoderOutput, SGDFDecoder, decode_outputs

EXPORT_POINTS = 1024  # example batch for the export; the point axis is dynamic
OPSET = 17


def onnxruntime_available() -> bool:
    try:
        import onnx  # noqa: F401  (the exporter needs it)
        import onnxruntime  # noqa: F401
    except ImportError:
        return False
    return True


class _RawOutputs(torch.nn.Module):
    """The decoder returning its raw head outputs (ONNX graphs return tensors, not dataclasses)."""

    def __init__(self, decoder: SGDFDecoder):
        super().__init__()
        self.decoder = decoder

    def forward(self, code: torch.Tensor, joint: torch.Tensor, xyz: torch.Tensor) -> torch.Tensor:
        return self.decoder(code, joint, xyz).raw


def export_decoder(decoder: SGDFDecoder) -> bytes:
    """The decoder as an ONNX model (bytes): inputs code (N, D), joint (N,), xyz (N, 3); output raw (N, OUT_DIM)."""
    n = EXPORT_POINTS
    example = (torch.zeros(n, decoder.config.code_dim), torch.zeros(n), torch.zeros(n, 3))
    axes = {name: {0: "points"} for name in ("code", "joint", "xyz", "raw")}
    buffer = io.BytesIO()
    module = _RawOutputs(decoder).eval().cpu()
    with warnings.catch_warnings():  # the TorchScript exporter's deprecation and tracer notes are not actionable here
        warnings.simplefilter("ignore")
        torch.onnx.export(
            module, example, buffer, dynamo=False, opset_version=OPSET, input_names=["code", "joint", "xyz"],
            output_names=["raw"], dynamic_axes=axes,
        )  # fmt: skip
    return buffer.getvalue()


class OnnxDecoder:
    """Drop-in for ``SGDFDecoder`` in inference (``decoder(code, joint, xyz)`` and ``sdf_only``), on the CPU."""

    def __init__(self, decoder: SGDFDecoder, threads: int | None = None):
        import onnxruntime as ort

        self.config = decoder.config
        options = ort.SessionOptions()
        options.intra_op_num_threads = threads if threads is not None else torch.get_num_threads()
        options.log_severity_level = 3
        self.session = ort.InferenceSession(export_decoder(decoder), options, providers=["CPUExecutionProvider"])

    def __call__(self, code: torch.Tensor, joint: torch.Tensor, xyz: torch.Tensor) -> DecoderOutput:
        code, joint, xyz = (torch.as_tensor(t).detach().cpu() for t in (code, joint, xyz))
        if joint.dim() == code.dim():
            joint = joint.squeeze(-1)
        feeds = {
            "code": np.ascontiguousarray(code.numpy(), np.float32),
            "joint": np.ascontiguousarray(joint.numpy(), np.float32),
            "xyz": np.ascontiguousarray(xyz.numpy(), np.float32),
        }
        (raw,) = self.session.run(["raw"], feeds)
        return decode_outputs(torch.from_numpy(raw))

    def sdf_only(self, code: torch.Tensor, joint: torch.Tensor, xyz: torch.Tensor) -> torch.Tensor:
        return self(code, joint, xyz).sdf
