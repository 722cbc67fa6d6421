"""One style (render/palette.py), every stability verdict shown, the vibration as the headline.

Issue 33: a colour meant different things in different figures, unknown
stability verdicts were invisible, and the "peak amplitude" was max |x(t)|
with its mean term, never said so.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tests.conftest import ROOT
from tests.synthetic import synthetic_case, synthetic_study
from workbench.render import palette
from workbench.render import study_figures as sf
from workbench.render.palette import damper_style


def _legend_texts(fig) -> list[str]:
    legends = list(fig.legends) + [ax.get_legend() for ax in fig.axes if ax.get_legend()]
    return [t.get_text() for lg in legends for t in lg.get_texts()]


@pytest.fixture
def unknowns():
    """A study where Hill could not decide some points (one of them a peak)."""
    r = synthetic_study(("cone", "cylinder"), forces=(3.84, 30.0))
    for c in r.cases:
        c.branch.stability[5:9] = -1
    c = r.select(damper="cone", phase_deg=0.0, force_n=30.0)[0]
    c.branch.stability[c.h1_peak_index] = -1
    return r


# ---- the palette ------------------------------------------------------------------------


def test_one_colour_line_style_and_marker_per_damper_all_distinct():
    styles = [palette.damper_style(d) for d in ("cone", "cylinder", "wedge")]
    for k in range(3):  # colour, line style, marker: each tells the dampers apart alone
        assert len({s[k] for s in styles}) == 3, styles
    # a damper's colour is never a contact state's colour
    assert not {s[0].lower() for s in styles} & {c.lower() for c in palette.STATUS_COLORS}
    # variants and unknown names get a fixed style
    assert palette.damper_style("cone [modes=24]") == styles[0]
    assert palette.damper_style("rod") == palette.damper_style("rod")


def test_contact_states_keep_their_order_in_greyscale():
    grey = [palette.lightness(c) for c in palette.STATUS_COLORS]
    assert all(b - a > 0.1 for a, b in zip(grey, grey[1:], strict=False)), grey


def test_the_figures_read_the_palette():
    """Every colour of a status or a damper a figure module uses is the palette's: each
    module that names status colours (found by reading the sources) has the palette's."""
    import importlib

    users = sorted(
        p.stem
        for p in (ROOT / "workbench" / "render").glob("*.py")
        if "STATUS_COLORS" in p.read_text() and p.stem != "palette"
    )
    assert {"contact_maps", "curves", "nlmode_figures", "status_figures"} <= set(users)
    for name in users:
        mod = importlib.import_module(f"workbench.render.{name}")
        assert tuple(mod.STATUS_COLORS) == palette.STATUS_COLORS, mod.__name__
    assert damper_style("wedge") == palette.damper_style("wedge")


def test_carried_verdicts_are_shown_as_carried(unknowns):
    """Verdicts carried from checked neighbours (codes 2 and 3, workbench.hbm.stability.along_path)
    reach the legends, the captions and the tables under their own name, never as plain
    stable or unstable: each is one row of VERDICTS."""
    from workbench.post.answer import cases_table

    c = unknowns.cases[0]
    c.branch.stability[20:30] = 2
    c.branch.stability[30:33] = 3
    t = cases_table(unknowns)
    assert t.column("stable (carried) points")[0] == "10"
    assert t.column("unstable (carried) points")[0] == "3"
    fig = sf.plot_receptances(unknowns.select(damper="cone", phase_deg=0.0), None)
    texts = _legend_texts(fig)
    assert any(s.startswith("stable (carried) (10 points)") for s in texts), texts
    assert any(s.startswith("unstable (carried) (3 points)") for s in texts), texts
    cap = palette.verdict_caption(palette.verdict_counts(c.branch.stability))
    assert "stable (carried) long dashes (10 points)" in cap, cap
    assert "unstable (carried) dash-dot (3 points)" in cap, cap
    # a carried piece is drawn with its own line style, not the checked verdict's
    styles = {v.code: v.ls for v in palette.VERDICTS}
    assert len(set(map(str, styles.values()))) == len(styles)


