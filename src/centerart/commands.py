"""What each ``centerart`` command runs: call the stage's API with the parsed config and print a short summary.

Kept apart from :mod:`centerart.cli` (which only parses and dispatches) so that importing the CLI stays cheap:
a stage's heavy imports (torch, SAPIEN, pybullet) happen only when its command runs.
"""

from __future__ import annotations

from pathlib import Path


def objects_generate(cfg) -> None:
    from centerart.assets.dataset import generate_objects

    result = generate_objects(cfg)
    for cat, c in result["counts"].items():
        print(
            f"{cat:18s} {c['objects']:4d} objects ({c['revolute']} revolute, {c['prismatic']} prismatic), "
            f"{c['rejected_attempts']} rejected attempts"
        )
    print(f"wrote {Path(cfg.out) / 'manifest.json'}")


def objects_show(cfg) -> None:
    from centerart.viz.objects_sheet import show_objects

    print(f"wrote {show_objects(cfg)}")


def grasps_generate(cfg) -> None:
    from centerart.grasps.generate import generate_grasps

    summary = generate_grasps(cfg)
    for cat, c in summary.items():
        print(
            f"{cat:18s} {c['items']:4d} (object, state) items, {c['labels']:6d} labels, yield {c['yield']:.3f}, "
            f"{c['items_with_100_labels']} items with >= 100 labels"
        )
    print(f"wrote {Path(cfg.out) / 'manifest.json'}")


def grasps_show(cfg) -> None:
    from centerart.viz.grasps_sheet import show_grasps

    print(f"wrote {show_grasps(cfg)}")


def sdf_generate(cfg) -> None:
    from centerart.sdf.generate import generate_sdf

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


def scenes_generate(cfg) -> None:
    from centerart.scenes.dataset import generate_scenes

    c = generate_scenes(cfg)["counts"]
    print(
        f"{c['scenes']} scenes, {c['images']} images from {c['objects_available']} objects, "
        f"{c['rejected_layouts']} layouts rejected by the collision check"
    )
    print(f"wrote {Path(cfg.out) / 'manifest.json'}")


def scenes_show(cfg) -> None:
    from centerart.viz.scenes_sheet import show_scenes

    print(f"wrote {show_scenes(cfg)}")


def predict(cfg) -> None:
    import numpy as np

    from centerart.predict import anchoring_summary, run_predict

    record = run_predict(cfg)
    for obj in record["objects"]:
        j, t = obj["joint"], np.asarray(obj["camera_T_object"])[:3, 3]
        print(
            f"object {obj['index']}: score {obj['score']:.2f}, {j['type']} joint at {j['state']:.2f} {j['unit']}, "
            f"centre ({t[0]:+.2f}, {t[1]:+.2f}, {t[2]:.2f}) m, {len(obj['grasps'])} grasps"
        )
        if (line := anchoring_summary(obj)) is not None:
            print(f"  {line}")
    timing = ", ".join(f"{k} {v:.2f}" for k, v in record["timing_s"].items())
    print(f"{len(record['objects'])} objects ({timing})")
    print(f"wrote {cfg.out}/ (predictions.json, overlay.png, scene.glb, meshes); 3-D view: centerart view {cfg.out}")
    if cfg.view:
        from centerart.viz.viewer import ViewConfig

        view(ViewConfig(path=cfg.out))


def demo(cfg) -> None:
    from centerart.demo import run_demo

    run_demo(cfg)


def train_decoder(cfg) -> None:
    from centerart.training.train_decoder import train_decoder as train

    result = train(cfg)
    shown = {k: round(v, 5) for k, v in result["metrics"].items() if k.startswith(("val", "train/"))}
    print(f"metrics: {shown}")
    print(f"wrote {result['checkpoint']}")


def train_encoder(cfg) -> None:
    from centerart.training.train_encoder import train_encoder as train

    result = train(cfg)
    shown = {k: round(v, 4) for k, v in result["metrics"].items() if k.startswith("val/") and v is not None}
    print(f"metrics: {shown}")
    print(f"wrote {result['checkpoint']}")


def encoder_show(cfg) -> None:
    from centerart.viz.encoder_sheet import show_encoder

    print(f"wrote {show_encoder(cfg)}")


def decoder_show(cfg) -> None:
    from centerart.viz.decoder_sheet import show_decoder

    print(f"wrote {show_decoder(cfg)}")


def eval_decoder(cfg) -> None:
    import json

    from centerart.evaluation.decoder_eval import evaluate_decoder
    from centerart.viz.decoder_eval_plots import draw_decoder_eval

    report = evaluate_decoder(cfg)
    print(json.dumps(report["summary"], indent=1))
    print(f"wrote {Path(cfg.out) / 'report.json'} and {draw_decoder_eval(report, Path(cfg.out))}")


