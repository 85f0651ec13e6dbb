"""Fuzz table: damaged inputs of every kind the project reads, and bad arguments, run through the CLI in-process.

Every case must end with exit code 2 and one ``centerart: error: ...`` line that names the input (a file name or an
option), with no traceback, and must leave nothing half-written (the output it names does not exist afterwards).
A case is (id, builder, name, leftovers): the builder copies what it damages into the case's folder and returns
the command's arguments; ``name`` must appear in the message; ``leftovers`` are paths (relative to the case's
folder) that must not exist afterwards.

Set ``CENTERART_FUZZ_LOG=file.jsonl`` to append each case's exit code and whether a traceback escaped (used for
the before / after table of issue 16).
"""

from __future__ import annotations

import json
import os
import shutil
import sys
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
import torch
from PIL import Image as PILImage

from centerart.cli import main
from centerart.models.checkpoint import default_checkpoint
from centerart.models.grasp_critic import critic_path

from . import damage as d


@dataclass(frozen=True)
class Case:
    id: str
    build: Callable  # (FuzzInputs, case folder) -> argv
    name: str  # must appear in the error message
    leftovers: tuple[str, ...] = ("out",)


def _obj(fx, tmp: Path) -> Path:
    return fx.copy(fx.object_dir, tmp / "objects" / fx.object_dir.name)


SHOW = ["--states", "1", "--image-width", "64", "--image-height", "48"]


def objects_show(damage: Callable[[Path], Path]):
    """`objects show` on the object after ``damage(object folder)``."""

    def build(fx, tmp):
        damage(_obj(fx, tmp))
        return ["objects", "show", str(tmp / "objects"), "--out", str(tmp / "out" / "x.png"), *SHOW]

    return build


def objects_resume(damage: Callable[[Path], Path]):
    """`objects generate` resuming into a folder that holds the damaged object."""

    def build(fx, tmp):
        damage(_obj(fx, tmp))
        return ["objects", "generate", "--category", "microwave", "--count", "1", "--out", str(tmp / "objects"),
                "--workers", "1"]  # fmt: skip

    return build


def grasps_generate(damage: Callable[[Path], Path]):
    def build(fx, tmp):
        damage(_obj(fx, tmp))
        return ["grasps", "generate", "--objects", str(tmp / "objects"), "--out", str(tmp / "out"), "--states", "1",
                "--per-state", "1", "--max-trials", "2", "--max-candidates", "20", "--workers", "1"]  # fmt: skip

    return build


def sdf_generate(damage: Callable[[Path], Path], labels: bool = False):
    def build(fx, tmp):
        damage(_obj(fx, tmp))
        grasps = tmp / "grasps"
        fx.copy(fx.labels_dir, grasps) if labels else grasps.mkdir()
        damage_labels = getattr(build, "labels_damage", None)
        if damage_labels:
            damage_labels(grasps / "microwave_0000" / "state_00.npz")
        return ["sdf", "generate", "--objects", str(tmp / "objects"), "--grasps", str(grasps), "--out",
                str(tmp / "out"), "--points", "600", "--states", "1", "--workers", "1"]  # fmt: skip

    return build


def sdf_with_labels(damage_labels: Callable[[Path], Path]):
    build = sdf_generate(lambda p: p, labels=True)
    build.labels_damage = damage_labels
    return build


def mesh(fn):
    return lambda obj: fn(d.target_mesh(obj))


def urdf(xpath: str, attribute: str, value: str):
    return lambda obj: d.set_xml(obj / "mobility.urdf", xpath, attribute, value)


def meta(keys: list, value):
    return lambda obj: d.set_json(obj / "meta.json", keys, value)


def nan_vertex(path: Path) -> Path:
    path.write_text(path.read_text().replace("v 0.00000000 0.00000000", "v nan 0.00000000", 1))
    return path


