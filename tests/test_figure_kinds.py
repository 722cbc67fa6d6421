"""Every matplotlib figure kind of the workbench: a Figure when asked, labelled axes with units.

Each plot function is called on small synthetic inputs shaped like a real
study with ``path=None``: it must return a Figure (nothing written) whose
labelled axes all carry a unit (or are counts, named below), and that
Figure saved must be a non-blank PNG. This is the floor; the figures themselves were
judged by looking at them (docs/CLOSING_NOTES.md lists the before/after files).
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from tests.conftest import assert_nonblank
from tests.synthetic import synthetic_study, synthetic_sweep
from workbench.hbm.io.examples import sdof_jenkins
from workbench.post.tables import curve_set
from workbench.render import curves
from workbench.render import study_figures as sf
from workbench.render.common import save_figure
from workbench.render.status_figures import plot_status_map, plot_status_shares
from workbench.render.sweep_figures import plot_sweep
from workbench.studies.kinds.fidelity import figures as ff
from workbench.studies.kinds.robustness import figures as rf

UNIT = re.compile(r"\(([^)]*[A-Za-z%/][^)]*)\)|, (%|s|Hz|mm|mJ|N)$")
COUNTS = {"contact pair number", "contact element", "stuck / 0"}


@pytest.fixture(scope="module")
def study():
    return synthetic_study(
        dampers=("cone", "cylinder", "wedge"), phases=(0.0, 180.0), forces=(0.96, 9.6, 30.0)
    )


@pytest.fixture(scope="module")
def sdof_branches():
    from workbench.hbm import frequency_response

    ex = sdof_jenkins()
    return [
        frequency_response(
            ex.system, ex.f1, lev, ex.band_hz, ex.outputs, harmonics=(0, 1, 3), nt=32
        )
        for lev in (0.2, 2.0)
    ]


def _kinds(study, sdof_branches):
    cases = curve_set(study, "wedge", 0.0)
    fam = study.select(phase_deg=0.0)
    sweep = synthetic_sweep("cf", (500.0, 1000.0, 5000.0), dampers=("cone",), phases=(180.0,))
    t = [11.76, 11.78, 11.80]
    errs = {
        q: {"in-phase 30 N": [2.0, 0.1, 0.0]}
        for q in ("peak_amplitude_mm", "peak_frequency_hz", "friction_energy_mj")
    }
    pts = [
        dict(
            label=f"nt={n}",
            group="nt",
            time_s=x,
            peak_amplitude_mm=e,
            peak_frequency_hz=e,
            friction_energy_mj=e,
            worst=e,
        )
        for n, x, e in zip((16, 64, 256), t, (2.0, 0.1, 0.0), strict=True)
    ]
    f = np.linspace(80, 170, 40)
    verdicts = np.r_[np.ones(30, int), -np.ones(5, int), np.zeros(5, int)]  # all three kinds
    check = dict(
        model="sdof",
        n_dofs=1,
        freq_hz=f,
        amp=1e-4 / (1 + ((f - 120) / 8) ** 2),
        stable=verdicts == 1,
        stability=verdicts,
        points=[dict(freq_hz=120.0, ti_amplitude=1e-4, ti_converged=True, diff_pct=0.1)],
    )
    return {
        "receptances": lambda p: sf.plot_receptances(cases, p, forces=study.forces),
        "receptance_overlay": lambda p: sf.plot_receptance_overlay(fam, p),
        "peak_vs_force": lambda p: sf.plot_peak_vs_force(fam, p),
        "energy_vs_force": lambda p: sf.plot_energy_vs_force(fam, p),
        "status_map": lambda p: plot_status_map(cases[1:], p),
        "status_shares": lambda p: plot_status_shares(fam, p),
        "sweep": lambda p: plot_sweep(sweep.cases, "cf", p),
        "sweep_receptances": lambda p: sf.plot_sweep_receptances(sweep.cases, "cf", p),
        "frf": lambda p: curves.plot_frf(sdof_branches, p, unit_scale=1e3, unit="mm"),
        "frf_status": lambda p: curves.plot_status_map(sdof_branches[-1], p),
        "fidelity_knob": lambda p: ff.plot_knob("nt", ["16", "64", "256"], t, errs, p),
        "fidelity_pareto": lambda p: ff.plot_pareto(pts, p, tolerance_pct=1.0),
        "hbm_vs_time": lambda p: rf.plot_hbm_vs_time([check], p),
    }


KINDS = (
    "receptances",
    "receptance_overlay",
    "peak_vs_force",
    "energy_vs_force",
    "status_map",
    "status_shares",
    "sweep",
    "sweep_receptances",
    "frf",
    "frf_status",
    "fidelity_knob",
    "fidelity_pareto",
    "hbm_vs_time",
)


@pytest.mark.parametrize("kind", KINDS)
def test_figure_kind(kind, study, sdof_branches, tmp_path):
    from matplotlib.figure import Figure

    draw = _kinds(study, sdof_branches)[kind]
    fig = draw(None)
    assert isinstance(fig, Figure) and not list(tmp_path.iterdir())
    labels = [(ax.get_xlabel(), ax.get_ylabel()) for ax in fig.axes if ax.get_visible()]
    xs = [x for x, _ in labels if x]
    ys = [y for _, y in labels if y]
    assert xs and ys, f"{kind}: unlabelled axes"
    for lab in xs + ys:
        assert lab.strip() in COUNTS or UNIT.search(lab), f"{kind}: no unit in {lab!r}"
    assert_nonblank(save_figure(fig, tmp_path / f"{kind}.png"))


def test_energy_round_off_is_never_a_number(study):
    """The in-phase cylinder's round-off energies read 'stuck / 0' in table and figure."""
    from workbench.post.tables import STUCK_TEXT, energy_table

    t = energy_table(study, 0.0)
    row = next(r for r in t.rows if r[0] == "cylinder")
    assert all(cell == STUCK_TEXT for cell in row[1:]), row
    fig = sf.plot_energy_vs_force(study.select(phase_deg=0.0), None)
    main, strip = fig.axes[:2]
    assert strip.get_ylabel() == STUCK_TEXT and "1e-06" in strip.get_title(loc="left")
    lo, _ = main.get_ylim()
    assert lo > 1e-3  # the log axis spans the real energies, not round-off
