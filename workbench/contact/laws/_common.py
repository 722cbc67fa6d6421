"""Helpers shared by the laws (not a law: modules starting with ``_`` are skipped)."""

from __future__ import annotations

from numba import njit

# A sample counts as slipping (for the status only; the force is limited
# either way) when the trial force exceeds the slip limit by more than this
# fraction of it. In the converged period an element that slipped only while
# the march started (elastic shakedown) touches its limit again to round-off,
# ~1e-15 relative, without slipping: it is stuck.
SLIP_TOL = 1e-9


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
