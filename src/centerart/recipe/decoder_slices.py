"""``centerart slices decoder``: train the SGDF decoder across working periods, one slice at a time, with a ledger.

The decoder's counterpart of :mod:`centerart.recipe.slices` (the encoder's). A run folder (``RUN``, committed)::

    RUN/run.json       the plan (:class:`DecoderSlicePlan`, ``"kind": "decoder"``)
    RUN/ledger.jsonl   one line per finished slice (fields: :data:`centerart.recipe.ledger.DECODER_LINE_FIELDS`)
    RUN/state.pt       decoder weights, shape codes, Adam moments and step
                       (:mod:`~centerart.training.decoder_slice_training`)
    RUN/decoder.pt     the same weights and codes as a decoder checkpoint (``centerart predict --decoder``)

Unlike the encoder's slices, every slice trains on the same data: the plan's objects (generated from its seed),
their grasp labels and SDF samples, made once in ``WORK`` from the plan's seeds (never committed). An auto-decoder
keeps one code per training object, so the object set is fixed for the run; what a slice adds is optimizer steps.
Slice 1 records the objects' content fingerprint and every later slice checks it, so a slice made on another
machine trains on the same objects. ``centerart slices status`` and ``replay`` read decoder runs too.
"""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Literal

from centerart.errors import CenterArtError
from centerart.recipe.ledger import DECODER_LINE_FIELDS, STATE, add_call_wall, check_run_files, read_ledger
from centerart.recipe.slices import commit_folder, compare_replay, finish_pending, load_plan, refuse_changed_settings
from centerart.utils.checks import at_least, between, positive
from centerart.utils.torch_cpu import use_cpu_threads

EXPORT = "decoder.pt"
SAVE_EVERY_S = 300.0  # progress saved this often (and when a slice stops early)


@dataclass
class DecoderSlicePlan:
    """What every slice of a decoder run shares (``RUN/run.json``)."""

    preset: str
    kind: str = "decoder"
    decoder_preset: Literal["tiny", "small", "paper"] = "small"
    decoder_overrides: dict = field(default_factory=dict)
    """Decoder config fields over the preset's, e.g. ``{"dropout": 0.2, "weight_norm": true}`` (the paper's
    regularisation on the small decoder); empty in plans made before it existed."""
    objects_seed: int = 0
    objects_count: int = 24
    """Objects per category (5 categories); ``heldout_object_fraction`` of them validate and are never trained on."""
    variety: Literal["classic", "extended"] = "classic"
    grasps: dict = field(default_factory=lambda: {"states": 6, "per_state": 100, "max_trials": 400,
                                                  "max_candidates": 12000, "keep_failures": 2000})  # fmt: skip
    """``centerart grasps generate`` settings of the objects' labels (the recipe's small preset)."""
    sdf_points: int = 50_000
    seed: int = 0
    """Seed of the split, the initial weights and codes, and every batch."""
    heldout_object_fraction: float = 0.15
    heldout_states_per_object: int = 1
    batch_items: int = 8
    points_per_item: int = 2048
    max_points_per_state: int = 40_000
    lr_decoder: float = 1e-3
    lr_codes: float = 2e-3
    code_weight: float = 1e-2
    warmup_steps: int = 0
    steps: int = 2400
    """Default optimizer steps per slice."""
    val_code_fit_steps: int = 100
    heldout_eval_states: int = 2
    """After each slice, ``centerart eval decoder`` on the held-out objects at this many states each (closed and
    open for 2; codes fitted to their SDF samples, meshes, the top 5 grasps executed, no critic): the Chamfer and
    physics figures that the near-surface SDF error does not show (0: off). It changes no weight, so plans made
    before it get it too, from their next slice on."""
    heldout_eval_resolution: int = 128
    """Mesh grid of that evaluation (cells per side)."""

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> DecoderSlicePlan:
        try:
            return cls(**data)
        except TypeError as err:
            raise CenterArtError(f"run.json: not a decoder slice plan ({err})") from None

    def train_config(self, work: Path):
        """The :class:`~centerart.training.train_decoder.TrainDecoderConfig` whose data, split, module and
        checkpoint this run shares with ``centerart train decoder`` (its epochs and Lightning fields unused)."""
        from centerart.training.train_decoder import TrainDecoderConfig

        fields = ("batch_items", "points_per_item", "max_points_per_state", "lr_decoder", "lr_codes", "code_weight",
                  "heldout_object_fraction", "heldout_states_per_object", "val_code_fit_steps", "seed")  # fmt: skip
        return TrainDecoderConfig(data=Path(work) / "sdf", out=Path(work), preset=self.decoder_preset, epochs=1,
                                  progress=False, decoder_overrides=dict(self.decoder_overrides),
                                  **{k: getattr(self, k) for k in fields})  # fmt: skip


