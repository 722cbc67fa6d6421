"""Helpers shared by the laws (not a law: modules starting with ``_`` are skipped)."""

from __future__ import annotations

from numba import njit

from . import SLIP_TOL  # noqa: F401 - the laws take it from here


@njit(cache=True)
def clear(want_jac, Fu, Fs, Su, Ss):
    """Zero the derivative outputs of a step."""
    if want_jac:
        Fu[:, :] = 0.0
        Fs[:, :] = 0.0
        Su[:, :] = 0.0
        Ss[:, :] = 0.0


@njit(cache=True)
def normal(un, kn, n0, f, Fu, want_jac):
    """Unilateral normal force ``N = max(0, n0 - kn un)``; writes ``f[2] = -N``. Returns N."""
    N = n0 - kn * un
    if N <= 0.0:
        f[2] = 0.0
        return 0.0
    f[2] = -N
    if want_jac:
        Fu[2, 2] = kn
    return N


@njit(cache=True)
def begin(u, kn, n0, want_jac, f, s_new, Fu, Fs, Su, Ss):
    """The part of a step every tangential law with state ``[T1, T2, u1, u2]`` shares:
    clear the derivatives, remember the displacement, apply the normal law, and on
    separation (returned N <= 0) set the tangential force and state to zero."""
    clear(want_jac, Fu, Fs, Su, Ss)
    s_new[2] = u[0]
    s_new[3] = u[1]
    if want_jac:
        Su[2, 0] = 1.0
        Su[3, 1] = 1.0
    N = normal(u[2], kn, n0, f, Fu, want_jac)
    if N <= 0.0:
        f[0] = 0.0
        f[1] = 0.0
        s_new[0] = 0.0
        s_new[1] = 0.0
    return N
