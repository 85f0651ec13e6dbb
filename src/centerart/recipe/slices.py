"""``centerart slices``: train the encoder across working periods, one slice at a time, with a ledger.

A run folder (``RUN``, committed to git) holds::

    RUN/run.json       the plan every slice shares (:class:`~centerart.recipe.slice_plan.SlicePlan`)
    RUN/ledger.jsonl   one line per finished slice (:mod:`centerart.recipe.ledger`)
    RUN/state.pt       weights, Adam moments and step after the last slice (:mod:`centerart.training.slice_training`)
    RUN/encoder.pt     the same weights as an encoder checkpoint (``centerart predict --encoder RUN/encoder.pt``)

A work folder (``WORK``, never committed: regenerated from seeds) holds the objects, the validation scenes and
each slice's scenes and progress. ``centerart slices next`` makes slice k = lines + 1: it renders the slice's
scenes (seeds from :func:`~centerart.recipe.slice_plan.slice_seeds`), continues ``RUN/state.pt`` for the slice's
steps (saving progress in ``WORK/slice_k/progress.pt`` every few minutes: an interrupted slice resumes), validates
on the fixed set, then writes the state, the encoder and the ledger line, in that order (a crash between them is
finished by the next call from ``WORK/slice_k/line.json``), and with ``--commit`` commits the run folder.
"""

from __future__ import annotations

import shutil
import subprocess
import time
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from centerart.errors import CenterArtError
from centerart.recipe.ledger import (
    DECODER_LINE_FIELDS,
    STATE,
    add_call_wall,
    append_line,
    check_run_files,
    read_ledger,
)
from centerart.recipe.slice_plan import SliceData, SlicePlan, plan_preset, slice_seeds
from centerart.utils.checks import at_least, positive
from centerart.utils.torch_cpu import use_cpu_threads

SAVE_EVERY_S = 300.0  # progress saved this often (and when a slice stops early)


@dataclass
class SlicesNextConfig:
    """Run the next slice of a sliced encoder training run (creates the run on first use)."""

    run: Path
    """Run folder (committed): run.json, ledger.jsonl, state.pt, encoder.pt."""
    work: Path = Path("runs/slices-work")
    """Work folder for data and progress (not committed; regenerated from seeds)."""
    preset: Literal["tiny", "small"] = "small"
    """Plan of a new run (ignored once RUN/run.json exists)."""
    init: Path | None = None
    """A new run starts from this encoder checkpoint instead of random weights (ignored once the run exists)."""
    seed_block: int = 0
    """Scene-seed block of a new run (ignored once the run exists); an --init made by a sliced run needs a
    block above that run's, so that no slice repeats the scenes its start (or the start's start) was trained on."""
    decoder: Path | None = None
    """A new run trains against this decoder checkpoint (e.g. a decoder run's ``decoder.pt``), copied into
    ``RUN/decoder.pt``, instead of the preset's (the shipped ``sgdf_small.pt``). Either way the objects per
    category follow from the decoder's training and held-out objects. An --init trained against another decoder
    is then a warm start (ignored once the run exists)."""
    shape_sdf: float = 0.0
    """Weight of a new run's decoded-shape loss term (``EncoderLossConfig.shape_sdf``: the regressed code judged
    through the frozen decoder; 0: none, as before it existed; ignored once the run exists)."""
    steps: int | None = None
    """Optimizer steps of this slice (default: the plan's)."""
    kitchen: int | None = None
    """Kitchen scenes of this slice (default: the plan's)."""
    single: int | None = None
    """Single-object scenes of this slice (default: the plan's)."""
    intrinsics: Literal["d415", "d415-half", "paper", "tiny"] | None = None
    """Camera of this slice's scenes (default: the plan's). d415-half renders at the small encoder's input size."""
    depth: Literal["true", "stereo", "stereo-model", "analytic"] | None = None
    """Realistic depth of this slice's scenes (default: the plan's). stereo-model: the full-size stereo sensor's
    measured errors drawn from the true depth, at any size (docs/scenes.md)."""
    lr_scale: float = 1.0
    """This slice's learning rate as a multiple of the plan's (lower it for the last slices of a run)."""
    stop_after: int | None = None
    """Stop after this many steps of the slice (progress is kept; rerun to resume)."""
    max_minutes: float = 0.0
    """Stop training after this much time in this call (0: no limit); rerun to resume."""
    workers: int | None = None
    """Scene rendering processes (default: all cores)."""
    loader_workers: int = 1
    threads: int = 0
    """torch CPU threads (0: torch default)."""
    commit: bool = False
    """git commit the run folder after the slice (the ledger line and the files it names)."""
    progress: bool = True

    def __post_init__(self):
        for name in ("steps", "kitchen", "single", "stop_after"):
            if getattr(self, name) is not None:
                at_least(f"--{name.replace('_', '-')}", getattr(self, name), 0 if name != "steps" else 1)
        positive("--lr-scale", self.lr_scale)
        for name in ("max_minutes", "loader_workers", "threads", "seed_block", "shape_sdf"):
            at_least(f"--{name.replace('_', '-')}", getattr(self, name), 0)


