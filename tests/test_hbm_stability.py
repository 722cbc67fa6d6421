"""Turning points, Hill stability, separation and lost contact."""

from __future__ import annotations

import numpy as np
import pytest

from workbench.contact import ContactElements
from workbench.hbm import (
    Fourier,
    HarmonicBalance,
    SolverOptions,
    System,
    frequency_response,
    time_response,
)
from workbench.hbm.forced.corrector import Corrector, Factorization
from workbench.hbm.io.examples import sdof_jenkins, sdof_unilateral, two_dof_contact, unit_jenkins
from workbench.hbm.stability.along_path import HOW_HILL
from workbench.hbm.stability.hill import (
    CARRIED_STABLE,
    CARRIED_UNSTABLE,
    STABLE,
    UNSTABLE,
    hill_arpack,
    hill_dense,
    hill_eig,
)

TWO_PI = 2 * np.pi
HARM = tuple(range(8))


@pytest.fixture(scope="module")
def unilateral():
    ex = sdof_unilateral()
    b = frequency_response(ex.system, ex.f1, 0.5, ex.band_hz, ex.outputs, harmonics=HARM)
    return ex, b


def test_linear_floquet_exponents_are_the_damped_poles():
    """Stuck contact: the kept (most centred) Hill exponents are the poles -zeta w_n +- i w_d
    themselves (eigenvector on harmonic 0 alone), not one of their copies shifted by i k w."""
    ex = sdof_jenkins(mu=1e6)  # never slips
    s = ex.system
    f = Fourier((0, 1, 2, 3), 64)
    hb = HarmonicBalance(s, ex.f1, f, [0], 1.0)
    w = TWO_PI * 120.0
    ev = hb.evaluate(hb.stuck_solution(w), w)
    st = hill_dense(*hb.hill_dense(ev), w, f.harmonics)
    wn = np.sqrt((s.K[0, 0] + s.contacts.kt1[0]) / s.M[0, 0])
    z = s.zeta[0]
    wd = wn * np.sqrt(1 - z * z)
    assert st.exponents.size == 2 and st.count_ok
    for target in (-z * wn + 1j * wd, -z * wn - 1j * wd):
        assert np.min(np.abs(st.exponents - target)) < 1e-8 * wn
    assert abs(st.max_real + z * wn) < 1e-8 * wn and st.stable


@pytest.mark.parametrize("space", ["condensed", "physical"])
def test_arpack_shift_invert_matches_the_dense_hill_exponents(space):
    """The Woodbury shift-invert (large models) finds the dense solver's exponents near 0,
    covers the disc |lambda| <= w/2 where any bifurcating exponent crosses, and agrees
    with the dense verdict."""
    rng = np.random.default_rng(2)
    n = 40
    A = rng.normal(size=(n, n))
    K = A @ A.T * 1e3 + 2e4 * np.eye(n)
    M = np.diag(rng.uniform(0.02, 0.1, n))
    dofs = [[i, i + 1, i + 2] for i in range(0, 12, 3)]
    el = ContactElements.from_dofs(n, dofs, mu=0.3, kt=3e4, kn=5e4, n0=0.5)
    s = System(M=M, K=K, zeta=0.01, contacts=el)
    f = Fourier((0, 1, 2, 3), 64)
    hb = HarmonicBalance(s, rng.normal(size=n) + 0j, f, [0], 1.0, space=space)
    w = TWO_PI * 40.0
    res = Corrector(hb, SolverOptions(), 1e-4, w).solve_natural(hb.stuck_solution(w), w)
    assert res.converged
    ev = hb.evaluate(res.x, w)
    assert set(ev.aft.status) & {1, 2}
    dense = hill_dense(*hb.hill_dense(ev), w, f.harmonics)
    assert dense.count_ok
    lu = Factorization(hb, ev, hb.residual_omega(ev))
    size, op = hb.hill_shift_invert(ev, lu.solve)
    assert size == 2 * n * f.nh
    arp = hill_arpack(size, op, w, f.harmonics, n_exp=6, n_max=400)
    assert arp.converged and arp.count_ok
    every = hill_eig(*hb.hill_dense(ev))[0]
    # every exponent ARPACK keeps is an eigenvalue of the dense problem (to ARPACK's 1e-6)
    for lam in arp.exponents:
        assert np.min(np.abs(every - lam)) < 1e-6 * abs(w)
    # the dense centred exponents inside the disc are all found
    inside = dense.exponents[np.abs(dense.exponents) < 0.45 * w]
    for lam in inside:
        assert np.min(np.abs(arp.exponents - lam)) < 1e-6 * abs(w)
    assert arp.verdict == dense.verdict


