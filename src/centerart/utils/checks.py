"""Checks of command options, called from each config's ``__post_init__`` so a bad value is refused where it is
parsed (CLI or Python), in one line that names the option, before any file is read or written."""

from __future__ import annotations

import math

from centerart.errors import CenterArtError


def finite(option: str, value: float) -> float:
    if not isinstance(value, int | float) or not math.isfinite(value):
        raise CenterArtError(f"{option} must be a finite number, got {value!r}")
    return value


def at_least(option: str, value: float | None, minimum: float, allow_none: bool = False) -> None:
    """``value >= minimum`` (and finite); ``None`` passes when ``allow_none``."""
    if value is None and allow_none:
        return
    finite(option, value)
    if value < minimum:
        raise CenterArtError(f"{option} must be >= {minimum}, got {value}")


def positive(option: str, value: float | None, allow_none: bool = False) -> None:
    """``value > 0`` (and finite); ``None`` passes when ``allow_none``."""
    if value is None and allow_none:
        return
    finite(option, value)
    if value <= 0:
        raise CenterArtError(f"{option} must be > 0, got {value}")


def between(option: str, value: float, lo: float, hi: float) -> None:
    finite(option, value)
    if not lo <= value <= hi:
        raise CenterArtError(f"{option} must be in [{lo}, {hi}], got {value}")


def workers(option: str, value: int | None) -> None:
    """A process count: None (all cores) or >= 1."""
    at_least(option, value, 1, allow_none=True)


def interval(option: str, pair, lo: float = -math.inf, hi: float = math.inf, strict_lo: bool = False) -> None:
    """A (min, max) pair of finite numbers with min <= max, both within [lo, hi] (above lo when ``strict_lo``)."""
    if pair is None:
        return
    values = list(pair)
    if len(values) != 2:
        raise CenterArtError(f"{option} takes two numbers (min max), got {values}")
    for v in values:
        finite(option, v)
        if v < lo or v > hi or (strict_lo and v <= lo):
            bound = f"> {lo}" if strict_lo and hi == math.inf else f"in [{lo}, {hi}]"
            raise CenterArtError(f"{option} {values[0]} {values[1]}: every value must be {bound}")
    if values[0] > values[1]:
        raise CenterArtError(f"{option} {values[0]} {values[1]}: min is larger than max")