@dataclass
class SlicesStatusConfig:
    """Print a sliced run's plan and ledger."""

    run: Path
    plot: Path | None = None
    """Also draw the learning curve (each validation figure against the run's steps, one point per slice) into
    this PNG."""


@dataclass
class SlicesReplayConfig:
    """Replay a run's ledger from its plan into WORK and compare the weights with RUN/state.pt."""

    run: Path
    work: Path = Path("runs/slices-replay")
    workers: int | None = None
    threads: int = 0
    tolerance: float = 1e-4
    """Largest absolute weight difference accepted (float reordering across machines)."""
    progress: bool = True


# ---------------------------------------------------------------------------- the run's plan and decoder
def load_plan(run: Path, plan_class=SlicePlan):
    """``RUN/run.json`` as a ``plan_class`` (the encoder's :class:`SlicePlan`, or a decoder run's plan); None
    before the run's first call."""
    import json

    path = Path(run) / "run.json"
    if not path.is_file():
        return None
    try:
        return plan_class.from_dict(json.loads(path.read_text()))
    except (json.JSONDecodeError, AttributeError) as err:
        raise CenterArtError(f"{path}: damaged run plan ({err})") from None


def run_kind(run: Path) -> str:
    """``"decoder"`` for a decoder run (:mod:`centerart.recipe.decoder_slices`), else ``"encoder"``."""
    import json

    path = Path(run) / "run.json"
    try:
        kind = json.loads(path.read_text()).get("kind", "encoder") if path.is_file() else "encoder"
    except (json.JSONDecodeError, AttributeError) as err:
        raise CenterArtError(f"{path}: damaged run plan ({err})") from None
    return "decoder" if kind == "decoder" else "encoder"


def create_plan(
    run: Path, preset: str, init: Path | None, seed_block: int = 0, decoder: Path | None = None,
    shape_sdf: float = 0.0,
) -> SlicePlan:  # fmt: skip
    """A new run's plan from ``preset`` (its decoder replaced by a copy of ``decoder`` when given, its loss's
    decoded-shape weight set to ``shape_sdf``), the decoder pinned by SHA-256, written to ``RUN/run.json``."""
    from centerart.models.checkpoint_files import file_sha256
    from centerart.models.encoder.config import preset as encoder_preset
    from centerart.utils.atomic import atomic_write_json

    plan = plan_preset(preset)
    plan.encoder = encoder_preset(plan.encoder_preset).to_dict()  # today's defaults, kept for every slice
    source = Path(decoder) if decoder is not None else _repo_path(plan.decoder)
    if decoder is None and not source.is_file():
        raise CenterArtError(f"{source}: the plan's decoder checkpoint is missing")
    # Read before anything is copied (a bad --decoder leaves no run folder), and from the shipped file too: it was
    # made from 8 objects per category until session 19 and from 24 since, and a plan keeps the count it was made with.
    plan.objects_count = decoder_objects_per_category(source)
    if decoder is not None:
        # A copy in the run folder, as for --init: a decoder run rewrites its decoder.pt at every slice.
        plan.decoder = _copy_into_run(source, Path(run) / "decoder.pt")
    plan.decoder_sha256 = file_sha256(source)
    plan.seed_block = seed_block
    plan.loss = {**plan.loss, "shape_sdf": float(shape_sdf)}
    if init is not None:
        if not Path(init).is_file():
            raise CenterArtError(f"--init {init}: no such encoder checkpoint")
        _check_seed_block(Path(init), seed_block)
        plan.init_other_decoder = decoder is not None and _trained_against(Path(init)) != plan.decoder_sha256
        # A copy in the run folder: the file it came from (the shipped encoder) may be replaced by this very run.
        plan.init, plan.init_sha256 = _copy_into_run(Path(init), Path(run) / "init.pt"), file_sha256(init)
    atomic_write_json(Path(run) / "run.json", plan.to_dict())
    return plan


def _copy_into_run(source: Path, target: Path) -> str:
    """Copy ``source`` to ``target`` (in the run folder); returns how the plan names the copy."""
    target.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(source, target)
    return _plan_path(target)