def test_continuation_passes_the_turning_points(unilateral):
    """A softening contact (the spring opens): the curve folds twice and is followed through."""
    ex, b = unilateral
    assert b.completed and not b.failed and b.freq_hz[-1] == pytest.approx(ex.band_hz[1])
    dw = np.diff(b.freq_hz)
    back = np.flatnonzero(dw < 0)
    assert back.size >= 3, "the branch must run backwards in frequency between the folds"
    assert np.sum(np.diff(np.sign(dw)) != 0) == 2
    assert set(np.unique(b.status)) == {0, 2}  # closed off resonance, opening near it
    assert b.energy_residual.max() < 1e-6


def test_hill_flags_exactly_the_middle_branch(unilateral):
    """The points between the two folds are the unstable ones (a saddle-node pair): checked
    unstable, or carried unstable between checked unstable points; the points around each
    fold are checked, not carried."""
    ex, b = unilateral
    back = np.flatnonzero(np.diff(b.freq_hz) < 0)
    middle = np.zeros(b.n_points, bool)
    middle[back.min() + 1 : back.max() + 1] = True  # points strictly after the first fold
    unstable = b.unstable | (b.stability == CARRIED_UNSTABLE)
    assert not b.unknown.any()
    for fold in (back.min(), back.max() + 1):  # the extreme-frequency point of each fold
        assert (b.stability_how[fold - 1 : fold + 2] == HOW_HILL).all()
    # allow the fold points themselves either way (an exponent crosses zero there)
    inner = middle.copy()
    inner[[back.min() + 1, back.max()]] = False
    assert unstable[inner].all()
    outer = ~middle
    outer[[back.min(), back.max() + 1]] = False
    assert not unstable[outer].any()


def test_time_integration_confirms_the_stability_verdicts(unilateral):
    """Started on each of the three coexisting solutions, Newmark stays on the stable ones
    (amplitude within 1 %) and leaves the unstable one (by more than 10 %)."""
    ex, b = unilateral
    back = np.flatnonzero(np.diff(b.freq_hz) < 0)
    lo_fold, hi_fold = b.freq_hz[back.max() + 1], b.freq_hz[back.min()]
    fq = 0.5 * (lo_fold + hi_fold)
    w = TWO_PI * fq
    f = Fourier(HARM, b.nt)
    hb = HarmonicBalance(ex.system, ex.f1, f, ex.outputs, 0.5)
    corr = Corrector(hb, SolverOptions(), 1e-5, w)
    segs = {
        "lower": np.arange(0, back.min() + 1),
        "middle": np.arange(back.min(), back.max() + 2),
        "upper": np.arange(back.max() + 1, b.n_points),
    }
    for name, idx in segs.items():
        j = idx[np.argmin(np.abs(b.freq_hz[idx] - fq))]
        res = corr.solve_natural(b.x[j], w)
        assert res.converged
        ev = hb.evaluate(res.x, w)
        Q = hb.response(ev)
        amp = hb.point_data(ev).out_amp[0]
        stable = hill_dense(*hb.hill_dense(ev), w, f.harmonics).stable
        assert stable == (name != "middle")
        q0, v0 = f.state_at(Q, w)
        tr = time_response(
            ex.system, ex.f1, 0.5, fq, ex.outputs, steps_per_period=1024, tol=1e-7, q0=q0, v0=v0
        )
        rel = abs(tr.amplitude[0] / amp - 1)
        if stable:
            assert rel < 1e-2, (name, rel)
        else:
            assert rel > 0.1, (name, rel)


def test_frequency_stepping_cannot_follow_the_fold(unilateral):
    """Plain frequency stepping jumps or stops at the fold: it never visits the middle branch."""
    ex, b = unilateral
    s = frequency_response(
        ex.system,
        ex.f1,
        0.5,
        ex.band_hz,
        ex.outputs,
        harmonics=HARM,
        options=SolverOptions(continuation="frequency"),
    )
    assert np.all(np.diff(s.freq_hz) > 0)
    # stable everywhere: checked (or linear) stable, or carried stable between such points
    assert np.all(s.stable | (s.stability == CARRIED_STABLE))
    if s.failed:
        assert "turning point" in s.message and s.n_points > 3


