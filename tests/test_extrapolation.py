"""Richardson extrapolation with the observed order: known limits, flags, the Jenkins AFT ladder."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from workbench.post.extrapolation import data_range, least_squares, observed_order, richardson


@pytest.mark.parametrize("p", [1.0, 2.0, 3.5])
@pytest.mark.parametrize("h", [[1.0, 2.0, 4.0], [3.0, 5.0, 9.0, 14.0]])  # uniform, non-uniform
def test_power_law_recovers_limit_and_order(p, h):
    q0, c = 2.5, 0.7
    q = [q0 + c * x**p for x in h]
    est = richardson(h, q)
    assert est.asymptotic and est.method == "richardson" and est.reason == ""
    assert math.isclose(est.order, p, rel_tol=1e-8)
    assert math.isclose(est.value, q0, rel_tol=1e-10)
    assert est.finest == q[0] and est.n_levels == 3


def test_higher_order_term_limit_inside_the_uncertainty():
    # q = q0 + C h^2 + D h^3, non-uniform levels, given coarsest first
    q0 = 10.0
    h = [0.4, 0.25, 0.15, 0.1]
    q = [q0 + 0.5 * x**2 - 0.2 * x**3 for x in h]
    est = richardson(h, q)
    assert est.asymptotic
    assert 1.5 < est.order < 2.5
    assert abs(est.value - q0) <= est.uncertainty
    assert abs(est.value - q0) < abs(q[-1] - q0)  # closer than the finest level
    assert est.error_pct(q0) < est.uncertainty_pct()


def test_observed_order_non_uniform_ratios():
    h = [1.0, 1.3, 2.9]
    assert math.isclose(observed_order(h, [1 + x**1.7 for x in h]), 1.7, rel_tol=1e-9)
    assert observed_order(h, [1.0, 2.0, 1.5]) is None  # sign change


def test_oscillating_data_are_flagged_and_not_extrapolated():
    """Differences that change sign: no extrapolation. If they do not grow as the levels get
    finer the limit is bounded by the spread (x 1.25) around the finest; if they grow,
    nothing bounds it."""
    est = richardson([1.0, 2.0, 4.0], [1.0, 1.02, 0.99])
    assert not est.asymptotic and est.trusted and est.method == "bounded"
    assert est.value == 1.0 and "oscillating" in est.reason
    assert est.uncertainty == pytest.approx(1.25 * 0.03, rel=1e-12)
    grow = richardson([1.0, 2.0, 4.0], [1.0, 0.96, 0.99])
    assert not grow.trusted and grow.method == "finest level" and grow.uncertainty is None
    assert "grow" in grow.reason


def test_a_decaying_oscillation_lies_within_its_bound():
    """q = 1 + 0.01 h (-1)^log2(h): the error halves and changes sign at every level; the
    limit 1 lies inside the bound of every three consecutive levels."""
    h = [2.0**k for k in range(6)]
    q = [1.0 + 0.01 * x * (-1) ** k for k, x in enumerate(h)]
    for i in range(4):
        est = richardson(h[i : i + 3], q[i : i + 3])
        assert est.method == "bounded" and est.trusted
        assert abs(est.value - 1.0) <= est.uncertainty
        assert est.uncertainty <= 1.25 * 0.06 * h[i] + 1e-15  # it shrinks with the levels


def test_implausible_order_is_flagged():
    # differences 1e-3 then 1e-6 at ratio 2: p ~ 10, beyond 0.5..8
    # bounded, not extrapolated: the limit within 1.25 times the levels' spread of the finest
    est = richardson([1.0, 2.0, 4.0], [1.0, 1.000001, 1.001001])
    assert not est.asymptotic and est.value == 1.0 and est.order > 8
    assert "above the plausible" in est.reason and est.method == "bounded" and est.trusted
    assert est.uncertainty == pytest.approx(1.25 * 0.001001, rel=1e-9)
    # a coarser difference smaller than the finer one: diverging, no power law
    est = richardson([1.0, 2.0, 4.0], [1.0, 1.001, 1.001001])
    assert not est.asymptotic and est.order is None and "no power law" in est.reason
    # nearly equal differences: p ~ 0.01, pre-asymptotic
    est = richardson([1.0, 2.0, 4.0], [1.0, 1.1, 1.2007])
    assert not est.asymptotic and est.order < 0.5 and not est.trusted


def test_round_off_and_too_few_levels():
    est = richardson([1.0, 2.0, 4.0], [3.0, 3.0 + 1e-13, 3.0 - 1e-13])
    assert not est.asymptotic and "round-off" in est.reason and est.value == 3.0
    assert est.trusted and est.method == "bounded"  # converged: the finest value stands
    assert est.uncertainty == pytest.approx(2e-13, rel=1e-3)
    est = richardson([1.0, 2.0, 4.0], [3.0, None, float("nan")])
    assert not est.asymptotic and est.value == 3.0 and "three are needed" in est.reason
    est = richardson([], [])
    assert est.value is None and est.error_pct(1.0) is None
    with pytest.raises(ValueError):
        richardson([1.0, 1.0, 2.0], [1.0, 2.0, 3.0])


# ---- physics: the Jenkins oscillator's peak against the AFT samples --------------------------


def _jenkins_peak(nt: int) -> float:
    """Peak amplitude of the unit Jenkins oscillator (dimensionless), level 0.9, harmonics 0-7."""
    from workbench.hbm import SolverOptions, frequency_response
    from workbench.hbm.io.examples import unit_jenkins

    ex = unit_jenkins()
    b = frequency_response(
        ex.system,
        ex.f1,
        0.9,
        ex.band_hz,
        [0],
        harmonics=tuple(range(8)),
        nt=nt,
        options=SolverOptions(stability=False, ds_max=0.02, peak_ftol=1e-10, peak_iterations=80),
    )
    assert not b.failed
    return float(b.summary()["peak_amplitude"])


def test_jenkins_peak_against_aft_samples_extrapolates_to_nt_1024():
    """The stick-slip kinks make the AFT's sampled friction force converge like a trapezoidal
    rule over a piecewise-smooth signal: order 2, lowered towards 1 while a transition
    instant is located only within one sample, so the observed order must lie in 1..3."""
    nts = [32, 64, 128, 256]
    q = [_jenkins_peak(nt) for nt in nts]
    fine = _jenkins_peak(1024)
    est = richardson([1.0 / n for n in nts], q)
    assert est.asymptotic, est.reason
    assert 1.0 <= est.order <= 3.0, est.order
    assert abs(est.value - fine) <= est.uncertainty, (est, fine)
    assert abs(est.value - fine) < abs(q[-1] - fine)  # the limit beats the finest level
    # the coarsest three (32, 64, 128 with harmonics up to 7) are pre-asymptotic: flagged
    coarse = richardson([1.0 / n for n in nts[:3]], q[:3])
    assert not coarse.asymptotic and coarse.method == "finest level"
    assert np.isfinite(est.uncertainty_pct())


def _fake_setting(values: dict, q: float):
    """A fidelity setting stand-in: knob ``values``, every quantity ``q`` at condition c."""
    from types import SimpleNamespace as NS

    from workbench.post.fidelity import QUANTITIES

    summ = {name: q for name, _, _ in QUANTITIES}
    res = NS(
        branch=NS(failed=False),
        summary=lambda: summ,
        refined_peak=lambda: summ,
        peak_resolution=lambda: {},
    )
    return NS(values=values, results={"c": res})


def test_levels_of_one_fineness_are_one_step_of_the_ladder():
    """'H 1' and 'H 0-1' share the highest harmonic (the fineness 1/H): the finer level is
    kept and the ladder still extrapolates (it raised "fineness must be distinct")."""
    from workbench.post.fidelity import QUANTITIES, ladder_limits

    def setting(hs, q):
        return _fake_setting({"harmonics": hs}, q)

    q = {1: 1.5, 3: 1.0 + 3.0**-2, 5: 1.0 + 5.0**-2, 7: 1.0 + 7.0**-2}  # q0 = 1, p = 2 in 1/H
    lad = [setting([1], 9.0), setting([0, 1], q[1])]
    lad += [setting(list(range(h + 1)), q[h]) for h in (3, 5, 7)]
    est = ladder_limits({"harmonics": lad})["harmonics"]["c"][QUANTITIES[0][0]]
    assert est.asymptotic and est.method == "richardson"
    assert est.order == pytest.approx(2.0, rel=1e-6)
    assert est.value == pytest.approx(1.0, rel=1e-9)


def test_a_modelling_choice_neither_corrects_nor_flags_the_limit():
    """The rigid or flexible damper is no ladder towards a limit: the all-knob limit is
    that of the discretisation knobs (here nt, q0 = 1 at order 2 in 1/nt)."""
    from workbench.post.fidelity import QUANTITIES, combined_limits, ladder_limits

    def setting(nt, rigid, q):
        return _fake_setting({"nt": nt, "rigid-damper": rigid}, q)

    qn = {n: 1.0 + 100.0 / n**2 for n in (16, 32, 64, 128)}
    ladders = {
        "nt": [setting(n, False, qn[n]) for n in (16, 32, 64, 128)],
        "rigid-damper": [setting(128, True, 5.0), setting(128, False, qn[128])],
    }
    ref = setting(128, False, qn[128])
    lim = combined_limits(ref, ladders, ladder_limits(ladders))["c"][QUANTITIES[0][0]]
    assert lim["asymptotic"], lim["reason"]
    assert lim["value"] == pytest.approx(1.0, rel=1e-9)
    assert "rigid-damper" not in lim["reason"]


def test_the_pick_judges_by_the_limit_only_where_it_is_trusted():
    """Quantity a: its limit is trusted, the error against it counts (2 %, although 0.5 %
    against the reference); quantity b: not trusted, the error against the reference."""
    from types import SimpleNamespace as NS

    from workbench.post.fidelity import QUANTITIES, pick_basis, pick_error

    qa, qb, qc = (q for q, _, _ in QUANTITIES)
    st = NS(
        results={"c": None},
        errors={"c": {qa: 0.5, qb: 1.0, qc: 0.1}},
        limit_errors={"c": {qa: 2.0, qb: 9.0, qc: 0.2}},
    )
    combined = {"c": {qa: {"trusted": True}, qb: {"trusted": False}, qc: {}}}
    assert pick_error(st, combined) == 2.0
    assert qa in pick_basis(combined) and qb not in pick_basis(combined)
    none = {"c": {q: {"trusted": False} for q in (qa, qb, qc)}}
    assert pick_error(st, none) == 1.0  # all against the reference
    assert pick_basis(none).startswith("errors against the reference")


def test_differences_within_the_resolution_are_bounded_by_it():
    """Three levels that differ by less than the quantity's resolution (a peak picked among
    points 0.5 Hz apart is known to 0.25 Hz): no power law is sought, whatever the signs;
    the limit is the finest level +- 1.25 x the resolution. Differences above it are
    judged as before."""
    q = [383.3, 383.1, 383.2]  # growing oscillation: untrusted without a resolution
    assert not richardson([1.0, 2.0, 4.0], q).trusted
    est = richardson([1.0, 2.0, 4.0], q, noise=0.25)
    assert est.trusted and est.method == "bounded" and est.value == 383.3
    assert est.uncertainty == pytest.approx(1.25 * 0.25, rel=1e-12)
    assert "resolution" in est.reason
    big = richardson([1.0, 2.0, 4.0], [383.3, 381.8, 382.8], noise=0.25)  # growing
    assert not big.trusted


def test_peak_resolution_of_a_sampled_parabola():
    """Points every 1 Hz on a = 1 - (f - 400.3)^2 / 100: the highest point is 400 Hz; the
    vertex lies 0.3 Hz and 0.0009 above it, within the resolution (0.5 Hz, 0.0025), and the
    refined peak finds it."""
    from types import SimpleNamespace as NS

    from workbench.post.results import CaseResult

    f = np.arange(390.0, 411.0)
    a = 1.0 - (f - 400.3) ** 2 / 100.0
    fake = NS(
        peak_index=10,
        branch=NS(n_points=len(f)),
        freq_hz=f,
        amp_mm=a,
        energy_mj=np.column_stack([2.0 * a, a]),
    )
    fake._peak_point = lambda: {"peak_frequency_hz": 400.0, "peak_amplitude_mm": a[10],
                                "friction_energy_mj": 3 * a[10]}  # fmt: skip
    fake.refined_peak = lambda: CaseResult.refined_peak(fake)
    top = CaseResult.refined_peak(fake)  # the parabola's vertex, from the three top points
    assert top["peak_frequency_hz"] == pytest.approx(400.3, abs=2e-3)
    assert top["peak_amplitude_mm"] == pytest.approx(1.0, abs=1e-6)
    assert top["friction_energy_mj"] == pytest.approx(3.0, abs=3e-6)
    # refined: the resolution is how far the interpolation moved each quantity
    r = CaseResult.peak_resolution(fake)
    assert r["peak_frequency_hz"] == pytest.approx(0.3, abs=2e-3)
    assert r["peak_amplitude_mm"] == pytest.approx(0.0009, abs=1e-6)
    assert r["friction_energy_mj"] == pytest.approx(3 * 0.0009, abs=3e-6)
    # not refined (a fold at the top: f not monotone): the highest point's own resolution
    fold = NS(**vars(fake))
    fold.freq_hz = f.copy()
    fold.freq_hz[11] = 399.5
    fold._peak_point = lambda: {"peak_frequency_hz": 400.0, "peak_amplitude_mm": a[10],
                                "friction_energy_mj": 3 * a[10]}  # fmt: skip
    fold.refined_peak = lambda: CaseResult.refined_peak(fold)
    r = CaseResult.peak_resolution(fold)
    assert r["peak_frequency_hz"] == 0.5
    assert r["peak_amplitude_mm"] == pytest.approx((2 * a[10] - a[9] - a[11]) / 8.0, rel=1e-9)
    assert r["friction_energy_mj"] == pytest.approx(1.5 * (a[10] - a[9]), rel=1e-9)


def test_scattered_ladders_of_four_levels_are_fitted_by_least_squares():
    """A mesh ladder that converges as h^2 but scatters by a few tenths of a percent (the
    frequencies of unstructured meshes, re-meshed at every size): the finest three fit no
    power law; the least-squares fit over all four levels recovers the limit within its
    uncertainty for every sign pattern of the scatter it fits (at least half of them; the
    rest look like no convergence and stay untrusted). A diverging ladder is not fitted."""
    h = np.array([7.0, 9.0, 11.0, 14.0])  # mm, finest first
    q_true = 380.0 + 0.02 * h**2  # Hz: 381.0 .. 383.9
    fitted = 0
    for signs in itertools.product((-1.0, 1.0), repeat=4):
        q = q_true + 0.25 * np.array(signs)
        est = richardson(h, q)
        if est.asymptotic:
            continue  # the three finest happened to read as a power law
        if not est.trusted:  # the scatter makes the levels look as if they did not converge
            assert est.method == "finest level" and est.uncertainty is None
            continue
        if est.method == "bounded":  # an oscillation whose differences shrink: data range
            assert abs(est.value - 380.0) <= est.uncertainty, (signs, est)
            continue
        assert est.method == "least squares" and est.n_levels == 4
        assert abs(est.value - 380.0) <= est.uncertainty, (signs, est)
        fitted += 1
    assert fitted >= 8
    # the point load's log(1/h) (docs/notes/energy_convergence.md): no fit
    div = richardson([0.75, 1.0, 1.5, 3.0], [29.03, 25.88, 24.30, 22.29])
    assert not div.trusted and div.method == "finest level"
    # three levels only: nothing to fit, the fallback stays
    three = richardson(h[:3], [381.0, 381.9, 381.5])
    assert three.method == "finest level" and not three.trusted


def test_a_clean_ladder_keeps_the_three_level_estimate():
    h = [1.0, 2.0, 4.0, 8.0]
    q = [2.0 + 0.3 * x**2 for x in h]
    est = richardson(h, q)
    assert est.method == "richardson" and est.order == pytest.approx(2.0, rel=1e-6)


def test_the_peak_point_is_the_summarys_peak():
    """refined_peak starts from the summary's peak values without computing the whole
    summary: the same numbers, None where the curve does not cover its peak (a failed one)."""
    from tests.synthetic import synthetic_study
    from workbench.post.results import _PEAK_KEYS

    study = synthetic_study(fail=("cone", 0.0, 30.0))
    n_none = 0
    for r in study.cases:
        s = r.summary()
        assert r._peak_point() == {k: s[k] for k in _PEAK_KEYS}
        n_none += s["peak_amplitude_mm"] is None
    assert n_none >= 1  # the failed case


def test_an_oscillatory_convergence_of_four_levels_is_bounded_by_its_data_range():
    """q = 1 + 0.01 h (-1)^k on h = 1, 2, 4, 8 (finest first): the differences change sign
    at every level and halve towards the finest, no power law fits and the least squares
    cannot read it; the limit 1 lies inside three times the data range around the finest
    level (Eca and Hoekstra's bound for an oscillatory convergence). The same oscillation
    growing towards the finest level is bounded by nothing."""
    h = [1.0, 2.0, 4.0, 8.0]
    q = [1.0 + 0.01 * x * (-1) ** k for k, x in enumerate(h)]  # 1.01, 0.98, 1.04, 0.92
    rng = data_range(h, q)
    assert rng.method == "bounded" and rng.trusted and not rng.corrects
    assert rng.value == q[0] and rng.n_levels == 4 and "data range" in rng.reason
    assert rng.uncertainty == pytest.approx(3.0 * (1.04 - 0.92), rel=1e-12)
    assert abs(rng.value - 1.0) <= rng.uncertainty
    assert data_range(h[::-1], q[::-1]) == rng  # any order of the levels
    # the ladder's estimate: the narrower of this bound and the least-squares fit
    est, fit = richardson(h, q), least_squares(h, q)
    assert est.trusted and est.uncertainty == min(rng.uncertainty, fit.uncertainty)
    assert abs(est.value - 1.0) <= est.uncertainty
    grow = [1.0 + 0.01 / x * (-1) ** k for k, x in enumerate(h)]  # largest step at the finest
    bad = richardson(h, grow)
    assert not bad.trusted and bad.method == "finest level"
    assert "does not shrink towards the finest" in bad.reason
    assert data_range(h, grow) is None
    # monotone ladders never get this bound, converging or not
    assert data_range(h, [2.0 + x for x in h]) is None
    assert data_range([0.75, 1.0, 1.5, 3.0], [29.03, 25.88, 24.30, 22.29]) is None
    assert data_range(h[:3], q[:3]) is None  # three levels: the three-level rules stand
    # point contacts, energy against points per line (heavy rig, 30 N): the differences
    # shrink on the whole (2.2, 9.7, 0.76, 1.4 mJ) but the finest step grows: no bound
    ppl = [1 / 45, 1 / 33, 1 / 23, 1 / 11, 1 / 5]
    assert data_range(ppl, [11.28, 12.65, 11.89, 2.20, 0.0]) is None


def test_a_fit_wider_than_the_data_range_gives_way_to_it():
    """Five levels that oscillate about 24.2 with steps shrinking towards the finest (0.06,
    0.11, 0.18, 0.33): the least-squares fit triples its band for the scatter (1.09), three
    times the data range (0.99) is narrower and is the one kept; the limit 24.2 lies inside
    both. Five levels of the pad rig's energy against points per line (24.10, 24.27, 24.24,
    24.23, 24.16 mJ, finest first) take their largest step at the finest level: an
    oscillation that grows, which keeps its fit."""
    h = [1 / 45, 1 / 33, 1 / 23, 1 / 17, 1 / 11]  # finest first
    q = [24.2, 24.26, 24.15, 24.33, 24.0]
    fit, est = least_squares(h, q), richardson(h, q)
    assert est.method == "bounded" and est.n_levels == 5 and "data range" in est.reason
    assert est.uncertainty == pytest.approx(3.0 * 0.33, rel=1e-9)
    assert est.uncertainty < fit.uncertainty
    assert abs(est.value - 24.2) <= est.uncertainty and abs(fit.value - 24.2) <= fit.uncertainty
    pads = [24.10, 24.27, 24.24, 24.23, 24.16]
    assert data_range(h, pads) is None and richardson(h, pads).method == "least squares"


def test_a_remeshing_knob_is_bounded_by_the_mesh_ladders_scatter():
    """A stuck cylinder's frequency on the pad rig: the contact-size ladder moves by 0.04 Hz
    without a trend (309.095, 309.091, 309.088, 309.128 Hz at 3 / 1.5 / 1 / 0.75 mm), which
    no rule reads. Each contact size meshes the model anew, and the global mesh ladder
    measures what that alone moves: its scatter about its h^1 trend (here 0.2 Hz). Within
    that, the contact ladder is bounded by it (x 1.25); a knob that does not re-mesh (nt)
    gets no such floor, and without a mesh ladder of four levels nothing changes."""
    from workbench.post.extrapolation import fit_scatter
    from workbench.post.fidelity import QUANTITIES, ladder_limits, remeshing_scatter

    q = QUANTITIES[1][0]
    sizes = [14.0, 11.0, 9.0, 8.0, 7.0, 6.0]
    wobble = [0.2, -0.2, 0.2, -0.2, 0.2, -0.2]
    mesh = [_fake_setting({"mesh-size": h}, 305.0 + 0.5 * h + w)
            for h, w in zip(sizes, wobble, strict=True)]  # fmt: skip
    sc = fit_scatter(sizes, [305.0 + 0.5 * h + w for h, w in zip(sizes, wobble, strict=True)])
    assert 0.15 < sc < 0.3
    contact = [309.095, 309.091, 309.088, 309.128]
    lad_c = [_fake_setting({"contact-mesh-size": h}, v)
             for h, v in zip([3.0, 1.5, 1.0, 0.75], contact, strict=True)]  # fmt: skip
    lad_n = [_fake_setting({"nt": n}, v) for n, v in zip([16, 32, 64, 128], contact, strict=True)]
    alone = ladder_limits({"contact-mesh-size": lad_c})["contact-mesh-size"]["c"][q]
    assert not alone.trusted  # the growing oscillation alone: bounded by nothing
    lim = ladder_limits({"mesh-size": mesh, "contact-mesh-size": lad_c, "nt": lad_n})
    assert remeshing_scatter({"mesh-size": mesh})[("c", q)] == pytest.approx(sc, rel=1e-12)
    est = lim["contact-mesh-size"]["c"][q]
    assert est.trusted and est.method == "bounded" and est.value == 309.128
    assert est.uncertainty == pytest.approx(1.25 * sc, rel=1e-12)
    assert "re-meshing scatter" in est.reason
    assert not lim["nt"]["c"][q].trusted  # nt does not re-mesh: no floor
    assert remeshing_scatter({"mesh-size": mesh[:3]}) == {}  # three levels: no scatter


def test_a_slow_ladder_with_one_coarse_flip_gets_no_data_range_bound():
    """q = h^0.1 (limit 0, converging far too slowly to read) on its four finest levels,
    the coarsest level out of line (a sign change at the coarse end only): the finest three
    do not oscillate, so the oscillatory bound (1.0 +- 0.69, which misses the limit 0)
    does not apply; the least-squares fit over all five levels, with its band tripled for
    the scatter, contains the limit."""
    h = [1.0, 2.0, 4.0, 8.0, 16.0]
    q = [x**0.1 for x in h[:4]] + [1.0]
    assert data_range(h, q) is not None  # the bound exists, and would be wrong here
    est = richardson(h, q)
    assert est.method == "least squares"
    assert abs(est.value - 0.0) <= est.uncertainty


def test_the_remeshing_scatter_bounds_oscillations_only_and_widens_narrow_bands():
    """A contact ladder that converges monotonically (q = 300 + 0.2 h^2) with its finest
    three within the re-meshing scatter is read by Richardson, not bounded by the scatter;
    its band is then widened to 1.25 times the scatter, never narrower. The same levels
    with the finest three oscillating are bounded by the scatter."""
    from workbench.post.fidelity import QUANTITIES, ladder_limits

    q = QUANTITIES[1][0]
    sizes = [14.0, 11.0, 9.0, 8.0, 7.0, 6.0]
    wob = [0.1, -0.1, 0.1, -0.1, 0.1, -0.1]
    mesh = [_fake_setting({"mesh-size": s}, 300.0 + 0.3 * s + w)
            for s, w in zip(sizes, wob, strict=True)]  # fmt: skip
    hs = [3.0, 1.5, 1.0, 0.75]
    mono = [_fake_setting({"contact-mesh-size": x}, 300.0 + 0.02 * x**2) for x in hs]
    lim = ladder_limits({"mesh-size": mesh, "contact-mesh-size": mono})
    est, sc = lim["contact-mesh-size"]["c"][q], None
    from workbench.post.fidelity import remeshing_scatter

    sc = remeshing_scatter({"mesh-size": mesh})[("c", q)]
    assert est.method == "richardson" and est.order == pytest.approx(2.0, rel=1e-6)
    assert est.value == pytest.approx(300.0, abs=1e-9)
    assert est.uncertainty == pytest.approx(1.25 * sc, rel=1e-12)  # widened to the scatter
    assert "widened to the re-meshing scatter" in est.reason
    osc = [_fake_setting({"contact-mesh-size": x}, v)
           for x, v in zip(hs, [300.3, 300.0, 300.05, 300.01], strict=True)]  # fmt: skip
    est = ladder_limits({"mesh-size": mesh, "contact-mesh-size": osc})["contact-mesh-size"]["c"][q]
    assert est.method == "bounded" and "re-meshing scatter" in est.reason
    assert est.uncertainty == pytest.approx(1.25 * sc, rel=1e-12)