def _trained_against(encoder: Path) -> str | None:
    """SHA-256 of the decoder an encoder checkpoint was trained against (None when it does not say)."""
    import torch

    blob = torch.load(encoder, map_location="cpu", weights_only=True)
    return (blob.get("decoder") or {}).get("sha256") if isinstance(blob, dict) else None


def decoder_objects_per_category(decoder: Path) -> int:
    """Objects per category the decoder's training and held-out objects were drawn from (``category_NNNN``
    names, the first N per category of one seed, as every recipe and decoder run makes them)."""
    import torch

    if not decoder.is_file():
        raise CenterArtError(f"--decoder {decoder}: no such decoder checkpoint")
    try:
        blob = torch.load(decoder, map_location="cpu", weights_only=True)
        names = list(blob["training_objects"]) + list(blob["split"]["heldout_objects"])
        counts = Counter(name.rsplit("_", 1)[0] for name in names)
        indices = [int(name.rsplit("_", 1)[1]) for name in names]
    except Exception as err:  # any unreadable or foreign file: one line naming it
        raise CenterArtError(f"--decoder {decoder}: not a decoder checkpoint with its objects ({err})") from None
    if max(indices) + 1 != max(counts.values()):
        raise CenterArtError(f"--decoder {decoder}: its objects are not the first N of each category")
    return max(counts.values())


def _check_seed_block(init: Path, seed_block: int) -> None:
    """Refuse a new run whose scenes would repeat those the --init encoder was trained on in a sliced run."""
    import torch

    try:
        trained = (torch.load(init, map_location="cpu", weights_only=True).get("train_config") or {}).get("sliced_run")
    except Exception:  # a damaged file: new_state reports it (load_encoder's one-line error)
        return
    # Blocks grow along a lineage (each run takes a block above its start's), so a block above the start's is one
    # that no ancestor of it rendered either.
    block = int(trained.get("seed_block", 0)) if isinstance(trained, dict) else None
    if block is not None and block >= seed_block:
        raise CenterArtError(
            f"--init {init}: trained on slices of seed block {block}; pass --seed-block {block + 1} (or higher) so "
            "the new run renders scenes no encoder it came from was trained on"
        )


def _plan_path(path: Path) -> str:
    """How a plan names a file: relative to the source tree's root when inside it (portable), else absolute."""
    root = Path(__file__).resolve().parents[3]
    path = path.resolve()
    return str(path.relative_to(root)) if path.is_relative_to(root) else str(path)


def _repo_path(path: str) -> Path:
    """A plan path: absolute, or relative to the source tree's root (where the shipped weights live)."""
    p = Path(path)
    return p if p.is_absolute() else Path(__file__).resolve().parents[3] / p


def checked_decoder(plan: SlicePlan) -> Path:
    return _checked_file(plan.decoder, plan.decoder_sha256, "the decoder this run trains against")


def checked_init(plan: SlicePlan) -> Path | None:
    return None if plan.init is None else _checked_file(plan.init, plan.init_sha256, "the encoder this run began from")


def _checked_file(name: str, sha256: str, what: str) -> Path:
    from centerart.models.checkpoint_files import file_sha256

    path = _repo_path(name)
    if not path.is_file() or file_sha256(path) != sha256:
        raise CenterArtError(f"{path}: not {what} (missing or SHA-256 differs; check out the commit that made the run)")
    return path


# ---------------------------------------------------------------------------- data
def prepare_objects(plan: SlicePlan, work: Path, decoder: Path, workers: int | None) -> dict[str, Path]:
    """Generate the plan's objects in ``WORK/objects`` and link the decoder's training and held-out objects into
    ``WORK/split/{train,heldout}``, after checking each training object's content fingerprint."""
    import torch

    from centerart.assets.dataset import GenerateObjectsConfig, generate_objects
    from centerart.recipe.adopt import objects_differing
    from centerart.recipe.steps import link_objects

    objects = work / "objects"
    generate_objects(GenerateObjectsConfig(
        out=objects, category="all", count=plan.objects_count, seed=plan.objects_seed, variety=plan.variety,
        workers=workers,
    ))  # fmt: skip
    blob = torch.load(decoder, map_location="cpu", weights_only=True)
    recorded, heldout = dict(blob.get("training_objects") or {}), list(blob["split"]["heldout_objects"])
    differ = objects_differing(recorded, objects)
    if not recorded or differ:
        raise CenterArtError(
            f"{decoder}: its training objects are not the plan's objects (seed {plan.objects_seed}, "
            f"{plan.objects_count} per category): {', '.join(differ[:4]) or 'none recorded'}"
        )
    return link_objects(work, {"train": sorted(recorded), "heldout": heldout})