def eval_compare(cfg) -> None:
    from centerart.evaluation.paired import compare_evaluations

    report = compare_evaluations(cfg)
    print(f"{cfg.key}: A = {cfg.a}, B = {cfg.b}")
    print("| set | object views | both | only A | only B | p (views) | objects | A better | B better | p (objects) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, c in sorted(report["sets"].items(), key=lambda kv: kv[0] == "all"):
        print(
            f"| {name} | {c['objects']} | {c['both']} | {c['only_a']} | {c['only_b']} | {c['sign_test_p']:.3f} | "
            f"{c['distinct_objects']} | {c['objects_a_better']} | {c['objects_b_better']} | "
            f"{c['object_sign_test_p']:.3f} |"
        )
    if cfg.out:
        print(f"wrote {cfg.out}")


def eval_scenes(cfg) -> None:
    from centerart.evaluation.scene_eval import evaluate_scenes
    from centerart.evaluation.scene_report import group_label
    from centerart.viz.eval_report import draw_eval_pictures

    report = evaluate_scenes(cfg)
    draw_eval_pictures(Path(cfg.out), report)
    for key, g in report["groups"].items():
        rates = f"SR {_rate(g['sr'])}  SR-axis {_rate(g['sr_axis'])}  RSR {_rate(g['rsr'])}"
        print(f"{group_label(report, key):40s} objects {g['objects']:4d}  {rates}")
    if report["scenes_missing"]:
        print(f"{len(report['scenes_missing'])} scenes not evaluated yet: rerun the same command to finish")
    print(f"wrote {Path(cfg.out) / 'report.md'} and report.json")


def _rate(x) -> str:
    return "  -  " if x is None else f"{x:.3f}"


def recipe(cfg) -> None:
    from centerart.recipe.runner import format_seconds, run_recipe

    records = run_recipe(cfg)
    if records:  # global rank 0
        total = sum(r.get("seconds", 0.0) for r in records.values())
        print(f"steps done: {', '.join(n for n, r in records.items() if r['status'] == 'done')}")
        print(f"time over all calls: {format_seconds(total)}; wrote {Path(cfg.out) / 'manifest.json'}")


def view(cfg) -> None:
    from centerart.viz.viewer import block_until_interrupted, serve_viewer, viewer_url

    server = serve_viewer(cfg, block=False)
    print(f"3-D viewer of {cfg.path}: open {viewer_url(server)} in a web browser (Ctrl+C to stop)", flush=True)
    block_until_interrupted(server)


def slices_next(cfg) -> None:
    from centerart.recipe.slices import STATUS_COLUMNS, commit_run, next_slice

    line = next_slice(cfg)
    if "stopped" not in line:
        v = line["validation"]
        figures = ", ".join(f"{k} {v[k]:.3f}" for k in STATUS_COLUMNS if k in v)
        _slice_done(cfg, line, f"{line['images']} new images; validation: {figures}", commit_run, "encoder.pt")


def slices_decoder(cfg) -> None:
    from centerart.recipe.decoder_slices import STATUS_COLUMNS, commit_decoder_run, next_decoder_slice

    line = next_decoder_slice(cfg)
    if "stopped" not in line:
        v = line["validation"]
        figures = ", ".join(f"{k} {v[k] * 1000:.2f} mm" for k in STATUS_COLUMNS if k in v)
        _slice_done(cfg, line, f"{line['objects']} objects; validation: {figures}", commit_decoder_run, "decoder.pt")


def _slice_done(cfg, line: dict, summary: str, commit, export: str) -> None:
    """Print a finished slice's line, then commit the run folder (``--commit``) or say what to commit."""
    print(f"slice {line['slice']} done: {line['steps']} steps, {summary}")
    if cfg.commit:
        print(commit(cfg.run, line))
    else:
        print(f"wrote {cfg.run}/ledger.jsonl, state.pt, {export}; commit them (git add {cfg.run}) to keep them")


def slices_status(cfg) -> None:
    from centerart.recipe.ledger import read_ledger
    from centerart.recipe.slices import learning_curve, status_table
    from centerart.recipe.stopping import stopping_rule, stopping_summary

    print(status_table(cfg.run), end="")
    if not read_ledger(cfg.run, {}):  # no slice yet (the table says so): no curve, no rule
        return
    curve = learning_curve(cfg.run)
    print("\n" + stopping_summary(stopping_rule(curve)))
    if cfg.plot is not None:
        from centerart.viz.learning_curve import draw_learning_curve

        print(f"learning curve: {draw_learning_curve(curve, cfg.plot)}")


def slices_replay(cfg) -> None:
    from centerart.recipe.slices import replay

    r = replay(cfg)
    diff = f"{r['max_abs_weight_diff']:.3g} <= {r['tolerance']:g}"
    print(
        f"replayed {r['slices']} slices ({r['steps']} steps): largest weight difference {diff}; the ledger "
        f"reproduces {cfg.run}/state.pt"
    )
