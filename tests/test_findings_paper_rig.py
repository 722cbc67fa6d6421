"""On the paper-like rig the comparison shows the paper's headline.

One small study (tests/studies/findings_paper_rig.toml: the three dampers,
in phase and out of phase, 9.6 and 30 N, 14 mm mesh, the rig and
contact of geometry/paper_rig.toml) runs once through the CLI; each test
checks one finding. The rig was calibrated with the linear coupling screen
so that the stuck cone stiffens the in-phase mode (k2/k >= 0.25); the
heavy default rig, where it does not, is tests/test_findings.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.conftest import ROOT, run_upd
from workbench.post.results import StudyResults

pytestmark = pytest.mark.xdist_group("findings_paper_rig")
MID, HIGH = 9.6, 30.0
STUDY = ROOT / "tests" / "studies" / "findings_paper_rig.toml"


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("findings_paper_rig")
    r = run_upd("study", STUDY, "--out", out, "--json", timeout=1500)
    assert r.code == 0, r
    assert r.json["n_cases"] == 12
    return out, StudyResults.load(out / "results.h5")


@pytest.fixture(scope="module")
def results(study) -> StudyResults:
    return study[1]


def one(results, damper, phase, force):
    (c,) = results.select(damper=damper, phase_deg=phase, force_n=force)
    assert c.branch.completed and not c.branch.failed, c.branch.message
    assert c.peak_covered, c.peak_note()
    return c.summary()


# Peaks are compared by their harmonic-1 amplitude (the vibration), as the paper's
# harmonics 1-3 have no mean term: out of phase the damper climbs into its groove while
# it slips (a ratchet), and that mean offset (0.08 mm on the cylinder at 9.6 N,
# measured) is part of max|x(t)| but not of the vibration.
A = "h1_amplitude_mm"


def test_the_screen_shows_the_coupling_the_rig_was_calibrated_for(study):
    """The screen (in the report and from `upd screen` on the same folder, which reuses
    the study's reduced models) puts the cone's in-phase k2/k above 0.25 and the
    cylinder's at 0 (it rolls); out of phase every damper stiffens the pair alike."""
    out, results = study
    rows = {(r["damper"], r["family"]): r for r in results.extras["screen"]}
    assert rows[("cone", "in-phase")]["k2_over_k"] > 0.25
    assert abs(rows[("cylinder", "in-phase")]["k2_over_k"]) < 2e-3
    outs = [rows[(d, "out-of-phase")]["k2_over_k"] for d in ("cone", "cylinder", "wedge")]
    assert min(outs) > 0.35 and np.ptp(outs) < 0.05, outs
    r = run_upd("screen", STUDY, "--out", out, "--json")
    assert r.code == 0, r
    again = {(x["damper"], x["family"]): x["k2_over_k"] for x in r.json["rows"]}
    assert again == {k: v["k2_over_k"] for k, v in rows.items()}
    assert (out / "tables" / "screen.csv").is_file()
    assert "Coupling screen" in (out / "report.html").read_text()


def test_out_of_phase_the_three_dampers_vibrate_and_dissipate_alike(results):
    """Out of phase the damper slides sideways whatever its shape: at 30 N each damper's
    harmonic-1 peak and friction energy at resonance are within 15 % of the three
    dampers' mean (measured: peaks 0.364 / 0.296 / 0.372 mm, energies 37.9 / 33.5 /
    38.6 mJ for cone / cylinder / wedge; the widest pair, cylinder against wedge,
    differs by 26 % in peak). At 9.6 N the peaks are alike too (0.283 / 0.272 / 0.332
    mm).

    This holds with the rig's mu 0.3. With mu 0.5 on its 30 deg faces (mu / tan(beta)
    = 0.87) the cylinder and the wedge ratchet into the groove and lock there, stuck
    with twice the preload, and their peaks at 30 N were 2-2.5 times the cone's: a
    state a run-up from rest reaches too (benchmarks/runup_ratchet.py, docs/FINDINGS.md).
    """
    for force in (MID, HIGH):
        s = [one(results, d, 180.0, force) for d in ("cone", "cylinder", "wedge")]
        a = np.array([x[A] for x in s])
        assert np.all(np.abs(a / a.mean() - 1) <= 0.15), (force, a)
    e = np.array([x["friction_energy_mj"] for x in s])  # at 30 N
    assert e.min() > 1.0, e
    assert np.all(np.abs(e / e.mean() - 1) <= 0.15), e


def test_in_phase_the_cylinder_rolls_and_stays_linear(results):
    """Receptance constant within 2 % and friction energy below 1e-9 of the cone's."""
    s = {f: one(results, "cylinder", 0.0, f) for f in (MID, HIGH)}
    cone = one(results, "cone", 0.0, HIGH)["friction_energy_mj"]
    recept = np.array([x[A] / f for f, x in s.items()])
    assert np.ptp(recept) < 0.02 * recept.mean(), recept
    for x in s.values():
        assert abs(x["friction_energy_mj"]) < 1e-9 * cone, (x, cone)


def test_in_phase_the_wedge_softens(results):
    """The wedge's resonance falls by at least 2 Hz from 9.6 to 30 N (paper: about 4 Hz
    from 0.096 to 30 N)."""
    lo, hi = one(results, "wedge", 0.0, MID), one(results, "wedge", 0.0, HIGH)
    assert lo["peak_frequency_hz"] - hi["peak_frequency_hz"] >= 2.0, (lo, hi)


def test_in_phase_the_cone_levels_off_below_the_wedge(results):
    """The headline: A(30 N) / A(9.6 N) <= 1.3 for the cone (the paper: 8.7e-2 / 7.8e-2
    = 1.12), and its peak at 30 N is below the wedge's."""
    a_mid = one(results, "cone", 0.0, MID)[A]
    a_hi = one(results, "cone", 0.0, HIGH)[A]
    wedge = one(results, "wedge", 0.0, HIGH)[A]
    assert a_hi / a_mid <= 1.3, (a_mid, a_hi)
    assert a_hi < wedge, (a_hi, wedge)


def test_in_phase_the_cone_keeps_contact_slipping_at_one_end_and_opening_at_the_other(results):
    """At 30 N every pair of the cone works (none stuck for the whole period), none
    separates for the whole period, and each line slips at one end and opens for part
    of the period at the other (measured: 22 stick-slip pairs and one partially
    separating pair at the far end, on each line).

    The paper's Fig. 12 shows stuck line centres with slipping ends; on this rig the
    cone's lines do not roll about their middle (measured at 9.6 N: every pair slips
    but a few near the far end, which stick or open), so that is not asserted (see
    docs/FINDINGS.md)."""
    c = results.select(damper="cone", phase_deg=0.0, force_n=HIGH)[0]
    st = c.branch.status[c.peak_index]
    n = st.size // 2
    assert not np.any(st == 3), st  # no full separation
    assert not np.any(st == 0), st  # no pair stuck for the whole period
    for line in (st[:n], st[n:]):
        ends = {int(line[0]), int(line[-1])}
        assert ends == {1, 2}, line  # one end slips, the other opens
