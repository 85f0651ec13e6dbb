"""Two scene evaluations of the same test scenes, paired object by object: which objects only one of them opens.

The shipping rule compares SR per test set; two models a few objects apart on one set may be equally good. This
pairs the rows of two ``centerart eval scenes`` outputs by (set, scene, view, depth mode, method, instance), counts
the objects both open, only the first opens, only the second opens, and gives the exact two-sided sign test on the
discordant pairs (the chance that two equally good models differ at least this much). Prints JSON:

    python benchmarks/paired_outcomes.py --a OUT_A --b OUT_B [--key sr_image] [--ignore-method] [--out paired.json]
    # OUT_A, OUT_B: `centerart eval scenes` outputs over the same scenes (their records/); the labels should be
    # shared (copy OUT_A/labels into OUT_B before its run) so that only the models differ.
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict
from pathlib import Path

from scipy.stats import binomtest

from bench_report import emit


def outcomes(eval_out: Path, key: str, with_method: bool = True) -> dict[tuple, bool]:
    """Every learned-method row of an evaluation's records: (set, scene, view, depth, method, instance) -> outcome;
    without the method when ``with_method`` is off (two inference settings, whose rows are named apart, e.g.
    ``centerart[pose]`` and ``centerart+sdf[pose]``; each evaluation must then hold one learned method)."""
    files = sorted(eval_out.glob("records/*/*.json"))
    if not files:
        raise SystemExit(f"{eval_out}: no records/<set>/<scene>.json (expected a `centerart eval scenes` output)")
    rows = {}
    for f in files:
        set_name = f.parent.name.rsplit("-", 1)[0]
        for row in json.loads(f.read_text())["rows"]:
            if row["method"].startswith("centerart") and key in row:
                method = row["method"] if with_method else "centerart"
                rows[(set_name, row["scene"], row["view"], row["depth"], method, row["instance"])] = bool(row[key])
    return rows


def sign_test_p(only_a: int, only_b: int) -> float:
    """Exact two-sided sign test on the discordant pairs; 1.0 when there are none."""
    n = only_a + only_b
    return 1.0 if n == 0 else float(binomtest(only_a, n, 0.5).pvalue)


def paired_table(a: dict[tuple, bool], b: dict[tuple, bool]) -> dict:
    """Counts per set (and over all sets) on the rows both evaluations hold."""
    common = sorted(set(a) & set(b))
    counts: dict[str, dict[str, int]] = defaultdict(lambda: {"objects": 0, "both": 0, "only_a": 0, "only_b": 0})
    for k in common:
        for name in (k[0], "all"):
            c = counts[name]
            c["objects"] += 1
            c["both"] += a[k] and b[k]
            c["only_a"] += a[k] and not b[k]
            c["only_b"] += b[k] and not a[k]
    for c in counts.values():
        c["sign_test_p"] = round(sign_test_p(c["only_a"], c["only_b"]), 4)
    return {"rows_only_in_a": len(set(a) - set(b)), "rows_only_in_b": len(set(b) - set(a)), "sets": dict(counts)}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--a", type=Path, required=True, help="first `centerart eval scenes` output")
    p.add_argument("--b", type=Path, required=True, help="second `centerart eval scenes` output")
    p.add_argument("--key", default="sr_image", help="row outcome to pair (sr_image: SR by image association)")
    p.add_argument(
        "--ignore-method",
        action="store_true",
        help="pair rows whatever their method is called (two inference settings, one method each)",
    )
    p.add_argument("--out", type=Path, default=None)
    args = p.parse_args()
    report = {"a": str(args.a), "b": str(args.b), "key": args.key}
    named = not args.ignore_method
    report |= paired_table(outcomes(args.a, args.key, named), outcomes(args.b, args.key, named))
    emit(report, args.out)


if __name__ == "__main__":
    main()
