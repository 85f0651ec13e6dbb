"""Deterministic seeds: every item gets its own generator derived from (global seed, item key)."""

from __future__ import annotations

import hashlib

import numpy as np


def item_seed(seed: int, *key: object) -> int:
    """A 63-bit seed that depends only on ``seed`` and ``key`` (stable across processes and Python runs)."""
    digest = hashlib.sha256(repr((int(seed), *key)).encode()).digest()
    return int.from_bytes(digest[:8], "little") >> 1


def item_rng(seed: int, *key: object) -> np.random.Generator:
    return np.random.default_rng(item_seed(seed, *key))