def render(objects: Path, out: Path, layout: str, count: int, views: int, seed: int, data, decoder, workers):
    """``centerart scenes generate`` of one set (resumable: finished scenes are kept); returns its view folders."""
    from centerart.scenes.dataset import GenerateScenesConfig, generate_scenes
    from centerart.training.encoder_data import checked_views

    if count == 0:
        return []
    generate_scenes(GenerateScenesConfig(
        objects=objects, out=out, layout=layout, count=count, views_per_scene=views, seed=seed, depth=data.depth,
        intrinsics=data.intrinsics, ir_shading=getattr(data, "ir_shading", "fast"), save_ir=False,
        save_masks=False, save_textures=False,  # the encoder reads neither (rgb, depths and labels only)
        decoder_checkpoint=decoder, workers=workers,
    ))  # fmt: skip
    return checked_views([out])


def slice_views(folders, work_slice: Path, data: SliceData, seeds: dict, decoder: Path, workers) -> list[Path]:
    kitchen = render(folders["train"], work_slice / "kitchen", "kitchen", data.kitchen, data.kitchen_views,
                     seeds["kitchen"], data, decoder, workers)  # fmt: skip
    single = render(folders["train"], work_slice / "single", "single", data.single, data.single_views,
                    seeds["single"], data, decoder, workers)  # fmt: skip
    return kitchen + single


def validation_views(plan: SlicePlan, folders, work: Path, workers) -> list[Path]:
    v = plan.validation
    kitchen = render(folders["heldout"], work / "val" / "kitchen", "kitchen", v.kitchen, v.kitchen_views,
                     v.kitchen_seed, v, None, workers)  # fmt: skip
    single = render(folders["heldout"], work / "val" / "single", "single", v.single, 1, v.single_seed, v, None, workers)
    return kitchen + single


# ---------------------------------------------------------------------------- one slice
def slice_settings(plan: SlicePlan, cfg: SlicesNextConfig, index: int, saved: dict | None) -> dict:
    """What slice ``index`` renders and trains (the plan's defaults with this call's overrides); a resumed slice
    keeps the settings it started with and refuses different ones."""
    data = SliceData(**{**plan.data.__dict__})
    for name in ("kitchen", "single", "intrinsics", "depth"):
        if getattr(cfg, name) is not None:
            setattr(data, name, getattr(cfg, name))
    settings = {
        "slice": index,
        "seeds": slice_seeds(index, plan.seed_block),
        "data": dict(data.__dict__),
        "steps": plan.steps if cfg.steps is None else cfg.steps,
        "batch_size": plan.batch_size,
        "lr_scale": float(cfg.lr_scale),
    }
    if saved is None:
        from centerart.utils.manifest import code_version

        return settings | {"code_version": code_version()}  # the code that starts the slice
    given = {"steps": cfg.steps, **{k: getattr(cfg, k) for k in ("kitchen", "single", "intrinsics", "depth")}}
    given["lr_scale"] = cfg.lr_scale  # never None: an omitted --lr-scale is 1.0, so it must be repeated
    refuse_changed_settings(index, {"steps": saved["steps"], **saved["data"], "lr_scale": saved["lr_scale"]}, given)
    return saved


def refuse_changed_settings(index: int, started: dict, given: dict) -> None:
    """One-line error when a resumed slice ``index`` is given (``given``: None = left out) other settings than
    those it ``started`` with. Each is named with both values: flags with a default (``--lr-scale``) count as
    that default when left out, so "leave them out" would not do."""
    changed = {k: (started[k], v) for k, v in given.items() if v is not None and v != started[k]}
    if changed:
        listed = ", ".join(f"{k}: {old} -> {new}" for k, (old, new) in changed.items())
        raise CenterArtError(f"slice {index} started with other settings ({listed}); rerun with those it started with")


def encoder_config(plan: SlicePlan, codes: dict):
    """The run's encoder config: the one its plan recorded, or (a plan saved before plans recorded it) the
    preset's with the values of fields added since taken as they were then (``LEGACY_DEFAULTS``)."""
    from centerart.models.encoder.config import LEGACY_DEFAULTS, EncoderConfig, preset

    code_dim = len(next(iter(codes.values())))
    if plan.encoder:
        return EncoderConfig.from_dict({**plan.encoder, "code_dim": code_dim})
    old = {k: v for k, v in preset(plan.encoder_preset).to_dict().items() if k not in LEGACY_DEFAULTS}
    return EncoderConfig.from_dict({**old, "code_dim": code_dim})