def test_lost_contact_stops_the_branch_and_keeps_it():
    """A free mass held only by a preloaded unilateral contact: when it opens, the state is
    singular; the branch stops there with a message and keeps the points before."""
    k = 4e4
    el = ContactElements.from_dofs(1, [[-1, -1, 0]], mu=0.0, kt=0.0, kn=k, n0=1.0)
    s = System(M=[[0.1]], K=[[0.0]], zeta=0.01, contacts=el)  # K singular: a free body
    b = frequency_response(s, np.array([1.0 + 0j]), 0.3, (60, 140), [0], harmonics=(0, 1, 2, 3))
    assert b.failed and not b.completed
    assert "lost contact" in b.message
    assert b.n_points >= 3 and np.all(b.status == 0)  # everything kept is still closed
    # the last kept point is close to opening: its amplitude nears n0 / kn
    assert b.out_amp[-1, 0] > 0.5 * 1.0 / k


def test_a_peak_trial_without_contact_is_never_the_peak(monkeypatch):
    """The peak search solves trials between branch points; one that lands on a state
    without contact (singular, where the continuation itself would stop) is a failed
    trial: never inserted as the peak, and the completed branch is not failed for it.
    Every state above the top branch point is flagged here as without contact, so every
    trial that would beat the branch points is refused and the peak is the top point."""
    import dataclasses

    ex = unit_jenkins()
    band = (0.5 / TWO_PI, 3.0 / TWO_PI)
    args = (ex.system, np.array([1.0 + 0j]), 1.0, band, [0])
    plain = frequency_response(*args, harmonics=HARM, options=SolverOptions(refine_peak=False))
    top = float(plain.out_amp[:, 0].max())
    refined = frequency_response(*args, harmonics=HARM)
    assert refined.out_amp[:, 0].max() > top * (1 + 1e-6)  # the search does beat the points
    real = HarmonicBalance.point_data

    def point_data(self, ev, **kw):
        pd = real(self, ev, **kw)
        return dataclasses.replace(pd, lost_contact=bool(pd.out_amp[0] > top * (1 + 1e-12)))

    monkeypatch.setattr(HarmonicBalance, "point_data", point_data)
    b = frequency_response(*args, harmonics=HARM)
    assert b.completed and not b.failed, b.message
    # at most the harmonic-1 peak was inserted (its trial stays below the top |y|)
    assert b.n_points <= plain.n_points + 1
    assert b.out_amp[:, 0].max() == top
    assert "without contact at" in b.message and "not used" in b.message


@pytest.fixture(scope="module")
def jenkins_branch():
    s = unit_jenkins().system
    band = (0.5 / TWO_PI, 3.0 / TWO_PI)
    # Hill's method at every point (stability_stride 1): the verdicts themselves are tested
    opts = SolverOptions(stability_stride=1)
    return s, frequency_response(
        s, np.array([1.0 + 0j]), 1.0, band, [0], harmonics=HARM, options=opts
    )


def test_jenkins_oscillator_is_stable_everywhere(jenkins_branch):
    """The classic friction oscillator has no unstable orbit: every point's verdict is stable
    with the count check passed, and the kept pair decays at -c / 2m (its two exponents
    sum to the trace -c/m of the linear part: the friction force does not depend on the
    velocity)."""
    _, b = jenkins_branch
    assert b.completed and np.all(b.stability == 1)
    assert not b.unstable.any() and not b.unknown.any()
    slipping = b.status[:, 0] == 1
    assert slipping.sum() > 10
    np.testing.assert_allclose(b.max_floquet_real, -0.01, rtol=1e-6)
    assert b.summary()["n_unstable"] == 0 and b.summary()["peak_stability"] == "stable"