def faces_out_of_range(path: Path) -> Path:
    path.write_text(path.read_text() + "f 1 2 99999\n")
    return path


TRAIN_DECODER = ["--preset", "tiny", "--epochs", "1", "--batch-items", "2", "--points-per-item", "64",
                 "--min-items-per-epoch", "2", "--no-progress"]  # fmt: skip


def train_decoder(damage_sdf=None, ckpt=None, extra=()):
    """`train decoder` on a copy of the SDF folder (one file damaged) or with a damaged OUT/lightning/last.ckpt."""

    def build(fx, tmp):
        data = fx.copy(fx.sdf_dir, tmp / "sdf")
        if damage_sdf:
            damage_sdf(data / "box_000" / "state_00.npz")
        if ckpt:
            (tmp / "out" / "lightning").mkdir(parents=True)
            ckpt(tmp / "out" / "lightning" / "last.ckpt")
        return ["train", "decoder", "--data", str(data), "--out", str(tmp / "out"), *TRAIN_DECODER, *extra]

    return build


def torch_file(blob):
    def write(path: Path) -> Path:
        torch.save(blob, path)
        return path

    return write


def shipped_decoder(fn):
    def write(path: Path) -> Path:
        shutil.copy(default_checkpoint(), path)
        return fn(path)

    return write


def decoder_show(ckpt):
    def build(fx, tmp):
        path = ckpt(fx, tmp / "decoder.pt")
        return ["decoder", "show", "--data", str(fx.sdf_dir), "--object", "box_000", "--checkpoint", str(path),
                "--out", str(tmp / "out" / "x.png"), "--states", "1", "--resolution", "16"]  # fmt: skip

    return build


#: A decoder with its grasp critic beside it: the file shipped from session 13 to 18, kept with its recipe run (the
#: decoder shipped since has none).
CRITIC_DECODER = Path(__file__).resolve().parents[2] / "benchmarks/results/recipe_cw1e-2/decoder/decoder.pt"


def with_critic(damage):
    """A decoder with its grasp critic beside it, the critic damaged."""

    def write(fx, path: Path) -> Path:
        shutil.copy(CRITIC_DECODER, path)
        damage(Path(shutil.copy(critic_path(CRITIC_DECODER), critic_path(path))))
        return path

    return write


def nocodes(fx, path: Path) -> Path:
    return Path(shutil.copy(fx.decoder_nocodes, path))


def damaged_decoder(fn):
    return lambda fx, path: shipped_decoder(fn)(path)


def scenes_generate(*extra, objects=True):
    def build(fx, tmp):
        args = ["scenes", "generate", "--objects", str(fx.object_dir.parent), "--out", str(tmp / "out"), "--count",
                "1", "--views-per-scene", "1", "--depth", "true", "--intrinsics", "tiny", "--layout", "single",
                "--workers", "1"]  # fmt: skip
        return [*args, *(e(fx, tmp) if callable(e) else e for e in extra)]

    return build


def out_file(argv_builder):
    """The command with ``--out`` naming an existing file."""

    def build(fx, tmp):
        argv = argv_builder(fx, tmp)
        (tmp / "out").write_text("precious")
        return argv

    return build


def plain(*argv):
    return lambda fx, tmp: [a(fx, tmp) if callable(a) else a for a in argv]


def scene_copy(damage, target: str):
    """A copy of the scene folder with ``target`` (relative to scene_000000) damaged; returns the folder."""

    def make(fx, tmp):
        scenes = fx.copy(fx.scenes_dir, tmp / "scenes")
        damage(scenes / "scene_000000" / target)
        return str(scenes)

    return make


VIEW = "views/00"


