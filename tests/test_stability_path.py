"""Hill's verdicts along a branch: checked where they can change, carried between, never
claimed where they were not established (workbench.hbm.stability.along_path)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from workbench.hbm import SolverOptions, frequency_response
from workbench.hbm.io.examples import sdof_jenkins, sdof_unilateral, two_dof_contact
from workbench.hbm.stability.along_path import (
    HOW_CARRIED,
    HOW_HILL,
    HOW_LINEAR,
    PENDING,
    StabilityPath,
)
from workbench.hbm.stability.hill import (
    CARRIED_STABLE,
    CARRIED_UNSTABLE,
    STABLE,
    UNKNOWN,
    UNSTABLE,
    Stability,
)

TWO_PI = 2 * np.pi


# -- the schedule on prescribed exponents ----------------------------------------------------
class Prescribed(StabilityPath):
    """A path whose Hill check returns prescribed exponents ``lam(i)`` at point ``i`` (1/s)."""

    def __init__(self, lam, omega=100.0, stride=8):
        opts = SolverOptions(stability_stride=stride)
        super().__init__(SimpleNamespace(n_el=1), None, opts)
        self.lam, self.omega, self.checked = lam, omega, []

    def _is_linear(self, ev):
        return False

    def _separates(self, ev):
        return False

    def check(self, ev):
        self.checked.append(ev.i)
        lam = np.atleast_1d(self.lam(ev.i))
        mr = float(lam.real.max())
        v = UNSTABLE if mr > 1e-6 * self.omega else STABLE
        self.stats["n_hill"] += 1
        return Stability(lam, mr, v, "dense")

    def _row_evaluation(self, rows, i):
        return SimpleNamespace(i=i, omega=self.omega)


def _branch(path, n):
    """Record ``n`` points in order (a frequency sweep with a flat top), then finish."""
    rows = {k: [] for k in ("freq_hz", "stability", "stable", "max_floquet_real",
                            "stability_how", "out_amp", "out_h1", "x")}  # fmt: skip
    for i in range(n):
        v, mr, how = path.at_point(SimpleNamespace(i=i, omega=path.omega))
        rows["freq_hz"].append(100.0 + i)
        rows["stability"].append(v)
        rows["stable"].append(v == STABLE)
        rows["max_floquet_real"].append(mr)
        rows["stability_how"].append(how)
        rows["out_amp"].append([1.0 + np.sin(np.pi * i / (n - 1))])  # the peak mid-band
        rows["out_h1"].append([1.0])
        rows["x"].append(np.zeros(1))
    path.finish(rows)
    return np.array(rows["stability"]), np.array(rows["stability_how"])


def _window(kind, lo, hi, depth=-2.0, height=3.0):
    """Exponents: the least-damped pair's real part rises smoothly (a Gaussian in the point
    index) from ``depth`` 1/s and is positive exactly for points lo..hi, with Im 0.3 w (a
    Neimark-Sacker pair) or w/2 (a period doubling); a well-damped pair besides."""
    mid, d0 = 0.5 * (lo + hi), 0.5 * (hi - lo) + 0.5  # zero crossings half a point outside
    sigma = d0 / np.sqrt(np.log((height - depth) / -depth))

    def lam(i):
        re = depth + (height - depth) * np.exp(-(((i - mid) / sigma) ** 2))
        im = {"ns": 0.3, "pd": 0.5}[kind] * 100.0
        return np.array([re + 1j * im, re - 1j * im, -40 + 10j, -40 - 10j])

    return lam


@pytest.mark.parametrize("kind", ["ns", "pd"])
def test_a_crossing_between_the_strided_checks_is_found(kind):
    """A Neimark-Sacker pair (Im 0.3 w) or a period-doubling pair (Im w/2) crosses into the
    right half-plane for points 19-23 of 60, inside what a plain stride of 8 would leave
    unchecked. Its real part, seen rising at the checks before (-2.0 1/s at point 10, -0.7 at
    18), brings the next check closer; every point of the window is then unstable, checked or
    carried between unstable checks, none is called stable, and the rest is stable."""
    lo, hi = 19, 23
    lam = _window(kind, lo, hi)
    truth = np.array([UNSTABLE if lam(i).real.max() > 1e-4 else STABLE for i in range(60)])
    assert set(np.flatnonzero(truth == UNSTABLE)) == set(range(lo, hi + 1))
    path = Prescribed(lam)
    v, how = _branch(path, 60)
    assert not (v == PENDING).any()
    unstable = (v == UNSTABLE) | (v == CARRIED_UNSTABLE)
    stable = (v == STABLE) | (v == CARRIED_STABLE)
    np.testing.assert_array_equal(unstable, truth == UNSTABLE)
    np.testing.assert_array_equal(stable, truth == STABLE)
    # the window's ends are checked, both sides of each end: the boundary is established
    for i in (lo - 1, lo, hi, hi + 1):
        assert how[i] == HOW_HILL, (i, how[i])
    assert len(path.checked) < 0.5 * 60  # and far from every point


def test_what_the_schedule_cannot_see_is_labelled_carried():
    """An exponent that jumps across the axis at one point, with nothing at the checks around
    it to announce it, is not found: that point is carried stable, labelled so (code 2, how
    carried), never plain stable. (Where the exponents move smoothly, see above, it is.)"""

    def lam(i):
        return np.array([(5.0 if i == 4 else -20.0) + 30j, -40 + 0j])

    v, how = _branch(Prescribed(lam, stride=8), 12)
    assert v[4] == CARRIED_STABLE and how[4] == HOW_CARRIED
    assert (v[how == HOW_HILL] == STABLE).all()
    assert not ((v == STABLE) & (how != HOW_HILL)).any()  # "stable" only where checked


# -- on real branches: the schedule against Hill at every point ------------------------------
def _compare(system, f1, level, band, outputs, harmonics, **kw):
    out = {}
    for stride in (1, SolverOptions().stability_stride):
        opts = SolverOptions(stability_stride=stride, **kw)
        out[stride] = frequency_response(
            system, f1, level, band, outputs, harmonics=harmonics, options=opts
        )
    return out[1], out[max(out)]


REAL = {
    "unilateral fold pair": lambda: (sdof_unilateral(), 0.5, tuple(range(8)), {}),
    "two-DOF separating, dense": lambda: (
        two_dof_contact(zeta=0.02, kxz=3e4, n0=3.0), 2.0, tuple(range(6)), {}),
    "two-DOF separating, ARPACK": lambda: (
        two_dof_contact(zeta=0.02, kxz=3e4, n0=3.0), 2.0, tuple(range(6)),
        {"hill_dense_limit": 0}),
}  # fmt: skip


@pytest.mark.parametrize("name", sorted(REAL))
def test_the_schedule_agrees_with_hill_at_every_point(name):
    """The same branch (the continuation does not depend on the stability), with Hill's
    method at every point and with the schedule: no carried verdict contradicts a definite
    verdict of the every-point run, and where the schedule checked, the verdicts are those of
    the every-point run (dense path: deterministic; the ARPACK path's verdict at a point may
    depend on the start vector the previous check left, so there a checked unknown may be a
    definite verdict of the other run); fewer checks."""
    ex, level, harm, kw = REAL[name]()
    every, sched = _compare(ex.system, ex.f1, level, ex.band_hz, ex.outputs, harm, **kw)
    assert every.n_points == sched.n_points > 20
    np.testing.assert_array_equal(every.freq_hz, sched.freq_hz)
    a, b = every.stability, sched.stability
    assert not ((b == CARRIED_STABLE) & (a == UNSTABLE)).any()
    assert not ((b == CARRIED_UNSTABLE) & (a == STABLE)).any()
    chk = sched.stability_how == HOW_HILL
    same = a[chk] == b[chk]
    if kw.get("hill_dense_limit") == 0:
        same |= b[chk] == UNKNOWN
    assert same.all()
    assert (a == UNSTABLE).any() and ((b == UNSTABLE) | (b == CARRIED_UNSTABLE)).any()
    assert chk.sum() <= (every.stability_how == HOW_HILL).sum()
    # every point where a contact opens is checked (the exponents jump there)
    hb_sep = (sched.status >= 2).any(axis=1)
    assert (sched.stability_how[hb_sep] == HOW_HILL).all()


def test_a_slipping_stretch_is_checked_at_a_fraction_of_its_points():
    """The friction oscillator slipping without separation: Hill's method at a few points of
    the slipping stretch, the stuck points linear, the rest carried; the verdicts those of
    Hill at every point (stable everywhere)."""
    ex = sdof_jenkins()
    every, sched = _compare(ex.system, ex.f1, 2.0, ex.band_hz, ex.outputs, tuple(range(8)))
    assert (every.stability == STABLE).all()
    assert set(sched.stability.tolist()) <= {STABLE, CARRIED_STABLE}
    slipping = (sched.status == 1).any(axis=1)
    assert slipping.sum() > 10
    assert (sched.stability_how[slipping] == HOW_HILL).sum() < 0.5 * slipping.sum()


def test_every_stuck_point_shares_one_linear_verdict():
    """A damper that never slips: the system is linear at every point, so one Hill check
    establishes all (the real parts of a linear system's exponents do not depend on the
    frequency): the others say 'linear', stable, with the same largest real part -zeta w_n."""
    ex = sdof_jenkins(mu=1e6)
    b = frequency_response(ex.system, ex.f1, 1.0, ex.band_hz, ex.outputs, harmonics=(0, 1, 2, 3))
    assert (b.stability == STABLE).all() and b.stable.all()
    assert (b.stability_how == HOW_HILL).sum() == 1 and (b.stability_how == HOW_LINEAR).sum() > 10
    wn = TWO_PI * ex.band_hz[1] / 1.2  # the stuck natural frequency (band end is 1.2 times it)
    np.testing.assert_allclose(b.max_floquet_real, -0.005 * wn, rtol=1e-6)