_TINY = DecoderSlicePlan(
    preset="tiny", decoder_preset="tiny", objects_count=1, sdf_points=3000, heldout_object_fraction=0.2,
    grasps={"states": 2, "per_state": 4, "max_trials": 30, "max_candidates": 300, "keep_failures": 20},
    batch_items=4, points_per_item=256, max_points_per_state=3000, lr_decoder=2e-3, lr_codes=2e-3, steps=3,
    val_code_fit_steps=5, heldout_eval_states=1, heldout_eval_resolution=24,
)  # fmt: skip
"""Tests: 5 objects (1 held out), 2 states of a few labels, 3000 SDF points, the tiny decoder, 3 steps a slice."""

_SMALL = DecoderSlicePlan(preset="small")
"""The small decoder on 24 objects per category (102 training objects, 18 held out: the 102-object decoder of
``benchmarks/results/decoder_scale/``, same seeds), the recipe's labels, points, batch and rates; 2,400 steps a
slice (about an hour at two threads)."""

PRESETS: dict[str, DecoderSlicePlan] = {"tiny": _TINY, "small": _SMALL}


@dataclass
class DecoderSlicesConfig:
    """Run the next slice of a sliced decoder training run (creates the run on first use)."""

    run: Path
    """Run folder (committed): run.json, ledger.jsonl, state.pt, decoder.pt."""
    work: Path = Path("runs/decoder-slices-work")
    """Work folder for objects, labels, SDF samples and progress (not committed; regenerated from seeds)."""
    preset: Literal["tiny", "small"] = "small"
    """Plan of a new run (ignored once RUN/run.json exists)."""
    dropout: float | None = None
    """Dropout after each hidden layer of a new run's decoder (the paper: 0.2; default: the preset's)."""
    weight_norm: bool | None = None
    """Weight normalisation of a new run's decoder layers (the paper: on; default: the preset's)."""
    steps: int | None = None
    """Optimizer steps of this slice (default: the plan's)."""
    lr_scale: float = 1.0
    """This slice's learning rates as a multiple of the plan's (lower it for the last slices of a run)."""
    stop_after: int | None = None
    """Stop after this many steps of the slice (progress is kept; rerun to resume)."""
    max_minutes: float = 0.0
    """Stop training after this much time in this call (0: no limit); rerun to resume."""
    workers: int | None = None
    """Processes making objects, labels and SDF samples (default: all cores)."""
    threads: int = 0
    """torch CPU threads (0: torch default)."""
    codes_from_sdf: bool = False
    """This slice's shape codes learn from the SDF alone: the grasp term's gradient is kept off them
    (``LossConfig.grasp_moves_codes``), and where the previous slice let it reach them, every code is first replaced
    by one fitted to the object's SDF samples (``refit_training_codes``). The grasp field is then trained on the
    codes a test-time fit finds for an object's surface. Recorded in the ledger line and replayed."""
    commit: bool = False
    """git commit the run folder after the slice (the ledger line and the files it names)."""
    progress: bool = True

    def __post_init__(self):
        if self.steps is not None:
            at_least("--steps", self.steps, 1)
        if self.stop_after is not None:
            at_least("--stop-after", self.stop_after, 0)
        positive("--lr-scale", self.lr_scale)
        at_least("--max-minutes", self.max_minutes, 0.0)
        at_least("--threads", self.threads, 0)
        if self.dropout is not None:
            between("--dropout", self.dropout, 0.0, 0.9)

    def decoder_overrides(self) -> dict:
        """The new run's decoder fields given on the command line."""
        given = {"dropout": self.dropout, "weight_norm": self.weight_norm}
        return {k: v for k, v in given.items() if v is not None}