def predict(extra=(), **replaced):
    """`predict` on the bundled example with inputs (rgb, depth, intrinsics, encoder) replaced by
    ``fn(case folder, original) -> path``."""
    from centerart.models.encoder.checkpoint import default_encoder
    from centerart.predict import EXAMPLE_DIR

    def build(fx, tmp):
        paths = {
            "rgb": EXAMPLE_DIR / "rgb.png",
            "depth": EXAMPLE_DIR / "depth.png",
            "intrinsics": EXAMPLE_DIR / "intrinsics.json",
            "encoder": default_encoder(),
        }
        for key, fn in replaced.items():
            paths[key] = fn(tmp, paths[key])
        args = [f"--{k}={v}" for k, v in paths.items()]
        return ["predict", *args, "--out", str(tmp / "out"), "--no-meshes", *extra]

    return build


def copied(name: str, fn):
    def make(tmp: Path, src: Path) -> Path:
        dst = tmp / name
        shutil.copy(src, dst)
        return fn(dst)

    return make


def written(name: str, writer):
    def make(tmp: Path, src: Path) -> Path:
        dst = tmp / name
        writer(dst)
        return dst

    return make


def intrinsics_with(keys: list, value):
    return copied("intrinsics.json", lambda p: d.set_json(p, keys, value))


def npy(array):
    return written("depth.npy", lambda p: np.save(p, array))


def png8(array):
    """An 8-bit depth PNG (a visualisation, not metric depth)."""
    return written("depth8.png", lambda p: PILImage.fromarray(array).save(p))


def eval_scenes(scenes, *extra, out_setup=None):
    def build(fx, tmp):
        folder = scenes(fx, tmp) if callable(scenes) else scenes
        if out_setup:
            out_setup(fx, tmp, folder)
        return ["eval", "scenes", "--scenes", str(folder), "--out", str(tmp / "out"), "--max-scenes", "1",
                "--no-progress", *extra]  # fmt: skip

    return build


def damaged_record(fx, tmp, folder):
    from centerart.evaluation.scene_eval import set_key

    record = tmp / "out" / "records" / set_key(Path(folder)) / "scene_000000.json"
    record.parent.mkdir(parents=True)
    record.write_text('{"scene": "scene_000000", "rows": [')


def train_encoder(scenes, *extra):
    def build(fx, tmp):
        folder = scenes(fx, tmp) if callable(scenes) else scenes
        more = [e(fx, tmp) if callable(e) else e for e in extra]
        return ["train", "encoder", "--scenes", str(folder), "--out", str(tmp / "out"), "--preset", "tiny",
                "--epochs", "1", "--batch-size", "1", "--no-progress", *more]  # fmt: skip

    return build


def view(make):
    return lambda fx, tmp: ["view", make(fx, tmp), "--port", "0"]


def prediction_with(text: str):
    def make(fx, tmp):
        folder = fx.copy(fx.prediction_dir, tmp / "prediction")
        (folder / "predictions.json").write_text(text)
        return str(folder)

    return make


def png_random(path: Path) -> Path:
    return d.random_bytes(path)


VALID_PREDICTIONS = {"format": "centerart-predictions", "version": 1,
                     "image": {"width": 64, "height": 48, "K": [[50, 0, 32], [0, 50, 24], [0, 0, 1]]}}  # fmt: skip
#: A well-formed Lightning checkpoint of some other model.
OTHER_MODEL = {"pytorch-lightning_version": "2.6.6", "epoch": 3, "global_step": 10, "loops": {},
               "optimizer_states": [], "state_dict": {"net.weight": torch.zeros(2, 2)}}  # fmt: skip
DOOR = "door_0-door.obj"
JOINT = "//joint[@type='revolute']"

