"""Furnishing of the ``extended`` object variety (issue 15, object realism): what real PartNet-Mobility objects
have inside and around their fronts and the classic generator leaves out.

:func:`furnish` runs after a category's layout, in the body frame of :mod:`centerart.assets.builder` (front plane
x = 0, body towards -x, y across the front, z up from the floor; metres). Per category (probabilities per object):

=================  =============================================================================================
refrigerator       1-4 glass shelves behind every door, 6-9 cm behind the front plane (room for the door's swing)
oven               1-2 wire racks in every oven cavity; ranges (lower than 1 m): four burner grates on top (60 %)
                   and a control back-guard behind them (50 %)
microwave          a glass turntable on the cavity floor (85 %); a display window on the control panel (70 %);
                   four rubber feet (60 %)
dishwasher         a lower and an upper basket rack on rails in the tub
storage_furniture  1-3 shelves behind every door taller than 35 cm (70 %); a countertop overhanging the front by
                   1-3 cm past the doors and the sides by 0-2 cm when lower than 1.05 m and no door flips up (60 %);
                   feet instead of the recessed plinth or under a plinth-less carcass (30 %)
=================  =============================================================================================

Every piece joins the base link (it does not move) and stays behind the carcass front plane or outside the fronts'
sweep; the physics checks of :mod:`centerart.assets.physics_checks` verify that no moving part touches it.
"""

from __future__ import annotations

import numpy as np

from centerart.assets.builder import EMBED, FRONT_GAP, PALETTES, Builder, Cell, pick, rgba
from centerart.assets.spec import VisualGroup, box_between, cylinder_along

WIRE = 0.004  # m: thickness of wire racks and baskets


def furnish(b: Builder, rng: np.random.Generator) -> dict:
    """Add the category's furnishing (module table) to ``b``; returns what was added (object params)."""
    fn = {
        "refrigerator": _refrigerator,
        "oven": _oven,
        "microwave": _microwave,
        "dishwasher": _dishwasher,
        "storage_furniture": _storage_furniture,
    }[b.category]
    return fn(b, rng)


def door_cells(b: Builder) -> list[tuple[Cell, str]]:
    return [(cell, hinge) for kind, cell, hinge in b.fronts if kind == "door"]


def shelves(b: Builder, cell: Cell, count: int, setback: float, thickness: float, color, material: str) -> None:
    """``count`` fixed shelves, evenly spaced in the opening behind ``cell``, from the back wall to ``setback`` m
    behind the front plane; their ends sink into the side walls or dividers."""
    op = b.opening(cell)
    back = -b.depth + b.t - EMBED
    zs = np.linspace(op.z0, op.z1, count + 2)[1:-1]
    prims = [
        box_between([back, op.y0 - EMBED, z - thickness / 2], [-setback, op.y1 + EMBED, z + thickness / 2]) for z in zs
    ]
    b.base.append(VisualGroup(f"shelves_{len(b.base)}", prims, rgba(color), material))


def basket(b: Builder, cell: Cell, z_floor: float, rim: float, setback: float, color) -> None:
    """A wire basket (floor and four low walls, ``WIRE`` thick) on two rails into the side walls, its floor at
    ``z_floor``, in the opening behind ``cell``."""
    op = b.opening(cell)
    x0, x1 = -b.depth + b.t + 0.02, -setback
    y0, y1 = op.y0 + 0.012, op.y1 - 0.012
    prims = [
        box_between([x0, y0, z_floor], [x1, y1, z_floor + WIRE]),
        box_between([x0, y0, z_floor], [x0 + WIRE, y1, z_floor + rim]),
        box_between([x1 - WIRE, y0, z_floor], [x1, y1, z_floor + rim]),
        box_between([x0, y0, z_floor], [x1, y0 + WIRE, z_floor + rim]),
        box_between([x0, y1 - WIRE, z_floor], [x1, y1, z_floor + rim]),
        # rails into the side walls, clear of the basket's corners (coplanar faces break the union's manifold)
        box_between([x0 + 0.02, op.y0 - EMBED, z_floor + 0.001], [x1 - 0.02, y0 + 0.002, z_floor + 0.01]),
        box_between([x0 + 0.02, y1 - 0.002, z_floor + 0.001], [x1 - 0.02, op.y1 + EMBED, z_floor + 0.01]),
    ]
    b.base.append(VisualGroup(f"basket_{len(b.base)}", prims, rgba(color), "metal"))


def display(b: Builder, cell: Cell, rng: np.random.Generator) -> None:
    """A dark display window on the upper part of a fixed control panel over ``cell``."""
    fx = FRONT_GAP + b.td
    inset = 0.15 * cell.width
    z1 = cell.z1 - 0.08 * cell.height
    z0 = z1 - min(0.05, 0.2 * cell.height) * float(rng.uniform(0.7, 1.0))
    prim = box_between([fx - EMBED, cell.y0 + inset, z0], [fx + 0.002, cell.y1 - inset, z1])
    b.base.append(VisualGroup(f"display_{len(b.base)}", [prim], rgba(PALETTES["glass"][0]), "glass"))


