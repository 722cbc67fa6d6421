"""Fourier layout and the alternating frequency/time scheme with its exact Jacobian."""

from __future__ import annotations

import numpy as np
import pytest

from workbench.contact import ContactElements
from workbench.errors import InputError
from workbench.hbm.core.aft import aft
from workbench.hbm.core.fourier import Fourier, default_nt


def test_synthesis_analysis_round_trip_and_derivative():
    """P E = I on the harmonics; nabla is d/dt of the trigonometric polynomial."""
    f = Fourier((0, 1, 2, 5), 64)
    np.testing.assert_allclose(f.P @ f.E, np.eye(f.nh), atol=1e-13)
    rng = np.random.default_rng(0)
    X = rng.normal(size=(f.nh, 3))
    w = 7.0
    tau = np.linspace(0, 2 * np.pi, 11)
    h = 1e-6
    num = (f.synth(X, tau + w * h) - f.synth(X, tau - w * h)) / (2 * h)
    np.testing.assert_allclose(f.synth(f.nabla(w) @ X, tau), num, rtol=0, atol=1e-6)


def test_custom_harmonic_list_and_complex_convention():
    f = Fourier((1, 3, 5))
    assert not f.has_dc and f.nh == 6 and f.nt == default_nt((1, 3, 5))
    # Re(F exp(i w t)) with F = 2 - 3i is 2 cos + 3 sin
    X = f.from_complex({1: np.array([2 - 3j])}, (1,))
    np.testing.assert_allclose(f.synth(X, np.array([0.0, np.pi / 2]))[:, 0], [2.0, 3.0])
    assert f.to_complex(X)[1][0] == 2 - 3j


@pytest.mark.parametrize(
    "harm, nt, param",
    [
        ((0,), 0, "harmonics"),
        ((0, 1, 1), 0, "harmonics"),
        ((0, 1, 8), 16, "nt"),
        ((-1, 1), 0, "harmonics"),
    ],
)
def test_bad_harmonics_refused(harm, nt, param):
    with pytest.raises(InputError) as e:
        Fourier(harm, nt)
    assert e.value.param == param


def test_amplitude_is_the_exact_maximum():
    """max |y(t)| of a trigonometric polynomial, against a dense evaluation."""
    f = Fourier((0, 1, 2, 3, 7))
    rng = np.random.default_rng(2)
    X = rng.normal(size=(f.nh, 4))
    dense = np.abs(f.synth(X, np.linspace(0, 2 * np.pi, 200001))).max(axis=0)
    got = f.amplitude(X, 64)
    # the dense grid itself is within (7 dtau)^2 / 2 = 2.4e-8 (relative) below the maximum
    assert np.all(got >= dense * (1 - 1e-12))
    np.testing.assert_allclose(got, dense, rtol=5e-8)


def test_stuck_element_is_linear():
    """An element that never slips nor opens carries exactly K_c u (the linear limit)."""
    el = ContactElements.from_dofs(3, [[0, 1, 2]], mu=0.5, kt=1e5, kn=3e5, n0=10.0)
    f = Fourier((0, 1, 2, 3), 64)
    rng = np.random.default_rng(1)
    U = rng.normal(size=(f.nh, 1, 3)) * 1e-6
    res = aft(U, el, f)
    # f = [T1, T2, -N] = [kt u1, kt u2, kn un - n0]
    expect = U * np.array([1e5, 1e5, 3e5])
    expect[0, 0, 2] -= 10.0
    np.testing.assert_allclose(res.F, expect, rtol=0, atol=1e-9)
    assert res.status[0] == 0


@pytest.mark.parametrize("law", ["decoupled", "circular", "dahl"])
@pytest.mark.parametrize("harm", [(0, 1, 2, 3), (1, 3, 5)])
def test_aft_jacobian_against_finite_differences(law, harm):
    """dF/dU from the march equals central differences (states with slip and separation).

    The force is piecewise smooth in U; a random state is almost surely
    away from the switching surfaces, and the step 1e-10 m (1e-5 of the
    motion) stays inside one piece. Tolerance 1e-6 of the largest entry:
    the finite-difference error is O(h^2) there, plus round-off 1e-16 / h.
    """
    rng = np.random.default_rng(11)
    n_el = 5
    el = ContactElements(
        W=np.eye(3 * n_el),
        mu=rng.uniform(0.2, 0.6, n_el),
        kt1=rng.uniform(1e5, 2e5, n_el),
        kt2=rng.uniform(1e5, 2e5, n_el),
        kn=rng.uniform(1e5, 3e5, n_el),
        n0=rng.uniform(1, 3, n_el),
        law=law,
    )
    f = Fourier(harm, 64)
    U = rng.normal(size=(f.nh, n_el, 3)) * 1e-5
    U[:, :3, 2] *= 0.15  # three elements stay closed, the others open for part of the period
    res = aft(U, el, f)
    assert set(res.status) >= {1, 2}, "want slipping and separating elements in the sample"
    J = res.J
    h = 1e-10
    err = 0.0
    for e in range(n_el):
        for b in range(3):
            for c in range(f.nh):
                Up, Um = U.copy(), U.copy()
                Up[c, e, b] += h
                Um[c, e, b] -= h
                col = (aft(Up, el, f, False).F - aft(Um, el, f, False).F)[:, e, :] / (2 * h)
                err = max(err, np.abs(col.T - J[e, :, :, b, c]).max())
                # other elements do not depend on this one
                other = np.delete((aft(Up, el, f, False).F - res.F), e, axis=1)
                assert np.abs(other).max() == 0.0
    assert err < 1e-6 * np.abs(J).max()
