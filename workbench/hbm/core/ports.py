"""Where a system is driven and read: the excitation vector and the observation matrix.

``f1`` (n complex amplitudes, N per unit level) and ``outputs`` (a DOF
list or an (n_out, n) matrix), checked against the system's size; shared
by the harmonic balance, the nonlinear modes and the time integration.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ...errors import InputError
from .system import System


def observation(system: System, outputs: object) -> np.ndarray:
    """(n_out, n) observation matrix from a DOF list or a matrix."""
    n = system.n
    if outputs is None:
        return np.eye(n)
    if sp.issparse(outputs):
        O = outputs.toarray()
    else:
        O = np.asarray(outputs)
    if (
        O.ndim == 2
        and O.shape[1] == n
        and O.dtype != object
        and np.issubdtype(O.dtype, np.floating)
    ):
        return O.astype(float)
    idx = np.atleast_1d(O)
    if idx.ndim != 1 or not np.all(np.equal(np.mod(idx, 1), 0)):
        raise InputError("outputs", outputs, f"a list of DOF indices or an (n_out, {n}) matrix")
    idx = idx.astype(int)
    bad = (idx < 0) | (idx >= n)
    if bad.any():
        raise InputError("outputs", int(idx[bad][0]), f"a DOF index 0 <= i < {n}")
    O = np.zeros((idx.size, n))
    O[np.arange(idx.size), idx] = 1.0
    return O


def excitation_vector(system: System, f1: object) -> np.ndarray:
    """(n,) complex harmonic-1 force per unit level (N): ``f(t) = level Re(f1 exp(i w t))``."""
    a = np.asarray(f1, dtype=complex).ravel()
    if a.shape != (system.n,) or not np.all(np.isfinite(a)):
        raise InputError("f1", f"shape {a.shape}", f"{system.n} finite complex amplitudes (N)")
    return a
