"""The 3-D friction contact law: vectorised kernel against a plain loop, status, energies."""

from __future__ import annotations

import numpy as np
import pytest

from workbench.contact import (
    FULL_SEPARATION,
    LAWS,
    PARTIAL_SEPARATION,
    STICK_SLIP,
    STUCK,
    ContactElements,
    classify,
    get_law,
    march_samples,
)
from workbench.contact.march import law_param_array
from workbench.errors import InputError
from workbench.hbm.core.aft import aft, work_per_cycle
from workbench.hbm.core.fourier import Fourier


def loop_law(u, mu, kt1, kt2, kn, n0, law):
    """The law written as plainly as possible: one element, one sample at a time."""
    n_el, nt, _ = u.shape
    f = np.zeros((n_el, nt, 3))
    slip = np.zeros(n_el, int)
    sep = np.zeros(n_el, int)
    for e in range(n_el):
        T = [0.0, 0.0]
        prev = [0.0, 0.0]
        end = None
        for p in range(1000):  # periods until the end-of-period force repeats
            slip[e] = sep[e] = 0
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
                f[e, j] = [T[0], T[1], -N]
                slip[e] += slipping
                sep[e] += N == 0.0
            scale = np.abs(f[e, :, :2]).max(axis=0)
            if p >= 1 and np.all(np.abs(np.array(T) - end) <= 1e-10 * scale):
                break
            end = np.array(T)
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


@pytest.mark.parametrize("law", LAWS)
def test_law_step_derivatives_against_finite_differences(law):
    """Each law's step: Fu, Fs, Su, Ss (the derivatives the march chains and the time
    integration uses as its tangent) equal central differences, on states that stick,
    slip and separate. Step 1e-11 m / 1e-6 N: inside one smooth piece; tolerance 1e-5 of
    the largest stiffness (O(h^2) plus round-off 1e-16 / h)."""
    rng = np.random.default_rng(5)
    lw = get_law(law)
    ns = lw.n_state
    kt, kn, mu, n0 = 1.5e5, 2e5, 0.4, 2.0
    lp = law_param_array(law, 1)[0]  # its own parameters, at their defaults
    checked = set()
    for _ in range(200):
        u = rng.normal(size=3) * np.array([2e-5, 2e-5, 8e-6])
        s = np.concatenate([rng.uniform(-1, 1, 2) * mu * n0, rng.normal(size=2) * 2e-5])
        out = [np.zeros(3), np.zeros(ns), np.zeros((3, 3)), np.zeros((3, ns))]
        out += [np.zeros((ns, 3)), np.zeros((ns, ns))]
        flag = lw.step(u, s, mu, kt, kt, kn, n0, lp, True, *out)
        checked.add(flag)
        f0, s0, Fu, Fs, Su, Ss = out

        def ev(uu, ss):
            o = [np.zeros(3), np.zeros(ns)] + [np.zeros((3, 3)), np.zeros((3, ns))]
            o += [np.zeros((ns, 3)), np.zeros((ns, ns))]
            lw.step(uu, ss, mu, kt, kt, kn, n0, lp, False, *o)
            return np.concatenate([o[0], o[1]])

        D = np.vstack([Fu, Su])
        h = 1e-11
        for b in range(3):
            e = np.zeros(3)
            e[b] = h
            fd = (ev(u + e, s) - ev(u - e, s)) / (2 * h)
            assert np.abs(fd - D[:, b]).max() < 1e-5 * kn, (law, flag, b)
        for k in range(ns):
            h = 1e-6 if k < 2 else 1e-11
            e = np.zeros(ns)
            e[k] = h
            fd = (ev(u, s + e) - ev(u, s - e)) / (2 * h)
            D = np.vstack([Fs, Ss])
            assert np.abs(fd - D[:, k]).max() < 1e-5 * max(kn, 1.0) * (1 if k >= 2 else 1e-5), (
                law,
                flag,
                k,
            )
    assert checked == {0, 1, 2}


@pytest.mark.parametrize("law", LAWS)
def test_march_stops_when_the_period_repeats(law):
    """The loop returned is the converged one: marching further changes it by < 1e-9 of
    the slip force, for motions near and beyond the slip threshold."""
    from workbench.contact import march

    rng = np.random.default_rng(8)
    n_el, nt = 12, 64
    el = random_elements(rng, n_el, law)
    tau = 2 * np.pi * np.arange(nt) / nt
    slip_dist = el.mu * el.n0 / el.kt1
    amp = slip_dist[:, None] * rng.uniform(0.8, 3.0, (n_el, 2))
    zero = np.zeros((n_el, nt))
    u = np.stack([amp[:, :1] * np.cos(tau), amp[:, 1:] * np.sin(tau + 0.3), zero], -1)
    E, P = np.zeros((nt, 1)), np.zeros((1, nt))
    args = (u, E, P, el.mu, el.kt1, el.kt2, el.kn, el.n0, law, False)
    a = march(*args)
    assert np.all(a["periods"] >= 2) and np.all(a["periods"] < 200)
    longer = march(*args, tol=0.0, max_periods=int(a["periods"].max()) + 20)
    err = np.abs(a["f"] - longer["f"]).max(axis=(1, 2)) / (el.mu * el.n0)
    assert err.max() < 1e-9


