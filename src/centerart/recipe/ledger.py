"""The ledger of a sliced training run: ``RUN/ledger.jsonl``, one JSON line per finished slice.

A line holds everything that made the slice (its scene seeds and counts, steps, batch size, learning-rate scale,
code version) and what it measured (validation figures, wall times), plus the SHA-256 of the state and encoder
files it wrote. Replaying the lines from the run's plan remakes the files (:func:`centerart.recipe.slices.replay`).
The run folder is consistent when the ledger's last line names the state file that is there; anything else (a
damaged line, a state written by another slice, a state without a ledger) is one clear error.
"""

from __future__ import annotations

import json
from pathlib import Path

from centerart.errors import CenterArtError
from centerart.models.checkpoint_files import file_sha256
from centerart.utils.atomic import atomic_write_bytes, atomic_write_json

LEDGER = "ledger.jsonl"
STATE = "state.pt"
#: ``WORK/slice_k/calls.json``: the wall seconds of each call that trained part of slice k.
CALLS = "calls.json"
#: Fields every ledger line has, with their types.
LINE_FIELDS = {
    "slice": int,
    "seeds": dict,
    "data": dict,
    "steps": int,
    "first_step": int,
    "batch_size": int,
    "lr_scale": float,
    "images": int,
    "state_sha256": str,
    "validation": dict,
    "code_version": str,
}

#: Fields every line of a decoder run's ledger has (:mod:`centerart.recipe.decoder_slices`): its data is fixed by
#: the plan, so a line records the objects' fingerprint instead of scene seeds and images.
DECODER_LINE_FIELDS = {
    "slice": int,
    "steps": int,
    "first_step": int,
    "batch_size": int,
    "lr_scale": float,
    "objects_sha256": str,
    "state_sha256": str,
    "validation": dict,
    "code_version": str,
}


def read_ledger(run: Path, fields: dict[str, type] = LINE_FIELDS) -> list[dict]:
    """The ledger's lines in order (empty when the run has none yet); a damaged line (not JSON, a field of
    ``fields`` missing, a wrong slice number) is one error naming it."""
    path = Path(run) / LEDGER
    if not path.is_file():
        return []
    lines = []
    for number, text in enumerate(path.read_text().splitlines(), 1):
        if not text.strip():
            continue
        try:
            line = json.loads(text)
        except json.JSONDecodeError as err:
            raise CenterArtError(f"{path}: line {number} is not JSON ({err.msg})") from None
        _check_line(line, path, number, len(lines) + 1, fields)
        lines.append(line)
    return lines


def _check_line(line, path: Path, number: int, expected_slice: int, fields: dict[str, type]) -> None:
    if not isinstance(line, dict):
        raise CenterArtError(f"{path}: line {number} is not a ledger record")
    for name, kind in fields.items():
        value = line.get(name)
        ok = isinstance(value, kind) or (kind is float and isinstance(value, int) and not isinstance(value, bool))
        if not ok:
            raise CenterArtError(f"{path}: line {number} lacks {name!r} ({kind.__name__})")
    if line["slice"] != expected_slice:
        raise CenterArtError(f"{path}: line {number} records slice {line['slice']}, expected {expected_slice}")


def check_run_files(run: Path, lines: list[dict]) -> Path | None:
    """``RUN/state.pt`` when it is the state the ledger's last line wrote (None for a run with no slice yet).

    Raises:
        CenterArtError: a state without a ledger, a ledger without its state, or a state another slice wrote.
    """
    state = Path(run) / STATE
    if not lines:
        if state.exists():
            raise CenterArtError(f"{state}: a training state without ledger lines; restore {LEDGER} or remove it")
        return None
    if not state.is_file():
        raise CenterArtError(f"{state}: missing, but {LEDGER} records {len(lines)} slices; restore it (git)")
    if file_sha256(state) != lines[-1]["state_sha256"]:
        raise CenterArtError(
            f"{state}: not the state slice {lines[-1]['slice']} of {LEDGER} wrote (SHA-256 differs); "
            "restore the pair from git"
        )
    return state


def append_line(run: Path, lines: list[dict], line: dict) -> None:
    """Write the ledger with ``line`` appended, atomically (a crash leaves the old ledger)."""
    text = "".join(json.dumps(x, sort_keys=True) + "\n" for x in [*lines, line])
    atomic_write_bytes(Path(run) / LEDGER, text.encode())


def add_call_wall(work_slice: Path, wall: dict[str, float]) -> dict:
    """Record one call's wall seconds (``{"data": s, "train": s}``) in ``WORK/slice_k/calls.json`` and return
    the slice's totals so far, ``{"calls": n, "wall_s": {stage: seconds}}``.

    A slice stopped by ``--max-minutes`` or ``--stop-after`` is finished by later calls, often in other sessions;
    its ledger line must state what the whole slice cost, not the last call's share, so each call that returns adds
    its own (a call killed before it returns leaves only its saved progress, and its time is not counted).
    """
    path = Path(work_slice) / CALLS
    try:
        calls = json.loads(path.read_text()) if path.is_file() else []
    except json.JSONDecodeError as err:
        raise CenterArtError(f"{path}: not JSON ({err.msg}); remove it to restart the slice's time count") from None
    calls.append({k: round(float(v), 1) for k, v in wall.items()})
    atomic_write_json(path, calls)
    stages = sorted({k for call in calls for k in call})
    return {"calls": len(calls), "wall_s": {k: round(sum(c.get(k, 0.0) for c in calls), 1) for k in stages}}