@pytest.mark.parametrize("omega", [1.01, 1.3, 1.7])
def test_jenkins_time_integration_settles_on_the_hbm_orbit(jenkins_branch, omega):
    """Newmark from rest reaches the orbit the harmonic balance found (stable verdict):
    amplitude within 1 % (the time step and the harmonic truncation, both ~0.1 %)."""
    s, b = jenkins_branch
    f = Fourier(HARM, b.nt)
    hb = HarmonicBalance(s, np.array([1.0 + 0j]), f, [0], 1.0)
    corr = Corrector(hb, SolverOptions(), 1e-2, omega)
    j = int(np.argmin(np.abs(b.freq_hz * TWO_PI - omega)))
    res = corr.solve_natural(b.x[j], omega)
    assert res.converged
    st = hill_dense(*hb.hill_dense(hb.evaluate(res.x, omega)), omega, f.harmonics)
    assert st.verdict == STABLE and st.count_ok
    amp = hb.point_data(res.x, omega).out_amp[0]
    tr = time_response(
        s, np.array([1.0 + 0j]), 1.0, omega / TWO_PI, [0], steps_per_period=512, tol=1e-8
    )
    assert abs(tr.amplitude[0] / amp - 1) < 1e-2


def test_two_dof_separating_point_stays_unstable():
    """The two-DOF example at level 3 N, 98.85 Hz (contact opening part of the period):
    a centred pair with a positive real part; count check passed, verdict unstable."""
    ex = two_dof_contact()
    w = TWO_PI * 98.85
    f = Fourier(tuple(range(6)), 128)
    hb = HarmonicBalance(ex.system, ex.f1, f, ex.outputs, 3.0)
    res = Corrector(hb, SolverOptions(), 1e-4, w).solve_natural(hb.stuck_solution(w), w)
    assert res.converged
    ev = hb.evaluate(res.x, w)
    assert ev.aft.status[0] == 2
    st = hill_dense(*hb.hill_dense(ev), w, f.harmonics)
    assert st.count_ok and st.verdict == UNSTABLE
    assert st.max_real > 0.01 * w


def test_a_contested_selection_is_unknown_and_the_orbit_is_indeed_left():
    """The two-DOF example with 0.5 % damping at 3 N, 94.29 Hz (separating): the four most
    centred eigenvectors give a stable set, but an exponent of real part +18 1/s ranks
    just behind them (RMS index 0.3 % larger). The verdict rests on that ranking, so it
    is unknown, not stable; and indeed a time integration started on the orbit leaves
    it: its largest distance from the orbit over periods 16-20 is about 4 times that over
    periods 6-10 (measured), where the kept exponents (real parts -24 1/s and below)
    would have it shrink by exp(-24 * 10 / 94) = 0.08."""
    from workbench.errors import SolveError
    from workbench.hbm.stability.hill import UNKNOWN

    ex = two_dof_contact(zeta=0.005)
    fq = 94.2859
    w = TWO_PI * fq
    f = Fourier(tuple(range(6)), 128)
    b = frequency_response(ex.system, ex.f1, 3.0, (ex.band_hz[0], fq), ex.outputs,
                           harmonics=f.harmonics, nt=f.nt)  # fmt: skip
    assert b.completed and b.freq_hz[-1] == pytest.approx(fq, rel=1e-12)
    assert b.stability[-1] == UNKNOWN
    hb = HarmonicBalance(ex.system, ex.f1, f, ex.outputs, 3.0)
    ev = hb.evaluate(b.x[-1], w)
    assert ev.aft.status.max() == 2  # the contact opens during the period
    st = hill_dense(*hb.hill_dense(ev), w, f.harmonics)
    assert st.verdict == UNKNOWN and not st.count_ok
    assert st.max_real < 0 and "hinges on the selection" in st.note
    q0, v0 = f.state_at(hb.response(b.x[-1], w), w)
    q, v, dist = q0, v0, []
    for _ in range(20):
        try:
            tr = time_response(ex.system, ex.f1, 3.0, fq, ex.outputs, harmonics=f.harmonics,
                               max_periods=1, q0=q, v0=v)  # fmt: skip
        except SolveError as e:  # one period is never "periodic": keep it
            tr = e.partial
        q, v = tr.q_end, tr.v_end
        dist.append(np.linalg.norm(q - q0) / np.linalg.norm(q0))
    # (the distance oscillates from period to period: compare maxima over five periods)
    assert max(dist[15:]) > 2 * max(dist[5:10]), dist


