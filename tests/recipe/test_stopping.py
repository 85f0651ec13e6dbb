"""The stopping rule of a sliced run: which slices set a best figure (rates up, distances down), how many slices
have passed since, and the plateau after three."""

from __future__ import annotations

from centerart.recipe.stopping import PLATEAU_SLICES, stopping_rule, stopping_summary


def _curve(rows: list[tuple]) -> dict:
    """Points (slice 0 = the start) with a recall (rate) and a translation (cm); None: not measured."""
    points = [{"slice": i, "recall": r, "translation_cm_median": t} for i, (r, t) in enumerate(rows)]
    return {"columns": ["recall", "translation_cm_median"], "units": {"recall": "rate", "translation_cm_median": "cm"},
            "points": points}  # fmt: skip


def test_a_slice_improves_when_a_rate_rises_or_a_distance_falls_past_every_earlier_point():
    #       start        1: recall up    2: both worse  3: cm down     4: equal is no gain
    rows = [(0.5, None), (0.6, 5.0), (0.55, 6.0), (0.55, 4.0), (0.6, 4.0)]
    rule = stopping_rule(_curve(rows))
    figures = [s["figures"] for s in rule["per_slice"]]
    # Slice 1 measures the translation for the first time: not an improvement of it.
    assert figures == [{"recall": (0.6, 0.5)}, {}, {"translation_cm_median": (4.0, 5.0)}, {}]
    assert rule["last_improvement"]["slice"] == 3 and rule["slices_without_improvement"] == 1
    assert not rule["plateau"]
    assert "slice 3 last set a best: translation_cm_median 4.000 (best before 5.000)" in stopping_summary(rule)


def test_three_slices_without_a_new_best_stop_the_run():
    rows = [(0.5, 5.0), (0.7, 4.0)] + [(0.69, 4.1)] * PLATEAU_SLICES
    rule = stopping_rule(_curve(rows))
    assert rule["slices_without_improvement"] == PLATEAU_SLICES and rule["plateau"]
    assert stopping_summary(rule).endswith("the run has stopped improving")
    never = stopping_rule(_curve([(0.5, 5.0), (0.4, 6.0)]))
    assert never["last_improvement"] is None and never["slices_without_improvement"] == 1
    assert "no slice has set a best validation figure yet" in stopping_summary(never)
