"""Procedural articulated objects for the paper's five categories.

Each call of :func:`generate_spec` draws one object from per-category ranges (below, in metres and radians)
with a seeded generator. Every object has exactly one *target* movable part; any other door or drawer it has is
a movable joint held closed. Ranges come from common appliance and kitchen-furniture sizes:

=================  ===========  ===========  ===========  ========================================================
category           width (y)    depth (x)    height (z)   layout and target part
=================  ===========  ===========  ===========  ========================================================
microwave          0.44-0.60    0.32-0.45    0.26-0.36    door (hinge left 85%, right 15%) + control panel;
                                                          door opens to 1.6-1.95 rad; glass window
oven               0.55-0.76    0.55-0.65    0.82-0.92    bottom-hinged door (to 1.45-1.57 rad) under a control
                                                          strip with knobs; 50% a storage drawer below (held)
refrigerator       0.55-0.90    0.60-0.75    1.45-1.90    one door, top freezer + main door, or main door over a
                                                          freezer drawer; side hinges to 1.7-2.2 rad; target any
dishwasher         0.45-0.60    0.55-0.62    0.80-0.87    one bottom-hinged door (to 1.45-1.57 rad) with a
                                                          control strip on top, over a plinth
storage_furniture  0.40-1.20    0.35-0.60    0.45-2.00    grid of 1-3 columns of doors and drawers (dividers);
                                                          side doors hinged on the outer edge (to 1.57-2.0 rad),
                                                          inner doors to pi/2, short wide doors may flip up;
                                                          drawers travel 60-80% of their depth; target any
=================  ===========  ===========  ===========  ========================================================

The ``extended`` variety (``generate_spec(..., variety="extended")``) widens the size ranges to real appliances
(:data:`EXTENDED_SIZES`), adds fridge layouts ``side_by_side`` and ``french`` (0.8-1.0 m wide) and oven layouts
``double`` (two cavities stacked, 1.0-1.3 m high) and ``twin`` (side by side, 0.9-1.2 m wide), then furnishes the
object (:mod:`centerart.assets.furnishing`: shelves, racks, baskets, turntables, displays, cooktops, countertops,
feet). The classic variety draws exactly the random numbers it always drew, so its objects stay byte-identical.

Wall/carcass thickness 0.012-0.022, front thickness 0.016-0.045 (appliances thicker), front gaps 3 mm.
Handles: bar, U/arch, knob, lip or none, with per-category weights; bar radius 6-11 mm, standoff 32-55 mm
(at least 22 mm free behind the grip), length 0.09-0.32 (fridges 0.25-0.6), inset 35-70 mm from the free edge.
"""

from __future__ import annotations

import numpy as np

from centerart.assets.builder import PALETTES, Builder, Cell, pick
from centerart.assets.furnishing import furnish
from centerart.assets.spec import ObjectSpec

VARIETIES = ("classic", "extended")


