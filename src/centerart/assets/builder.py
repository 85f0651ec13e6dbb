"""Building blocks of generated furniture: a carcass, dividers, doors, drawers, handles and fixed panels.

Construction frame ("body frame", metres): the carcass front plane is x = 0 and its body extends to x = -depth;
y runs across the front (+y = the viewer's right), z up from the floor at z = 0. Doors and drawer fronts sit
in front of that plane. :meth:`Builder.finish` moves everything so that the base link frame becomes the
canonical object frame (origin at the closed bounding-box centre).

Clearances that keep physics honest:
- a door's hinge line is on the front outer corner of the door, so for 0 <= q <= pi/2 no point of the door
  passes behind its closed back face and it stays on its own side of the hinge; only doors hinged on the
  object's outer edge may open further (they swing outside the carcass);
- drawer trays are smaller than their opening by ``DRAWER_CLEARANCE`` on every side;
- bar and U handles keep at least ``MIN_HANDLE_CLEARANCE`` between the grip and the front face, so a gripper
  finger (1 cm x 2 cm) fits behind them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from centerart.assets.spec import (
    HandleSpec,
    JointSpec,
    LinkSpec,
    ObjectSpec,
    VisualGroup,
    box_between,
    cylinder_along,
)

FRONT_GAP = 0.003  # m between the carcass front plane and the back of doors / drawer fronts
DRAWER_CLEARANCE = 0.006  # m between a drawer tray and its opening, on every side
MIN_HANDLE_CLEARANCE = 0.022  # m of free space between a bar/U grip and the front face
EMBED = 0.001  # m that attached pieces sink into each other so their union is one solid

PALETTES = {
    "painted": [
        (0.93, 0.93, 0.91),
        (0.85, 0.82, 0.74),
        (0.62, 0.64, 0.66),
        (0.55, 0.66, 0.72),
        (0.58, 0.66, 0.55),
        (0.18, 0.24, 0.36),
        (0.12, 0.12, 0.13),
        (0.75, 0.35, 0.28),
    ],
    "wood": [(0.72, 0.55, 0.36), (0.42, 0.28, 0.18), (0.86, 0.76, 0.60), (0.60, 0.42, 0.26)],
    "metal": [(0.76, 0.77, 0.79), (0.16, 0.16, 0.17), (0.72, 0.60, 0.32), (0.86, 0.87, 0.89)],
    "appliance": [(0.94, 0.94, 0.94), (0.76, 0.77, 0.79), (0.14, 0.14, 0.15), (0.60, 0.61, 0.63)],
    "glass": [(0.07, 0.08, 0.10)],
    "plastic": [(0.10, 0.10, 0.11), (0.85, 0.85, 0.85)],
}

HANDLE_TYPES = ("bar", "u", "knob", "lip", "none")


@dataclass
class Cell:
    """A rectangle of the front plane (y0 < y1, z0 < z1) and which of its sides lie on the carcass outside."""

    y0: float
    y1: float
    z0: float
    z1: float
    outer: frozenset[str] = frozenset()  # subset of {"left", "right", "bottom", "top"}

    @property
    def width(self) -> float:
        return self.y1 - self.y0

    @property
    def height(self) -> float:
        return self.z1 - self.z0


def rgba(color, alpha: float = 1.0) -> tuple[float, float, float, float]:
    return (float(color[0]), float(color[1]), float(color[2]), alpha)


class Builder:
    """Accumulates links, joints and handles of one object. ``rng`` makes every choice."""

    def __init__(self, category: str, rng: np.random.Generator, wall: float, front_thickness: float):
        self.category = category
        self.rng = rng
        self.t = wall
        self.td = front_thickness
        self.base: list[VisualGroup] = []
        self.links: list[LinkSpec] = []
        self.joints: list[JointSpec] = []
        self.handles: list[HandleSpec] = []
        self.depth = 0.0
        self.width = 0.0
        self.height = 0.0
        self.z_base = 0.0
        # (kind, cell, hinge) of every front: door / drawer / panel; hinge is None but for doors. Later
        # furnishing (shelves behind doors, displays on panels) reads it.
        self.fronts: list[tuple[str, Cell, str | None]] = []

    # ------------------------------------------------------------- carcass
    def carcass(self, width: float, depth: float, height: float, z_base: float, color, material: str) -> None:
        """Five panels (back, sides, top, bottom) from z_base to height; a recessed plinth below z_base."""
        t, w2 = self.t, width / 2
        self.depth, self.width, self.height, self.z_base = depth, width, height, z_base
        prims = [
            box_between([-depth, -w2, z_base], [-depth + t, w2, height]),  # back
            box_between([-depth, -w2, z_base], [0, -w2 + t, height]),  # left side
            box_between([-depth, w2 - t, z_base], [0, w2, height]),  # right side
            box_between([-depth, -w2, height - t], [0, w2, height]),  # top
            box_between([-depth, -w2, z_base], [0, w2, z_base + t]),  # bottom
        ]
        if z_base > 0:
            prims.append(box_between([-depth + 0.02, -w2 + 0.02, 0.0], [-0.05, w2 - 0.02, z_base + EMBED]))
        self.base.append(VisualGroup("body", prims, rgba(color), material))

    def feet(self, radius: float, height: float, color, material: str) -> None:
        """Four cylindrical feet under the carcass corners (inset 4 cm). They replace the recessed plinth when the
        carcass has one (from the floor to its bottom); otherwise they lift it: they hang ``height`` below z = 0,
        which :meth:`finish` re-centres away."""
        body = self.base[0]
        if self.z_base > 0:
            body.primitives.pop()  # the recessed plinth, last of the carcass primitives
            z0, z1 = 0.0, self.z_base + EMBED
        else:
            z0, z1 = -height, EMBED
        d, w2, inset = self.depth, self.width / 2, 0.04 + radius
        prims = [
            cylinder_along(2, [x, y, (z0 + z1) / 2], radius, z1 - z0)
            for x in (-d + inset, -inset)
            for y in (-w2 + inset, w2 - inset)
        ]
        self.base.append(VisualGroup(f"feet_{len(self.base)}", prims, rgba(color), material))

    def divider(self, horizontal: bool, at: float, lo: float, hi: float, color, material: str) -> None:
        """A shelf (horizontal, at height ``at``, spanning y in [lo, hi]) or a partition (vertical, at y)."""
        t, d = self.t, self.depth
        if horizontal:
            prim = box_between([-d + t - EMBED, lo, at - t / 2], [0, hi, at + t / 2])
        else:
            prim = box_between([-d + t - EMBED, at - t / 2, lo], [0, at + t / 2, hi])
        self.base.append(VisualGroup(f"divider_{len(self.base)}", [prim], rgba(color), material))

    def opening(self, cell: Cell) -> Cell:
        """The hole behind a cell: the cell minus the walls (t) and half-dividers (t/2) around it."""
        t = self.t

        def inset(side):
            return t if side in cell.outer else t / 2

        return Cell(
            cell.y0 + inset("left"),
            cell.y1 - inset("right"),
            cell.z0 + inset("bottom"),
            cell.z1 - inset("top"),
        )

    def fixed_panel(self, cell: Cell, color, material: str, knobs: int = 0, knob_color=None) -> None:
        """A non-moving front (control panel) over a cell, optionally with a row of control knobs."""
        g, td = FRONT_GAP, self.td
        prims = [
            box_between([-EMBED, cell.y0 + g / 2, cell.z0 + g / 2], [g + td, cell.y1 - g / 2, cell.z1 - g / 2]),
            box_between([-self.t, cell.y0 + g / 2, cell.z0 + g / 2], [0.0, cell.y1 - g / 2, cell.z1 - g / 2]),
        ]
        self.base.append(VisualGroup(f"panel_{len(self.base)}", prims, rgba(color), material))
        self.fronts.append(("panel", cell, None))
        if knobs:
            zc = (cell.z0 + cell.z1) / 2
            r = min(0.018, 0.3 * cell.height)
            ys = np.linspace(cell.y0, cell.y1, knobs + 2)[1:-1]
            kp = [cylinder_along(0, [g + td + 0.008 - EMBED, y, zc], r, 0.016) for y in ys]
            self.base.append(VisualGroup(f"knobs_{len(self.base)}", kp, rgba(knob_color or (0.1, 0.1, 0.1)), "plastic"))

    # ------------------------------------------------------------- moving fronts
    def door(
        self,
        cell: Cell,
        hinge: str,
        upper: float,
        color,
        material: str,
        handle: dict,
        window: tuple | None = None,
        strip: tuple | None = None,
    ) -> str:
        """A door over ``cell`` hinged on its ``hinge`` edge (left/right/bottom/top). Returns the joint name.

        ``window`` = (inset, color): a dark glass pane on the front; ``strip`` = (height, color): a control strip
        along the top of the door.
        """
        g, td = FRONT_GAP, self.td
        lo = np.array([g, cell.y0 + g / 2, cell.z0 + g / 2])
        hi = np.array([g + td, cell.y1 - g / 2, cell.z1 - g / 2])
        front_x = hi[0]
        hinge_pt, axis = {
            "left": ([front_x, lo[1], 0.0], [0.0, 0.0, -1.0]),
            "right": ([front_x, hi[1], 0.0], [0.0, 0.0, 1.0]),
            "bottom": ([front_x, 0.0, lo[2]], [0.0, 1.0, 0.0]),
            "top": ([front_x, 0.0, hi[2]], [0.0, -1.0, 0.0]),
        }[hinge]
        origin = np.array(hinge_pt)
        groups = [VisualGroup("door", [box_between(lo, hi)], rgba(color), material)]
        if window is not None:
            inset, wcolor = window
            top = hi[2] - (strip[0] if strip else 0.0)
            glass = box_between(
                [front_x - EMBED, lo[1] + inset, lo[2] + inset], [front_x + 0.002, hi[1] - inset, top - inset]
            )
            groups.append(VisualGroup("window", [glass], rgba(wcolor), "glass"))
        if strip is not None:
            h, scolor = strip
            groups.append(
                VisualGroup(
                    "strip",
                    [box_between([front_x - EMBED, lo[1], hi[2] - h], [front_x + 0.003, hi[1], hi[2]])],
                    rgba(scolor),
                    "plastic",
                )
            )
        free_edge = {"left": "right", "right": "left", "bottom": "top", "top": "bottom"}[hinge]
        self.fronts.append(("door", cell, hinge))
        self._handle(groups, handle, lo, hi, free_edge, strip[0] if strip else 0.0)
        return self._add_moving(f"door_{len(self.links)}", groups, origin, axis, "revolute", 0.0, upper, "door")

    def drawer(self, cell: Cell, color, material: str, handle: dict, travel_fraction: float) -> str:
        """A drawer: front slab over ``cell`` plus an open-top tray sliding along +x. Returns the joint name."""
        g, td, c, tw = FRONT_GAP, self.td, DRAWER_CLEARANCE, 0.012
        lo = np.array([g, cell.y0 + g / 2, cell.z0 + g / 2])
        hi = np.array([g + td, cell.y1 - g / 2, cell.z1 - g / 2])
        op = self.opening(cell)
        back = -self.depth + self.t + 0.01
        y0, y1, z0, z1 = op.y0 + c, op.y1 - c, op.z0 + c, op.z1 - c - 0.01
        tray = [
            box_between([back, y0, z0], [g + EMBED, y1, z0 + tw]),  # floor
            box_between([back, y0, z0], [g + EMBED, y0 + tw, z1]),  # left
            box_between([back, y1 - tw, z0], [g + EMBED, y1, z1]),  # right
            box_between([back, y0, z0], [back + tw, y1, z1]),  # back
        ]
        groups = [
            VisualGroup("front", [box_between(lo, hi)], rgba(color), material),
            VisualGroup("tray", tray, rgba(np.clip(np.asarray(color) * 0.85, 0, 1)), material),
        ]
        self._handle(groups, handle, lo, hi, "center", 0.0)
        self.fronts.append(("drawer", cell, None))
        travel = travel_fraction * (g - back)
        origin = np.array([hi[0], (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2])
        return self._add_moving(
            f"drawer_{len(self.links)}", groups, origin, [1.0, 0.0, 0.0], "prismatic", 0.0, travel, "drawer"
        )

    def _add_moving(self, name, groups, origin, axis, jtype, lower, upper, role) -> str:
        shifted = [VisualGroup(g.name, [p.shifted(-origin) for p in g.primitives], g.rgba, g.material) for g in groups]
        self.links.append(LinkSpec(name, shifted, density=self._density(role)))
        damping, friction = (0.2, 0.05) if jtype == "revolute" else (2.0, 0.1)
        self.joints.append(
            JointSpec(
                f"joint_{name}",
                jtype,
                "base",
                name,
                origin.copy(),
                np.asarray(axis, float),
                lower,
                upper,
                damping,
                friction,
                role,
            )
        )
        for h in self.handles:
            if h.link == "__pending__":
                h.link = name
                h.center = h.center - origin
        return f"joint_{name}"

    def _density(self, role: str) -> float:
        # Effective density of a door/drawer of this category: appliance doors are steel skins with insulation,
        # furniture fronts are MDF or wood (600-750 kg/m^3).
        return {"refrigerator": 350.0, "oven": 900.0, "dishwasher": 600.0, "microwave": 700.0}.get(self.category, 650.0)

    # ------------------------------------------------------------- handles
    def _handle(self, groups: list[VisualGroup], h: dict, lo, hi, free_edge: str, strip: float) -> None:
        """Add handle ``h`` (see :meth:`sample_handle`) to the front face of the box lo..hi (body frame, m).

        ``free_edge`` (left, right, top, bottom; anything else: a drawer) is the edge that opens; ``strip`` (m) is
        the height of the control strip along the front's top edge (0 without one), which grips stay below. The
        handle's geometry goes to ``groups``; its :class:`HandleSpec` waits on ``self.handles`` for the link that
        receives the front.
        """
        kind = h["type"]
        if kind == "none":
            return
        vertical = free_edge in ("left", "right")
        c = _grip_centre(h, lo, hi, free_edge, strip)
        span = (hi[2] - lo[2]) if vertical else (hi[1] - lo[1])
        length = float(min(h["length"], 0.85 * span))
        ax = 2 if vertical else 1
        # keep the grip on the front face
        lim_lo, lim_hi = lo[ax] + length / 2 + 0.01, hi[ax] - length / 2 - 0.01
        c[ax] = np.clip(c[ax], lim_lo, max(lim_lo, lim_hi))
        if kind in ("bar", "u"):
            prims, spec = _bar_handle(kind, c, ax, length, h["radius"], h["standoff"])
        elif kind == "knob":
            prims, spec = _knob_handle(c, h["knob_radius"], h["standoff"])
        elif kind == "lip":
            across = 1 if vertical else 2
            prims, spec = _lip_handle(c, ax, across, length, h, lo, hi, free_edge, strip)
        else:
            raise ValueError(f"unknown handle type {kind!r}")
        groups.append(VisualGroup("handle", prims, rgba(h["color"]), "metal"))
        self.handles.append(spec)

    def sample_handle(self, kinds: tuple[str, ...], weights: tuple[float, ...], long_bar: bool = False) -> dict:
        rng = self.rng
        kind = str(rng.choice(kinds, p=np.asarray(weights) / np.sum(weights)))
        metal = PALETTES["metal"][rng.integers(len(PALETTES["metal"]))]
        return {
            "type": kind,
            "color": metal,
            "length": float(rng.uniform(0.25, 0.6) if long_bar else rng.uniform(0.09, 0.32)),
            "radius": float(rng.uniform(0.006, 0.011)),
            "standoff": float(rng.uniform(0.032, 0.055)),
            "inset": float(rng.uniform(0.035, 0.07)),
            "along": float(rng.uniform(0.4, 0.65)),
            "knob_radius": float(rng.uniform(0.013, 0.022)),
            "lip_depth": float(rng.uniform(0.018, 0.03)),
            "lip_thickness": float(rng.uniform(0.01, 0.016)),
        }

    # ------------------------------------------------------------- result
    def finish(self, target_joint: str, params: dict) -> ObjectSpec:
        """Re-centre on the closed bounding box and return the spec (base frame = canonical frame)."""
        base = LinkSpec("base", self.base, density=500.0)
        links = [base, *self.links]
        pts = [p.mesh().vertices for g in base.groups for p in g.primitives]
        for j, link in zip(self.joints, self.links, strict=True):
            pts += [p.mesh().vertices + j.origin for p in link.primitives()]
        allpts = np.concatenate(pts)
        center = (allpts.min(0) + allpts.max(0)) / 2
        base.groups = [
            VisualGroup(g.name, [p.shifted(-center) for p in g.primitives], g.rgba, g.material) for g in base.groups
        ]
        for j in self.joints:
            j.origin = j.origin - center
        params = {**params, "bounding_box_extents": (allpts.max(0) - allpts.min(0)).round(4).tolist()}
        return ObjectSpec(self.category, links, self.joints, target_joint, self.handles, params)


def _grip_centre(h: dict, lo, hi, free_edge: str, strip: float) -> np.ndarray:
    """Grip centre (body frame, m) on the front face x = hi[0] of the box lo..hi, near its ``free_edge``."""
    fx = hi[0]
    inset = h["inset"]
    if free_edge == "right":
        return np.array([fx, hi[1] - inset, lo[2] + h["along"] * (hi[2] - lo[2])])
    if free_edge == "left":
        return np.array([fx, lo[1] + inset, lo[2] + h["along"] * (hi[2] - lo[2])])
    if free_edge == "top":
        return np.array([fx, (lo[1] + hi[1]) / 2, hi[2] - strip - inset])
    if free_edge == "bottom":
        return np.array([fx, (lo[1] + hi[1]) / 2, lo[2] + inset])
    # drawer: centre, in the upper part of tall fronts
    c = np.array([fx, (lo[1] + hi[1]) / 2, lo[2] + max(0.5, h["along"]) * (hi[2] - lo[2])])
    c[2] = min(c[2], hi[2] - 0.04)
    return c


def _bar_handle(kind: str, c: np.ndarray, ax: int, length: float, r: float, s: float) -> tuple[list, HandleSpec]:
    """A bar (cylinder on two legs) or U (box) grip of radius ``r`` along body axis ``ax``, ``s`` (m) in front
    of the front-face point ``c``; the standoff grows to leave MIN_HANDLE_CLEARANCE behind the grip."""
    axis_vec = np.eye(3)[ax]
    s = max(s, r + MIN_HANDLE_CLEARANCE + 0.002)
    grip_c = c + np.array([s, 0.0, 0.0])
    leg_off = length / 2 - (0.015 if kind == "bar" else r)
    prims = []
    if kind == "bar":
        prims.append(cylinder_along(ax, grip_c, r, length))
        for sign in (-1, 1):
            p = c + sign * leg_off * axis_vec + np.array([s / 2 - EMBED / 2, 0, 0])
            prims.append(cylinder_along(0, p, 0.75 * r, s + EMBED))
    else:
        half = np.full(3, r)
        half[ax] = length / 2
        prims.append(box_between(grip_c - half, grip_c + half))
        for sign in (-1, 1):
            p = c + sign * leg_off * axis_vec
            leg_half = np.full(3, r)
            leg_half[0] = 0.0
            prims.append(box_between(p - leg_half - np.array([EMBED, 0, 0]), p + leg_half + np.array([s, 0, 0])))
    return prims, HandleSpec(kind, "__pending__", grip_c, axis_vec, length, 2 * r, s - r)


def _knob_handle(c: np.ndarray, kr: float, stem: float) -> tuple[list, HandleSpec]:
    """A round knob of radius ``kr`` on a stem (its length clamped to 18-35 mm) out of the front-face point ``c``."""
    stem = min(max(stem, 0.018), 0.035)
    prims = [
        cylinder_along(0, c + np.array([stem / 2 - EMBED / 2, 0, 0]), 0.006, stem + EMBED),
        cylinder_along(0, c + np.array([stem + 0.008, 0, 0]), kr, 0.016),
    ]
    spec = HandleSpec(
        "knob", "__pending__", c + np.array([stem + 0.008, 0, 0]), np.array([1.0, 0, 0]), 0.016, 2 * kr, stem
    )
    return prims, spec


def _lip_handle(
    c: np.ndarray, ax: int, across: int, length: float, h: dict, lo, hi, free_edge: str, strip: float
) -> tuple[list, HandleSpec]:
    """A pull ridge along the free edge, standing proud of the front (body frame, m)."""
    depth, thick = h["lip_depth"], h["lip_thickness"]
    half = np.zeros(3)
    half[ax] = length / 2
    edge = c.copy()
    if free_edge == "right":
        edge[across] = hi[1] - thick / 2
    elif free_edge == "left":
        edge[across] = lo[1] + thick / 2
    elif free_edge in ("top", "center"):
        edge[across] = hi[2] - strip - thick / 2
    else:
        edge[across] = lo[2] + thick / 2
    half[across] = thick / 2
    lo_p = edge - half + np.array([-EMBED, 0, 0])
    hi_p = edge + half + np.array([depth, 0, 0])
    return [box_between(lo_p, hi_p)], HandleSpec(
        "lip", "__pending__", (lo_p + hi_p) / 2, np.eye(3)[ax], length, thick, 0.0
    )


def pick(rng: np.random.Generator, palette: str):
    colors = PALETTES[palette]
    return colors[rng.integers(len(colors))]
