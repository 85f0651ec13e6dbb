"""Two closed-loop evaluations of the same scenes, paired object by object (``benchmarks/paired_outcomes.py``).

Two models a few successes apart on one test set may be equally good. Pairing the rows of two ``centerart eval
scenes`` outputs by (set, scene, view, depth mode, method, instance) gives, per set, the object views both open,
only the first opens and only the second opens, and the exact two-sided sign test on those discordant views (the
chance that two equally good models differ at least this much).

The views of one object are not independent: a test set shows each of its objects in several scenes (the
repository's 100 single scenes show 20 objects), and whether an object opens depends mostly on the object. So each
set also gets the sign test with distinct objects as the unit (``object_sign_test_p``): an object counts for the
evaluation that opens it in more of its views, ties left out; in ``all`` an object counts once per set.
"""

from __future__ import annotations

import json
from collections import defaultdict
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from scipy.stats import binomtest

from centerart.errors import CenterArtError

RowKey = tuple[str, str, int, str, str, int, str]
"""(set, scene, view, depth mode, method, instance, object id) of one learned-method row."""


def learned_rows(eval_out: Path) -> Iterator[tuple[str, dict]]:
    """(set name, row) of every learned-method row of an evaluation's ``records/<set>/<scene>.json``, in file order;
    the set name is the folder's without its path hash. An output without records is one error naming it."""
    files = sorted(Path(eval_out).glob("records/*/*.json"))
    if not files:
        raise CenterArtError(f"{eval_out}: no records/<set>/<scene>.json (expected a `centerart eval scenes` output)")
    for f in files:
        set_name = f.parent.name.rsplit("-", 1)[0]
        for row in json.loads(f.read_text())["rows"]:
            if row["method"].startswith("centerart"):
                yield set_name, row


def read_outcomes(eval_out: Path, key: str = "sr_image", with_method: bool = True) -> dict[RowKey, bool]:
    """Every learned-method row of an evaluation (:func:`learned_rows`) -> its outcome ``key``; with ``with_method``
    off the method is left out of the key (two inference settings, whose rows are named apart, e.g.
    ``centerart[pose]`` and ``centerart+sdf[pose]``; each evaluation must then hold one learned method)."""
    rows = {}
    for set_name, row in learned_rows(eval_out):
        if key in row:
            method = row["method"] if with_method else "centerart"
            rows[(set_name, row["scene"], row["view"], row["depth"], method, row["instance"], row["object_id"])] = bool(
                row[key]
            )
    return rows


def sign_test_p(only_a: int, only_b: int) -> float:
    """Exact two-sided sign test on the discordant pairs; 1.0 when there are none."""
    n = only_a + only_b
    return 1.0 if n == 0 else float(binomtest(only_a, n, 0.5).pvalue)


def paired_table(a: dict[RowKey, bool], b: dict[RowKey, bool]) -> dict:
    """Counts and both sign tests per set (and over all sets) on the rows both evaluations hold."""
    common = sorted(set(a) & set(b))
    counts: dict[str, dict] = defaultdict(lambda: {"objects": 0, "both": 0, "only_a": 0, "only_b": 0})
    for k in common:
        for name in (k[0], "all"):
            c = counts[name]
            c["objects"] += 1
            c["both"] += a[k] and b[k]
            c["only_a"] += a[k] and not b[k]
            c["only_b"] += b[k] and not a[k]
    for c in counts.values():
        c["sign_test_p"] = round(sign_test_p(c["only_a"], c["only_b"]), 4)
    for name, c in by_object(a, b, common).items():
        counts[name] |= c
    return {"rows_only_in_a": len(set(a) - set(b)), "rows_only_in_b": len(set(b) - set(a)), "sets": dict(counts)}


def by_object(a: dict[RowKey, bool], b: dict[RowKey, bool], common: list[RowKey]) -> dict[str, dict]:
    """Per set: distinct objects, how many open in more views with ``a`` and with ``b``, and the sign test on those."""
    margin: dict[str, dict[tuple, int]] = defaultdict(lambda: defaultdict(int))
    for k in common:
        for name in (k[0], "all"):
            margin[name][(k[0], k[-1])] += int(b[k]) - int(a[k])
    out = {}
    for name, per_object in margin.items():
        a_better = sum(1 for m in per_object.values() if m < 0)
        b_better = sum(1 for m in per_object.values() if m > 0)
        out[name] = {"distinct_objects": len(per_object), "objects_a_better": a_better, "objects_b_better": b_better,
                     "object_sign_test_p": round(sign_test_p(a_better, b_better), 4)}  # fmt: skip
    return out


@dataclass
class CompareEvalsConfig:
    """Pair two closed-loop evaluations of the same scenes: per set, the object views only one of them opens and the
    sign test on views and on distinct objects (read ``object_sign_test_p``)."""

    a: Path
    """First ``centerart eval scenes`` output (its records/)."""
    b: Path
    """Second ``centerart eval scenes`` output over the same scenes (best with the first one's labels copied in)."""
    key: str = "sr_image"
    """Row outcome to pair (sr_image: SR by image association; sr: the 3-D centre match)."""
    ignore_method: bool = False
    """Pair rows whatever their learned method is called (two inference settings, one method each)."""
    out: Path | None = None
    """Also write the table as JSON here."""


def compare_evaluations(cfg: CompareEvalsConfig) -> dict:
    """:func:`paired_table` of the two outputs, with their paths and the outcome key (written to ``cfg.out``)."""
    from centerart.utils.atomic import atomic_write_json

    named = not cfg.ignore_method
    a, b = read_outcomes(cfg.a, cfg.key, named), read_outcomes(cfg.b, cfg.key, named)
    if not set(a) & set(b):
        raise CenterArtError(f"{cfg.a} and {cfg.b}: no row in common (other scenes, or other methods: --ignore-method)")
    report = {"a": str(cfg.a), "b": str(cfg.b), "key": cfg.key, **paired_table(a, b)}
    if cfg.out:
        atomic_write_json(Path(cfg.out), report)
    return report
