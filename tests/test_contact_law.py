"""The 3-D friction contact law: vectorised kernel against a plain loop, status, energies."""

from __future__ import annotations

import numpy as np
import pytest

from workbench.contact import (
    FULL_SEPARATION,
    PARTIAL_SEPARATION,
    STICK_SLIP,
    STUCK,
    ContactElements,
    classify,
    march_samples,
)
from workbench.contact.law import accept_step, law_step
from workbench.errors import InputError
from workbench.hbm.aft import aft, work_per_cycle
from workbench.hbm.fourier import Fourier


def loop_law(u, mu, kt1, kt2, kn, n0, law):
    """The law written as plainly as possible: one element, one sample at a time."""
    n_el, nt, _ = u.shape
    f = np.zeros((n_el, nt, 3))
    slip = np.zeros(n_el, int)
    sep = np.zeros(n_el, int)
    for e in range(n_el):
        T = [0.0, 0.0]
        prev = [0.0, 0.0]
        for p in range(2):
            for j in range(nt):
                N = max(0.0, n0[e] - kn[e] * u[e, j, 2])
                Tp = [
                    T[0] + kt1[e] * (u[e, j, 0] - prev[0]),
                    T[1] + kt2[e] * (u[e, j, 1] - prev[1]),
                ]
                slipping = False
                if N == 0.0:
                    T = [0.0, 0.0]
                elif law == "decoupled":
                    T = []
                    for a in range(2):
                        if abs(Tp[a]) > mu[e] * N:
                            T.append(np.sign(Tp[a]) * mu[e] * N)
                            slipping = True
                        else:
                            T.append(Tp[a])
                else:
                    r = np.hypot(*Tp)
                    if r > mu[e] * N:
                        T = [mu[e] * N * Tp[0] / r, mu[e] * N * Tp[1] / r]
                        slipping = True
                    else:
                        T = Tp
                prev = [u[e, j, 0], u[e, j, 1]]
                if p == 1:
                    f[e, j] = [T[0], T[1], -N]
                    slip[e] += slipping
                    sep[e] += N == 0.0
    return f, slip, sep


def random_elements(rng, n_el, law):
    W = np.eye(3 * n_el)
    return ContactElements(
        W=W,
        mu=rng.uniform(0.1, 0.8, n_el),
        kt1=rng.uniform(1e5, 3e5, n_el),
        kt2=rng.uniform(1e5, 3e5, n_el),
        kn=rng.uniform(1e5, 4e5, n_el),
        n0=rng.uniform(0.5, 3.0, n_el),
        law=law,
    )