def start_state(plan: SlicePlan, run: Path, lines: list[dict], work_slice: Path, config):
    """The state slice k starts (or resumes) from, and the slice step it is at."""
    from centerart.training.slice_training import load_state

    start_sha = lines[-1]["state_sha256"] if lines else "init"
    progress = work_slice / "progress.pt"
    if progress.is_file():
        state = load_state(progress, config)
        if state.meta.get("start_sha") == start_sha:
            return state, int(state.meta["slice_step"])
    state = load_state(run / STATE, config) if lines else initial_state(plan, config)
    state.meta = {"start_sha": start_sha, "slice_step": 0}
    return state, 0


def initial_state(plan: SlicePlan, config):
    """The state a run's first slice starts from: random weights, or its --init (checked against the run's
    decoder unless the plan says the init was trained against another one)."""
    from centerart.training.slice_training import new_state

    decoder = None if plan.init_other_decoder else checked_decoder(plan)
    return new_state(config, plan.seed, checked_init(plan), decoder)


def train_on(state, views, codes, plan: SlicePlan, settings: dict, start: int, options: dict):
    """Continue ``state`` over slice ``settings`` from slice step ``start``; returns the slice step reached.

    ``options``: ``workers`` (loader processes), ``max_seconds``, ``stop_after``, ``save`` (a callable taking the
    state, run every SAVE_EVERY_S seconds and at the end), ``progress``."""
    from tqdm import tqdm

    from centerart.models.encoder.losses import EncoderLossConfig, code_scale
    from centerart.training.encoder_data import EncoderViewDataset
    from centerart.training.slice_training import SliceSchedule, StepLoop, run_steps, slice_batches

    k, steps = settings["slice"], settings["steps"]
    stop = min(steps, options.get("stop_after") or steps)
    batches = slice_batches(len(views), settings["batch_size"], steps, plan.seed, k)[:stop]
    dataset = EncoderViewDataset(
        views, state.encoder.config, codes, plan.augment_config(), seed=plan.seed * 100_000 + k
    )
    schedule = SliceSchedule(plan.lr, plan.warmup_steps, settings["lr_scale"])
    loss = EncoderLossConfig.from_dict(plan.loss)  # a plan saved before a loss field trains as it did then
    loop = StepLoop(batches, schedule, loss, code_scale(codes) if codes else None, options.get("workers", 1),
                    options.get("max_seconds", 0.0), decoded_shape_of(plan, loss, codes))  # fmt: skip
    bar = tqdm(total=steps, initial=start, desc=f"slice {k}", disable=not options.get("progress", True))
    last_save = [time.perf_counter()]

    def on_step(done: int, terms: dict) -> None:
        state.meta["slice_step"] = done
        bar.update(1)
        bar.set_postfix(loss=f"{terms['loss']:.3f}", refresh=False)
        if options.get("save") and time.perf_counter() - last_save[0] > SAVE_EVERY_S:
            options["save"](state)
            last_save[0] = time.perf_counter()

    reached = run_steps(state, dataset, loop, start, on_step) if start < stop else start
    bar.close()
    if options.get("save"):
        options["save"](state)
    return reached


def decoded_shape_of(plan: SlicePlan, loss, codes: dict):
    """The frozen decoder and query points of the decoded-shape term when the plan's loss weighs it (else None)."""
    if loss.shape_sdf <= 0:
        return None
    from centerart.models.checkpoint import load_decoder
    from centerart.models.encoder.decoded_shape import DecodedShape

    loaded = load_decoder(checked_decoder(plan))
    return DecodedShape.build(loaded.decoder, codes, loaded.bounds, seed=plan.seed)