def u(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(rng.uniform(lo, hi))


def generate_spec(category: str, rng: np.random.Generator, variety: str = "classic") -> ObjectSpec:
    """One random object of ``category`` and ``variety`` (see the module table)."""
    try:
        fn = _BUILDERS[category]
    except KeyError:
        raise ValueError(f"unknown category {category!r}; choose from {sorted(_BUILDERS)}") from None
    if variety not in VARIETIES:
        raise ValueError(f"unknown object variety {variety!r}; choose from {list(VARIETIES)}")
    extended = variety == "extended"
    b, target, params = fn(rng, extended)
    if extended:  # the classic variety draws nothing more, so its objects stay byte-identical
        params = {**params, "variety": variety, "furnishing": furnish(b, rng)}
    return b.finish(target, params)


def size(rng: np.random.Generator, category: str, extended: bool) -> tuple[float, float, float]:
    """Width (y), depth (x), height (z) in metres from the variety's ranges (module table)."""
    ranges = (EXTENDED_SIZES if extended else CLASSIC_SIZES)[category]
    return u(rng, *ranges[0]), u(rng, *ranges[1]), u(rng, *ranges[2])


def rescale(value: float, src: tuple[float, float], dst: tuple[float, float]) -> float:
    """``value`` mapped linearly from the range ``src`` to ``dst`` (a layout's own size range, no new draw)."""
    return dst[0] + (value - src[0]) / (src[1] - src[0]) * (dst[1] - dst[0])


CLASSIC_SIZES = {  # (width, depth, height) ranges in metres: the module table
    "microwave": ((0.44, 0.60), (0.32, 0.45), (0.26, 0.36)),
    "oven": ((0.55, 0.76), (0.55, 0.65), (0.82, 0.92)),
    "refrigerator": ((0.55, 0.90), (0.60, 0.75), (1.45, 1.90)),
    "dishwasher": ((0.45, 0.60), (0.55, 0.62), (0.80, 0.87)),
    "storage_furniture": ((0.40, 1.20), (0.35, 0.60), (0.45, 2.00)),
}
EXTENDED_SIZES = {
    "microwave": ((0.40, 0.76), (0.30, 0.45), (0.23, 0.45)),
    "oven": ((0.50, 0.90), (0.55, 0.70), (0.82, 0.95)),
    "refrigerator": ((0.55, 1.00), (0.60, 0.80), (1.45, 1.95)),
    "dishwasher": ((0.45, 0.60), (0.55, 0.65), (0.80, 0.88)),
    "storage_furniture": ((0.35, 1.60), (0.30, 0.65), (0.40, 2.10)),
}
DOUBLE_OVEN_HEIGHT = (1.00, 1.30)  # m: a wall oven with two cavities stacked
TWIN_OVEN_WIDTH = (0.90, 1.20)  # m: a range with two ovens side by side
WIDE_FRIDGE_WIDTH = (0.80, 1.00)  # m: side-by-side and French-door fridges


def _microwave(rng, extended: bool):
    W, D, H = size(rng, "microwave", extended)
    b = Builder("microwave", rng, wall=u(rng, 0.012, 0.018), front_thickness=u(rng, 0.025, 0.04))
    body = pick(rng, "appliance")
    b.carcass(W, D, H, 0.0, body, "metal")
    panel_w = u(rng, 0.22, 0.30) * W
    hinge = "left" if rng.random() < 0.85 else "right"
    if hinge == "left":
        door_cell = Cell(-W / 2, W / 2 - panel_w, 0.0, H, frozenset({"left", "top", "bottom"}))
        panel_cell = Cell(W / 2 - panel_w, W / 2, 0.0, H, frozenset({"right", "top", "bottom"}))
        b.divider(False, W / 2 - panel_w, 0.0, H, body, "metal")
    else:
        door_cell = Cell(-W / 2 + panel_w, W / 2, 0.0, H, frozenset({"right", "top", "bottom"}))
        panel_cell = Cell(-W / 2, -W / 2 + panel_w, 0.0, H, frozenset({"left", "top", "bottom"}))
        b.divider(False, -W / 2 + panel_w, 0.0, H, body, "metal")
    b.fixed_panel(
        panel_cell,
        pick(rng, "plastic"),
        "plastic",
        knobs=int(rng.integers(0, 3)),
        knob_color=pick(rng, "metal"),
    )
    handle = b.sample_handle(("bar", "u", "lip", "none"), (0.4, 0.2, 0.25, 0.15))
    door_color = body if rng.random() < 0.6 else pick(rng, "plastic")
    target = b.door(
        door_cell,
        hinge,
        u(rng, 1.6, 1.95),
        door_color,
        "metal",
        handle,
        window=(u(rng, 0.035, 0.06), PALETTES["glass"][0]),
    )
    return b, target, {"width": W, "depth": D, "height": H, "hinge": hinge, "handle": handle["type"]}


def _oven(rng, extended: bool):
    W, D, H = size(rng, "oven", extended)
    plinth = u(rng, 0.04, 0.09)
    b = Builder("oven", rng, wall=u(rng, 0.015, 0.022), front_thickness=u(rng, 0.035, 0.045))
    body = pick(rng, "appliance")
    layout = str(rng.choice(["single", "double", "twin"], p=[0.5, 0.25, 0.25])) if extended else "single"
    if layout == "double":
        H = rescale(H, EXTENDED_SIZES["oven"][2], DOUBLE_OVEN_HEIGHT)
    elif layout == "twin":
        W = rescale(W, EXTENDED_SIZES["oven"][0], TWIN_OVEN_WIDTH)
    b.carcass(W, D, H, plinth, body, "metal")
    strip = u(rng, 0.08, 0.13)
    params = {"width": W, "depth": D, "height": H}
    if layout == "single":
        target, extra = _oven_single(b, rng, W, H, plinth, strip, body)
    else:
        target, extra = _oven_pair(b, rng, W, H, plinth, strip, body, stacked=layout == "double")
    return b, target, {**params, **({"layout": layout} if extended else {}), **extra}


def _control_strip(b: Builder, rng, W: float, H: float, strip: float, body) -> None:
    """The oven's control strip with knobs along the top, over a shelf that closes the cavity below it."""
    b.fixed_panel(
        Cell(-W / 2, W / 2, H - strip, H, frozenset({"left", "right", "top"})),
        pick(rng, "plastic"),
        "plastic",
        knobs=int(rng.integers(3, 6)),
        knob_color=pick(rng, "metal"),
    )
    b.divider(True, H - strip, -W / 2, W / 2, body, "metal")


def _oven_single(b: Builder, rng, W: float, H: float, plinth: float, strip: float, body) -> tuple[str, dict]:
    """One bottom-hinged door under the control strip, 50 % a storage drawer below it."""
    has_drawer = rng.random() < 0.5
    drawer_h = u(rng, 0.12, 0.17) if has_drawer else 0.0
    z_door0 = plinth + drawer_h
    _control_strip(b, rng, W, H, strip, body)
    handle = b.sample_handle(("bar", "u"), (0.85, 0.15))
    outer = frozenset({"left", "right"} | ({"bottom"} if not has_drawer else set()))
    target = b.door(
        Cell(-W / 2, W / 2, z_door0, H - strip, outer),
        "bottom",
        u(rng, 1.45, 1.57),
        body,
        "metal",
        handle,
        window=(u(rng, 0.06, 0.1), PALETTES["glass"][0]),
    )
    if has_drawer:
        b.divider(True, z_door0, -W / 2, W / 2, body, "metal")
        b.drawer(
            Cell(-W / 2, W / 2, plinth, z_door0, frozenset({"left", "right", "bottom"})),
            body,
            "metal",
            b.sample_handle(("bar", "u", "lip"), (0.5, 0.2, 0.3)),
            u(rng, 0.6, 0.8),
        )
    return target, {"drawer": has_drawer, "handle": handle["type"]}


def _oven_pair(b: Builder, rng, W: float, H: float, plinth: float, strip: float, body, stacked: bool):
    """Two oven cavities with bottom-hinged doors under the control strip: stacked (a wall oven) or side by side
    (a wide range, the left one 50-62 % of the width); the target is either door."""
    _control_strip(b, rng, W, H, strip, body)
    handle = b.sample_handle(("bar", "u"), (0.85, 0.15))
    window = u(rng, 0.06, 0.1)
    if stacked:
        split = plinth + u(rng, 0.42, 0.5) * (H - strip - plinth)
        b.divider(True, split, -W / 2, W / 2, body, "metal")
        cells = [
            Cell(-W / 2, W / 2, split, H - strip, frozenset({"left", "right"})),
            Cell(-W / 2, W / 2, plinth, split, frozenset({"left", "right", "bottom"})),
        ]
    else:
        split = -W / 2 + u(rng, 0.5, 0.62) * W
        b.divider(False, split, plinth, H - strip, body, "metal")
        cells = [
            Cell(-W / 2, split, plinth, H - strip, frozenset({"left", "bottom"})),
            Cell(split, W / 2, plinth, H - strip, frozenset({"right", "bottom"})),
        ]
    upper = u(rng, 1.45, 1.57)
    doors = [b.door(c, "bottom", upper, body, "metal", handle, window=(window, PALETTES["glass"][0])) for c in cells]
    return doors[int(rng.integers(2))], {"drawer": False, "handle": handle["type"]}


def _refrigerator(rng, extended: bool):
    W, D, H = size(rng, "refrigerator", extended)
    plinth = u(rng, 0.02, 0.06)
    b = Builder("refrigerator", rng, wall=u(rng, 0.02, 0.03), front_thickness=u(rng, 0.04, 0.06))
    body = pick(rng, "appliance")
    hinge = "left" if rng.random() < 0.5 else "right"
    layouts = ["single", "top_freezer", "bottom_freezer"] + (["side_by_side", "french"] if extended else [])
    layout = str(rng.choice(layouts))
    if layout in ("side_by_side", "french"):
        W = rescale(W, EXTENDED_SIZES["refrigerator"][0], WIDE_FRIDGE_WIDTH)
    b.carcass(W, D, H, plinth, body, "metal")  # draws nothing: the classic draw order is kept
    joints = _FRIDGE_LAYOUTS[layout](b, rng, W, H, plinth, hinge, body)
    target = joints[int(rng.integers(len(joints)))]
    return b, target, {"width": W, "depth": D, "height": H, "layout": layout, "hinge": hinge}


def _stacked_cells(b: Builder, W: float, H: float, plinth: float, split: float, body) -> tuple[Cell, Cell]:
    """Lower and upper cell of a body divided by a shelf at height ``split`` (m); draws nothing."""
    b.divider(True, split, -W / 2, W / 2, body, "metal")
    lower = Cell(-W / 2, W / 2, plinth, split, frozenset({"left", "right", "bottom"}))
    upper = Cell(-W / 2, W / 2, split, H, frozenset({"left", "right", "top"}))
    return lower, upper


def _fridge_handle(b: Builder) -> dict:
    return b.sample_handle(("bar", "u", "lip"), (0.6, 0.2, 0.2), long_bar=True)


def _fridge_single(b: Builder, rng, W, H, plinth, hinge, body) -> list[str]:
    cell = Cell(-W / 2, W / 2, plinth, H, frozenset({"left", "right", "top", "bottom"}))
    upper = u(rng, 1.7, 2.2)  # drawn before the handle (the classic order)
    return [b.door(cell, hinge, upper, body, "metal", _fridge_handle(b))]


def _fridge_top_freezer(b: Builder, rng, W, H, plinth, hinge, body) -> list[str]:
    main, top = _stacked_cells(b, W, H, plinth, H - u(rng, 0.25, 0.35) * (H - plinth), body)
    h = _fridge_handle(b)
    return [
        b.door(main, hinge, u(rng, 1.7, 2.2), body, "metal", {**h, "along": u(rng, 0.6, 0.8)}),
        b.door(
            top, hinge, u(rng, 1.7, 2.2), body, "metal", {**h, "along": u(rng, 0.2, 0.4), "length": 0.6 * h["length"]}
        ),
    ]


def _fridge_bottom_freezer(b: Builder, rng, W, H, plinth, hinge, body) -> list[str]:
    bottom, main = _stacked_cells(b, W, H, plinth, plinth + u(rng, 0.28, 0.38) * (H - plinth), body)
    h = _fridge_handle(b)
    return [
        b.door(main, hinge, u(rng, 1.7, 2.2), body, "metal", {**h, "along": u(rng, 0.25, 0.45)}),
        b.drawer(bottom, body, "metal", {**h, "along": 0.8, "length": 0.5 * W}, u(rng, 0.6, 0.75)),
    ]


def _fridge_side_by_side(b: Builder, rng, W, H, plinth, hinge, body) -> list[str]:
    """Freezer door on the left (35-45 % of the width), fridge door on the right, both hinged outside."""
    split = -W / 2 + u(rng, 0.35, 0.45) * W
    b.divider(False, split, plinth, H, body, "metal")
    left = Cell(-W / 2, split, plinth, H, frozenset({"left", "top", "bottom"}))
    right = Cell(split, W / 2, plinth, H, frozenset({"right", "top", "bottom"}))
    upper, h = u(rng, 1.7, 2.2), _fridge_handle(b)
    return [b.door(left, "left", upper, body, "metal", h), b.door(right, "right", upper, body, "metal", h)]


def _fridge_french(b: Builder, rng, W, H, plinth, hinge, body) -> list[str]:
    """Two doors hinged outside over a freezer drawer (28-35 % of the height)."""
    split = plinth + u(rng, 0.28, 0.35) * (H - plinth)
    bottom, _ = _stacked_cells(b, W, H, plinth, split, body)
    b.divider(False, 0.0, split, H, body, "metal")
    left = Cell(-W / 2, 0.0, split, H, frozenset({"left", "top"}))
    right = Cell(0.0, W / 2, split, H, frozenset({"right", "top"}))
    h = _fridge_handle(b)
    upper, door_h = u(rng, 1.7, 2.2), {**h, "along": u(rng, 0.3, 0.5)}
    return [
        b.door(left, "left", upper, body, "metal", door_h),
        b.door(right, "right", upper, body, "metal", door_h),
        b.drawer(bottom, body, "metal", {**h, "along": 0.8, "length": 0.5 * W}, u(rng, 0.6, 0.75)),
    ]


_FRIDGE_LAYOUTS = {
    "single": _fridge_single,
    "top_freezer": _fridge_top_freezer,
    "bottom_freezer": _fridge_bottom_freezer,
    "side_by_side": _fridge_side_by_side,
    "french": _fridge_french,
}


def _dishwasher(rng, extended: bool):
    W, D, H = size(rng, "dishwasher", extended)
    plinth = u(rng, 0.08, 0.12)
    b = Builder("dishwasher", rng, wall=u(rng, 0.015, 0.02), front_thickness=u(rng, 0.035, 0.05))
    body = pick(rng, "appliance")
    b.carcass(W, D, H, plinth, body, "metal")
    handle = b.sample_handle(("bar", "u", "lip"), (0.5, 0.2, 0.3))
    cell = Cell(-W / 2, W / 2, plinth, H, frozenset({"left", "right", "top", "bottom"}))
    target = b.door(
        cell,
        "bottom",
        u(rng, 1.45, 1.57),
        body,
        "metal",
        handle,
        strip=(u(rng, 0.06, 0.1), pick(rng, "plastic")),
    )
    return b, target, {"width": W, "depth": D, "height": H, "handle": handle["type"]}


def _storage_furniture(rng, extended: bool):
    W, D, H = size(rng, "storage_furniture", extended)
    plinth = u(rng, 0.0, 0.1) if rng.random() < 0.7 else 0.0
    b = Builder("storage_furniture", rng, wall=u(rng, 0.015, 0.022), front_thickness=u(rng, 0.016, 0.024))
    wooden = rng.random() < 0.5
    material = "wood" if wooden else "painted"
    body = pick(rng, material)
    front = body if rng.random() < 0.6 else pick(rng, "wood" if wooden else "painted")
    b.carcass(W, D, H, plinth, body, material)
    n_cols = int(rng.integers(1, 4)) if W > 0.7 else int(rng.integers(1, 3))
    handle = b.sample_handle(("bar", "u", "knob", "lip", "none"), (0.35, 0.2, 0.2, 0.15, 0.1))
    edges = np.linspace(-W / 2, W / 2, n_cols + 1)
    for y in edges[1:-1]:
        b.divider(False, y, plinth, H, body, material)
    movable = []
    for ci in range(n_cols):
        y0, y1 = edges[ci], edges[ci + 1]
        outer_lr = ({"left"} if ci == 0 else set()) | ({"right"} if ci == n_cols - 1 else set())
        # rows in this column: drawers at the top and/or doors below
        n_drawers = int(rng.integers(0, 5)) if H < 1.2 else int(rng.integers(0, 3))
        avail = H - plinth
        drawer_h = u(rng, 0.12, 0.25)
        n_drawers = min(n_drawers, int(avail // drawer_h))
        has_door = n_drawers == 0 or (avail - n_drawers * drawer_h > 0.25 and rng.random() < 0.7)
        if not has_door:
            drawer_h = avail / max(n_drawers, 1)
        z_top = H
        for k in range(n_drawers):
            z0 = z_top - drawer_h
            outer = frozenset(
                outer_lr
                | ({"top"} if k == 0 else set())
                | ({"bottom"} if (not has_door and k == n_drawers - 1) else set())
            )
            if not (not has_door and k == n_drawers - 1):
                b.divider(True, z0, y0, y1, body, material)
            movable.append(
                b.drawer(
                    Cell(y0, y1, z0, z_top, outer),
                    front,
                    material,
                    {**handle, "type": handle["type"] if handle["type"] != "none" else "lip"},
                    u(rng, 0.6, 0.8),
                )
            )
            z_top = z0
        if has_door:
            cell = Cell(
                y0,
                y1,
                plinth,
                z_top,
                frozenset(outer_lr | {"bottom"} | ({"top"} if n_drawers == 0 else set())),
            )
            if cell.width > cell.height * 1.4 and rng.random() < 0.5:
                hinge, upper = "top", u(rng, 1.2, 1.57)
            elif "left" in outer_lr and ("right" not in outer_lr or rng.random() < 0.5):
                hinge, upper = "left", u(rng, 1.57, 2.0)
            elif "right" in outer_lr:
                hinge, upper = "right", u(rng, 1.57, 2.0)
            else:
                hinge, upper = str(rng.choice(["left", "right"])), float(np.pi / 2)
            movable.append(b.door(cell, hinge, upper, front, material, handle))
    target = movable[int(rng.integers(len(movable)))]
    return (
        b,
        target,
        {
            "width": W,
            "depth": D,
            "height": H,
            "columns": n_cols,
            "handle": handle["type"],
            "material": material,
        },
    )


_BUILDERS = {
    "microwave": _microwave,
    "oven": _oven,
    "refrigerator": _refrigerator,
    "dishwasher": _dishwasher,
    "storage_furniture": _storage_furniture,
}
