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


def _scenes_generate():
    from centerart.scenes.dataset import GenerateScenesConfig

    return GenerateScenesConfig


def _scenes_generate_run():
    from centerart.scenes.dataset import generate_scenes

    def run(cfg):
        result = generate_scenes(cfg)
        c = result["counts"]
        print(
            f"{c['scenes']} scenes, {c['images']} images from {c['objects_available']} objects, "
            f"{c['rejected_layouts']} layouts rejected by the collision check"
        )
        print(f"wrote {Path(cfg.out) / 'manifest.json'}")

    return run


def _scenes_show():
    from centerart.viz.scenes_sheet import ShowScenesConfig

    return ShowScenesConfig


def _scenes_show_run():
    from centerart.viz.scenes_sheet import show_scenes

    return lambda cfg: print(f"wrote {show_scenes(cfg)}")


def _demo():
    from centerart.demo import DemoConfig

    return DemoConfig


def _demo_run():
    from centerart.demo import run_demo

    return run_demo


COMMANDS: dict[str, dict[str, Command]] = {
    "objects": {
        "generate": Command(
            _objects_generate,
            _objects_generate_run,
            "generate procedural articulated objects (PartNet-Mobility layout)",
        ),
        "show": Command(_objects_show, _objects_show_run, "contact sheet of objects at closed/half/open states"),
    },
    "scenes": {
        "generate": Command(
            _scenes_generate,
            _scenes_generate_run,
            "render kitchen/single scenes: RGB, true + realistic depth, masks, encoder labels",
        ),
        "show": Command(_scenes_show, _scenes_show_run, "contact sheet of rendered scenes with their labels"),
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