# ---------------------------------------------------------------------------- plan and data
def create_decoder_plan(run: Path, preset: str, overrides: dict | None = None) -> DecoderSlicePlan:
    from centerart.utils.atomic import atomic_write_json

    if preset not in PRESETS:
        raise CenterArtError(f"unknown decoder slice preset {preset!r}; choose from {', '.join(PRESETS)}")
    plan = DecoderSlicePlan.from_dict(PRESETS[preset].to_dict())
    plan.decoder_overrides = {**plan.decoder_overrides, **(overrides or {})}
    Path(run).mkdir(parents=True, exist_ok=True)
    atomic_write_json(Path(run) / "run.json", plan.to_dict())
    return plan


def prepare_data(plan: DecoderSlicePlan, work: Path, workers: int | None, progress: bool) -> str:
    """Objects, grasp labels and SDF samples of the plan in ``WORK`` (each stage resumes: finished items are
    kept); returns the SHA-256 over the objects' content fingerprints."""
    import hashlib

    from centerart.assets.dataset import GenerateObjectsConfig, generate_objects
    from centerart.assets.fingerprint import fingerprint_folders
    from centerart.grasps.generate import GenerateGraspsConfig, generate_grasps
    from centerart.sdf.generate import GenerateSdfConfig, generate_sdf

    objects, grasps = work / "objects", work / "grasps"
    generate_objects(GenerateObjectsConfig(out=objects, category="all", count=plan.objects_count,
                                           seed=plan.objects_seed, variety=plan.variety, workers=workers))  # fmt: skip
    generate_grasps(GenerateGraspsConfig(objects=objects, out=grasps, seed=plan.objects_seed, workers=workers,
                                         **plan.grasps))  # fmt: skip
    generate_sdf(GenerateSdfConfig(objects=objects, grasps=grasps, out=work / "sdf", points=plan.sdf_points,
                                   states=plan.grasps["states"], workers=workers, seed=plan.objects_seed),
                 progress=progress)  # fmt: skip
    folders = {p.name: p for p in sorted(objects.iterdir()) if (p / "mobility.urdf").is_file()}
    prints = json.dumps(fingerprint_folders(folders), sort_keys=True)
    return hashlib.sha256(prints.encode()).hexdigest()


def check_objects(lines: list[dict], objects_sha: str, work: Path) -> None:
    if lines and lines[0]["objects_sha256"] != objects_sha:
        raise CenterArtError(
            f"{work / 'objects'}: not the objects slice 1 trained on (content fingerprints differ); the plan's "
            "generators changed since: check out the commit that made the run, or start a new run"
        )


# ---------------------------------------------------------------------------- one slice
def slice_settings(plan: DecoderSlicePlan, cfg: DecoderSlicesConfig, index: int, saved: dict | None,
                   previous: dict) -> dict:  # fmt: skip
    """What slice ``index`` trains (the plan's defaults with this call's overrides; ``previous``: the last ledger
    line, empty for the first slice); a resumed slice keeps the settings it started with and refuses others."""
    from centerart.utils.manifest import code_version

    if saved is not None:
        given = {"steps": cfg.steps, "lr_scale": cfg.lr_scale, "codes_from_sdf": cfg.codes_from_sdf}
        # codes_from_sdf is absent from lines made without it
        refuse_changed_settings(index, {k: saved.get(k, False) for k in given}, given)
        return saved
    steps = plan.steps if cfg.steps is None else cfg.steps
    settings = {"slice": index, "steps": steps, "batch_size": plan.batch_items, "lr_scale": float(cfg.lr_scale),
                "code_version": code_version()}  # fmt: skip
    if cfg.codes_from_sdf:  # absent from lines made without it (and from every line before it existed)
        settings |= {"codes_from_sdf": True, "refit_codes": not previous.get("codes_from_sdf", False)}
    return settings


