"""Adopt a finished decoder step from another recipe run: ``centerart recipe --decoder-from RUN``.

Why: the ``small`` decoder trains for one to two hours on 2 CPU cores and its encoder for another hour; a machine
that keeps only the repository between sessions cannot resume such a run from its disk. The decoder can be
trained in one session and kept (``RUN/manifest.json`` and the top-level files of ``RUN/decoder/``), and a later
run regenerates the data steps (they are seeded and deterministic) and adopts it instead of training again.

Adoption is refused unless the source's decoder step finished, with the same settings as this run plans (the
resource fields aside, as when resuming), and unless the checkpoint's training objects are this run's objects by
content fingerprint (:mod:`centerart.assets.fingerprint`). Nothing is written before every check has passed; the
folder is copied atomically, then the source's record enters this run's manifest with ``adopted_from`` added.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from centerart.assets.fingerprint import fingerprint_folders
from centerart.errors import CenterArtError
from centerart.recipe.steps import Paths
from centerart.utils.atomic import atomic_directory

OPTION = "--decoder-from"
#: What a decoder step leaves at the top of its folder that later steps read (the Lightning checkpoints and logs
#: are only for resuming its training and are not adopted).
REQUIRED_FILES = ("decoder.pt", "split.json")


def source_record(source: Path) -> dict:
    """The finished decoder record of the recipe run at ``source`` (its folder must hold ``manifest.json`` and
    ``decoder/decoder.pt`` + ``decoder/split.json``)."""
    path = Path(source) / "manifest.json"
    if not path.is_file():
        raise CenterArtError(f"{OPTION} {source}: no manifest.json; name the output folder of a recipe run")
    try:
        manifest = json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as err:
        raise CenterArtError(f"{OPTION} {path}: damaged ({err})") from None
    record = manifest.get("steps", {}).get("decoder") if isinstance(manifest, dict) else None
    if manifest.get("stage") != "recipe" or not isinstance(record, dict) or record.get("status") != "done":
        raise CenterArtError(f"{OPTION} {path}: holds no finished decoder step of a recipe run")
    for name in REQUIRED_FILES:
        if not (Path(source) / "decoder" / name).is_file():
            raise CenterArtError(f"{OPTION} {source}: decoder/{name} is missing")
    return record


def check_training_objects(checkpoint: Path, objects: Path) -> None:
    """The checkpoint trained on this run's objects: every recorded fingerprint matches the folder of that id."""
    import torch  # here, not at the top: the command line's --help and checks stay fast

    try:
        recorded = torch.load(checkpoint, map_location="cpu", weights_only=True).get("training_objects")
    except Exception as err:  # a damaged or foreign file: torch raises many kinds
        raise CenterArtError(f"{OPTION} {checkpoint}: not a readable decoder checkpoint ({err})") from None
    if not isinstance(recorded, dict) or not recorded:
        raise CenterArtError(f"{OPTION} {checkpoint}: records no training objects; cannot check it belongs here")
    differ = objects_differing(recorded, objects)
    if differ:
        raise CenterArtError(
            f"{OPTION} {checkpoint}: trained on other objects than {objects} holds ({', '.join(differ[:5])}"
            f"{', ...' if len(differ) > 5 else ''}); run the data steps with the source run's options"
        )


def objects_differing(recorded: dict[str, str | None], objects: Path) -> list[str]:
    """The ids of ``recorded`` (id -> content fingerprint) whose folder in ``objects`` has another fingerprint (or
    none), sorted."""
    here = fingerprint_folders({oid: Path(objects) / oid for oid in recorded})
    return sorted(oid for oid, fp in recorded.items() if fp is None or here[oid] != fp)


def adopt_decoder(source: Path, record: dict, paths: Paths, changed: list[str]) -> dict:
    """Copy the source run's decoder into ``paths.decoder`` and return the record for this run's manifest.

    ``record``: the source's decoder record (:func:`source_record`); ``changed``: the settings in which it differs
    from this run's plan (computed by the runner, as for resuming); any difference refuses the adoption.
    """
    source = Path(source).resolve()
    if changed:
        raise CenterArtError(
            f"{OPTION} {source}: its decoder was made with other settings ({', '.join(changed[:6])}); "
            "use the same options"
        )
    check_training_objects(source / "decoder" / "decoder.pt", paths.objects)
    with atomic_directory(paths.decoder) as tmp:
        for f in sorted((source / "decoder").iterdir()):
            if f.is_file() and not f.name.startswith("."):  # decoder.pt, its critic, split, config, metrics
                shutil.copy2(f, tmp / f.name)
    return {**record, "adopted_from": str(source)}