def test_verdict_runs_join_and_the_doubtful_end_wins():
    runs = palette.verdict_runs(np.array([1, 1, -1, 1, 0, 0, 1]))
    assert runs == [(slice(0, 2), 1), (slice(1, 4), -1), (slice(3, 7), 0)]
    # carried verdicts: a piece touching a carried point is carried; unstable outweighs all
    runs = palette.verdict_runs(np.array([1, 2, 2, 1, 3, 0]))
    assert runs == [(slice(0, 4), 2), (slice(3, 5), 3), (slice(4, 6), 0)]
    assert palette.verdict_runs(np.array([], int)) == []


# ---- every verdict visible --------------------------------------------------------------


def test_unknown_verdicts_in_legends_tables_and_captions(unknowns, tmp_path):
    from workbench.post.answer import cases_table
    from workbench.render.sections import build_sections

    cone = unknowns.select(damper="cone", phase_deg=0.0)
    n_unknown = int(sum((c.branch.stability == -1).sum() for c in cone))
    fig = sf.plot_receptances(cone, None)
    assert f"unknown ({n_unknown} points)" in _legend_texts(fig)
    assert "unstable (0 points)" in _legend_texts(fig)  # shown even when absent
    fig = sf.plot_receptance_overlay(unknowns.select(phase_deg=0.0), None)
    assert any(s.startswith("unknown (") for s in _legend_texts(fig))
    fig = sf.plot_peak_vs_force(unknowns.select(phase_deg=0.0), None)
    assert "peak unknown" in _legend_texts(fig)

    t = cases_table(unknowns)
    for word in ("stable points", "unstable points", "unknown points"):
        assert word in t.header
    row = t.rows[[r[:3] for r in t.rows].index(("cone", "in-phase", "30"))]
    assert row[t.header.index("stability at the peak")] == "unknown"
    assert row[t.header.index("unknown points")] == str(
        int(
            (
                unknowns.select(damper="cone", phase_deg=0.0, force_n=30.0)[0].branch.stability
                == -1
            ).sum()
        )
    )

    secs = build_sections(unknowns, tmp_path)
    caps = [f["caption"] for s in secs for f in s["figures"] if "receptance" in f["path"]]
    assert caps and all("unknown" in c for c in caps)
    answer = next(s for s in secs if s["id"] == "answer")
    sure = " ".join(answer["notes"])
    assert "unknown" in sure and "cone in-phase (unknown)" in sure


# ---- the vibration amplitude as the headline -------------------------------------------


def test_the_headline_amplitude_is_harmonic_1_with_max_and_mean_beside_it():
    """A response with a mean: max |x(t)| = |mean| + (harmonic 1, for a pure sine); the
    tables give the harmonic-1 amplitude, and max |x(t)| and the mean, labelled."""
    from workbench.post.answer import answer, answer_table
    from workbench.post.results import StudyResults

    c = synthetic_case("cylinder", 180.0, 30.0)
    b = c.branch
    mean = -0.1e-3  # m: a damper ratcheting into its groove shifts the blade
    b.out_harm[:, 0, 0] = mean
    b.out_amp[:, 0] = b.out_h1[:, 0] + abs(mean)
    r = StudyResults("s", "comparison", [c, synthetic_case("cone", 180.0, 30.0)])
    t = answer_table(answer(r)["rows"])
    row = t.rows[[x[1] for x in t.rows].index("cylinder")]
    i = c.h1_peak_index
    assert float(row[t.header.index("amplitude, harmonic 1 (mm)")]) == pytest.approx(
        b.out_h1[i, 0] * 1e3, rel=1e-3
    )
    assert float(row[t.header.index("max |x(t)| (mm)")]) == pytest.approx(
        (b.out_h1[i, 0] + 0.1e-3) * 1e3, rel=1e-3
    )
    assert row[t.header.index("mean x (mm)")] == "-0.1"
    s = c.summary()
    assert s["h1_amplitude_mm"] == pytest.approx(b.out_h1[i, 0] * 1e3)
    assert s["h1_mean_mm"] == pytest.approx(-0.1)
    assert s["h1_max_abs_mm"] - s["h1_amplitude_mm"] == pytest.approx(0.1)
    # the receptances are the harmonic-1 amplitude per newton
    np.testing.assert_allclose(c.h1_receptance_mm_per_n, b.out_h1[:, 0] * 1e3 / 30.0)