def test_circular_law_near_the_threshold_needs_more_than_two_periods():
    """A circular-ish motion just above the slip radius: the state settles slowly (radial
    return shrinks the offset geometrically), so two periods are not the converged loop.
    Marched from rest (``growth=0``): the law's growth periods would settle most of it."""
    from workbench.contact import march

    el = _one_element(mu=0.5, kt=1e5, kn=2e5, n0=2.0, law="circular")  # slip 1e-5 m
    nt = 128
    tau = 2 * np.pi * np.arange(nt) / nt
    u = np.stack([1.05e-5 * np.cos(tau), 0.95e-5 * np.sin(tau), 0 * tau], -1)[None]
    E, P = np.zeros((nt, 1)), np.zeros((1, nt))
    args = (u, E, P, el.mu, el.kt1, el.kt2, el.kn, el.n0, "circular", False)
    conv = march(*args, growth=0)
    two = march(*args, tol=np.inf, max_periods=2, growth=0)
    assert conv["periods"][0] > 5
    assert np.abs(conv["f"] - two["f"]).max() > 1e-3 * 0.5 * 2.0


def test_dahl_loop_is_the_analytic_one():
    """Dahl's law under u = x cos(w t), constant N: the loop's tips are
    +-mu N tanh(kt x / mu N) and its area 4 L x - 2 (T_x + L)(L / kt)(1 - exp(-2 kt x / L))
    (L = mu N); the law integrates each step exactly, so only the trapezoid rule on the
    area errs, O(1/nt^2): 1e-5 at nt = 4096."""
    from workbench.hbm.core.loops import loop_dissipation

    mu, kt, n0, x = 0.5, 1e5, 2.0, 3e-5
    L = mu * n0
    el = ContactElements.from_dofs(3, [[0, 1, 2]], mu=mu, kt=kt, kn=0.0, n0=n0, law="dahl")
    nt = 4096
    tau = 2 * np.pi * np.arange(nt) / nt
    u = np.stack([x * np.cos(tau), 0 * tau, 0 * tau], -1)[None]
    out = march_samples(u, el)
    a = kt * x / L
    Tx = L * np.tanh(a)
    assert abs(out["f"][0, 0, 0] - Tx) < 1e-9 * L  # the march stops at a 1e-10 repeat
    area = 4 * L * x - 2 * (Tx + L) * (L / kt) * (1 - np.exp(-2 * a))
    assert abs(loop_dissipation(u, out["f"])[0] / area - 1) < 1e-5


def test_a_new_law_is_found_by_the_registry():
    """The laws are discovered from their modules: the element record, the model file
    choices and the march accept "dahl" with no other code naming it."""
    assert {"decoupled", "circular", "dahl"} <= set(LAWS) and LAWS[0] == "decoupled"
    el = _one_element(law="dahl")
    assert el.law == "dahl"
    with pytest.raises(InputError) as e:
        get_law("coulomb")
    assert e.value.param == "law"


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
    from workbench.hbm.core.loops import loop_dissipation

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


def test_march_says_when_the_cap_is_hit(caplog):
    """A cap too small for the circular law near its threshold: the element is reported as
    not converged (and a warning logged); with room it converges after more periods."""
    import logging
    import sys

    from workbench.contact import march

    march_mod = sys.modules["workbench.contact.march"]  # the package exports the function

    el = _one_element(mu=0.5, kt=1e5, kn=2e5, n0=2.0, law="circular")
    nt = 128
    tau = 2 * np.pi * np.arange(nt) / nt
    u = np.stack([1.01e-5 * np.cos(tau), 0.99e-5 * np.sin(tau), 0 * tau], -1)[None]
    args = (u, np.zeros((nt, 1)), np.zeros((1, nt)), el.mu, el.kt1, el.kt2, el.kn, el.n0)
    march_mod._warned.discard("circular")
    with caplog.at_level(logging.WARNING, logger="workbench.contact.march"):
        short = march(*args, "circular", False, max_periods=3)
    assert not short["converged"][0] and short["periods"][0] == 3
    assert "did not repeat" in caplog.text
    full = march(*args, "circular", False)
    assert full["converged"][0] and full["periods"][0] > 3