def _refrigerator(b: Builder, rng: np.random.Generator) -> dict:
    n = 0
    for cell, _ in door_cells(b):
        count = int(np.clip(round(b.opening(cell).height / 0.35), 1, 4))
        shelves(b, cell, count, float(rng.uniform(0.06, 0.09)), 0.006, (0.85, 0.9, 0.92), "plastic")
        n += count
    return {"shelves": n}


def _oven(b: Builder, rng: np.random.Generator) -> dict:
    racks = 0
    for cell, _ in door_cells(b):
        count = int(rng.integers(1, 3))
        shelves(b, cell, count, 0.03, WIRE, pick(rng, "metal"), "metal")
        racks += count
    out = {"racks": racks, "cooktop": False, "back_guard": False}
    if b.height < 1.0 and rng.random() < 0.6:
        out["cooktop"] = True
        d, w2, h = b.depth, b.width / 2, b.height
        grate = (0.12, 0.12, 0.13)
        xs, ys = (-0.72 * d, -0.28 * d), (-w2 / 2, w2 / 2)
        half = min(0.2 * d, 0.4 * w2)
        prims = [box_between([x - half, y - half, h - EMBED], [x + half, y + half, h + 0.012]) for x in xs for y in ys]
        b.base.append(VisualGroup(f"grates_{len(b.base)}", prims, rgba(grate), "metal"))
        if rng.random() < 0.5:
            out["back_guard"] = True
            guard = box_between([-d, -w2, h - EMBED], [-d + 0.06, w2, h + float(rng.uniform(0.06, 0.14))])
            b.base.append(VisualGroup(f"back_guard_{len(b.base)}", [guard], rgba(pick(rng, "appliance")), "metal"))
    return out


def _microwave(b: Builder, rng: np.random.Generator) -> dict:
    out = {"turntable": False, "display": False, "feet": False}
    op = b.opening(door_cells(b)[0][0])
    if rng.random() < 0.85:
        out["turntable"] = True
        x_back, x_front = -b.depth + b.t, -0.02
        c = [(x_back + x_front) / 2, (op.y0 + op.y1) / 2]
        r = 0.42 * min(op.width, x_front - x_back)
        prims = [
            cylinder_along(2, [*c, op.z0 + 0.011], r, 0.006),
            cylinder_along(2, [*c, op.z0 + 0.004], 0.025, 0.008 + 2 * EMBED),  # hub into the floor
        ]
        b.base.append(VisualGroup(f"turntable_{len(b.base)}", prims, rgba((0.8, 0.85, 0.85)), "glass"))
    panels = [c for kind, c, _ in b.fronts if kind == "panel"]
    if panels and rng.random() < 0.7:
        out["display"] = True
        display(b, panels[0], rng)
    if rng.random() < 0.6:
        out["feet"] = True
        b.feet(0.012, float(rng.uniform(0.008, 0.015)), (0.1, 0.1, 0.1), "plastic")
    return out


def _dishwasher(b: Builder, rng: np.random.Generator) -> dict:
    cell = door_cells(b)[0][0]
    op = b.opening(cell)
    color = pick(rng, "metal")
    basket(b, cell, op.z0 + 0.04, float(rng.uniform(0.08, 0.12)), 0.03, color)
    basket(b, cell, op.z0 + float(rng.uniform(0.48, 0.56)) * op.height, float(rng.uniform(0.06, 0.09)), 0.03, color)
    return {"baskets": 2}


def _storage_furniture(b: Builder, rng: np.random.Generator) -> dict:
    out = {"shelves": 0, "countertop": False, "feet": False}
    body = b.base[0]
    for cell, _ in door_cells(b):
        height = b.opening(cell).height
        if height > 0.35 and rng.random() < 0.7:
            count = int(min(3, height // 0.3))
            shelves(b, cell, count, float(rng.uniform(0.01, 0.03)), b.t, body.rgba[:3], body.material)
            out["shelves"] += count
    flips_up = any(h == "top" for _, h in door_cells(b))
    if b.height < 1.05 and not flips_up and rng.random() < 0.6:
        out["countertop"] = True
        front = FRONT_GAP + b.td + float(rng.uniform(0.01, 0.03))
        side, th, w2 = float(rng.uniform(0.0, 0.02)), float(rng.uniform(0.02, 0.04)), b.width / 2
        top = box_between([-b.depth, -w2 - side, b.height - EMBED], [front, w2 + side, b.height + th])
        kind = "wood" if rng.random() < 0.5 else "painted"
        b.base.append(VisualGroup(f"countertop_{len(b.base)}", [top], rgba(pick(rng, kind)), kind))
    if rng.random() < 0.3:
        out["feet"] = True
        b.feet(float(rng.uniform(0.015, 0.025)), float(rng.uniform(0.06, 0.12)), pick(rng, "metal"), "metal")
    return out
