"""Lowest eigenpairs of ``K x = lam M x`` by block shift-and-invert Krylov with MUMPS block solves.

Why not SLEPc's Krylov-Schur here: it applies ``K^-1`` one vector at a time,
and on a 3-D P2 mesh each MUMPS triangular solve is memory-bound (0.13-0.20 s
on the 9 mm cone damper, 48 M factor entries) while a block of 6 right-hand
sides costs about 40 ms a column: the fixed-interface modes of a
Craig-Bampton reduction took 70-80 single solves. This solver builds the
block Krylov space of ``T = K^-1 M`` from a random start block,

    V = [T X, T^2 X, T^3 X, ...]   (M-orthonormalised: two passes of block
                                    Gram-Schmidt, then an eigen-based
                                    orthonormalisation inside the block)

and takes Rayleigh-Ritz pairs of ``(V^T K V, V^T M V)``. A pair is
converged when its residual in the transformed problem (the quantity SLEPc
tests with shift-and-invert) is below ``tol``:

    || lam K^-1 M phi - phi || / || phi || <= tol,

from the blocks ``T V`` kept as the space is built (no solve of their own),
checked once the space holds ``4 n`` vectors. The space grows by one
block until all ``n`` pairs converge, or a :class:`SolveError` names what
was reached. The start block is drawn over the global rows from a fixed
seed, so the result does not depend on the number of ranks beyond
round-off.

``K`` must be positive definite (the fixed interface holds the body):
the factor given is the one of ``K`` (shift 0), reused by the caller for
the constraint modes.
"""

from __future__ import annotations

import logging

import numpy as np

from ..errors import SolveError
from .parallel import allsum
from .parallel import dense_mult as _mult
from .parallel import dense_solve as _solve

log = logging.getLogger(__name__)

SEED = 20261127
# residual floor of this measure in double precision: about 5e-12 on the 9 mm meshes; at
# 1e-10 the eigenvalues are exact to about 1e-20 (quadratic) and the modes to 1e-10 / gap
TOL = 1e-10
BLOCK = 6  # right-hand sides per block: about 40 ms a column against 200 ms alone (9 mm cone)
MAX_DIM_PER_PAIR = 30  # the Krylov space may grow to this many vectors per pair sought


def _orthonormalise(W, V, BV, b_mult, comm):
    """``(W, BW)``: W made M-orthonormal to the blocks of V and within itself.

    Two passes of block classical Gram-Schmidt against V (``V^T M W = BV^T W``),
    then an eigen-decomposition of the block's Gram matrix; directions with a
    Gram eigenvalue below 1e-10 of the largest are dropped (a converged space).
    """
    for _ in range(2):
        for Vj, BVj in zip(V, BV, strict=True):
            W = W - Vj @ allsum(comm, BVj.T @ W)
    BW = b_mult(W)
    G = allsum(comm, W.T @ BW)
    s, U = np.linalg.eigh(0.5 * (G + G.T))
    keep = s > 1e-10 * max(float(s.max(initial=0.0)), 1e-300)
    C = U[:, keep] / np.sqrt(s[keep])
    return W @ C, BW @ C


def _grow(G, cross, corner):
    """The symmetric Gram matrix G bordered by a new block's column ``cross`` and ``corner``."""
    d, b = cross.shape
    out = np.empty((d + b, d + b))
    out[:d, :d], out[:d, d:], out[d:, :d] = G, cross, cross.T
    out[d:, d:] = 0.5 * (corner + corner.T)
    return out


def _ritz(V, TV, Ar, Br, n, comm):
    """The ``n`` lowest Ritz pairs of the space V (list of blocks) and their largest residual."""
    from scipy.linalg import eigh

    lam, Y = eigh(Ar, Br, subset_by_index=(0, n - 1))
    Phi = np.zeros((V[0].shape[0], n))
    TPhi = np.zeros_like(Phi)
    k = 0
    for Vj, TVj in zip(V, TV, strict=True):
        Yj = Y[k : k + Vj.shape[1]]
        Phi += Vj @ Yj
        TPhi += TVj @ Yj
        k += Vj.shape[1]
    R = TPhi * lam[None, :] - Phi  # lam T phi - phi
    num = allsum(comm, np.sum(R * R, axis=0))
    den = allsum(comm, np.sum(Phi * Phi, axis=0))
    return lam, Phi, float(np.sqrt(num / np.maximum(den, 1e-300)).max())