#: Code-fit steps and points per step of a slice's code refit: the closed-loop code oracle's
#: (``evaluation.code_oracle.ORACLE_CODE_FIT``), whose data loss is within 1 % of ``centerart eval decoder``'s
#: (200 x 4096).
REFIT_STEPS, REFIT_POINTS = 200, 1024


def apply_code_settings(run: _Run, state, settings: dict, progress: bool = False, save_to: Path | None = None) -> float:
    """Set the slice's loss on ``state`` (grasp gradient on the codes or not) and, where the slice refits the codes
    and ``state`` has not been refitted yet, refit them (``state.meta["codes_refit"]`` records it) and save the
    state to ``save_to`` (the slice's progress: a refit takes minutes). Returns the refit's wall seconds (0: none)."""
    from dataclasses import replace

    from centerart.training.decoder_slice_training import refit_training_codes, save_decoder_state

    from_sdf = bool(settings.get("codes_from_sdf", False))
    state.module.loss_config = replace(state.module.loss_config, grasp_moves_codes=not from_sdf)
    if not settings.get("refit_codes") or "codes_refit" in (state.meta or {}):
        return 0.0
    t0 = time.perf_counter()
    moved = refit_training_codes(state, run.data.train, REFIT_STEPS, run.plan.seed, REFIT_POINTS, progress)
    state.meta = {**(state.meta or {}), "codes_refit": {k: round(v, 6) for k, v in moved.items()}}
    if save_to is not None:
        save_decoder_state(save_to, state)
    return time.perf_counter() - t0


class _Run:
    """A decoder run's loaded pieces: plan, data, the module builder and the batches."""

    def __init__(self, plan: DecoderSlicePlan, work: Path):
        from centerart.training.decoder_data import PointBatchDataset
        from centerart.training.decoder_slice_training import KeyedBatches
        from centerart.training.slice_training import SliceSchedule
        from centerart.training.train_decoder import load_split_data

        self.plan, self.work = plan, work
        self.train_cfg = plan.train_config(work)
        self.data = load_split_data(self.train_cfg)
        dataset = PointBatchDataset(self.data.train, self.data.code_index, plan.points_per_item)
        self.batches = KeyedBatches(dataset, plan.batch_items, plan.seed)
        self.schedule = lambda scale: SliceSchedule(1.0, plan.warmup_steps, scale)

    def build(self):
        from centerart.training.train_decoder import build_module

        return build_module(self.train_cfg, self.data)

    def new_state(self):
        from centerart.training.decoder_slice_training import new_decoder_state

        return new_decoder_state(self.build, self.plan.seed)

    def load(self, path: Path):
        from centerart.training.decoder_slice_training import load_decoder_state

        return load_decoder_state(path, self.build())

    def validate(self, state) -> dict:
        from centerart.training.decoder_slice_training import validate_decoder

        p = self.plan
        figures = validate_decoder(state, self.data.heldout_states, p.seed, p.batch_items, p.points_per_item)
        return {k: round(v, 6) for k, v in figures.items()}


def start_state(run: _Run, run_dir: Path, lines: list[dict], work_slice: Path):
    """The state slice k starts (or resumes) from."""
    start_sha = lines[-1]["state_sha256"] if lines else "new"
    progress = work_slice / "progress.pt"
    if progress.is_file():
        state = run.load(progress)
        if state.meta.get("start_sha") == start_sha:
            return state
    state = run.load(run_dir / STATE) if lines else run.new_state()
    state.meta = {"start_sha": start_sha}
    return state


