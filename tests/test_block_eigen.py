"""The block shift-and-invert Krylov eigen solver (workbench/fe/block_eigen.py) on chains of
springs and masses whose eigenvalues are known in closed form."""

from __future__ import annotations

import numpy as np
import pytest

from workbench.errors import SolveError
from workbench.fe.block_eigen import block_eigen


def _chain(n_dofs: int, k: float, m: float, copies: int = 1):
    """(K, M, factor of K): ``copies`` fixed-fixed chains of n_dofs masses, as PETSc AIJ."""
    from petsc4py import PETSc

    N = n_dofs * copies
    K = PETSc.Mat().createAIJ((N, N), nnz=3, comm=PETSc.COMM_SELF)
    M = PETSc.Mat().createAIJ((N, N), nnz=1, comm=PETSc.COMM_SELF)
    for c in range(copies):
        for i in range(n_dofs):
            r = c * n_dofs + i
            K.setValue(r, r, 2 * k)
            if i:
                K.setValue(r, r - 1, -k)
                K.setValue(r - 1, r, -k)
            M.setValue(r, r, m)
    K.assemble()
    M.assemble()
    ksp = PETSc.KSP().create(PETSc.COMM_SELF)
    ksp.setOperators(K)
    ksp.setType("preonly")
    ksp.getPC().setType("cholesky")
    ksp.getPC().setFactorSolverType("mumps")
    ksp.setUp()
    return K, M, ksp.getPC().getFactorMatrix(), ksp


def _exact(n_dofs: int, k: float, m: float) -> np.ndarray:
    j = np.arange(1, n_dofs + 1)
    return np.sort(2 * k / m * (1 - np.cos(j * np.pi / (n_dofs + 1))))


@pytest.mark.parametrize("n, block", [(12, 6), (5, 1), (8, 16)])
def test_lowest_eigenpairs_of_a_chain(n, block):
    from mpi4py import MPI

    nd, k, m = 400, 2.0e9, 0.05
    K, M, F, keep = _chain(nd, k, m)
    lam, X, info = block_eigen(K, M, F, n, MPI.COMM_SELF, block=block)
    exact = _exact(nd, k, m)[:n]
    # round-off floor of the Rayleigh quotient: about eps * lam_max / lam_1 = 1.5e-11 here
    assert np.abs(lam / exact - 1).max() < 1e-10
    assert info["residual"] <= 1e-10
    Md = np.full(nd, m)
    assert np.abs(X.T @ (Md[:, None] * X) - np.eye(n)).max() < 1e-10  # M-orthonormal
    # each vector is the sine mode of its eigenvalue (up to sign)
    i = np.arange(1, nd + 1)
    for j in range(n):
        s = np.sin((j + 1) * np.pi * i / (nd + 1))
        s /= np.sqrt(m * s @ s)
        assert abs(abs(s @ (Md * X[:, j])) - 1) < 1e-9
    keep.destroy()


def test_repeated_eigenvalues_are_all_found():
    """Two identical chains: every eigenvalue is double; both copies of each are returned."""
    from mpi4py import MPI

    nd, k, m = 150, 1.0e6, 1.0
    K, M, F, keep = _chain(nd, k, m, copies=2)
    lam, X, info = block_eigen(K, M, F, 8, MPI.COMM_SELF)
    exact = np.repeat(_exact(nd, k, m)[:4], 2)
    assert np.abs(lam / exact - 1).max() < 1e-10  # round-off floor: eps * lam_max / lam_1
    assert np.abs(X.T @ X - np.eye(8)).max() < 1e-10  # M = I: orthonormal within each pair
    keep.destroy()


def test_a_space_too_small_is_reported_with_what_it_reached():
    from mpi4py import MPI

    K, M, F, keep = _chain(2000, 1.0, 1.0)
    with pytest.raises(SolveError, match=r"12 pairs in a space of \d+ vectors .* residual"):
        block_eigen(K, M, F, 12, MPI.COMM_SELF, max_dim=60, what="chain")
    keep.destroy()
