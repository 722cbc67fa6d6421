"""Harmonic balance residual: Jacobians, linear limits, recovery of every DOF, energy balance."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from workbench.contact import ContactElements
from workbench.errors import InputError
from workbench.hbm import (
    Fourier,
    HarmonicBalance,
    SolverOptions,
    System,
    frequency_response,
    modal_damping,
)
from workbench.hbm.forced.corrector import Factorization
from workbench.hbm.io.examples import sdof_jenkins, two_dof_contact

TWO_PI = 2 * np.pi


def small_system(backend_c: str, n: int = 6, seed: int = 0):
    """A random chain with three 3-D elements (one against the ground)."""
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n, n))
    K = A @ A.T * 2e4 + 5e4 * np.eye(n)
    M = np.diag(rng.uniform(0.05, 0.2, n))
    el = ContactElements.from_dofs(
        n,
        [[0, 1, 2], [3, 4, -1], [5, -1, 4]],
        other=[[3, -1, -1], [-1, -1, -1], [-1, -1, 2]],
        mu=0.4,
        kt=8e4,
        kn=1.5e5,
        n0=rng.uniform(0.5, 1.5, 3),
    )
    if backend_c == "modal":
        return System(M=M, K=K, zeta=0.02, contacts=el)
    C = 1e-4 * K + 2.0 * np.diag(rng.uniform(0, 1, n))  # not modal: the direct backend
    return System(M=M, K=K, C=C, contacts=el)


@pytest.mark.parametrize("space", ["condensed", "physical"])
@pytest.mark.parametrize("backend", ["modal", "direct"])
def test_residual_jacobians_against_finite_differences(space, backend):
    """dr/dx and dr/dw are exact (central differences, tolerance 1e-6 relative)."""
    sysm = small_system(backend)
    f = Fourier((0, 1, 2, 3), 64)
    rng = np.random.default_rng(4)
    f1 = rng.normal(size=sysm.n) + 1j * rng.normal(size=sysm.n)
    hb = HarmonicBalance(sysm, f1 * 3, f, [0], space=space)
    assert hb.space == space and hb.lin.kind == backend
    w = TWO_PI * 60.0
    x = hb.stuck_solution(w) * 4 + rng.normal(size=hb.N) * 2e-6
    ev = hb.evaluate(x, w)
    assert set(ev.aft.status) & {1, 2}, "the state must slip or separate somewhere"
    J = hb.dense_jacobian(ev)
    h = 1e-10
    Jfd = np.column_stack(
        [(hb.residual(x + h * e, w) - hb.residual(x - h * e, w)) / (2 * h) for e in np.eye(hb.N)]
    )
    assert np.abs(J - Jfd).max() < 1e-6 * np.abs(J).max()
    v = rng.normal(size=hb.N)
    np.testing.assert_allclose(hb.jvp(ev, v), J @ v, rtol=0, atol=1e-12 * np.abs(J @ v).max())
    dw = 1e-4
    fd_w = (hb.residual(x, w + dw) - hb.residual(x, w - dw)) / (2 * dw)
    assert np.abs(fd_w - hb.residual_omega(ev)).max() < 1e-6 * np.abs(fd_w).max()
    # the reduced / single-precision factorisations solve with J
    b = rng.normal(size=hb.N)
    for single in (False, True):
        F = Factorization(hb, ev, hb.residual_omega(ev), single=single)
        np.testing.assert_allclose(J @ F.solve(b, refine=2 if single else 0), b, atol=1e-9)


def _linear_frf(M, K, C, f1, freq_hz, dof):
    """|H(w) f1| at one DOF, by direct solves (batched)."""
    w = TWO_PI * np.asarray(freq_hz)[:, None, None]
    Z = K[None] - w**2 * M[None] + 1j * w * C[None]
    rhs = np.broadcast_to(np.asarray(f1, complex)[None, :, None], (Z.shape[0], K.shape[0], 1))
    return np.abs(np.linalg.solve(Z, rhs)[:, dof, 0])


def test_mu_very_large_gives_the_stuck_linear_frf():
    """mu -> infinity: every contact stuck, the branch is the direct solve of K + W^T K_c W."""
    ex = two_dof_contact(mu=1e6, n0=1e4)  # never slips, never opens
    s = ex.system
    b = frequency_response(s, ex.f1, 2.0, (80, 300), [0, 1], harmonics=(0, 1, 2, 3))
    assert b.completed and not b.failed and b.n_points > 10
    assert np.all(b.status == 0)
    C = modal_damping(s.M, s.K, s.zeta, s.contacts)
    for j in (0, 1):
        ref = _linear_frf(s.M, s.regularised_stiffness(), C, 2.0 * ex.f1, b.freq_hz, j)
        # a linear response: harmonic 1 only, exact to the solver tolerance
        np.testing.assert_allclose(b.out_h1[:, j], ref, rtol=1e-9)
        np.testing.assert_allclose(b.out_amp[:, j], ref, rtol=1e-9)
    assert b.energy_residual.max() < 1e-9
    assert np.all(b.stable)


def test_mu_zero_gives_the_free_frf():
    """mu = 0 (and a closed contact): no tangential force; only the normal spring remains."""
    ex = two_dof_contact(mu=0.0, n0=1e3)  # a preload far above the motion: never opens
    s = ex.system
    b = frequency_response(s, ex.f1, 1.0, (60, 200), [0, 1], harmonics=(0, 1, 2, 3))
    assert b.completed and np.all(b.status == 1)  # "slipping" at zero force all the time
    K = s.K + np.diag([0.0, s.contacts.kn[0]])
    C = modal_damping(s.M, s.K, s.zeta, s.contacts)
    for j in (0, 1):
        ref = _linear_frf(s.M, K, C, ex.f1, b.freq_hz, j)
        np.testing.assert_allclose(b.out_h1[:, j], ref, rtol=1e-8)


def test_zero_preload_on_a_tangential_element_gives_the_free_frf():
    """N0 = 0 on a single-tangential-DOF element: no friction at all, the free oscillator."""
    ex = sdof_jenkins(n0=0.0)
    s = ex.system
    b = frequency_response(s, ex.f1, 1.0, (60, 160), [0], harmonics=(0, 1, 2, 3))
    assert b.completed and np.all(b.status == 3)
    C = modal_damping(s.M, s.K, s.zeta, s.contacts)
    ref = _linear_frf(s.M, s.K, C, ex.f1, b.freq_hz, 0)
    np.testing.assert_allclose(b.out_h1[:, 0], ref, rtol=1e-8)
    # the free resonance m, k is inside the band and resolved: peak at 100 Hz (0.1 %)
    assert abs(b.summary()["peak_frequency_hz"] - 100.0) < 0.1


@pytest.mark.parametrize("backend", ["modal", "direct"])
def test_recovered_dofs_satisfy_the_full_harmonic_balance(backend):
    """q = H (P - W^T G): the uncondensed equations Z q + W^T F(W q) = P hold."""
    sysm = small_system(backend)
    f = Fourier((0, 1, 2, 3), 64)
    rng = np.random.default_rng(8)
    f1 = rng.normal(size=sysm.n) + 0j
    hb = HarmonicBalance(sysm, f1 * 5, f, None)
    opts = SolverOptions()
    from workbench.hbm.forced.corrector import Corrector

    w = TWO_PI * 55.0
    corr = Corrector(hb, opts, 1e-5, w)
    res = corr.solve_natural(hb.stuck_solution(w), w)
    assert res.converged
    ev = hb.evaluate(res.x, w)
    Q = hb.response(ev)  # (nh, n)
    U = Q @ sysm.contacts.W.T.toarray()
    from workbench.hbm.core.aft import aft

    F = aft(U.reshape(f.nh, sysm.n_el, 3), sysm.contacts, f, False).F.reshape(f.nh, -1)
    C = sysm.C if sysm.C is not None else modal_damping(sysm.M, sysm.K, sysm.zeta, sysm.contacts)
    nab = f.nabla(w)
    lhs = (
        Q @ sysm.K.T + (nab @ Q) @ C.T + (nab @ nab @ Q) @ sysm.M.T + F @ sysm.contacts.W.toarray()
    )
    rhs = hb.P
    assert set(ev.aft.status) & {1, 2}
    assert np.abs(lhs - rhs).max() < 1e-8 * np.abs(rhs).max()


def test_modal_and_direct_backends_agree():
    """Modal damping given as zeta or as the equivalent C matrix: the same solution."""
    a = small_system("modal")
    C = modal_damping(a.M, a.K, 0.02, a.contacts)
    b = System(M=a.M, K=a.K, C=C, contacts=a.contacts)
    f1 = np.arange(1.0, a.n + 1) + 0j
    r = []
    for sysm, backend in ((a, "auto"), (b, "direct")):
        br = frequency_response(
            sysm,
            f1,
            2.0,
            (40, 45),
            [0, 2],
            options=SolverOptions(
                backend=backend, continuation="frequency", ds0=0.25, ds_max=0.25, refine_peak=False
            ),
        )
        r.append(br)
    assert r[0].stats["backend"] == "modal" and r[1].stats["backend"] == "direct"
    np.testing.assert_allclose(r[0].freq_hz, r[1].freq_hz)
    np.testing.assert_allclose(r[0].out_amp, r[1].out_amp, rtol=1e-8)


def test_energy_balance_closes_on_every_point():
    """Work of the excitation = viscous + friction (+ the normal spring's quadrature work).

    Two cases: pure stick-slip (constant N) and stick-slip with partial
    separation; the relative residual stays below 1e-6 at every point.
    """
    for ex, level in ((sdof_jenkins(), 1.0), (two_dof_contact(), 3.0)):
        b = frequency_response(
            ex.system, ex.f1, level, ex.band_hz, ex.outputs, harmonics=(0, 1, 2, 3, 4, 5)
        )
        assert b.completed, b.message
        assert b.energy_residual.max() < 1e-6
        assert np.all(b.work_friction >= -1e-12 * b.work_ext.max())  # friction dissipates
        assert np.all(b.work_visc > 0)
        assert (b.status > 0).any()


def test_bad_inputs_are_refused_with_the_parameter():
    ex = sdof_jenkins()
    with pytest.raises(InputError) as e:
        frequency_response(ex.system, ex.f1, 1.0, (100, 90))
    assert e.value.param == "band_hz[1]"
    with pytest.raises(InputError) as e:
        frequency_response(ex.system, ex.f1, -1.0, (90, 100))
    assert e.value.param == "level"
    with pytest.raises(InputError) as e:
        frequency_response(ex.system, ex.f1, 1.0, (90, 100), harmonics=(0, 2, 3))
    assert e.value.param == "harmonics"
    with pytest.raises(InputError) as e:
        frequency_response(ex.system, ex.f1, 1.0, (90, 100), outputs=[3])
    assert e.value.param == "outputs"
    with pytest.raises(InputError) as e:
        System(M=np.eye(2), K=np.ones((3, 3)))
    assert e.value.param == "K"


def test_singular_regularised_system_is_refused():
    """A free mass with no contact able to hold it: reported before any solve."""
    el = ContactElements.from_dofs(2, [[0]], mu=0.3, kt=1e4, n0=1.0)  # nothing holds DOF 1
    s = System(M=np.eye(2), K=np.zeros((2, 2)), zeta=0.01, contacts=el)
    from workbench.errors import SolveError

    with pytest.raises(SolveError, match="singular"):
        frequency_response(s, np.array([1.0, 0.0]), 1.0, (1, 2))


def test_modal_damping_on_stuck_modes():
    """zeta on the modes of K + W^T K_c W, also when K alone is singular (a free body)."""
    el = ContactElements.from_dofs(2, [[-1, -1, 1]], mu=0.3, kt=1e4, kn=2e4, n0=1.0)
    K = np.array([[1e4, -1e4], [-1e4, 1e4]])  # free-free pair of masses
    M = np.diag([0.2, 0.1])
    C = modal_damping(M, K, [0.01, 0.03], el)
    lam, phi = sla.eigh(K + el.stuck_stiffness().toarray(), M)
    np.testing.assert_allclose(np.diag(phi.T @ C @ phi), 2 * np.array([0.01, 0.03]) * np.sqrt(lam))


def test_system_without_contacts_is_its_linear_frf():
    """No contact element: the solver still works (physical unknowns) and gives H(w) f."""
    M, K = np.diag([1.0, 0.5]), np.array([[2.0, -1.0], [-1.0, 2.0]]) * 1e4
    s = System(M=M, K=K, zeta=0.01)
    b = frequency_response(s, np.array([1.0, 0.3j]), 2.0, (5, 40), [0, 1])
    assert b.completed and b.status.shape == (b.n_points, 0) and np.all(b.stable)
    C = modal_damping(M, K, 0.01)
    for j in (0, 1):
        ref = _linear_frf(M, K, C, 2.0 * np.array([1.0, 0.3j]), b.freq_hz, j)
        np.testing.assert_allclose(b.out_amp[:, j], ref, rtol=1e-9)
    # the peak search lands on the maximum of the exact FRF (to 1e-6 of it)
    grid = np.linspace(5, 40, 200001)
    top = _linear_frf(M, K, C, 2.0 * np.array([1.0, 0.3j]), grid, 0).max()
    assert b.summary()["peak_amplitude"] == pytest.approx(top, rel=1e-6)


def test_evaluations_are_explicit_state():
    """An evaluation is a record: a later evaluation elsewhere does not change what an
    earlier one gives (Jacobian, point data), and the frozen System is not written."""
    sysm = small_system("modal")
    f = Fourier((0, 1, 2, 3), 64)
    rng = np.random.default_rng(4)
    hb = HarmonicBalance(sysm, (rng.normal(size=sysm.n) + 0j) * 3, f, [0])
    before = dict(vars(sysm))
    w = TWO_PI * 60.0
    x0 = hb.stuck_solution(w) * 4
    ev0 = hb.evaluate(x0, w)
    J0, pd0 = hb.dense_jacobian(ev0), hb.point_data(ev0)
    hb.evaluate(x0 * 3 + 1e-6, w * 1.1)  # elsewhere
    np.testing.assert_array_equal(hb.dense_jacobian(ev0), J0)
    assert hb.point_data(ev0).out_amp[0] == pd0.out_amp[0]
    assert vars(sysm).keys() == before.keys()
    assert not [k for k in vars(hb) if k.startswith("_") and k != "_pos"]
