"""Stability of a periodic solution by Hill's method.

A perturbation ``dq = exp(lambda t) p(t)`` of a periodic solution, with
``p`` on the same harmonics, solves Hill's quadratic eigenproblem

    (Delta0 + lambda Delta1 + lambda^2 Delta2) p = 0,
    Delta0 = Z_H + B_H^T D B_H   (the harmonic balance Jacobian on all DOFs),
    Delta1 = C (x) I + 2 M (x) nabla,   Delta2 = M (x) I,

(``nabla`` the time derivative on the harmonics, ``D`` the contact
Jacobian from the AFT). The truncated problem repeats every Floquet
exponent shifted by ``i k w``; the representatives kept are those with
``|Im lambda| <= w / 2``. The solution is unstable when one of them has a
positive real part (above ``tol * w``).

Small problems are solved densely (state size ``2 n nh`` up to
``dense_limit``). Larger ones use ARPACK in shift-invert mode about 0 on
the state-space form ``A z = lambda B z``: each application of
``A^-1 B`` needs ``Delta0^-1``, which the Woodbury identity gives from the
LU of the (much smaller) harmonic balance Jacobian the corrector already
works with; the exponents nearest 0 are those that cross into the right
half-plane at a fold or a Neimark-Sacker bifurcation of the response.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla


@dataclass
class Stability:
    """Floquet exponents kept for one solution (1/s) and the verdict."""

    exponents: np.ndarray  # complex, |Im| <= w/2
    max_real: float  # largest real part (1/s)
    stable: bool
    method: str  # "dense" | "arpack"
    converged: bool = True
    start: np.ndarray | None = None  # ARPACK start vector for the next point


def select(lam: np.ndarray, omega: float) -> np.ndarray:
    """The exponents with ``|Im| <= w/2`` (all of them if none qualifies)."""
    lam = np.asarray(lam)
    lam = lam[np.isfinite(lam)]
    keep = lam[np.abs(lam.imag) <= 0.5 * omega * (1 + 1e-9)]
    return keep if keep.size else lam


def hill_dense(
    d0: np.ndarray, d1: np.ndarray, d2: np.ndarray, omega: float, tol: float = 1e-6
) -> Stability:
    """All Hill exponents of a small problem from its dense matrices."""
    n = d0.shape[0]
    lu = sla.lu_factor(d2, check_finite=False)
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -sla.lu_solve(lu, d0, check_finite=False)
    A[n:, n:] = -sla.lu_solve(lu, d1, check_finite=False)
    lam = np.linalg.eigvals(A)
    keep = select(lam, omega)
    mr = float(np.max(keep.real)) if keep.size else -np.inf
    return Stability(exponents=keep, max_real=mr, stable=mr <= tol * omega, method="dense")


def hill_arpack(
    size: int,
    op,
    omega: float,
    n_exp: int = 6,
    tol: float = 1e-6,
    seed: int = 0,
    v0: np.ndarray | None = None,
) -> Stability:
    """The ``n_exp`` Hill exponents nearest 0 through ARPACK on ``A^-1 B`` (``op``).

    ``v0``: a start vector, e.g. :attr:`Stability.start` of the previous point
    of a branch (the Ritz vectors change little from one point to the next).
    """
    from scipy.sparse.linalg import ArpackNoConvergence, LinearOperator, eigs

    L = LinearOperator((size, size), matvec=op, dtype=float)
    k = min(n_exp, size - 2)
    if v0 is None or v0.shape != (size,) or not np.all(np.isfinite(v0)):
        v0 = np.random.default_rng(seed).standard_normal(size)
    converged = True
    try:
        mu, vec = eigs(
            L,
            k=k,
            which="LM",
            v0=v0,
            ncv=min(size - 1, max(2 * k + 1, 20)),
            # Ritz values to 1e-6 (relative): Re(lambda) within 1e-6 |lambda| <= 1e-6 w / 2,
            # below the threshold unstable_tol * w of the verdict
            tol=1e-6,
            maxiter=2000,
        )
        start = (vec.real + vec.imag).sum(axis=1)
    except ArpackNoConvergence as e:
        mu = e.eigenvalues
        start = None
        converged = False
    keep_mu = np.abs(mu) > 0
    mu = mu[keep_mu]
    lam = 1.0 / mu
    keep = select(lam, omega)
    mr = float(np.max(keep.real)) if keep.size else -np.inf
    return Stability(
        exponents=keep,
        max_real=mr,
        stable=mr <= tol * omega,
        method="arpack",
        converged=converged,
        start=start,
    )