def train_slice(run: _Run, state, settings: dict, cfg: DecoderSlicesConfig, until: int) -> int:
    """Continue ``state`` to global step ``until`` (or this call's stop), saving progress every few minutes."""
    from tqdm import tqdm

    from centerart.training.decoder_slice_training import run_decoder_steps, save_decoder_state

    stop = until if cfg.stop_after is None else min(until, state.step + cfg.stop_after)
    first = until - settings["steps"]
    bar = tqdm(total=settings["steps"], initial=state.step - first, desc=f"slice {settings['slice']}",
               disable=not cfg.progress)  # fmt: skip
    last_save, progress = [time.perf_counter()], run.work / f"slice_{settings['slice']:03d}" / "progress.pt"

    def on_step(terms: dict) -> None:
        bar.update(1)
        bar.set_postfix(loss=f"{terms['loss']:.4f}", refresh=False)
        if time.perf_counter() - last_save[0] > SAVE_EVERY_S:
            save_decoder_state(progress, state)
            last_save[0] = time.perf_counter()

    reached = run_decoder_steps(state, run.batches, run.schedule(settings["lr_scale"]), stop,
                                cfg.max_minutes * 60, on_step)  # fmt: skip
    bar.close()
    save_decoder_state(progress, state)
    return reached


def next_decoder_slice(cfg: DecoderSlicesConfig, echo=print) -> dict:
    """Run (or resume, or finish writing) the next slice of ``cfg.run``; returns its ledger line, or a status
    dict ``{"stopped": step, "of": steps}`` when the slice stopped early."""
    from centerart.utils.atomic import atomic_write_json

    run_dir, work = Path(cfg.run), Path(cfg.work)
    plan = load_plan(run_dir, DecoderSlicePlan) or create_decoder_plan(run_dir, cfg.preset, cfg.decoder_overrides())
    made = asdict(plan.train_config(work).decoder_config())
    differ = {k: v for k, v in cfg.decoder_overrides().items() if made[k] != v}
    if differ:
        made_with = ", ".join(f"{k}={made[k]}" for k in differ)
        raise CenterArtError(f"{run_dir}: the run's decoder was made with {made_with}; --dropout and --weight-norm "
                             "apply to a new run only")  # fmt: skip
    lines = read_ledger(run_dir, DECODER_LINE_FIELDS)
    k = len(lines) + 1
    work_slice = work / f"slice_{k:03d}"
    if (work_slice / "line.json").is_file() and finish_pending(run_dir, lines, work_slice, EXPORT):
        echo(f"slice {k}: its files were written by an interrupted call; ledger line added")
        return read_ledger(run_dir, DECODER_LINE_FIELDS)[-1]
    check_run_files(run_dir, lines)
    use_cpu_threads(cfg.threads)
    t0 = time.perf_counter()
    objects_sha = prepare_data(plan, work, cfg.workers, cfg.progress)
    check_objects(lines, objects_sha, work)
    run = _Run(plan, work)
    state = start_state(run, run_dir, lines, work_slice)
    saved = work_slice / "settings.json"
    settings = slice_settings(plan, cfg, k, json.loads(saved.read_text()) if saved.is_file() else None,
                              lines[-1] if lines else {})  # fmt: skip
    atomic_write_json(saved, settings)
    data_s = time.perf_counter() - t0
    refit_s = apply_code_settings(run, state, settings, cfg.progress, work_slice / "progress.pt")
    if not lines and "start_validation" not in settings:  # where the run starts, for its learning curve
        settings["start_validation"] = run.validate(state)
        atomic_write_json(saved, settings)
    first = lines[-1]["first_step"] + lines[-1]["steps"] if lines else 0
    t1 = time.perf_counter()
    reached = train_slice(run, state, settings, cfg, first + settings["steps"])
    wall = {"data": data_s, "train": time.perf_counter() - t1} | ({"refit_codes": refit_s} if refit_s else {})
    spent = add_call_wall(work_slice, wall)
    if reached < first + settings["steps"]:
        echo(f"slice {k}: stopped at step {reached - first} of {settings['steps']}; rerun the same command to resume")
        return {"stopped": reached - first, "of": settings["steps"]}
    line = {**settings, "first_step": first, "objects_sha256": objects_sha, "calls": spent["calls"]}
    if "codes_refit" in (state.meta or {}):
        line["codes_refit"] = state.meta["codes_refit"]
    return _finish_slice(run, run_dir, lines, work_slice, state, line, spent["wall_s"])


