"""Where the two soup sign methods disagree on real PartNet-Mobility objects. Prints JSON.

    PYTHONPATH=$PWD/src python benchmarks/sdf_sign_disagreement.py --real ../shared/partnet-mobility-samples

Per object, on ``--points`` sample points of the closed state (the sampler and seeds of `sdf generate`): the sign
agreement of ray escape and flood fill (both per part, soup shell applied), how many points each calls inside
alone, and the width of the gap each disagreeing point sits in: rays cast both ways along the direction to its
nearest surface point, hit distances added (a point between two parallel sheets 4 cm apart gets 40 mm; a ray
that leaves the object makes the width infinite). Disagreement concentrated in narrow gaps points at slabs
whose openings one method finds and the other does not (see docs/sdf.md); elsewhere it would be a plain error.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import open3d as o3d

from bench_report import run_main
from centerart.assets.articulated_object import ArticulatedObject
from centerart.assets.dataset import list_objects
from centerart.sdf.sampling import SamplingConfig, sample_points, soup_check_inside, soup_sign_inside
from centerart.sdf.signs import raycasting_scene
from centerart.sdf.surface import object_surface
from centerart.utils.seeding import item_rng


def gap_widths(scene: o3d.t.geometry.RaycastingScene, points: np.ndarray) -> np.ndarray:
    """m, free length through each point along the direction to its nearest surface point, both ways."""
    closest = scene.compute_closest_points(o3d.core.Tensor(points.astype(np.float32)))["points"].numpy()
    towards = closest - points
    towards /= np.maximum(np.linalg.norm(towards, axis=1, keepdims=True), 1e-12)
    width = np.zeros(len(points))
    for sign in (1.0, -1.0):
        rays = np.concatenate([points, sign * towards], axis=1).astype(np.float32)
        width += scene.cast_rays(o3d.core.Tensor(rays))["t_hit"].numpy()
    return width


def object_row(folder: Path, points: int, slab_m: float) -> dict:
    obj = ArticulatedObject.load(folder)
    cfg = SamplingConfig()
    surface = object_surface(obj, obj.denormalize(0.0))
    if surface.closed:
        return {"object": obj.object_id, "closed_mesh": True}
    pts = sample_points(surface.mesh, points, cfg, item_rng(0, obj.object_id, 0))
    scene = raycasting_scene(surface.mesh)
    dist = scene.compute_distance(o3d.core.Tensor(pts)).numpy()

    def negative(inside: np.ndarray) -> np.ndarray:
        return np.where(inside, -dist, dist) - cfg.soup_shell < 0

    escape = negative(soup_sign_inside(surface, pts, cfg))
    flood = negative(soup_check_inside(surface, pts, cfg))
    differ = escape != flood
    width = gap_widths(scene, pts[differ].astype(float))
    finite = width[np.isfinite(width)]
    return {
        "object": obj.object_id,
        "pieces": len(surface.pieces),
        "points": points,
        "agreement": round(float(1.0 - differ.mean()), 4),
        "inside_by_escape_only": int((escape & ~flood).sum()),
        "inside_by_flood_only": int((flood & ~escape).sum()),
        f"share_of_disagreement_in_gaps_up_to_{round(slab_m * 1000)}_mm": (
            round(float((width <= slab_m).mean()), 3) if differ.any() else None
        ),
        "gap_width_mm_quantiles_0_50_90": (
            [round(float(v) * 1000, 1) for v in np.quantile(finite, [0.0, 0.5, 0.9])] if len(finite) else None
        ),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--real", type=Path, default=Path(__file__).resolve().parents[2] / "shared" / "partnet-mobility-samples"
    )
    parser.add_argument("--points", type=int, default=10_000)
    parser.add_argument("--slab-mm", type=float, default=50.0, help="gap width counted as a slab interior")
    args = parser.parse_args()
    if not args.real.is_dir():
        raise SystemExit(f"{args.real}: no such folder of PartNet-Mobility objects (pass --real DIR)")
    rows = [object_row(f, args.points, args.slab_mm / 1000) for f in list_objects(args.real)]
    print(json.dumps({"benchmark": "sdf_sign_disagreement", "rows": rows}, indent=1))


if __name__ == "__main__":
    run_main(main)
