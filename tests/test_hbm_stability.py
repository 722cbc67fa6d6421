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
from workbench.hbm.corrector import Corrector, Factorization
from workbench.hbm.examples import sdof_jenkins, sdof_unilateral
from workbench.hbm.stability import hill_arpack, hill_dense

TWO_PI = 2 * np.pi
HARM = tuple(range(8))


@pytest.fixture(scope="module")
def unilateral():
    ex = sdof_unilateral()
    b = frequency_response(ex.system, ex.f1, 0.5, ex.band_hz, ex.outputs, harmonics=HARM)
    return ex, b


def test_linear_floquet_exponents_are_the_damped_poles():
    """Stuck contact: Hill's exponents are -zeta w_n +- i w_d, folded into |Im| <= w / 2."""
    ex = sdof_jenkins(mu=1e6)  # never slips
    s = ex.system
    f = Fourier((0, 1, 2, 3), 64)
    hb = HarmonicBalance(s, ex.f1, f, [0], 1.0)
    w = TWO_PI * 120.0
    hb.residual(hb.stuck_solution(w), w)
    st = hill_dense(*hb.hill_dense(w), w)
    wn = np.sqrt((s.K[0, 0] + s.contacts.kt1[0]) / s.M[0, 0])
    z = s.zeta[0]
    wd = wn * np.sqrt(1 - z * z)
    folded = (wd + w / 2) % w - w / 2  # the representative of +i w_d in |Im| <= w / 2
    for target in (-z * wn + 1j * folded, -z * wn - 1j * folded):
        assert np.min(np.abs(st.exponents - target)) < 1e-8 * wn
    assert abs(st.max_real + z * wn) < 1e-8 * wn and st.stable


@pytest.mark.parametrize("space", ["condensed", "physical"])
def test_arpack_shift_invert_matches_the_dense_hill_exponents(space):
    """The Woodbury shift-invert (large models) finds the dense solver's exponents near 0."""
    rng = np.random.default_rng(2)
    n = 40
    A = rng.normal(size=(n, n))
    K = A @ A.T * 1e3 + 2e4 * np.eye(n)
    M = np.diag(rng.uniform(0.02, 0.1, n))
    dofs = [[i, i + 1, i + 2] for i in range(0, 12, 3)]
    el = ContactElements.from_dofs(n, dofs, mu=0.3, kt=3e4, kn=5e4, n0=0.5)
    s = System(M=M, K=K, zeta=0.01, contacts=el)
    f = Fourier((0, 1, 2, 3), 64)
    hb = HarmonicBalance(s, rng.normal(size=n) + 0j, f, [0], 4.0, space=space)
    w = TWO_PI * 40.0
    res = Corrector(hb, SolverOptions(), 1e-4, w).solve_natural(hb.stuck_solution(w), w)
    assert res.converged
    hb.residual(res.x, w)
    assert set(hb.aft.status) & {1, 2}
    dense = hill_dense(*hb.hill_dense(w), w)
    lu = Factorization(hb, res.x, w, 1.0, 1.0, hb.residual_omega(res.x, w))
    size, op = hb.hill_shift_invert(w, lu.solve)
    assert size == 2 * n * f.nh
    arp = hill_arpack(size, op, w, n_exp=6)
    assert arp.converged
    # every exponent ARPACK returns is one of the dense ones
    for lam in arp.exponents:
        assert np.min(np.abs(dense.exponents - lam)) < 1e-6 * abs(w)
    near0 = dense.exponents[np.argsort(np.abs(dense.exponents))][:4]
    for lam in near0:
        assert np.min(np.abs(arp.exponents - lam)) < 1e-6 * abs(w)


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
    """The points between the two folds are the unstable ones (a saddle-node pair)."""
    ex, b = unilateral
    back = np.flatnonzero(np.diff(b.freq_hz) < 0)
    middle = np.zeros(b.n_points, bool)
    middle[back.min() + 1 : back.max() + 1] = True  # points strictly after the first fold
    unstable = ~b.stable
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
        Q = hb.response(res.x, w)
        amp = hb.point_data(res.x, w).out_amp[0]
        stable = hill_dense(*hb.hill_dense(w), w).stable
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
    assert np.all(s.stable)
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