def next_slice(cfg: SlicesNextConfig, echo=print) -> dict:
    """Run (or resume, or finish writing) the next slice of ``cfg.run``; returns its ledger line, or a status
    dict ``{"stopped": step, "of": steps}`` when the slice stopped early."""
    import json

    from centerart.models.checkpoint import load_shape_codes
    from centerart.utils.atomic import atomic_write_json

    run, work = Path(cfg.run), Path(cfg.work)
    plan = load_plan(run) or create_plan(run, cfg.preset, cfg.init, cfg.seed_block, cfg.decoder, cfg.shape_sdf)
    lines = read_ledger(run)
    k = len(lines) + 1
    work_slice = work / f"slice_{k:03d}"
    if (work_slice / "line.json").is_file() and finish_pending(run, lines, work_slice):
        echo(f"slice {k}: its files were written by an interrupted call; ledger line added")
        return read_ledger(run)[-1]
    check_run_files(run, lines)
    decoder = checked_decoder(plan)
    use_cpu_threads(cfg.threads)
    codes = load_shape_codes(decoder)
    config = encoder_config(plan, codes)
    state, start = start_state(plan, run, lines, work_slice, config)  # a state of another layout stops here
    saved = work_slice / "settings.json"
    settings = slice_settings(plan, cfg, k, json.loads(saved.read_text()) if saved.is_file() else None)
    atomic_write_json(saved, settings)
    t0 = time.perf_counter()
    folders = prepare_objects(plan, work, decoder, cfg.workers)
    val = validation_views(plan, folders, work, cfg.workers)
    views = slice_views(folders, work_slice, SliceData(**settings["data"]), settings["seeds"], decoder, cfg.workers)
    data_s = time.perf_counter() - t0
    if not lines and "start_validation" not in settings and val:  # where the run starts, for its learning curve
        settings["start_validation"] = _validation(state, val, codes, decoder, work)
        atomic_write_json(saved, settings)
    options = {"workers": cfg.loader_workers, "max_seconds": cfg.max_minutes * 60, "stop_after": cfg.stop_after,
               "save": lambda s: _save_progress(s, work_slice), "progress": cfg.progress}  # fmt: skip
    t1 = time.perf_counter()
    reached = train_on(state, views, codes, plan, settings, start, options)
    spent = add_call_wall(work_slice, {"data": data_s, "train": time.perf_counter() - t1})
    if reached < settings["steps"]:
        echo(f"slice {k}: stopped at step {reached} of {settings['steps']}; rerun the same command to resume")
        return {"stopped": reached, "of": settings["steps"]}
    return _finish_slice(run, lines, work_slice, plan, state, {**settings, "calls": spent["calls"]}, codes, decoder,
                         val, spent["wall_s"], len(views))  # fmt: skip


def _save_progress(state, work_slice: Path) -> None:
    from centerart.training.slice_training import save_state

    save_state(work_slice / "progress.pt", state)


def _finish_slice(run, lines, work_slice, plan, state, settings, codes, decoder, val, wall, images) -> dict:
    """Validate, then write state, encoder and ledger line (the line goes to ``WORK/slice_k/line.json`` first)."""
    from centerart.models.checkpoint_files import file_sha256
    from centerart.training.slice_training import save_state
    from centerart.utils.atomic import atomic_write_json
    from centerart.utils.manifest import code_version

    t0 = time.perf_counter()
    figures = _validation(state, val, codes, decoder, work_slice.parent) if val else {}
    wall["validation"] = time.perf_counter() - t0
    state.meta = {"slices": settings["slice"]}
    staged = save_state(work_slice / STATE, state)
    distinct = images + sum(line["images"] for line in lines)
    line = {**settings, "first_step": state.step - settings["steps"], "images": images,
            "distinct_images": distinct, "images_seen": state.step * settings["batch_size"],
            "validation": figures,
            "wall_s": {k: round(v, 1) for k, v in wall.items()},
            "state_sha256": file_sha256(staged), "finished_with": code_version(), "threads": _threads(),
            "finished": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}  # fmt: skip
    _export_encoder(work_slice / "encoder.pt", state, plan, decoder, codes, line)
    line["encoder_sha256"] = file_sha256(work_slice / "encoder.pt")
    atomic_write_json(work_slice / "line.json", line)
    finish_pending(run, lines, work_slice)
    return line


def _validation(state, views: list[Path], codes: dict, decoder: Path, work: Path) -> dict:
    """The fixed validation set's figures for ``state``'s encoder (rounded for the ledger), with the regressed
    codes' decoded-SDF error on its objects (``shape_sdf_mm_*``: the run's decoder, ``WORK/objects``)."""
    from centerart.training.encoder_data import EncoderViewDataset
    from centerart.training.slice_training import validate

    dataset = EncoderViewDataset(views, state.encoder.config, codes, None)
    figures = validate(state.encoder, dataset, codes, shape_error=shape_judge(decoder, work / "objects"))
    return {k: round(v, 5) for k, v in figures.items()}


def shape_judge(decoder: Path, objects: Path):
    """The judge of the regressed shape codes on validation views (:mod:`~centerart.training.shape_validation`):
    the run's frozen decoder and the objects' folders."""
    from centerart.models.checkpoint import load_decoder
    from centerart.training.shape_validation import HeldOutShapeError

    return HeldOutShapeError(load_decoder(decoder).decoder, objects)


def _threads() -> int:
    import torch

    return int(torch.get_num_threads())


