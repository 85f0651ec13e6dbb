"""The decoder-slice table row of ``centerart eval decoder`` reports, optionally on a subset of their objects.

A decoder slice's ledger evaluates all of its run's held-out objects (``heldout_eval/report.json`` in the slice's
work folder); the comparison across runs in ``results/decoder_slices/`` is on the 12 objects that both the
102-object runs and the shipped 34-object decoder held out. Their states are the same evaluation either way, so
the row is read from the report's per-state results rather than evaluated again. Prints a markdown row per
report: Chamfer mean / median (mm), F@1cm, top-1 closed / open, any of 5 closed / open, label precision@5, and
top-1 over all states.

    python benchmarks/decoder_report_row.py REPORT.json [REPORT2.json ...] [--objects TWELVE]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
from pathlib import Path

from bench_report import run_main

#: The 12 objects that decoder-small-102, its paper-reg twin and the shipped decoder all held out.
TWELVE = (
    "dishwasher_0014 dishwasher_0021 dishwasher_0023 microwave_0008 microwave_0012 microwave_0013 microwave_0016 "
    "refrigerator_0011 refrigerator_0012 storage_furniture_0011 storage_furniture_0019 storage_furniture_0023"
).split()
CLOSED, OPEN = 0, 5  # the state indices evaluated with --states-per-object 2


def row(states: list[dict]) -> str:
    def mean(key, index=None):
        return statistics.mean(s[key] for s in states if index is None or s["state_index"] == index)

    chamfer = [s["chamfer_mm"] for s in states]
    return (
        f"{statistics.mean(chamfer):.1f} / {statistics.median(chamfer):.1f} | {mean('fscore'):.2f} | "
        f"{mean('physics_top1', CLOSED):.2f} / {mean('physics_top1', OPEN):.2f} | "
        f"{mean('physics_any5', CLOSED):.2f} / {mean('physics_any5', OPEN):.2f} | {mean('precision_at_k'):.2f} | "
        f"{mean('physics_top1'):.2f}"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("reports", type=Path, nargs="+")
    parser.add_argument("--objects", choices=["all", "twelve"], default="all")
    args = parser.parse_args(argv)
    for path in args.reports:
        try:
            states = json.loads(path.read_text())["states"]
        except (OSError, ValueError, KeyError) as err:
            print(f"error: {path}: not a readable decoder eval report ({type(err).__name__})", file=sys.stderr)
            return 2
        if args.objects == "twelve":
            states = [s for s in states if s["object_id"] in TWELVE]
        if not states:
            print(f"error: {path}: no state of the chosen objects", file=sys.stderr)
            return 2
        print(f"| {path} ({len(states)} states) | {row(states)} |")
    return 0


if __name__ == "__main__":
    run_main(main)
