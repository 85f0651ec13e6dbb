"""The ``centerart`` command: ``centerart <group> <command> [options]``; ``--help`` at every level.

Each command's options are generated from its typed config dataclass (tyro), so the CLI, the Python API and
the saved configs always agree. Errors in the user's input print one clear line and exit with status 2.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import tyro

from centerart.errors import CenterArtError


@dataclass(frozen=True)
class Command:
    config: Callable[[], type]
    run: Callable[[], Callable[[Any], Any]]
    help: str


def _objects_generate():
    from centerart.assets.dataset import GenerateObjectsConfig

    return GenerateObjectsConfig


def _objects_generate_run():
    from centerart.assets.dataset import generate_objects

    def run(cfg):
        result = generate_objects(cfg)
        for cat, c in result["counts"].items():
            print(
                f"{cat:18s} {c['objects']:4d} objects ({c['revolute']} revolute, {c['prismatic']} prismatic), "
                f"{c['rejected_attempts']} rejected attempts"
            )
        print(f"wrote {Path(cfg.out) / 'manifest.json'}")

    return run


def _objects_show():
    from centerart.viz.objects_sheet import ShowObjectsConfig

    return ShowObjectsConfig


def _objects_show_run():
    from centerart.viz.objects_sheet import show_objects

    return lambda cfg: print(f"wrote {show_objects(cfg)}")


def _grasps_generate():
    from centerart.grasps.generate import GenerateGraspsConfig

    return GenerateGraspsConfig


def _grasps_generate_run():
    from centerart.grasps.generate import generate_grasps

    def run(cfg):
        summary = generate_grasps(cfg)
        for cat, c in summary.items():
            print(
                f"{cat:18s} {c['items']:4d} (object, state) items, {c['labels']:6d} labels, yield {c['yield']:.3f}, "
                f"{c['items_with_100_labels']} items with >= 100 labels"
            )
        print(f"wrote {Path(cfg.out) / 'manifest.json'}")

    return run


def _grasps_show():
    from centerart.grasps.show import ShowGraspsConfig

    return ShowGraspsConfig


def _grasps_show_run():
    from centerart.grasps.show import show_grasps

    return lambda cfg: print(f"wrote {show_grasps(cfg)}")


def _sdf_generate():
    from centerart.sdf.generate import GenerateSdfConfig

    return GenerateSdfConfig


def _sdf_generate_run():
    from centerart.sdf.generate import generate_sdf

    def run(cfg):
        summary = generate_sdf(cfg)
        c = summary["counts"]
        print(
            f"{c['objects']} objects, {c['states']} states, {c['points']} points "
            f"({c['states_without_grasps']} states without grasps)"
        )
        for oid, o in summary["objects"].items():
            flag = "" if o["meets_min_sign_agreement"] else f"  BELOW {summary['min_sign_agreement']:.0%}"
            print(
                f"  {oid:28s} sign agreement {o['sign_agreement_min']:.4f} (min), "
                f"{o['sign_method']} vs {o['check_method']}{flag}"
            )
        print(f"wrote {Path(cfg.out) / 'manifest.json'}")

    return run


def _demo():
    from centerart.demo import DemoConfig

    return DemoConfig


def _demo_run():
    from centerart.demo import run_demo

    return run_demo


def _train_decoder():
    from centerart.training.train_decoder import TrainDecoderConfig

    return TrainDecoderConfig


def _train_decoder_run():
    from centerart.training.train_decoder import train_decoder

    def run(cfg):
        result = train_decoder(cfg)
        m = result["metrics"]
        shown = {k: round(v, 5) for k, v in m.items() if k.startswith(("val", "train/"))}
        print(f"metrics: {shown}")
        print(f"wrote {result['checkpoint']}")

    return run


def _decoder_show():
    from centerart.inference.decoder_show import ShowDecoderConfig

    return ShowDecoderConfig


def _decoder_show_run():
    from centerart.inference.decoder_show import show_decoder

    return lambda cfg: print(f"wrote {show_decoder(cfg)}")


def _eval_decoder():
    from centerart.evaluation.decoder_eval import EvalDecoderConfig

    return EvalDecoderConfig


def _eval_decoder_run():
    import json

    from centerart.evaluation.decoder_eval import evaluate_decoder

    def run(cfg):
        report = evaluate_decoder(cfg)
        print(json.dumps(report["summary"], indent=1))
        print(f"wrote {Path(cfg.out) / 'report.json'}")

    return run


COMMANDS: dict[str, dict[str, Command]] = {
    "objects": {
        "generate": Command(
            _objects_generate,
            _objects_generate_run,
            "generate procedural articulated objects (PartNet-Mobility layout)",
        ),
        "show": Command(_objects_show, _objects_show_run, "contact sheet of objects at closed/half/open states"),
    },
    "grasps": {
        "generate": Command(
            _grasps_generate,
            _grasps_generate_run,
            "physics-verified grasp labels per (object, joint state)",
        ),
        "show": Command(_grasps_show, _grasps_show_run, "draw stored grasp labels as gripper markers on an object"),
    },
    "sdf": {
        "generate": Command(
            _sdf_generate, _sdf_generate_run, "SDF samples + nearest-grasp targets per (object, joint state)"
        ),
    },
    "train": {
        "decoder": Command(_train_decoder, _train_decoder_run, "auto-decoder training of the SGDF decoder"),
    },
    "decoder": {
        "show": Command(_decoder_show, _decoder_show_run, "reconstructions with top grasps at several joint states"),
    },
    "eval": {
        "decoder": Command(_eval_decoder, _eval_decoder_run, "decoder shape/grasp/physics metrics per split"),
    },
    "demo": {"": Command(_demo, _demo_run, "the main job on its built-in default (see README quick start)")},
}


def _usage() -> str:
    lines = ["usage: centerart <group> <command> [options]   (add --help to any command)", "", "commands:"]
    for group, cmds in COMMANDS.items():
        for name, cmd in cmds.items():
            lines.append(f"  {(group + ' ' + name).strip():28s} {cmd.help}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(_usage())
        return 0
    group = argv.pop(0)
    if group not in COMMANDS:
        print(f"centerart: unknown command group {group!r}\n\n{_usage()}", file=sys.stderr)
        return 2
    cmds = COMMANDS[group]
    if "" in cmds:
        name = ""
    elif not argv or argv[0] in ("-h", "--help"):
        print(_usage())
        return 0 if argv else 2
    else:
        name = argv.pop(0)
        if name not in cmds:
            print(f"centerart {group}: unknown command {name!r}\n\n{_usage()}", file=sys.stderr)
            return 2
    cmd = cmds[name]
    prog = f"centerart {group} {name}".strip()
    cfg = tyro.cli(cmd.config(), args=argv, prog=prog, description=cmd.help)
    try:
        cmd.run()(cfg)
    except CenterArtError as err:
        print(f"centerart: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(
            "centerart: interrupted; finished items are kept, rerun the same command to resume",
            file=sys.stderr,
        )
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