def _export_encoder(path: Path, state, plan: SlicePlan, decoder: Path, codes: dict, line: dict) -> None:
    import torch

    from centerart.models.encoder.checkpoint import save_encoder

    recorded = torch.load(decoder, map_location="cpu", weights_only=True)["training_objects"]
    train_config = {"sliced_run": plan.to_dict(), "slice": {k: v for k, v in line.items() if k != "validation"}}
    metrics = {f"val/{k}": v for k, v in line["validation"].items()}
    save_encoder(path, state.encoder, decoder, sorted(codes), train_config, metrics, dict(recorded))


def finish_pending(run: Path, lines: list[dict], work_slice: Path, export: str = "encoder.pt") -> bool:
    """Copy a finished slice's files from WORK into RUN, then append its line (last: the line is the commit
    point). False when the staged files are not the next slice's (then nothing is touched)."""
    import json

    from centerart.models.checkpoint_files import file_sha256
    from centerart.utils.atomic import atomic_write_bytes

    line = json.loads((work_slice / "line.json").read_text())
    staged = {STATE: work_slice / STATE, export: work_slice / export}
    if line.get("slice") != len(lines) + 1 or file_sha256(staged[STATE]) != line["state_sha256"]:
        return False
    for name, path in staged.items():
        atomic_write_bytes(run / name, path.read_bytes())
    append_line(run, lines, line)
    return True


def commit_run(run: Path, line: dict) -> str:
    """``git commit`` of an encoder run's folder with a message naming the slice; returns git's one-line summary."""
    message = (f"slices: {Path(run).resolve().name} slice {line['slice']} ({line['steps']} steps, {line['images']} "
               f"new images; val recall {line['validation'].get('recall', float('nan')):.3f})")  # fmt: skip
    return commit_folder(run, message)


def commit_folder(run: Path, message: str) -> str:
    """``git add`` and ``git commit`` of the run folder alone; returns git's one-line summary."""
    run = Path(run).resolve()
    try:
        subprocess.run(["git", "-C", str(run), "add", "--", "."], check=True, capture_output=True, text=True)
        done = subprocess.run(["git", "-C", str(run), "commit", "-m", message, "--", "."], check=True,
                              capture_output=True, text=True)  # fmt: skip
    except (OSError, subprocess.CalledProcessError) as err:
        detail = (getattr(err, "stderr", "") or str(err)).strip().splitlines()
        raise CenterArtError(f"--commit: git commit of {run} failed ({detail[-1] if detail else err})") from None
    return done.stdout.strip().splitlines()[0]


# ---------------------------------------------------------------------------- status, replay
#: Validation figures of the status table and the command's summary (keys of encoder_metrics.summarize).
STATUS_COLUMNS = ("recall", "precision", "translation_cm_median", "rotation_deg_median", "joint_type_accuracy",
                  "shape_sdf_mm_median")  # fmt: skip


def status_table(run: Path) -> str:
    """The plan in one line and one row per ledger line (markdown); an encoder or a decoder run."""
    if run_kind(run) == "decoder":
        from centerart.recipe.decoder_slices import decoder_status_table

        return decoder_status_table(run)
    plan = load_plan(run)
    if plan is None:
        raise CenterArtError(f"{run}: no run.json (not a sliced run; `centerart slices next --run {run}` makes one)")
    lines = read_ledger(run)
    check_run_files(run, lines)
    head = (f"{run}: preset {plan.preset}, encoder {plan.encoder_preset}, batch {plan.batch_size}, lr {plan.lr}, "
            f"decoder {plan.decoder} ({plan.decoder_sha256[:12]})\n\n")  # fmt: skip
    cols = ("slice", "steps", "total steps", "new images", "distinct images", "hours", *STATUS_COLUMNS)
    rows = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for x in lines:
        v = x["validation"]
        figures = [f"{v[c]:.3f}" if c in v else "-" for c in STATUS_COLUMNS]
        hours = sum(x.get("wall_s", {}).values()) / 3600
        row = [x["slice"], x["steps"], x["first_step"] + x["steps"], x["images"], x.get("distinct_images", "-"),
               f"{hours:.2f}", *figures]  # fmt: skip
        rows.append("| " + " | ".join(str(r) for r in row) + " |")
    return head + "\n".join(rows) + ("\n" if lines else "\n(no slice yet)\n")