def test_a_period_doubling_pair_is_seen_by_the_strip():
    """A 3-DOF contact system (random matrices, seed 11) whose orbit doubles its period
    at 80.25 Hz: the pair of Floquet exponents Re +38 1/s, Im = +-w/2 (a real negative
    multiplier) lies just outside |lambda| <= w/2 and ranks below the 2n most centred
    eigenvectors, which are all stable. The strip |Im| <= 0.51 w sees it: the dense
    verdict is unknown (the selections disagree), the sparse path's unstable, never
    stable; and a time integration started on the orbit ends on a period-2 orbit."""
    from workbench.errors import SolveError
    from workbench.hbm.stability.hill import UNKNOWN

    rng = np.random.default_rng(11)
    n = int(rng.choice([3, 4, 6]))  # the draws of the search that found this case, in order
    A = rng.normal(size=(n, n))
    K = A @ A.T * 1e3 + 2e4 * np.eye(n)
    M = np.diag(rng.uniform(0.02, 0.1, n))
    choices = ([5e4, 2e5], [0.2, 0.5, 2.0], [0.002, 0.005, 0.01])
    kn, n0, zeta = (float(rng.choice(c)) for c in choices)
    assert (n, kn, n0, zeta) == (3, 5e4, 2.0, 0.002)
    el = ContactElements.from_dofs(n, [[0, 1, 2]], mu=0.3, kt=3e4, kn=kn, n0=n0)
    s = System(M=M, K=K, zeta=zeta, contacts=el)
    f1 = rng.normal(size=n) + 0j
    f_lo = 0.85 * np.sqrt(np.linalg.eigvals(np.linalg.solve(M, K)).real.min()) / TWO_PI
    fq, level, f = 80.2545456269211, 3 * n0, Fourier(tuple(range(6)))
    verdicts = {}
    for path, opts in (("dense", SolverOptions()), ("sparse", SolverOptions(hill_dense_limit=0))):
        b = frequency_response(s, f1, level, (f_lo, fq), None, harmonics=f.harmonics, options=opts)
        assert b.completed and b.freq_hz[-1] == pytest.approx(fq, rel=1e-12)
        verdicts[path] = int(b.stability[-1])
    assert verdicts == {"dense": UNKNOWN, "sparse": UNSTABLE}
    w = TWO_PI * fq
    hb = HarmonicBalance(s, f1, f, None, level)
    ev = hb.evaluate(b.x[-1], w)
    st = hill_dense(*hb.hill_dense(ev), w, f.harmonics)
    assert st.max_real < 0 and "disagree" in st.note  # the centred set alone says stable
    # time integration from the orbit: after the departure, period ends alternate
    q, v = f.state_at(hb.response(b.x[-1], w), w)
    ends = []
    for _ in range(300):
        try:
            tr = time_response(s, f1, level, fq, None, harmonics=f.harmonics, max_periods=1,
                               q0=q, v0=v)  # fmt: skip
        except SolveError as e:  # one period is never "periodic": keep it
            tr = e.partial
        q, v = tr.q_end, tr.v_end
        ends.append(q.copy())
    e = np.array(ends[-4:])
    one, two = np.linalg.norm(e[3] - e[2]), np.linalg.norm(e[3] - e[1])
    assert two < 0.01 * one, (one, two)


def test_stability_off_is_unknown_not_stable():
    """Without Hill's method the verdict is unknown (-1), never stable, in data and CSV."""
    s = unit_jenkins().system
    b = frequency_response(
        s,
        np.array([1.0 + 0j]),
        1.0,
        (0.8 / TWO_PI, 1.2 / TWO_PI),
        [0],
        harmonics=(0, 1, 2, 3),
        options=SolverOptions(stability=False),
    )
    assert b.n_points and np.all(b.stability == -1) and not b.stable.any()
    sm = b.summary()
    assert sm["n_unstable"] == 0 and sm["n_stability_unknown"] == b.n_points
    assert sm["peak_stability"] == "unknown"


def test_count_check_flags_an_ambiguous_selection():
    """Two eigenvectors equally centred across the cut (a tie): the count check fails and
    the verdict is unknown, even though every kept exponent is stable."""
    from workbench.hbm.stability.hill import select_centred

    harmonics = (0, 1)
    # three eigenvectors on (Q0, Qc1, Qs1) of one coordinate: two identical in weight
    P = np.zeros((3, 1, 3), complex)
    P[0, 0, 0] = 1.0  # harmonic 0 only: rms 0
    P[1, 0, 1] = P[1, 0, 2] = 1.0  # cos 1 only: rms 1 (twice: a tie at the cut)
    lam = np.array([-1.0, -2.0 + 1j, -2.0 - 1j])
    keep, _, ok = select_centred(lam, P, harmonics, 2)
    assert not ok and keep.size == 2