def block_eigen(
    A,
    B,
    F,
    n: int,
    comm,
    *,
    tol: float = TOL,
    block: int | None = None,
    max_dim: int | None = None,
    what: str = "modes",
    b_mult=None,
) -> tuple[np.ndarray, np.ndarray, dict]:
    """The ``n`` lowest eigenpairs of the SPD pencil (A, B), ``F`` the factor of ``A``.

    ``b_mult``: a faster ``X -> B X`` on this rank's rows (default: PETSc's product).

    Returns ``(lam, X, info)``: eigenvalues ascending, this rank's rows of
    the B-normalised eigenvectors (columns), and ``info`` (block size,
    space dimension, block solves, largest residual). Collective.
    """
    n_global = A.getSize()[0]
    r0, r1 = A.getOwnershipRange()
    if b_mult is None:

        def b_mult(X):
            return _mult(B, X, n_global, comm)

    b = int(block or BLOCK)
    max_dim = int(max_dim or MAX_DIM_PER_PAIR * max(n, 1))
    if n <= 0:
        return np.zeros(0), np.zeros((r1 - r0, 0)), dict(block=b, dim=0, solves=0, residual=0.0)
    b = min(b, n_global)
    rng = np.random.default_rng(SEED)
    X = rng.standard_normal((n_global, b))[r0:r1]  # drawn over global rows: rank-independent
    V, BV, TV = [], [], []  # blocks: the M-orthonormal basis, M V and T V = K^-1 M V
    Ar, Br = np.zeros((0, 0)), np.zeros((0, 0))  # V^T K V, V^T M V
    W = _solve(F, b_mult(X), n_global, comm)
    solves, worst, dim = b, np.inf, 0
    while dim < min(max_dim, n_global):
        W, BW = _orthonormalise(W, V, BV, b_mult, comm)
        if W.shape[1] == 0:
            break  # an invariant subspace: its pairs were checked when it last grew (or below)
        # T W: the next block before its orthonormalisation, kept so that the Ritz
        # vectors' residuals need no solve of their own
        TW = _solve(F, BW, n_global, comm)
        AW = _mult(A, W, n_global, comm)
        solves += W.shape[1]
        cA = np.vstack([allsum(comm, Vj.T @ AW) for Vj in V] or [np.zeros((0, W.shape[1]))])
        cB = np.vstack([allsum(comm, Vj.T @ BW) for Vj in V] or [np.zeros((0, W.shape[1]))])
        Ar = _grow(Ar, cA, allsum(comm, W.T @ AW))
        Br = _grow(Br, cB, allsum(comm, W.T @ BW))
        V.append(W)
        BV.append(BW)
        TV.append(TW)
        dim += W.shape[1]
        if dim >= 4 * n:  # the Ritz pairs are far from converged before (residual > 1e-3)
            lam, Phi, worst = _ritz(V, TV, Ar, Br, n, comm)
            log.debug("%s: space %d, largest residual %.1e", what, dim, worst)
            if worst <= tol:
                return lam, Phi, dict(block=b, dim=dim, solves=solves, residual=worst)
        W = TW
    if n <= dim < 4 * n:  # an invariant subspace found early: its pairs were not checked
        lam, Phi, worst = _ritz(V, TV, Ar, Br, n, comm)
        if worst <= tol:
            return lam, Phi, dict(block=b, dim=dim, solves=solves, residual=worst)
    raise SolveError(
        f"{what}: the block Krylov eigen solve did not converge: {n} pairs in a space of "
        f"{dim} vectors (block {b}), largest residual {worst:.1e} > {tol:.0e}"
    )