def learning_curve(run: Path) -> dict:
    """A sliced run's validation figures against its steps: where it started (its first line's
    ``start_validation``, at step 0) and after each slice.

    Returns ``{"run", "kind", "columns", "units", "points"}``; each point has ``slice`` (0: the start),
    ``total_steps``, ``distinct_images`` (encoder runs; None for a decoder run) and the figures of ``columns``
    (the status table's, a decoder run's distances in mm), None where a line lacks one."""
    kind = run_kind(run)
    if kind == "decoder":
        from centerart.recipe.decoder_slices import EVAL_COLUMNS
        from centerart.recipe.decoder_slices import STATUS_COLUMNS as DECODER_COLUMNS

        lines = read_ledger(run, DECODER_LINE_FIELDS)
        scales = {c: 1000.0 for c in DECODER_COLUMNS} | {c: 1.0 for c in EVAL_COLUMNS}
        units = {c: "mm" for c in DECODER_COLUMNS} | {EVAL_COLUMNS[0]: "mm", EVAL_COLUMNS[1]: "rate"}
    else:
        lines = read_ledger(run)
        scales = {c: 1.0 for c in STATUS_COLUMNS}
        units = {"recall": "rate", "precision": "rate", "translation_cm_median": "cm",
                 "rotation_deg_median": "deg", "joint_type_accuracy": "rate", "shape_sdf_mm_median": "mm"}  # fmt: skip
    if not lines:
        raise CenterArtError(f"{run}: no slice in its ledger yet, so no learning curve")
    columns = [c for c in scales if any(c in x["validation"] for x in lines)]

    def point(slice_index: int, steps: int, images, figures: dict) -> dict:
        values = {c: (float(figures[c]) * scales[c] if c in figures else None) for c in columns}
        return {"slice": slice_index, "total_steps": steps, "distinct_images": images, **values}

    points = [point(0, 0, 0 if kind == "encoder" else None, lines[0].get("start_validation", {}))]
    for x in lines:
        images = x.get("distinct_images") if kind == "encoder" else None
        points.append(point(x["slice"], x["first_step"] + x["steps"], images, x["validation"]))
    return {"run": str(run), "kind": kind, "columns": columns, "units": {c: units[c] for c in columns},
            "points": points}  # fmt: skip


def replay(cfg: SlicesReplayConfig, echo=print) -> dict:
    """Remake the run's state from its plan and ledger (same seeds, same steps) and compare the weights."""
    from centerart.models.checkpoint import load_shape_codes
    from centerart.training.slice_training import load_state

    run, work = Path(cfg.run), Path(cfg.work)
    if run_kind(run) == "decoder":
        from centerart.recipe.decoder_slices import replay_decoder

        use_cpu_threads(cfg.threads)
        return replay_decoder(run, work, cfg.workers, cfg.tolerance, cfg.progress, echo)
    plan = load_plan(run)
    if plan is None:
        raise CenterArtError(f"{run}: no run.json (not a sliced run)")
    lines = read_ledger(run)
    target = check_run_files(run, lines)
    if target is None:
        raise CenterArtError(f"{run}: no slice to replay yet")
    use_cpu_threads(cfg.threads)
    decoder = checked_decoder(plan)
    folders = prepare_objects(plan, work, decoder, cfg.workers)
    codes = load_shape_codes(decoder)
    state = initial_state(plan, encoder_config(plan, codes))
    for line in lines:
        views = slice_views(folders, work / f"slice_{line['slice']:03d}", SliceData(**line["data"]), line["seeds"],
                            decoder, cfg.workers)  # fmt: skip
        if len(views) != line["images"]:
            raise CenterArtError(f"slice {line['slice']}: rendered {len(views)} views, the ledger {line['images']}")
        train_on(state, views, codes, plan, line, 0, {"workers": 0, "progress": cfg.progress})
        echo(f"slice {line['slice']}: replayed {line['steps']} steps")
    saved = load_state(target, state.encoder.config)
    return compare_replay(run, len(lines), (state.step, state.encoder), (saved.step, saved.encoder), cfg.tolerance)


def compare_replay(run: Path, slices: int, replayed: tuple, saved: tuple, tolerance: float) -> dict:
    """The replay's summary when ``replayed`` (step, module) equals ``saved`` (the committed state) in step and
    within ``tolerance`` in every weight; else one error line."""
    pairs = zip(replayed[1].state_dict().values(), saved[1].state_dict().values(), strict=True)
    diff = max(float((a - b).abs().max()) for a, b in pairs)
    if replayed[0] != saved[0] or diff > tolerance:
        raise CenterArtError(f"replay of {run} differs from its state.pt: steps {replayed[0]} vs {saved[0]}, "
                             f"largest weight difference {diff:.3g} (tolerance {tolerance:g})")  # fmt: skip
    return {"slices": slices, "steps": replayed[0], "max_abs_weight_diff": diff, "tolerance": tolerance}