def _eigvecs(*rows):
    """Eigenvectors (nh = 5: Q0, Qc1, Qs1, Qc2, Qs2) of one coordinate, one per row."""
    P = np.zeros((5, 1, len(rows)), complex)
    for j, r in enumerate(rows):
        P[:, 0, j] = r
    return P


def test_contested_only_where_the_ranking_can_reverse_the_verdict():
    """A dropped centred exponent 3 % behind the cut contests a stable kept set when it is
    unstable; it does not contest an unstable set whose unstable exponent is the most
    centred of all (swapping the last kept one cannot remove it)."""
    from workbench.hbm.stability.hill import contested

    harmonics, w = (0, 1, 2), 100.0
    far = [0, 0, 0, 1, 1j]  # leaning on harmonic 2: ranked last
    P = _eigvecs([1, 0, 0, 0, 0], [1, 1, 0, 0, 0], [1, 1.06, 0, 0, 0], far, far)
    stable_set = np.array([-3.0, -5.0, +6.0, -7.0, -8.0])  # rival +6 just behind the cut
    assert contested(stable_set, P, harmonics, 2, w) == 6.0
    unstable_set = np.array([+30.0, -5.0, -6.0, -7.0, -8.0])  # +30 has rms 0, far from the cut
    assert contested(unstable_set, P, harmonics, 2, w) is None
    at_the_cut = np.array([-3.0, +5.0, -6.0, -7.0, -8.0])  # the unstable one is the last kept
    assert contested(at_the_cut, P, harmonics, 2, w) == -6.0


def test_an_empty_selection_gives_no_second_opinion():
    """With harmonics 0-1 every strip exponent leans on the top harmonic and is left out:
    an empty strip must not count as a stable opinion against an unstable kept set (nor an
    empty kept set against the strip)."""
    from workbench.hbm.stability.hill import second_opinion

    w, none = 100.0, np.zeros(0, complex)
    assert second_opinion(np.array([2.0 + 10j]), none, w, 1e-6) == ""
    assert second_opinion(none, np.array([2.0 + 10j]), w, 1e-6) == ""
    assert "disagree" in second_opinion(np.array([-2.0]), np.array([2.0 + 10j]), w, 1e-6)


def test_the_band_end_is_reached_by_smaller_steps_when_the_guess_fails():
    """A step that passed the band end across a kink: Newton from the interpolated guess and
    from the step's own solution fails at the band end; frequency steps from the last point,
    halved while they fail, still put the last point exactly on it (the CF sweep's cylinder
    at 5 kN needed this)."""
    from workbench.hbm.path.engine import reach_end
    from workbench.hbm.path.problem import Solution
    from workbench.hbm.path.rows import Rows
    from workbench.hbm.path.step import StepRule

    class Stub:  # the solution is x = w^2; Newton converges only from a guess whose own
        start, end = 10.0, 11.0  # frequency sqrt(x0) lies at most 0.3 rad/s below the one asked

        def __init__(self):
            self.calls = []
            self.rows = Rows(("w",))

        def solve_at(self, x0, w):
            w0 = float(np.sqrt(x0[0]))
            ok = 0.0 <= w - w0 <= 0.3
            self.calls.append((w0, w, ok))
            return Solution(np.array([w]), w, ok, 3, "stub", np.array([w * w]))

        def end_guess(self, p, q):
            return p.raw + (self.end - p.param) / (q.param - p.param) * (q.raw - p.raw)

        def refresh(self):
            pass

        def record(self, p, at_end=False):
            self.rows.add(w=(p.param, p.raw[0], at_end))

    corr = Stub()
    rule = StepRule(mode="arclength", ds0=0.1, ds_min=1e-3, ds_max=0.2, end="retry")
    cur = Solution(np.array([10.0]), 10.0, True, 3, "", np.array([100.0]))
    new = Solution(np.array([12.0]), 12.0, True, 3, "", np.array([144.0]))
    assert reach_end(corr, rule, cur, new)
    assert corr.rows.cols["w"] == [(11.0, 121.0, True)]
    assert not any(ok for _, _, ok in corr.calls[:3])  # interpolated (twice), then the step's
    assert all(w <= 11.0 for _, w, _ in corr.calls)
