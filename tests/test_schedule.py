"""The cases of a comparison or sweep study: handed out costliest first to whichever rank is
free, with a cost estimate that knows whether the damper slips at the case's force."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from workbench.studies.engine.schedule import (
    case_cost,
    run_tasks,
    schedule_efficiency,
    simulate_schedule,
)


def _case(damper, phase, force, harmonics=(0, 1, 2, 3)):
    return SimpleNamespace(
        damper=damper, variant="", phase_deg=phase, force_n=force,
        settings={"harmonics": list(harmonics)}, name=f"{damper}-{phase:g}-{force:g}",
    )  # fmt: skip


def _prep(pairs):
    return SimpleNamespace(assembled=SimpleNamespace(n_pairs=pairs))


SCREEN = [  # the screen's slip onsets (N) of each model and phase; None: never slips
    {"damper": "wedge", "variant": "", "phase_deg": 180.0, "f_slip_n": 5.0},
    {"damper": "wedge", "variant": "", "phase_deg": 0.0, "f_slip_n": 12.0},
    {"damper": "cone", "variant": "", "phase_deg": 0.0, "f_slip_n": 2.0},
    {"damper": "cylinder", "variant": "", "phase_deg": 0.0, "f_slip_n": None},
]


def test_a_slipping_damper_costs_more_than_a_stuck_one():
    wedge = _prep(146)
    stuck = case_cost(_case("wedge", 180.0, 3.84), wedge, SCREEN)
    slips = case_cost(_case("wedge", 180.0, 9.6), wedge, SCREEN)
    assert slips == pytest.approx(3.5 * stuck)
    # the same force slips out of phase and not in phase (the screen's onsets differ)
    assert case_cost(_case("wedge", 0.0, 9.6), wedge, SCREEN) == pytest.approx(stuck)
    # a cylinder that never slips; a case the screen does not know is taken to slip
    cyl, cone = _prep(46), _prep(46)
    assert case_cost(_case("cylinder", 0.0, 30.0), cyl, SCREEN) < case_cost(
        _case("cone", 0.0, 30.0), cone, SCREEN
    )
    assert case_cost(_case("cone", 180.0, 30.0), cone, SCREEN) == pytest.approx(
        case_cost(_case("cone", 0.0, 30.0), cone, SCREEN)
    )
    # the size of the system counts: a wedge curve outweighs a cone curve at equal regime
    assert stuck > case_cost(_case("cone", 0.0, 1.0), cone, SCREEN)


def test_the_paper_rig_curves_keep_both_ranks_busy():
    """The paper-like rig's 42 curve times of issue 28's run (s): round robin after a sort
    by a cost that did not know the slip regime left one rank idle for minutes; the shared
    counter, costliest first by the slip-aware estimate, ends within the longest curve of the
    ideal split."""
    measured = {
        ("wedge", 180.0): [1.9, 9.0, 461.0, 495.0, 679.0, 754.0, 915.0],
        ("wedge", 0.0): [3.0, 13.5, 124.0, 128.0, 130.0, 131.0, 133.0],
        ("cone", 0.0): [1.7, 3.0, 6.0, 7.0, 7.5, 8.0, 9.0],
        ("cone", 180.0): [1.7, 2.5, 5.0, 5.5, 6.0, 6.5, 7.0],
        ("cylinder", 0.0): [1.7] * 7,
        ("cylinder", 180.0): [1.8, 2.0, 4.0, 4.5, 5.0, 5.5, 6.0],
    }
    forces = [0.096, 3.84, 9.6, 15.0, 20.0, 25.0, 30.0]
    screen = [
        {"damper": d, "variant": "", "phase_deg": p, "f_slip_n": fs}
        for (d, p), fs in {
            ("wedge", 180.0): 5.0, ("wedge", 0.0): 5.0, ("cone", 0.0): 2.2,
            ("cone", 180.0): 2.0, ("cylinder", 0.0): None, ("cylinder", 180.0): 3.0,
        }.items()
    ]  # fmt: skip
    pairs = {"wedge": 146, "cone": 46, "cylinder": 46}
    cases = [
        (_case(d, p, f), t)
        for (d, p), ts in measured.items()
        for f, t in zip(forces, ts, strict=True)
    ]
    order = sorted(cases, key=lambda ct: -case_cost(ct[0], _prep(pairs[ct[0].damper]), screen))
    costs = [t for _, t in order]
    dynamic = simulate_schedule(costs, 2, static=False)
    total = sum(costs)
    assert dynamic <= total / 2 + max(costs) / 2 + 1e-9
    # the old way: a cost sort blind to slipping, then round robin
    blind = sorted(cases, key=lambda ct: -pairs[ct[0].damper])
    static = simulate_schedule([t for _, t in blind], 2, static=True)
    assert static > dynamic * 1.1
    # the slip-aware order puts every slipping wedge curve out of phase first
    assert {c.force_n for c, _ in order[:5]} == {9.6, 15.0, 20.0, 25.0, 30.0}


def test_each_rank_busy_time_and_the_balance_are_reported():
    rec = run_tasks(5, lambda k: {"k2": k * k})
    s = schedule_efficiency(rec, 1)
    assert len(s["busy_per_rank_s"]) == 1 and s["ranks"] == 1
    assert s["busy_s"] == pytest.approx(sum(r["end"] - r["start"] for r in rec))
    assert 0.0 < s["efficiency"] <= 1.0 + 1e-9
