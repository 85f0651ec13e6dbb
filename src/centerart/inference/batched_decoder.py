"""Decode all objects of an image at once: per-object work runs in lockstep threads whose decoder calls are merged.

The coarse-to-fine mesher and the grasp extraction call the decoder many times per object, each call depending on
the previous one's answer. Rather than rewrite them for several objects, each object's work runs unchanged in its
own thread with a proxy decoder; a proxy call waits until every still-running object has made its next call (or
finished), and then one decoder call on the concatenated points (each point with its own object's shape and joint
code) answers them all. Five objects thus cost about as many decoder calls as one, with batches five times larger:
what a GPU wants, and on a CPU it overlaps each object's numpy work with the others' (measured in
``benchmarks/predict_bench.py``).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import TypeVar

import torch

from centerart.models.decoder import OUT_DIM, DecoderOutput, decode_outputs

T = TypeVar("T")


class _Batcher:
    """Collects one pending call per live task; the call that completes the set runs the merged batch."""

    def __init__(self, decoder, tasks: int, chunk: int):
        self.decoder, self.chunk = decoder, chunk
        self.cond = threading.Condition()
        self.live = tasks
        self.pending: dict[int, tuple[torch.Tensor, torch.Tensor, torch.Tensor]] = {}
        self.answers: dict[int, torch.Tensor | BaseException] = {}

    def call(self, task: int, code: torch.Tensor, joint: torch.Tensor, xyz: torch.Tensor) -> torch.Tensor:
        with self.cond:
            self.pending[task] = (code, joint.reshape(-1), xyz)
            self._flush_if_complete()
            while task not in self.answers:
                self.cond.wait()
            answer = self.answers.pop(task)
        if isinstance(answer, BaseException):
            raise answer
        return answer

    def finished(self) -> None:
        with self.cond:
            self.live -= 1
            self._flush_if_complete()

    def _flush_if_complete(self) -> None:
        """Run the merged call once every live task is waiting (called with the lock held)."""
        if not self.pending or len(self.pending) < self.live:
            return
        tasks = sorted(self.pending)
        parts = [self.pending.pop(t) for t in tasks]
        sizes = [len(p[2]) for p in parts]
        try:
            code, joint, xyz = (torch.cat([p[i] for p in parts]) for i in range(3))
            with torch.no_grad():
                raw = torch.cat(
                    [
                        self.decoder(code[i : i + self.chunk], joint[i : i + self.chunk], xyz[i : i + self.chunk]).raw
                        for i in range(0, len(xyz), self.chunk)
                    ]
                ) if len(xyz) else torch.zeros(0, OUT_DIM, device=xyz.device)  # fmt: skip
            for t, out in zip(tasks, torch.split(raw, sizes), strict=True):
                self.answers[t] = out
        except BaseException as err:  # every waiting task sees the failure instead of hanging
            for t in tasks:
                self.answers[t] = err
        self.cond.notify_all()


class _ProxyDecoder:
    """What one task sees: ``decoder(code, joint, xyz)`` and ``sdf_only``, answered through the batcher."""

    def __init__(self, batcher: _Batcher, task: int, config):
        self.batcher, self.task, self.config = batcher, task, config

    def __call__(self, code: torch.Tensor, joint: torch.Tensor, xyz: torch.Tensor) -> DecoderOutput:
        return decode_outputs(self.batcher.call(self.task, code, joint, xyz))

    def sdf_only(self, code: torch.Tensor, joint: torch.Tensor, xyz: torch.Tensor) -> torch.Tensor:
        return self(code, joint, xyz).sdf


def run_batched(decoder, tasks: list[Callable[[object], T]], chunk: int = 65536) -> list[T]:
    """Run ``task(decoder_proxy)`` for every task in lockstep threads, merging their decoder calls; results in
    task order. One task runs directly on ``decoder`` (no threads)."""
    if len(tasks) <= 1:
        return [task(decoder) for task in tasks]
    batcher = _Batcher(decoder, len(tasks), chunk)
    results: list = [None] * len(tasks)
    errors: list[BaseException | None] = [None] * len(tasks)

    def worker(i: int) -> None:
        try:
            results[i] = tasks[i](_ProxyDecoder(batcher, i, decoder.config))
        except BaseException as err:
            errors[i] = err
        finally:
            batcher.finished()

    threads = [threading.Thread(target=worker, args=(i,), daemon=True) for i in range(len(tasks))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for err in errors:
        if err is not None:
            raise err
    return results
