"""Two scene evaluations of the same scenes, paired object by object, as JSON (``centerart eval compare`` prints the
same as a table; ``centerart.evaluation.paired``): the object views only one of them opens, with the sign test on
views and on distinct objects.

    python benchmarks/paired_outcomes.py --a OUT_A --b OUT_B [--key sr_image] [--ignore-method] [--out paired.json]
    # OUT_A, OUT_B: `centerart eval scenes` outputs over the same scenes (their records/); the labels should be
    # shared (copy OUT_A/labels into OUT_B before its run) so that only the models differ.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from bench_report import emit, run_main
from centerart.evaluation.paired import CompareEvalsConfig, compare_evaluations


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--a", type=Path, required=True, help="first `centerart eval scenes` output")
    p.add_argument("--b", type=Path, required=True, help="second `centerart eval scenes` output")
    p.add_argument("--key", default="sr_image", help="row outcome to pair (sr_image: SR by image association)")
    p.add_argument("--ignore-method", action="store_true", help="pair rows whatever their method is called")
    p.add_argument("--out", type=Path, default=None)
    args = p.parse_args()
    emit(compare_evaluations(CompareEvalsConfig(args.a, args.b, args.key, args.ignore_method)), args.out)


if __name__ == "__main__":
    run_main(main)
