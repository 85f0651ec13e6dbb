"""Structure checks of JSON files the project reads (labels, scene descriptions, predictions), so a damaged or
hand-edited file is one message naming the field (``objects[0].camera_T_object: ...``) instead of a crash later.

A schema is: a Python type (``str``, ``int``, ``float``: finite, ints accepted, ``bool``, ``dict``, ``list``);
:func:`array` (nested lists of finite numbers of a given shape, checked with numpy); a dict of schemas (keys ending
in ``?`` are optional); a one-element list ``[schema]`` (a list of such items); :func:`optional` (``null`` or
the schema); or :data:`ANY`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

ANY = object()


class _Array:
    def __init__(self, *shape: int | None):
        self.shape = shape


class _Optional:
    def __init__(self, schema: Any):
        self.schema = schema


def array(*shape: int | None) -> _Array:
    """Nested lists of finite numbers with this shape (None: any size)."""
    return _Array(*shape)


def optional(schema: Any) -> _Optional:
    return _Optional(schema)


def json_problem(value: Any, schema: Any, where: str = "") -> str | None:
    """What is wrong with ``value`` against ``schema`` (``"<field>: <problem>"``), or None."""
    here = where or "the file"
    if schema is ANY:
        return None
    if isinstance(schema, _Optional):
        return None if value is None else json_problem(value, schema.schema, where)
    if isinstance(schema, _Array):
        return _array_problem(value, schema.shape, here)
    if isinstance(schema, dict):
        return _dict_problem(value, schema, where)
    if isinstance(schema, list):
        if not isinstance(value, list):
            return f"{here}: expected a list, got {_kind(value)}"
        for i, item in enumerate(value):
            problem = json_problem(item, schema[0], f"{where}[{i}]")
            if problem:
                return problem
        return None
    return _scalar_problem(value, schema, here)


def _dict_problem(value: Any, schema: dict, where: str) -> str | None:
    if not isinstance(value, dict):
        return f"{where or 'the file'}: expected an object, got {_kind(value)}"
    for key, sub in schema.items():
        name = key.rstrip("?")
        if name not in value:
            if key.endswith("?"):
                continue
            return f"{where + '.' if where else ''}{name}: missing"
        problem = json_problem(value[name], sub, f"{where + '.' if where else ''}{name}")
        if problem:
            return problem
    return None


def _scalar_problem(value: Any, kind: type, here: str) -> str | None:
    if kind is float:
        ok = isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
        return None if ok else f"{here}: expected a finite number, got {_kind(value)}"
    if kind is int:
        ok = isinstance(value, int) and not isinstance(value, bool)
        return None if ok else f"{here}: expected an integer, got {_kind(value)}"
    return None if isinstance(value, kind) else f"{here}: expected {kind.__name__}, got {_kind(value)}"


def _array_problem(value: Any, shape: tuple, here: str) -> str | None:
    expected = "x".join("n" if s is None else str(s) for s in shape)
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return f"{here}: expected a {expected} array of numbers, got {_kind(value)}"
    if a.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, a.shape, strict=False)):
        return f"{here}: expected a {expected} array, got shape {a.shape}"
    if not np.isfinite(a).all():
        return f"{here}: holds NaN or infinite values"
    return None


def _kind(value: Any) -> str:
    text = repr(value)
    return f"{type(value).__name__} {text[:40]}{'...' if len(text) > 40 else ''}"
