"""ONNX Runtime against eager torch on the CPU for the encoder (640x480 input letterboxed to the preset) and the
decoder MLP (a batch of query points): same outputs within tolerance? faster? Prints JSON.

    # onnx and onnxruntime are project dependencies (the predictor runs the decoder with them on CPUs)
    PYTHONPATH=src python benchmarks/onnx_bench.py --threads 2 --out benchmarks/onnx_bench_result.json
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

from bench_report import emit, run_main
from centerart.models.checkpoint import load_decoder
from centerart.models.encoder.checkpoint import load_encoder


class EncoderFlat(torch.nn.Module):
    """The encoder with its output flattened to tensors (ONNX graphs return tensors, not dataclasses)."""

    def __init__(self, encoder):
        super().__init__()
        self.encoder = encoder

    def forward(self, rgb, depth):
        out = self.encoder(rgb, depth)
        return (out.heatmap, *out.dense.values())


class DecoderFlat(torch.nn.Module):
    def __init__(self, decoder):
        super().__init__()
        self.decoder = decoder

    def forward(self, code, joint, xyz):
        out = self.decoder(code, joint, xyz)
        return out.sdf, out.offset, out.rotation


def timed(fn, repeats: int) -> float:
    fn()
    t0 = time.perf_counter()
    for _ in range(repeats):
        fn()
    return (time.perf_counter() - t0) / repeats


def compare(name, module, inputs, repeats, threads, folder):
    import onnxruntime as ort

    path = Path(folder) / f"{name}.onnx"
    torch.onnx.export(module, inputs, str(path), dynamo=False, opset_version=17)
    opts = ort.SessionOptions()
    opts.intra_op_num_threads = threads
    sess = ort.InferenceSession(str(path), opts, providers=["CPUExecutionProvider"])
    feeds = {i.name: x.numpy() for i, x in zip(sess.get_inputs(), inputs, strict=True)}
    with torch.no_grad():
        ref = [t.numpy() for t in module(*inputs)]
        t_torch = timed(lambda: module(*inputs), repeats)
    got = sess.run(None, feeds)
    t_ort = timed(lambda: sess.run(None, feeds), repeats)
    err = max(float(np.abs(a - b).max()) for a, b in zip(ref, got, strict=True))
    return {"torch_ms": 1000 * t_torch, "onnxruntime_ms": 1000 * t_ort, "max_abs_difference": err}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--points", type=int, default=65536)
    ap.add_argument("--repeats", type=int, default=10)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    enc = load_encoder().encoder.eval()
    dec = load_decoder().decoder.eval()
    cfg = enc.config
    rgb, depth = (
        torch.rand(1, 3, cfg.input_height, cfg.input_width),
        torch.rand(1, 1, cfg.input_height, cfg.input_width) + 1,
    )
    n = args.points
    dec_in = (torch.randn(n, dec.config.code_dim) * 0.05, torch.rand(n), torch.rand(n, 3) - 0.5)
    report = {"threads": args.threads}
    with tempfile.TemporaryDirectory() as tmp:
        report["encoder"] = compare("encoder", EncoderFlat(enc), (rgb, depth), args.repeats, args.threads, tmp)
        report["decoder"] = {
            "points": n,
            **compare("decoder", DecoderFlat(dec), dec_in, args.repeats, args.threads, tmp),
        }
    emit(report, args.out)


if __name__ == "__main__":
    run_main(main)