# fmt: off
CASES = [
    # ---------------------------------------------------------------- object folders
    Case("obj-empty-door-mesh", objects_show(mesh(d.empty)), DOOR),
    Case("obj-random-bytes-door-mesh", sdf_generate(mesh(d.random_bytes)), DOOR),
    Case("obj-truncated-door-mesh", objects_show(mesh(lambda p: d.truncate(p, 0.4))), DOOR),
    Case("obj-nan-vertex", objects_show(mesh(nan_vertex)), DOOR),
    Case("obj-face-index-out-of-range", objects_show(mesh(faces_out_of_range)), DOOR),
    Case("obj-empty-door-mesh-sdf", sdf_generate(mesh(d.empty)), DOOR),
    Case("urdf-truncated", objects_show(lambda o: d.truncate(o / "mobility.urdf")), "mobility.urdf"),
    Case("urdf-random-bytes", objects_show(lambda o: d.random_bytes(o / "mobility.urdf")), "mobility.urdf"),
    Case("urdf-nan-joint-origin", grasps_generate(urdf(f"{JOINT}/origin", "xyz", "nan 0 0")), "mobility.urdf"),
    Case("urdf-nan-joint-origin-sdf", sdf_generate(urdf(f"{JOINT}/origin", "xyz", "nan 0 0")), "mobility.urdf"),
    Case("urdf-nan-visual-origin", objects_show(urdf("//visual/origin", "xyz", "0 nan 0")), "mobility.urdf"),
    Case("urdf-nan-inertial-origin", sdf_generate(urdf("//inertial/origin", "rpy", "0 0 nan")), "mobility.urdf"),
    Case("urdf-inf-joint-limit", objects_show(urdf(f"{JOINT}/limit", "upper", "inf")), "mobility.urdf"),
    Case("urdf-zero-joint-axis", objects_show(urdf(f"{JOINT}/axis", "xyz", "0 0 0")), "mobility.urdf"),
    Case("urdf-nan-mass", grasps_generate(urdf("//inertial/mass", "value", "nan")), "mobility.urdf"),
    Case("urdf-negative-mass", grasps_generate(urdf("//inertial/mass", "value", "-5")), "mobility.urdf"),
    Case("urdf-nan-inertia", grasps_generate(urdf("//inertial/inertia", "ixx", "nan")), "mobility.urdf"),
    Case("urdf-text-in-number", objects_show(urdf(f"{JOINT}/origin", "xyz", "abc 0 0")), "mobility.urdf"),
    Case("urdf-huge-origin", objects_show(urdf(f"{JOINT}/origin", "xyz", "1e30 0 0")), "mobility.urdf"),
    Case("urdf-nan-mesh-scale", objects_show(urdf("//visual/geometry/mesh", "scale", "nan 1 1")), "mobility.urdf"),
    Case("urdf-negative-box-size", grasps_generate(urdf("//collision/geometry/box", "size", "-1 1 1")),
         "mobility.urdf"),
    Case("meta-random-bytes", objects_show(lambda o: d.random_bytes(o / "meta.json")), "meta.json"),
    Case("meta-not-an-object", objects_show(meta([], [1, 2])), "meta.json"),
    Case("meta-target-joint-number", objects_show(meta(["target_joint"], 5)), "meta.json"),
    Case("meta-generator-record-resumed", objects_resume(meta(["generator"], {"name": "centerart", "record": 3})),
         "meta.json", ()),
    # ---------------------------------------------------------------- --out naming an existing file
    Case("out-file-objects-generate", out_file(plain("objects", "generate", "--category", "microwave", "--count", "1",
         "--out", lambda fx, t: str(t / "out"), "--workers", "1")), "--out", ()),
    Case("out-file-grasps-generate", out_file(grasps_generate(lambda p: p)), "--out", ()),
    Case("out-file-sdf-generate", out_file(sdf_generate(lambda p: p)), "--out", ()),
    Case("out-file-scenes-generate", out_file(scenes_generate()), "--out", ()),
    Case("out-file-train-decoder", out_file(train_decoder()), "--out", ()),
    Case("out-file-predict", out_file(predict()), "--out", ()),
    Case("out-file-recipe", out_file(plain("recipe", "--preset", "tiny", "--out", lambda fx, t: str(t / "out"))),
         "--out", ()),
    # ---------------------------------------------------------------- arguments
    Case("arg-radius-negative", scenes_generate("--radius-m", "-1", "-2"), "--radius-m"),
    Case("arg-radius-reversed", scenes_generate("--radius-m", "3", "1"), "--radius-m"),
    Case("arg-elevation-out-of-range", scenes_generate("--elevation-deg", "10", "200"), "--elevation-deg"),
    Case("arg-objects-count-negative", plain("objects", "generate", "--count", "-1", "--out",
         lambda fx, t: str(t / "out")), "--count"),
    Case("arg-objects-workers-negative", plain("objects", "generate", "--count", "0", "--workers", "-1", "--out",
         lambda fx, t: str(t / "out")), "--workers"),
    Case("arg-grasps-states-zero", plain("grasps", "generate", "--objects", lambda fx, t: str(fx.object_dir),
         "--out", lambda fx, t: str(t / "out"), "--states", "0"), "--states"),
    Case("arg-sdf-points-zero", plain("sdf", "generate", "--objects", lambda fx, t: str(fx.object_dir), "--grasps",
         lambda fx, t: str(fx.labels_dir), "--out", lambda fx, t: str(t / "out"), "--points", "0"), "--points"),
    Case("arg-train-decoder-epochs-zero", train_decoder(extra=("--epochs", "0")), "--epochs"),
    Case("arg-train-decoder-batch-zero", train_decoder(extra=("--batch-items", "0")), "--batch-items"),
    Case("arg-train-decoder-code-weight-negative", train_decoder(extra=("--code-weight", "-0.01")), "--code-weight"),
    Case("arg-train-decoder-code-weight-nan", train_decoder(extra=("--code-weight", "nan")), "--code-weight"),
    Case("arg-train-encoder-batch-zero", train_encoder(lambda fx, t: str(fx.scenes_dir), "--batch-size", "0"),
         "--batch-size"),
    Case("arg-recipe-workers-zero", plain("recipe", "--preset", "tiny", "--out", lambda fx, t: str(t / "out"),
         "--workers", "0"), "--workers"),
    Case("arg-recipe-decoder-from-missing", plain("recipe", "--preset", "tiny", "--out", lambda fx, t: str(t / "out"),
         "--decoder-from", lambda fx, t: str(t / "nowhere")), "--decoder-from"),
    Case("arg-recipe-code-weight-negative", plain("recipe", "--preset", "tiny", "--out", lambda fx, t: str(t / "out"),
         "--decoder.code-weight", "-1"), "--decoder.code-weight"),
    Case("arg-recipe-same-seeds", plain("recipe", "--preset", "tiny", "--out", lambda fx, t: str(t / "out"),
         "--seed", "5", "--test-seed", "5"), "--test-seed"),
    Case("arg-eval-scenes-workers-zero", eval_scenes(lambda fx, t: str(fx.scenes_dir), "--workers", "0"),
         "--workers"),
    Case("arg-predict-depth-scale-negative", predict(extra=("--depth-scale", "-1")), "--depth-scale"),
    Case("arg-objects-show-states-zero", plain("objects", "show", lambda fx, t: str(fx.object_dir), "--out",
         lambda fx, t: str(t / "out" / "x.png"), "--states", "0"), "--states"),
    Case("arg-scenes-show-tile-zero", plain("scenes", "show", lambda fx, t: str(fx.scenes_dir), "--out",
         lambda fx, t: str(t / "out" / "x.png"), "--tile-width", "0"), "--tile-width"),
    # ---------------------------------------------------------------- checkpoints
    Case("ckpt-nocodes-decoder-show", decoder_show(nocodes), "decoder.pt"),
    Case("ckpt-nocodes-eval-decoder", plain("eval", "decoder", "--data", lambda fx, t: str(fx.sdf_dir), "--objects",
         lambda fx, t: str(fx.object_dir), "--checkpoint", lambda fx, t: str(nocodes(fx, t / "decoder.pt")),
         "--out", lambda fx, t: str(t / "out"), "--no-physics"), "decoder.pt"),
    Case("ckpt-nocodes-scenes-generate", scenes_generate("--decoder-checkpoint",
         lambda fx, t: str(nocodes(fx, t / "decoder.pt"))), "decoder.pt"),
    Case("ckpt-truncated-decoder-show", decoder_show(damaged_decoder(d.truncate)), "decoder.pt"),
    Case("ckpt-random-decoder-show", decoder_show(damaged_decoder(d.random_bytes)), "decoder.pt"),
    Case("ckpt-empty-decoder-show", decoder_show(damaged_decoder(d.empty)), "decoder.pt"),
    Case("ckpt-codes-wrong-shape", decoder_show(lambda fx, p: torch_file({**torch.load(default_checkpoint(),
         weights_only=True), "codes": torch.zeros(3)})(p)), "decoder.pt"),
    Case("critic-random-decoder-show", decoder_show(with_critic(d.random_bytes)), "decoder.pt.critic.json"),
    Case("critic-truncated-decoder-show", decoder_show(with_critic(d.truncate)), "decoder.pt.critic.json"),
    Case("critic-nan-weights-decoder-show", decoder_show(with_critic(lambda p: d.set_json(p, ["weights", 0], "nan"))),
         "decoder.pt.critic.json"),
    Case("critic-of-another-decoder-show", decoder_show(with_critic(lambda p: d.set_json(p, ["info",
         "decoder_sha256"], "0" * 64))), "decoder.pt.critic.json"),
    Case("ckpt-random-predict-encoder", predict(encoder=copied("encoder.pt", d.random_bytes)), "encoder.pt"),
    Case("ckpt-truncated-predict-encoder", predict(encoder=copied("encoder.pt", d.truncate)), "encoder.pt"),
    Case("ckpt-lightning-truncated", train_decoder(ckpt=shipped_decoder(d.truncate)), "last.ckpt",
         ("out/config.json", "out/split.json", "out/logs")),
    Case("ckpt-lightning-random", train_decoder(ckpt=d.random_bytes), "last.ckpt",
         ("out/config.json", "out/split.json", "out/logs")),
    Case("ckpt-lightning-empty", train_decoder(ckpt=d.empty), "last.ckpt",
         ("out/config.json", "out/split.json", "out/logs")),
    Case("ckpt-lightning-foreign-dict", train_decoder(ckpt=torch_file({"weights": torch.zeros(3)})), "last.ckpt",
         ("out/config.json", "out/split.json", "out/logs")),
    Case("ckpt-lightning-is-decoder-pt", train_decoder(ckpt=shipped_decoder(lambda p: p)), "last.ckpt",
         ("out/config.json", "out/split.json", "out/logs")),
    Case("ckpt-lightning-other-model", train_decoder(ckpt=torch_file(OTHER_MODEL)), "last.ckpt",
         ("out/config.json", "out/split.json", "out/logs")),
    Case("ckpt-train-encoder-decoder-random", train_encoder(lambda fx, t: str(fx.scenes_dir), "--decoder",
         lambda fx, t: str(d.random_bytes(t / "decoder.pt"))), "decoder.pt"),
    # ---------------------------------------------------------------- .npz records
    Case("npz-labels-random-bytes", sdf_with_labels(d.random_bytes), "state_00.npz"),
    Case("npz-labels-truncated", sdf_with_labels(d.truncate), "state_00.npz"),
    Case("npz-labels-poses-wrong-shape", sdf_with_labels(lambda p: d.set_npz(p, "poses", np.zeros((3, 3)))),
         "state_00.npz"),
    Case("npz-labels-nan-poses", sdf_with_labels(lambda p: d.set_npz(p, "poses", np.full((3, 4, 4), np.nan))),
         "state_00.npz"),
    Case("npz-labels-poses-strings", sdf_with_labels(lambda p: d.set_npz(p, "poses", np.array(["a", "b"]))),
         "state_00.npz"),
    Case("npz-sdf-truncated", train_decoder(damage_sdf=d.truncate), "state_00.npz"),
    Case("npz-sdf-random-bytes", train_decoder(damage_sdf=d.random_bytes), "state_00.npz"),
    Case("npz-sdf-points-wrong-shape", train_decoder(damage_sdf=lambda p: d.set_npz(p, "points", np.zeros((600, 2)))),
         "state_00.npz"),
    Case("npz-sdf-points-strings", train_decoder(damage_sdf=lambda p: d.set_npz(p, "points", np.array(["x"] * 600))),
         "state_00.npz"),
    Case("npz-sdf-missing-key", train_decoder(damage_sdf=lambda p: d.set_npz(p, "sdf", None)), "state_00.npz"),
    Case("npz-sdf-nan-joint", train_decoder(damage_sdf=lambda p: d.set_npz(p, "q_normalized", np.nan)),
         "state_00.npz"),
    # ---------------------------------------------------------------- scenes: scene.json, labels.json, PNG images
    Case("scenes-show-labels-random", plain("scenes", "show", scene_copy(d.random_bytes, f"{VIEW}/labels.json"),
         "--out", lambda fx, t: str(t / "out" / "x.png")), "labels.json"),
    Case("scenes-show-rgb-truncated", plain("scenes", "show", scene_copy(d.truncate, f"{VIEW}/rgb.png"),
         "--out", lambda fx, t: str(t / "out" / "x.png")), "rgb.png"),
    Case("scenes-show-labels-K-string", plain("scenes", "show", scene_copy(lambda p: d.set_json(p, ["K"], "abc"),
         f"{VIEW}/labels.json"), "--out", lambda fx, t: str(t / "out" / "x.png")), "labels.json"),
    Case("train-encoder-labels-truncated", train_encoder(scene_copy(d.truncate, f"{VIEW}/labels.json")),
         "labels.json"),
    Case("train-encoder-rgb-random", train_encoder(scene_copy(png_random, f"{VIEW}/rgb.png")), "rgb.png"),
    Case("encoder-show-labels-objects-wrong-type", plain("encoder", "show", "--scenes",
         scene_copy(lambda p: d.set_json(p, ["objects"], 7), f"{VIEW}/labels.json"), "--out",
         lambda fx, t: str(t / "out" / "x.png")), "labels.json"),
    Case("eval-scenes-missing-folder", eval_scenes(lambda fx, t: str(t / "nope")), "nope"),
    Case("eval-scenes-garbage-folder", eval_scenes(lambda fx, t: str(d.random_bytes(t / "junk.bin").parent)),
         "no scenes"),
    Case("eval-scenes-scene-json-random", eval_scenes(scene_copy(d.random_bytes, "scene.json")), "scene.json"),
    Case("eval-scenes-scene-json-nan-pose", eval_scenes(scene_copy(lambda p: d.set_json(p, ["objects", 0,
         "world_T_object", 0, 3], float("nan")), "scene.json")), "scene.json"),
    Case("eval-scenes-scene-json-objects-string", eval_scenes(scene_copy(lambda p: d.set_json(p, ["objects"], "x"),
         "scene.json")), "scene.json"),
    Case("eval-scenes-damaged-record", eval_scenes(lambda fx, t: str(fx.scenes_dir), out_setup=damaged_record),
         "scene_000000.json", ()),
    # ---------------------------------------------------------------- predict inputs
    Case("predict-rgb-missing", predict(rgb=lambda t, s: t / "missing.png"), "missing.png"),
    Case("predict-rgb-random", predict(rgb=copied("rgb.png", d.random_bytes)), "rgb.png"),
    Case("predict-rgb-truncated", predict(rgb=copied("rgb.png", d.truncate)), "rgb.png"),
    Case("predict-depth-png-random", predict(depth=copied("depth.png", d.random_bytes)), "depth.png"),
    Case("predict-depth-png-8bit", predict(depth=png8(np.full((480, 640), 150, np.uint8))), "depth8.png"),
    Case("predict-depth-npy-random", predict(depth=written("depth.npy", d.random_bytes)), "depth.npy"),
    Case("predict-depth-npy-strings", predict(depth=npy(np.full((480, 640), "a"))), "depth.npy"),
    Case("predict-depth-npy-complex", predict(depth=npy(np.ones((480, 640), complex))), "depth.npy"),
    Case("predict-depth-npy-all-nan", predict(depth=npy(np.full((480, 640), np.nan, np.float32))), "depth"),
    Case("predict-intrinsics-random", predict(intrinsics=copied("intrinsics.json", d.random_bytes)), "intrinsics"),
    Case("predict-intrinsics-yaml-garbage", predict(intrinsics=written("camera.yaml", lambda p: p.write_text(
         "K: [1, 2\n  - : :"))), "camera.yaml"),
    Case("predict-intrinsics-nan-fx", predict(intrinsics=intrinsics_with(["K", 0, 0], float("nan"))), "intrinsics"),
    Case("predict-intrinsics-width-text", predict(intrinsics=intrinsics_with(["width"], "abc")), "intrinsics"),
    Case("predict-intrinsics-K-string", predict(intrinsics=intrinsics_with(["K"], "abc")), "intrinsics"),
    Case("predict-intrinsics-list", predict(intrinsics=written("k.json", lambda p: p.write_text("[1, 2]"))), "k.json"),
    Case("predict-gravity-zero", predict(extra=("--gravity", "0", "0", "0")), "--gravity"),
    Case("predict-gravity-nan", predict(extra=("--gravity", "nan", "1", "0")), "--gravity"),
    # ---------------------------------------------------------------- view
    Case("view-missing-folder", view(lambda fx, t: str(t / "nope")), "nope"),
    Case("view-predictions-random", view(prediction_with(d.RANDOM.decode("latin-1"))), "predictions.json"),
    Case("view-predictions-objects-int", view(prediction_with(json.dumps({**VALID_PREDICTIONS, "objects": 5}))),
         "predictions.json"),
]
# fmt: on


