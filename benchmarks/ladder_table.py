"""The anchoring ladder as one table: per grasp setting (``inference.grasp_anchoring.LADDER``, cumulative) and test
set, SR under image association and under the 3-D match with realistic and true depth, the stage analysis (SR with
the true pose and joint swapped in), the share of top grasps closing on free air (``no_contact``) and RSR, read
from one or more ``centerart eval scenes --grasps ...`` reports. Prints Markdown; ``--json`` writes the numbers.

    python benchmarks/ladder_table.py --reports eval_ladder/report.json --out ladder.md --json ladder.json
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from bench_report import run_main

SETTINGS = ("proposal", "checks", "snap", "square", "observed", "handle", "full", "pose")


def method_setting(method: str) -> str | None:
    """The ladder setting of a learned method's name (``centerart`` is ``full``), None for other methods."""
    if method == "centerart":
        return "full"
    if method.startswith("centerart[") and method.endswith("]"):
        return method[len("centerart[") : -1]
    return None


def ladder_rows(report: dict) -> list[dict]:
    """One row per (set, setting or reference method, depth) with the ladder's figures."""
    rows = []
    for key, g in report["groups"].items():
        set_key, method, depth = key.split("|")
        setting = method_setting(method) or method
        stage = report.get("stages", {}).get(key, {})
        objects = g["objects"] or 1
        rows.append({
            "set": report["sets"][set_key]["label"] if "label" in report["sets"].get(set_key, {}) else set_key,
            "setting": setting, "depth": depth, "objects": g["objects"],
            "sr_image": g.get("sr_image"), "sr_3d": g["sr"], "rsr": g["rsr"],
            "sr_true_pose": stage.get("sr_image_with_true_pose_and_joint", stage.get("sr_with_true_pose_and_joint")),
            "no_contact": g["aborts"].get("no_contact", 0) / objects,
            "published": (g.get("published_protocol") or {}).get("sr"),
        })  # fmt: skip
    return rows


def _f(x) -> str:
    return "-" if x is None else f"{x:.2f}"


def markdown(rows: list[dict]) -> str:
    order = {s: i for i, s in enumerate((*SETTINGS, "baseline", "oracle"))}
    rows = sorted(rows, key=lambda r: (r["set"], r["depth"] != "realistic", r["depth"], order.get(r["setting"], 99)))
    lines = [
        "| test set | depth | grasps | objects | SR img | SR 3-D | SR img, true pose + joint | no_contact | RSR | "
        "published protocol |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['set']} | {r['depth']} | {r['setting']} | {r['objects']} | {_f(r['sr_image'])} | {_f(r['sr_3d'])} | "
            f"{_f(r['sr_true_pose'])} | {_f(r['no_contact'])} | {_f(r['rsr'])} | {_f(r['published'])} |"
        )
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reports", type=Path, nargs="+", required=True)
    ap.add_argument("--out", type=Path, default=None, help="write the Markdown table here too")
    ap.add_argument("--json", type=Path, default=None, help="write the rows as JSON")
    args = ap.parse_args()
    rows = [r for p in args.reports for r in ladder_rows(json.loads(Path(p).read_text()))]
    text = markdown(rows)
    print(text)
    if args.out:
        args.out.write_text(text)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    run_main(main)