def test_answer_ranks_and_gives_ratios():
    from workbench.post.answer import answer

    r = synthetic_study(forces=(9.6, 30.0))
    a = answer(r)
    assert a["force_n"] == 30.0
    rows = a["rows"][0.0]
    amps = [x.amp_mm for x in rows]
    assert amps == sorted(amps) and rows[0].ratio == pytest.approx(1.0)
    assert rows[-1].ratio == pytest.approx(amps[-1] / amps[0])
    first = a["sentences"][0]
    assert first.startswith("In-phase, at 30 N") and f"{rows[-1].ratio:#.3g} times" in first


# ---- readable numbers and axes ----------------------------------------------------------


def test_numbers_in_tables():
    from workbench.post.tables import STUCK_TEXT, energy_text, fixed, num

    assert num(0.18432193) == "0.1843" and num(383.866) == "383.9" and num(13600.0) == "13600"
    assert num(4.0e10) == "4e10" and num(9.15e11) == "9.15e11" and num(-0.0) == "0"
    assert num(2.431e-5, 3) == "2.43e-5" and num(None) == "n/a"
    assert fixed(-1e-9, 3) == "-1e-09" and fixed(-0.00001, 1) == "-1e-05"
    assert fixed(-0.0) == "0"
    assert energy_text(8e-22, 1e-6) == STUCK_TEXT == "zero (no slip)"
    assert energy_text(24.31, 1e-6) == "24.3"


def test_report_cells_and_headers(tmp_path):
    from workbench.render.report import _cell, _header

    assert _header("hbm_peak_amplitude_mm") == "hbm peak amplitude (mm)"
    assert _header("syn_peak_frequency_hz") == "syn peak frequency (Hz)"
    assert _header("peak amplitude (mm)") == "peak amplitude (mm)"
    assert _cell("0.183919375") == "0.1839" and _cell("383.87") == "383.87"
    assert _cell("-0.0") == "0" and _cell("True") == "yes" and _cell("1234567") == "1234567"


def test_synthesis_errors_axis_is_readable():
    """Errors from 0.001 % to 0.5 %: a log axis with a labelled tick at every decade (the
    symlog axis had two ticks, 0 and 1)."""
    from workbench.render.nlmode_figures import plot_synthesis_errors

    rows = [
        {"label": f"{d}, {fam}", "force_n": f, "error_pct": e, "valid": True}
        for d, fam, e0 in (("cone", "in-phase", 0.51), ("wedge", "out-of-phase", 0.002))
        for f, e in ((3.84, e0), (30.0, e0 / 3))
    ]
    fig = plot_synthesis_errors(rows, None)
    ax = fig.axes[0]
    assert ax.get_yscale() == "log"
    lo, hi = ax.get_ylim()
    ticks = [t for t in ax.get_yticks() if lo <= t <= hi]
    assert len(ticks) >= 3, ticks
    # colour per damper, line style per family
    lines = {ln.get_label(): ln for ln in ax.get_lines() if not ln.get_label().startswith("_")}
    assert lines["cone, in-phase"].get_color() == palette.damper_color("cone")
    assert lines["wedge, out-of-phase"].get_color() == palette.damper_color("wedge")
    assert lines["cone, in-phase"].get_linestyle() != lines["wedge, out-of-phase"].get_linestyle()


def test_section_positions_never_read_minus_zero():
    from workbench.render.scene import mm_text

    assert mm_text(-1e-12) == "0.0" and mm_text(-2.5e-3) == "-2.5"


def test_verdict_dataclass_is_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        palette.VERDICTS[0].label = "x"  # type: ignore[misc]


def test_how_sure_names_the_failed_curve_and_the_synthesis_check():
    from workbench.post.answer import answer

    r = synthetic_study(("cone", "wedge"), forces=(9.6, 30.0), fail=("wedge", 0.0, 30.0))
    r.extras["nlmodes"] = {
        "rows": [
            {"label": "cone, in-phase", "force_n": 30.0, "error_pct": -0.51, "valid": True},
            {"label": "wedge, in-phase", "force_n": 30.0, "error_pct": 7.0, "valid": False},
        ]
    }
    a = answer(r)
    sure = " ".join(a["sure"])
    assert "1 failed (wedge-0deg-30N)" in sure and "lower bounds" in sure
    assert "within 0.51 %" in sure and "1 of 2 peaks" in sure
    # the failed wedge's peak is a lower bound wherever it is quoted
    assert ">= " in a["sentences"][0]
