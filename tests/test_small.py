"""The compiled small-system corrector takes the same steps as the PETSc SNES corrector.

Both solve the same harmonic balance with the same Newton iterations, line
search and convergence test (workbench.hbm.forced.small_kernels), so a branch
computed with either has the same points, the same Newton iteration counts
and the same solutions to round-off. Tolerances: the two paths factor the
Jacobian differently (the compiled path a full dense LU, the PETSc path a
reduced one on the non-stuck elements) and sum in other orders, so
solutions differ by round-off amplified by the Newton system's condition:
1e-9 relative on the unknowns, 1e-10 on the peak amplitude (measured:
1e-13 to 1e-11).
"""

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
)
from workbench.hbm.forced.small import SmallCorrector, eligible
from workbench.hbm.io.examples import sdof_jenkins, two_dof_contact, unit_jenkins

TWO_PI = 2 * np.pi


def _both(system, f1, level, band, outputs, harmonics, nt=None, **kw):
    out = {}
    for c in ("off", "auto"):
        opts = SolverOptions(compiled=c, **kw)
        out[c] = frequency_response(
            system, f1, level, band, outputs, harmonics=harmonics, nt=nt, options=opts
        )
    return out["off"], out["auto"]


CASES = {
    "unit Jenkins at the slip force": lambda: (unit_jenkins(), 1.0, tuple(range(8)), 128),
    "unit Jenkins below it": lambda: (unit_jenkins(), 0.8, tuple(range(8)), 128),
    "sdof Jenkins": lambda: (sdof_jenkins(), 1.0, tuple(range(8)), 128),
    "two-DOF, separating": lambda: (two_dof_contact(), 3.0, tuple(range(6)), 128),
    "two-DOF, circular law": lambda: (two_dof_contact(law="circular"), 2.0, (0, 1, 2, 3), 64),
    "two-DOF, Dahl's law": lambda: (two_dof_contact(law="dahl"), 2.0, (0, 1, 2, 3), 64),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_the_compiled_branch_is_the_petsc_branch(name):
    """Same points, same Newton iterations, same solutions and peaks to round-off."""
    ex, level, harm, nt = CASES[name]()
    a, b = _both(ex.system, ex.f1, level, ex.band_hz, ex.outputs, harm, nt)
    assert a.stats["mode"] == "newton" and b.stats["mode"] == "compiled"
    assert a.n_points == b.n_points > 10
    np.testing.assert_array_equal(a.newton_its, b.newton_its)
    scale = np.abs(a.x).max()
    assert np.abs(a.x - b.x).max() <= 1e-9 * scale
    np.testing.assert_allclose(b.freq_hz, a.freq_hz, rtol=1e-12)
    sa, sb = a.summary(), b.summary()
    assert sb["peak_amplitude"] == pytest.approx(sa["peak_amplitude"], rel=1e-10)
    assert sb["peak_frequency_hz"] == pytest.approx(sa["peak_frequency_hz"], rel=1e-10)
    np.testing.assert_array_equal(a.stability, b.stability)
    np.testing.assert_array_equal(a.status, b.status)
    assert a.stats["n_snes"] == b.stats["n_snes"]  # the same solves (peak trials included)
    # the same line search trials: residual evaluations agree but for those made outside the
    # solves (a kept evaluation is reused where the PETSc path evaluates a point again)
    assert 0 <= a.stats["n_residual"] - b.stats["n_residual"] <= 3


def test_the_compiled_solve_keeps_the_evaluation_of_its_solution():
    """The evaluation a compiled solve leaves (no new AFT for the point's outputs) is the one
    HarmonicBalance computes at the solution: residual, contact forces, Jacobian, loops."""
    ex = two_dof_contact()
    f = Fourier(tuple(range(6)), 128)
    hb = HarmonicBalance(ex.system, ex.f1, f, ex.outputs, 3.0)
    opts = SolverOptions()
    assert eligible(hb, opts)
    w = TWO_PI * 98.85
    corr = SmallCorrector(hb, opts, 1e-4, w)
    res = corr.solve_natural(hb.stuck_solution(w), w)
    assert res.converged
    kept = corr.evaluated(res.x, w)
    fresh = hb.evaluate(res.x, kept.omega)
    assert kept is corr.ev
    for name in ("U", "G", "D", "Yz"):
        np.testing.assert_allclose(getattr(kept, name), getattr(fresh, name), rtol=1e-12,
                                   atol=1e-12 * np.abs(getattr(fresh, name)).max())  # fmt: skip
    # the residual at a solution is round-off: compared on the scale of the unknowns
    np.testing.assert_allclose(kept.r, fresh.r, rtol=0, atol=1e-12 * np.abs(res.x).max())
    for name in ("F", "u", "f", "n_slip", "n_sep", "contact"):
        np.testing.assert_allclose(getattr(kept.aft, name), getattr(fresh.aft, name),
                                   rtol=1e-12, atol=1e-12)  # fmt: skip
    assert kept.aft.status.max() == 2  # the contact opens: the separated branch is exercised


def test_who_takes_the_compiled_path():
    """Small systems with modal damping; never a direct-damped one, the finite-difference
    Jacobian, another line search or a system above the Newton limit."""
    ex = unit_jenkins()  # C = 0.02: modal (one DOF)
    f = Fourier(tuple(range(4)))
    hb = HarmonicBalance(ex.system, ex.f1, f, [0])
    assert eligible(hb, SolverOptions())
    for kw in (
        dict(compiled="off"),
        dict(jacobian="fd"),
        dict(line_search="cp"),
        dict(linear_solver="lagged"),
        dict(auto_newton_limit=2),
    ):
        assert not eligible(hb, SolverOptions(**kw)), kw
    # viscous damping that the modes do not diagonalise: the direct backend, PETSc path
    M, K = np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]])
    C = np.array([[0.1, 0.0], [0.0, 0.0]])
    el = ContactElements.from_dofs(2, [[0]], mu=1.0, kt=5.0, n0=1.0)
    hb2 = HarmonicBalance(System(M=M, K=K, C=C, contacts=el), np.array([1.0, 0]), f, [0])
    assert hb2.lin.kind == "direct" and not eligible(hb2, SolverOptions())


# slow: numba compiles the kernels just in time (about a minute per law when not cached)
@pytest.mark.slow
def test_the_just_in_time_kernels_are_the_ahead_of_time_ones(monkeypatch):
    """The JIT fallback (kernels edited since the module was built) gives the same branch as
    the ahead-of-time module, when there is one (else it is what the other tests ran)."""
    from workbench.hbm.forced import small, small_aot

    ex = two_dof_contact()
    run = dict(harmonics=tuple(range(6)), nt=128)
    aot = frequency_response(ex.system, ex.f1, 3.0, ex.band_hz, ex.outputs, **run)
    monkeypatch.setattr(small_aot, "load", lambda law, what="solve": None)
    small._jit.clear()
    jit = frequency_response(ex.system, ex.f1, 3.0, ex.band_hz, ex.outputs, **run)
    assert jit.stats["mode"] == aot.stats["mode"] == "compiled"
    assert jit.n_points == aot.n_points
    np.testing.assert_array_equal(jit.newton_its, aot.newton_its)
    np.testing.assert_allclose(jit.x, aot.x, rtol=0, atol=1e-12 * np.abs(aot.x).max())
