"""The test-set manifest of a scene evaluation: which objects (by content fingerprint) and states it holds, and
the refusal of any object a checkpoint was trained on (:mod:`centerart.evaluation.heldout`)."""

from __future__ import annotations

from pathlib import Path

from centerart.assets.fingerprint import object_fingerprint
from centerart.errors import CenterArtError
from centerart.evaluation.heldout import check_held_out, checkpoint_training_objects, training_overlap
from centerart.scenes.description import SceneDescription


def describe_set(folder: Path, scene_dirs: list[Path]) -> dict:
    """Objects (id -> fingerprint, category, folder) and per-scene object states of one scenes folder."""
    objects: dict[str, dict] = {}
    scenes = {}
    layouts = set()
    for d in scene_dirs:
        scene = SceneDescription.load(d / "scene.json")
        layouts.add(scene.layout)
        scenes[d.name] = [
            {"name": s.name, "object_id": s.object_id, "state": s.joint_state, "normalized": s.joint_state_normalized}
            for s in scene.objects
        ]
        for s in scene.objects:
            if not (Path(s.path) / "mobility.urdf").is_file():
                raise CenterArtError(f"{d / 'scene.json'}: object folder {s.path} is missing (scenes moved?)")
            key = f"{s.object_id}@{s.path}"
            if key not in objects:
                objects[key] = {"object_id": s.object_id, "category": s.category, "path": s.path,
                                "fingerprint": object_fingerprint(s.path)}  # fmt: skip
    if len(layouts) != 1:
        raise CenterArtError(f"{folder}: scenes of several layouts ({sorted(layouts)}); keep one layout per folder")
    return {"folder": str(Path(folder).resolve()), "layout": layouts.pop(), "objects": objects, "scenes": scenes}


def check_test_sets(
    folders, sets: dict[str, list[Path]], encoder: Path, decoder: Path, allow_training_objects: bool = False
) -> dict:
    """The test-set manifest (per set: layout, objects, states); raises when a set holds a training object,
    unless ``allow_training_objects`` (diagnostics), which records the overlap instead."""
    trained = [checkpoint_training_objects(decoder, "decoder"), checkpoint_training_objects(encoder, "encoder")]
    described, overlap = {}, []
    for folder, (name, dirs) in zip(folders, sets.items(), strict=True):
        info = describe_set(Path(folder), dirs)
        fingerprints = {o["object_id"]: o["fingerprint"] for o in info["objects"].values()}
        if allow_training_objects:
            overlap += [f"{name}: {line}" for line in training_overlap(fingerprints, trained)]
        else:
            check_held_out(fingerprints, trained, str(folder))
        described[name] = info
    return {
        "sets": described,
        "held_out": not overlap,
        "training_overlap": overlap,
        "checkpoints": {
            t.checkpoint.name: {"path": str(t.checkpoint), "training_objects": len(t.fingerprints) + len(t.ids_only)}
            for t in trained
        },
    }
