"""The ``centerart`` command: ``centerart <group> <command> [options]``; ``--help`` at every level.

Each command's options are generated from its typed config dataclass (tyro), so the CLI, the Python API and
the saved configs always agree. Errors in the user's input print one clear line and exit with status 2.
Configs and runners are named as ``module:attribute`` strings and imported only when their command runs.
"""

from __future__ import annotations

import importlib
import sys
from dataclasses import dataclass

import tyro

from centerart.errors import CenterArtError
from centerart.utils.torch_cpu import flush_denormals


@dataclass(frozen=True)
class Command:
    config: str  # "module:ConfigDataclass"
    run: str  # "module:function(config)"
    help: str
    default: str | None = None  # "module:function(argv)": the config's defaults for this command line (presets)


def _resolve(ref: str):
    module, attr = ref.split(":")
    return getattr(importlib.import_module(module), attr)


COMMANDS: dict[str, dict[str, Command]] = {
    "objects": {
        "generate": Command(
            "centerart.assets.dataset:GenerateObjectsConfig",
            "centerart.commands:objects_generate",
            "generate procedural articulated objects (PartNet-Mobility layout)",
        ),
        "show": Command(
            "centerart.viz.objects_sheet:ShowObjectsConfig",
            "centerart.commands:objects_show",
            "contact sheet of objects at closed/half/open states",
        ),
    },
    "grasps": {
        "generate": Command(
            "centerart.grasps.generate:GenerateGraspsConfig",
            "centerart.commands:grasps_generate",
            "physics-verified grasp labels per (object, joint state)",
        ),
        "show": Command(
            "centerart.viz.grasps_sheet:ShowGraspsConfig",
            "centerart.commands:grasps_show",
            "draw stored grasp labels as gripper markers on an object",
        ),
    },
    "sdf": {
        "generate": Command(
            "centerart.sdf.generate:GenerateSdfConfig",
            "centerart.commands:sdf_generate",
            "SDF samples + nearest-grasp targets per (object, joint state)",
        ),
    },
    "scenes": {
        "generate": Command(
            "centerart.scenes.dataset:GenerateScenesConfig",
            "centerart.commands:scenes_generate",
            "kitchen / single-object scenes: RGB, true and realistic depth, masks, encoder labels",
        ),
        "show": Command(
            "centerart.viz.scenes_sheet:ShowScenesConfig",
            "centerart.commands:scenes_show",
            "contact sheet: RGB | true depth | realistic depth | masks | heatmaps, poses as axes",
        ),
    },
    "train": {
        "decoder": Command(
            "centerart.training.train_decoder:TrainDecoderConfig",
            "centerart.commands:train_decoder",
            "auto-decoder training of the SGDF decoder",
        ),
        "encoder": Command(
            "centerart.training.train_encoder:TrainEncoderConfig",
            "centerart.commands:train_encoder",
            "RGB-D encoder training on rendered scenes (targets: the decoder's shape codes)",
        ),
    },
    "decoder": {
        "show": Command(
            "centerart.viz.decoder_sheet:ShowDecoderConfig",
            "centerart.commands:decoder_show",
            "reconstructions with top grasps at several joint states",
        ),
    },
    "encoder": {
        "show": Command(
            "centerart.viz.encoder_sheet:ShowEncoderConfig",
            "centerart.commands:encoder_show",
            "encoder predictions (heatmap, peaks, poses, joint axes) next to the ground truth",
        ),
    },
    "eval": {
        "decoder": Command(
            "centerart.evaluation.decoder_eval:EvalDecoderConfig",
            "centerart.commands:eval_decoder",
            "decoder shape/grasp/physics metrics per split",
        ),
        "scenes": Command(
            "centerart.evaluation.scene_eval:EvalScenesConfig",
            "centerart.commands:eval_scenes",
            "closed-loop evaluation: predicted grasps executed in physics on held-out scenes (SR, RSR, report)",
        ),
        "compare": Command(
            "centerart.evaluation.paired:CompareEvalsConfig",
            "centerart.commands:eval_compare",
            "pair two scene evaluations object by object: which objects only one opens, with sign tests",
        ),
    },
    "predict": {
        "": Command(
            "centerart.predict:PredictConfig",
            "centerart.commands:predict",
            "objects, joints, meshes and ranked grasps from one RGB-D image (default: a bundled example)",
        )
    },
    "demo": {
        "": Command(
            "centerart.demo:DemoConfig",
            "centerart.commands:demo",
            "the main job on its built-in default (see README quick start)",
        )
    },
    "recipe": {
        "": Command(
            "centerart.recipe.config:RecipeConfig",
            "centerart.commands:recipe",
            "objects -> labels -> SDF -> decoder -> scenes -> encoder -> evaluation in one resumable command",
            default="centerart.recipe.config:cli_default",
        )
    },
    "slices": {
        "next": Command(
            "centerart.recipe.slices:SlicesNextConfig",
            "centerart.commands:slices_next",
            "train the encoder one slice further (new scenes, same run, one ledger line); resumable",
        ),
        "decoder": Command(
            "centerart.recipe.decoder_slices:DecoderSlicesConfig",
            "centerart.commands:slices_decoder",
            "train the SGDF decoder one slice further (same objects, more steps, one ledger line); resumable",
        ),
        "status": Command(
            "centerart.recipe.slices:SlicesStatusConfig",
            "centerart.commands:slices_status",
            "a sliced run's plan and ledger (validation figures per slice); --plot draws its learning curve",
        ),
        "replay": Command(
            "centerart.recipe.slices:SlicesReplayConfig",
            "centerart.commands:slices_replay",
            "remake a sliced run's state from its ledger and check it equals the committed one",
        ),
    },
    "view": {
        "": Command(
            "centerart.viz.viewer:ViewConfig",
            "centerart.commands:view",
            "interactive 3-D viewer of a prediction folder, in a web browser",
        )
    },
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
    try:
        # Parsing inside the try: configs check their values in __post_init__ and raise CenterArtError there.
        default = _resolve(cmd.default)(argv) if cmd.default else None
        cfg = tyro.cli(_resolve(cmd.config), args=argv, prog=prog, description=cmd.help, default=default)
        flush_denormals()  # before any torch work starts threads (utils/torch_cpu.py says why)
        _resolve(cmd.run)(cfg)
    except CenterArtError as err:
        print(f"centerart: error: {err}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("centerart: interrupted; finished items are kept, rerun the same command to resume", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
