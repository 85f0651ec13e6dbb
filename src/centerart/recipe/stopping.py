"""The stopping rule of a sliced run, computed from its learning curve (``slices.learning_curve``).

Issue 29's "done when": a run stops when three consecutive slices no longer improve its validation figures. Here a
slice *improves* when at least one figure beats the best of every earlier point of the curve (the run's start
included), by any margin; a figure a slice measures for the first time is not an improvement. Which way is better
follows from the figure's unit: rates (recall, precision, accuracy, top-1) up, distances and angles down.
"""

from __future__ import annotations

#: Consecutive slices without a new best figure after which the run counts as no longer improving.
PLATEAU_SLICES = 3
#: Units whose figures are better when higher; every other unit (cm, mm, deg) is better when lower.
HIGHER_IS_BETTER = frozenset({"rate"})


def new_bests(curve: dict) -> list[dict]:
    """For each slice of the curve (its points after the start): ``{"slice", "figures"}``, ``figures`` mapping each
    figure the slice made the best so far to ``(new value, previous best)``."""
    best: dict[str, float] = {}
    out = []
    for point in curve["points"]:
        improved = {}
        for column in curve["columns"]:
            value = point.get(column)
            if value is None:
                continue
            before = best.get(column)
            higher = curve["units"][column] in HIGHER_IS_BETTER
            if before is None or (value > before if higher else value < before):
                best[column] = value
                if before is not None:
                    improved[column] = (value, before)
        if point["slice"] > 0:
            out.append({"slice": point["slice"], "figures": improved})
    return out


def stopping_rule(curve: dict) -> dict:
    """The rule's state: ``slices_without_improvement`` (the trailing slices that set no best figure),
    ``last_improvement`` (the last slice that did, or None), ``plateau`` (True once the trailing count reaches
    ``PLATEAU_SLICES``) and ``per_slice`` (``new_bests``)."""
    per_slice = new_bests(curve)
    improving = [s for s in per_slice if s["figures"]]
    last = improving[-1] if improving else None
    trailing = len(per_slice) - (per_slice.index(last) + 1 if last else 0)
    return {"plateau_slices": PLATEAU_SLICES, "slices_without_improvement": trailing, "last_improvement": last,
            "plateau": trailing >= PLATEAU_SLICES, "per_slice": per_slice}  # fmt: skip


def stopping_summary(rule: dict) -> str:
    """One line for ``slices status``: the last slice that set a best figure, and whether the run has stopped."""
    n, last = rule["slices_without_improvement"], rule["last_improvement"]
    if last is None:
        where = "no slice has set a best validation figure yet"
    else:
        bests = ", ".join(f"{c} {v:.3f} (best before {b:.3f})" for c, (v, b) in last["figures"].items())
        where = f"slice {last['slice']} last set a best: {bests}"
    verdict = "the run has stopped improving" if rule["plateau"] else "the run goes on"
    return (f"stopping rule ({rule['plateau_slices']} consecutive slices without a new best validation figure): "
            f"{where}; {n} slice(s) since; {verdict}")  # fmt: skip
