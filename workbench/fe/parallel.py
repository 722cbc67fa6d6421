"""Small MPI helpers on numpy arrays (buffer-based, identical result on every rank)."""

from __future__ import annotations

import numpy as np


def allsum(comm, a) -> np.ndarray:
    """Element-wise sum over ranks of a float array (or scalar)."""
    from mpi4py import MPI

    x = np.ascontiguousarray(a, dtype=np.float64)
    if comm.size == 1:
        return x.copy()
    out = np.empty_like(x)
    comm.Allreduce(x, out, op=MPI.SUM)
    return out


def allmin(comm, a) -> np.ndarray:
    from mpi4py import MPI

    x = np.ascontiguousarray(a, dtype=np.float64)
    out = np.empty_like(x)
    comm.Allreduce(x, out, op=MPI.MIN)
    return out


def allmax(comm, a) -> np.ndarray:
    from mpi4py import MPI

    x = np.ascontiguousarray(a, dtype=np.float64)
    out = np.empty_like(x)
    comm.Allreduce(x, out, op=MPI.MAX)
    return out


def allrows(comm, a: np.ndarray) -> np.ndarray:
    """Stack every rank's rows (rank order) on every rank."""
    parts = comm.allgather(np.asarray(a))
    return np.concatenate(parts, axis=0) if parts else np.asarray(a)


def dense_rows(comm, local: np.ndarray, n_global_rows: int):
    """A PETSc MPIDENSE matrix from this rank's rows (copied, column-major)."""
    from petsc4py import PETSc

    arr = np.asfortranarray(local, dtype=PETSc.ScalarType)
    ncols = arr.shape[1]
    D = PETSc.Mat().createDense(((arr.shape[0], n_global_rows), (PETSc.DECIDE, ncols)), comm=comm)
    D.setUp()
    D.getDenseArray()[:] = arr
    D.assemble()
    return D


def dense_mult(A, X: np.ndarray, n_global_rows: int, comm) -> np.ndarray:
    """This rank's rows of ``A @ X`` (A a PETSc AIJ matrix, X this rank's rows of a block)."""
    D = dense_rows(comm, X, n_global_rows)
    Y = A.matMult(D)
    out = Y.getDenseArray().copy()
    D.destroy()
    Y.destroy()
    return out


def dense_solve(F, X: np.ndarray, n_global_rows: int, comm) -> np.ndarray:
    """This rank's rows of ``A^-1 X`` (F the factor of A) by one multi-right-hand-side solve."""
    D = dense_rows(comm, X, n_global_rows)
    Y = D.duplicate()
    F.matSolve(D, Y)
    out = Y.getDenseArray().copy()
    D.destroy()
    Y.destroy()
    return out


def sparse_solve(F, B, n_global_rows: int, comm) -> np.ndarray:
    """This rank's rows of ``A^-1 B`` for a sparse ``B`` (this rank's rows, scipy sparse).

    Serial: MUMPS is given the right-hand sides as sparse columns
    (ICNTL(20)), so its forward elimination only visits the parts of the
    elimination tree the columns touch: for the constraint modes, whose
    right-hand sides live next to the interface, 2.5-3.5x faster than
    :func:`dense_solve` on the 9 mm rigs. PETSc takes the columns as the
    rows of a matrix wrapped as its transpose. Under MPI this falls back to
    :func:`dense_solve`: with PETSc 3.18 the distributed form returned wrong
    solutions on the toy rig (caught by the constraint modes' residual
    check) and was slower on two ranks than the dense solve on one.
    """
    if comm.size > 1:
        return dense_solve(F, B.toarray(), n_global_rows, comm)
    import scipy.sparse as sp
    from petsc4py import PETSc

    Bt = sp.csr_matrix(B.T)  # compressed columns of B
    nc = Bt.shape[0]
    idx = PETSc.IntType
    T = PETSc.Mat().createAIJ(
        size=(nc, n_global_rows),
        csr=(Bt.indptr.astype(idx), Bt.indices.astype(idx), Bt.data),
        comm=PETSc.COMM_SELF,
    )
    Bv = PETSc.Mat().createTranspose(T)
    X = PETSc.Mat().createDense((n_global_rows, nc), comm=PETSc.COMM_SELF)
    X.setUp()
    F.matSolve(Bv, X)
    out = X.getDenseArray().copy()
    for m in (X, Bv, T):
        m.destroy()
    return out


def info(log, comm, msg: str, *args) -> None:
    """``log.info`` on rank 0 only (every rank computes the same thing)."""
    if comm is None or comm.rank == 0:
        log.info(msg, *args)