def _finish_slice(run: _Run, run_dir: Path, lines: list[dict], work_slice: Path, state, line: dict, wall) -> dict:
    """Validate, then write state, decoder and ledger line (the line goes to ``WORK/slice_k/line.json`` first)."""
    import torch

    from centerart.models.checkpoint_files import file_sha256
    from centerart.training.decoder_slice_training import save_decoder_state
    from centerart.training.train_decoder import export_decoder
    from centerart.utils.atomic import atomic_write_json
    from centerart.utils.manifest import code_version

    t0 = time.perf_counter()
    line["validation"] = run.validate(state)
    wall["validation"] = time.perf_counter() - t0
    state.meta = {"slices": line["slice"]}
    staged = save_decoder_state(work_slice / STATE, state)
    line |= {"objects": len(run.data.split.train_objects), "heldout_objects": len(run.data.split.heldout_objects),
             "wall_s": {k: round(v, 1) for k, v in wall.items()}, "state_sha256": file_sha256(staged),
             "finished_with": code_version(), "threads": int(torch.get_num_threads()),
             "finished": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}  # fmt: skip
    sliced = {"plan": run.plan.to_dict(), "slice": line["slice"], "step": state.step}
    # The loss config's code prior is what new shape codes are fitted under (LoadedDecoder.code_weight).
    train_config = {**asdict(run.train_cfg), "loss": asdict(run.train_cfg.loss_config()), "sliced_run": sliced}
    metrics = {**line["validation"], "step": state.step}
    export_decoder(work_slice / EXPORT, run.train_cfg, state.module, run.data, train_config, metrics)
    line["decoder_sha256"] = file_sha256(work_slice / EXPORT)
    if run.plan.heldout_eval_states > 0:
        t0 = time.perf_counter()
        line["validation"] |= evaluate_heldout(run, work_slice / EXPORT, work_slice)
        line["wall_s"]["heldout_eval"] = round(time.perf_counter() - t0, 1)
    atomic_write_json(work_slice / "line.json", line)
    finish_pending(run_dir, lines, work_slice, EXPORT)
    return line


#: Figures of :func:`evaluate_heldout` (``centerart eval decoder``'s held-out-object summary) kept in the line;
#: the Chamfer figures are over the non-empty meshes (absent when every mesh is empty).
HELDOUT_EVAL_FIGURES = (
    "chamfer_mm", "chamfer_mm_median", "fscore", "empty_meshes", "physics_top1", "physics_any5", "states"
)  # fmt: skip


def evaluate_heldout(run: _Run, checkpoint: Path, work_slice: Path) -> dict:
    """``centerart eval decoder`` of ``checkpoint`` on the run's held-out objects (``WORK/slice_k/heldout_eval``):
    their codes fitted to all their SDF samples, meshes, and the top 5 grasps executed in physics (no critic:
    the decoder alone); returns the summary's :data:`HELDOUT_EVAL_FIGURES` as ``heldout_eval/<name>``."""
    from centerart.evaluation.decoder_eval import EvalDecoderConfig, evaluate_decoder

    sdf = work_slice / "heldout_sdf"  # eval decoder reads every object of its --data: only the held-out ones
    sdf.mkdir(parents=True, exist_ok=True)
    for oid in run.data.split.heldout_objects:
        if not (sdf / oid).exists():
            (sdf / oid).symlink_to((run.work / "sdf" / oid).resolve())
    cfg = EvalDecoderConfig(
        data=sdf, objects=run.work / "objects", grasps=run.work / "grasps", checkpoint=checkpoint,
        out=work_slice / "heldout_eval", states_per_object=run.plan.heldout_eval_states,
        resolution=run.plan.heldout_eval_resolution, grasp_critic=False, seed=run.plan.seed,
    )  # fmt: skip
    summary = evaluate_decoder(cfg)["summary"].get("heldout_object", {})
    return {
        f"heldout_eval/{k}": round(float(summary[k]), 6) for k in HELDOUT_EVAL_FIGURES if summary.get(k) is not None
    }