def run_cli(argv: list[str], capsys) -> tuple[int, str, bool]:
    """(exit code, stderr, whether an exception escaped main: a traceback for a user)."""
    escaped = False
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    except Exception:
        escaped = True
        code = 1
        print(traceback.format_exc(), end="", file=sys.stderr)
    err = capsys.readouterr().err
    return code, err, escaped or "Traceback" in err


def _log(case: Case, code: int, err: str, tb: bool) -> None:
    log = os.environ.get("CENTERART_FUZZ_LOG")
    if log:
        last = [line for line in err.strip().splitlines() if line.strip()][-1:] or [""]
        with open(log, "a") as f:
            f.write(json.dumps({"case": case.id, "code": code, "traceback": tb, "last": last[0][:300]}) + "\n")


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_damaged_input_is_one_clear_error(case: Case, fuzz_inputs, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv = case.build(fuzz_inputs, tmp_path)
    code, err, tb = run_cli(argv, capsys)
    _log(case, code, err, tb)
    assert not tb, err[-3000:]
    assert code == 2, err[-3000:]
    lines = [line for line in err.strip().splitlines() if line.strip()]
    errors = [line for line in lines if line.startswith("centerart: error:")]
    assert len(errors) == 1 and lines[-1] == errors[0], err[-3000:]
    assert case.name in errors[0], errors[0]
    assert "weights_only" not in err
    for rel in case.leftovers:
        assert not (tmp_path / rel).exists(), f"{rel} left behind"
    assert not list(tmp_path.rglob(".tmp-*")), "temporary files left behind"