@pytest.mark.parametrize("law", ["decoupled", "circular"])
def test_kernel_matches_plain_loop(law):
    """Vectorised numba march = the plain loop, sample by sample (to round-off)."""
    rng = np.random.default_rng(3)
    n_el, nt = 7, 48
    el = random_elements(rng, n_el, law)
    tau = 2 * np.pi * np.arange(nt) / nt
    # smooth periodic motions large enough to slip and, for some, to separate
    amp = rng.uniform(2e-6, 3e-5, (n_el, 3, 3))
    ph = rng.uniform(0, 2 * np.pi, (n_el, 3, 3))
    u = np.einsum(
        "edk,edkt->etd", amp, np.cos(np.arange(1, 4)[None, None, :, None] * tau + ph[..., None])
    )
    out = march_samples(u, el)
    f, slip, sep = loop_law(u, el.mu, el.kt1, el.kt2, el.kn, el.n0, law)
    np.testing.assert_allclose(out["f"], f, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(out["n_slip"], slip)
    np.testing.assert_array_equal(out["n_sep"], sep)
    assert (sep > 0).any(), "the random motions should separate some element"
    assert (slip > 0).any(), "the random motions should make some element slip"


@pytest.mark.parametrize("law", ["decoupled", "circular"])
def test_time_step_law_matches_loop_and_tangent(law):
    """law_step (time integration) gives the loop's forces and its tangent is df/du."""
    rng = np.random.default_rng(5)
    n_el, nt = 5, 40
    el = random_elements(rng, n_el, law)
    tau = 2 * np.pi * np.arange(nt) / nt
    u = rng.uniform(5e-6, 3e-5, (n_el, 1, 3)) * np.cos(
        tau[None, :, None] + rng.uniform(0, 6, (n_el, 1, 3))
    )
    f_loop, _, _ = loop_law(u, el.mu, el.kt1, el.kt2, el.kn, el.n0, law)
    state = np.zeros((n_el, 4))
    f = np.zeros((n_el, 3))
    Kt = np.zeros((n_el, 3, 3))
    flags = np.zeros(n_el, dtype=np.int64)
    got = np.zeros((n_el, nt, 3))
    for p in range(2):
        for j in range(nt):
            uj = np.ascontiguousarray(u[:, j])
            law_step(uj, state, el.mu, el.kt1, el.kt2, el.kn, el.n0, el.law_code, f, Kt, flags)
            if p == 1 and j == nt // 3:
                # consistent tangent by central differences from the same history
                h = 1e-11
                fd = np.zeros((n_el, 3, 3))
                for b in range(3):
                    fp, fm = np.zeros_like(f), np.zeros_like(f)
                    for sgn, out in ((1, fp), (-1, fm)):
                        up = uj.copy()
                        up[:, b] += sgn * h
                        law_step(
                            up,
                            state,
                            el.mu,
                            el.kt1,
                            el.kt2,
                            el.kn,
                            el.n0,
                            el.law_code,
                            out,
                            np.zeros_like(Kt),
                            flags,
                        )
                    fd[:, :, b] = (fp - fm) / (2 * h)
                law_step(uj, state, el.mu, el.kt1, el.kt2, el.kn, el.n0, el.law_code, f, Kt, flags)
                scale = max(el.kt1.max(), el.kn.max())
                assert np.abs(fd - Kt).max() < 1e-5 * scale
            accept_step(uj, f, state)
            if p == 1:
                got[:, j] = f
    np.testing.assert_allclose(got, f_loop, rtol=0, atol=1e-12)


def _one_element(mu=0.5, kt=1e5, kn=2e5, n0=2.0, law="decoupled"):
    return ContactElements.from_dofs(3, [[0, 1, 2]], mu=mu, kt=kt, kn=kn, n0=n0, law=law)


def test_status_classification_cases():
    """Four constructed motions give the four statuses."""
    el = _one_element()  # slip distance mu n0 / kt = 1e-5 m, opens at un = n0 / kn = 1e-5 m
    nt = 64
    c = np.cos(2 * np.pi * np.arange(nt) / nt)
    cases = {
        STUCK: np.stack([3e-6 * c, 0 * c, 0 * c], -1),  # well inside the elastic range
        STICK_SLIP: np.stack([4e-5 * c, 0 * c, 0 * c], -1),  # beyond mu N / kt
        PARTIAL_SEPARATION: np.stack([0 * c, 0 * c, 2e-5 * c], -1),  # opens for part
        FULL_SEPARATION: np.stack([1e-6 * c, 0 * c, 3e-5 + 0 * c], -1),  # always open
    }
    for expected, u in cases.items():
        out = march_samples(u[None], el)
        assert classify(out["n_slip"], out["n_sep"], nt)[0] == expected, expected


@pytest.mark.parametrize("law", ["decoupled", "circular"])
def test_elastic_shakedown_is_stuck(law):
    """Slip only while the march starts, then a loop that just touches the limit: stuck.

    u = U0 + A cos: the element starts from rest, so its first sample carries
    kt (U0 + A) > mu N and slips; afterwards the force swings by 2 kt A < 2 mu N
    and the converged period touches the limit (to round-off) without slipping.
    The status must say stuck and the converged loop must dissipate nothing.
    """
    mu, kt, n0 = 0.5, 1e5, 2.0  # slip distance mu n0 / kt = 1e-5 m
    el = ContactElements.from_dofs(3, [[0, 1, 2]], mu=mu, kt=kt, kn=2e5, n0=n0, law=law)
    nt = 64
    c = np.cos(2 * np.pi * np.arange(nt) / nt)
    u = np.stack([8e-6 + 6e-6 * c, 0 * c, 0 * c], -1)  # kt (U0 + A) = 1.4 mu n0
    out = march_samples(u[None], el)
    T = out["f"][0, :, 0]
    assert np.isclose(T.max(), mu * n0, rtol=1e-12)  # shaken down onto the limit
    assert classify(out["n_slip"], out["n_sep"], nt)[0] == STUCK
    du = np.diff(np.append(u[:, 0], u[0, 0]))
    assert abs(np.sum(0.5 * (T + np.roll(T, -1)) * du)) < 1e-12 * mu * n0 * 6e-6


@pytest.mark.parametrize("law", ["decoupled", "circular"])
def test_energy_per_cycle_is_the_jenkins_loop_area(law):
    """Harmonic tangential motion, constant N: dissipation 4 mu N (x - mu N / kt).

    Both the harmonic (Galerkin) work and the trapezoid on the loop are
    compared; with 1024 samples both are within 1e-4 of the area (the only
    error is where the clip falls between samples, O(1/nt^2)).
    """
    mu, kt, n0 = 0.4, 2e5, 5.0
    el = ContactElements.from_dofs(1, [[0]], mu=mu, kt=kt, n0=n0, law=law)
    x = 6e-5
    f = Fourier((0, 1, 2, 3, 4, 5), 1024)
    U = np.zeros((f.nh, 1, 3))
    U[f.index(1, "c"), 0, 0] = x
    res = aft(U, el, f, want_jac=False)
    exact = 4 * mu * n0 * (x - mu * n0 / kt)
    galerkin = work_per_cycle(res.F, U, f)[0, 0]  # the harmonics of the loop
    uu, T = res.u[0, :, 0], res.f[0, :, 0]
    du = np.diff(np.append(uu, uu[0]))
    trapz = np.sum(0.5 * (T + np.roll(T, -1)) * du)
    # with only 5 harmonics the Galerkin work still equals the area: u is harmonic 1 only
    assert abs(galerkin - exact) < 1e-4 * exact
    assert abs(trapz - exact) < 1e-4 * exact


def test_circular_equals_decoupled_along_one_axis():
    """Motion along t1 only: the circular limit is the decoupled one (to round-off)."""
    nt = 96
    tau = 2 * np.pi * np.arange(nt) / nt
    u = np.stack(
        [5e-5 * np.cos(tau) + 1e-5 * np.sin(2 * tau), 0 * tau, 4e-6 * np.cos(tau + 0.3)], -1
    )[None]
    a = march_samples(u, _one_element(law="decoupled"))
    b = march_samples(u, _one_element(law="circular"))
    np.testing.assert_allclose(a["f"], b["f"], rtol=0, atol=1e-13)
    np.testing.assert_array_equal(a["n_slip"], b["n_slip"])
    assert a["n_slip"][0] > 0


def test_from_dofs_builds_relative_rotated_maps():
    """W = R (S_damper - S_platform); ground elements have no platform columns."""
    n = 8
    R = np.array([[0, 1, 0], [-1, 0, 0], [0, 0, 1.0]])  # rows t1, t2, n in x, y, z
    el = ContactElements.from_dofs(
        n,
        [[0, 1, 2], [5, -1, -1]],
        other=[[3, 4, 6], [7, -1, -1]],
        frames=np.stack([R, np.eye(3)]),
        mu=0.3,
        kt=1e5,
        kn=1e5,
        n0=1.0,
    )
    q = np.arange(1.0, n + 1)
    u = (el.W @ q).reshape(2, 3)
    np.testing.assert_allclose(u[0], R @ (q[[0, 1, 2]] - q[[3, 4, 6]]))
    np.testing.assert_allclose(u[1], [q[5] - q[7], 0, 0])
    np.testing.assert_array_equal(el.active, [[True, True, True], [True, False, False]])
    # the balance force carries the preloads: W^T f(0) with f(0) = [0, 0, -n0]
    np.testing.assert_allclose(el.balance_force(), el.W.T @ np.array([0, 0, -1.0, 0, 0, -1.0]))


@pytest.mark.parametrize(
    "kw, param",
    [
        (dict(dofs=[[0, 1]]), "dofs"),
        (dict(dofs=[[0, 9, 1]]), "dofs[0][1]"),
        (dict(dofs=[[0]], mu=-0.1), "mu[0]"),
        (dict(dofs=[[0]], law="coulomb"), "law"),
    ],
)
def test_bad_elements_are_refused_with_the_parameter(kw, param):
    args = dict(mu=0.3, kt=1e5)
    args.update(kw)
    dofs = args.pop("dofs")
    with pytest.raises(InputError) as e:
        ContactElements.from_dofs(4, dofs, **args)
    assert e.value.param == param


def test_loop_dissipation_is_never_negative_and_matches_the_loop_area():
    """Per-element friction energy (trapezoid on the converged loop) is a dissipation.

    Constant N: it equals the Jenkins loop area 4 mu N (x - mu N / kt) to the
    trapezoid error. With the contact opening for part of the period (tangential
    and normal motion out of phase) the force jumps to zero; whatever the phase,
    the energy taken by the element over a cycle stays >= 0.
    """
    from workbench.hbm.balance import loop_dissipation

    mu, kt, kn, n0 = 0.5, 1e5, 2e5, 2.0
    el = ContactElements.from_dofs(3, [[0, 1, 2]], mu=mu, kt=kt, kn=kn, n0=n0)
    nt = 1024
    tau = 2 * np.pi * np.arange(nt) / nt
    x = 3e-5
    u = np.stack([x * np.cos(tau), 0 * tau, 0 * tau], -1)
    out = march_samples(u[None], el)
    exact = 4 * mu * n0 * (x - mu * n0 / kt)
    assert abs(loop_dissipation(u[None], out["f"])[0] - exact) < 1e-4 * exact
    for phase in np.linspace(0, 2 * np.pi, 13):
        un = 1.5e-5 * np.cos(tau + phase)  # opens for part of the period (n0 / kn = 1e-5)
        u = np.stack([x * np.cos(tau), 0 * tau, un], -1)
        out = march_samples(u[None], el)
        assert out["n_sep"][0] > 0
        assert loop_dissipation(u[None], out["f"])[0] >= -1e-12 * exact