def commit_decoder_run(run: Path, line: dict) -> str:
    v = line["validation"]
    if "heldout_eval/chamfer_mm" in v:
        figure = (f"held-out objects' Chamfer {v['heldout_eval/chamfer_mm']:.1f} mm, top-1 "
                  f"{v.get('heldout_eval/physics_top1', float('nan')):.2f}")  # fmt: skip
    else:
        figure = (
            f"held-out objects' SDF error near the surface {v.get('val_object/sdf_near', float('nan')) * 1000:.2f} mm"
        )
    message = f"slices: {Path(run).resolve().name} slice {line['slice']} ({line['steps']} decoder steps; {figure})"
    return commit_folder(run, message)


# ---------------------------------------------------------------------------- status, replay
#: Validation figures of the status table, in mm (keys of DecoderModule's metrics).
STATUS_COLUMNS = ("val_object/sdf", "val_object/sdf_near", "val_object/grasp_near", "val_state/sdf_near",
                  "val_state/grasp_near")  # fmt: skip
#: Figures of the held-out evaluation in the status table (Chamfer in mm, top-1 a rate).
EVAL_COLUMNS = ("heldout_eval/chamfer_mm", "heldout_eval/physics_top1")


def decoder_status_table(run: Path) -> str:
    plan = load_plan(run, DecoderSlicePlan)
    lines = read_ledger(run, DECODER_LINE_FIELDS)
    check_run_files(run, lines)
    head = (f"{run}: decoder run, preset {plan.preset}, decoder {plan.decoder_preset}, {plan.objects_count} objects "
            f"per category (seed {plan.objects_seed}), batch {plan.batch_items} x {plan.points_per_item} points, lr "
            f"{plan.lr_decoder} / {plan.lr_codes} (codes){_overrides_note(plan)}; figures in mm\n\n")  # fmt: skip
    cols = ("slice", "steps", "total steps", "lr scale", "hours", *STATUS_COLUMNS, *EVAL_COLUMNS, "codes learn from")
    rows = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for x in lines:
        v = x["validation"]
        figures = [f"{v[c] * 1000:.2f}" if c in v else "-" for c in STATUS_COLUMNS]
        figures += [f"{v[c]:.2f}" if c in v else "-" for c in EVAL_COLUMNS]
        hours = sum(x.get("wall_s", {}).values()) / 3600
        codes = ("sdf, refitted" if x.get("refit_codes") else "sdf") if x.get("codes_from_sdf") else "sdf, grasps"
        row = [x["slice"], x["steps"], x["first_step"] + x["steps"], x["lr_scale"], f"{hours:.2f}", *figures, codes]
        rows.append("| " + " | ".join(str(r) for r in row) + " |")
    return head + "\n".join(rows) + ("\n" if lines else "\n(no slice yet)\n")


def _overrides_note(plan: DecoderSlicePlan) -> str:
    return "".join(f", {k} {v}" for k, v in sorted(plan.decoder_overrides.items()))


def replay_decoder(run_dir: Path, work: Path, workers: int | None, tolerance: float, progress: bool, echo) -> dict:
    """Remake the run's state from its plan and ledger (same data, same steps) and compare the weights."""
    from centerart.training.decoder_slice_training import run_decoder_steps

    plan = load_plan(run_dir, DecoderSlicePlan)
    lines = read_ledger(run_dir, DECODER_LINE_FIELDS)
    target = check_run_files(run_dir, lines)
    if target is None:
        raise CenterArtError(f"{run_dir}: no slice to replay yet")
    check_objects(lines, prepare_data(plan, work, workers, progress), work)
    run = _Run(plan, work)
    state = run.new_state()
    for line in lines:
        state.meta = {}  # a line that refits refits the state as replayed so far
        apply_code_settings(run, state, line, progress)
        run_decoder_steps(state, run.batches, run.schedule(line["lr_scale"]), line["first_step"] + line["steps"])
        echo(f"slice {line['slice']}: replayed {line['steps']} steps")
    saved = run.load(target)
    return compare_replay(run_dir, len(lines), (state.step, state.module), (saved.step, saved.module), tolerance)
