"""PETSc/SLEPc back end: shift-and-invert eigen solves and MUMPS factorisations.

Solver options go through the PETSc options database under a prefix per
role (``upd_modes_``, ``upd_cb_``, ``upd_free_``), never through sys.argv.
Our defaults are written only where the user has not set the key (for
example with ``PETSC_OPTIONS="-upd_modes_st_mat_mumps_icntl_14 200"``), and
removed again after the solve. The Craig-Bampton reduction factorises its
interior stiffness with a plain KSP under ``upd_cb_`` (no ``st_``:
``-upd_cb_mat_mumps_icntl_14 200``) and finds its fixed-interface modes
with :mod:`.block_eigen`, not SLEPc.

Defaults of the SLEPc solves (``upd modes``): Krylov-Schur, shift-and-invert
(``st_type sinvert``) with a ``preonly`` KSP and an LU factorisation by
MUMPS; MUMPS ICNTL(14) (extra work space, %) raised to 80 because the 3-D
P2 fill estimate is often short.
Do not set ``st_pc_type cholesky``: from the options database it drops MUMPS
and runs PETSc's own serial factorisation (about 12 times slower here).
"""

from __future__ import annotations

import logging
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import SolveError

log = logging.getLogger(__name__)

EIGEN_TOL = 1e-12  # relative residual; eigenvector errors scale with tol / gap
MUMPS_ICNTL14 = 80


@contextmanager
def petsc_options(prefix: str, defaults: dict[str, Any]):
    """Set ``defaults`` under ``prefix`` unless already set; remove what was added on exit."""
    from petsc4py import PETSc

    opts = PETSc.Options()
    added = []
    for k, v in defaults.items():
        key = prefix + k
        if not opts.hasName(key):
            opts[key] = v
            added.append(key)
    try:
        yield
    finally:
        for key in added:
            opts.delValue(key)


def mumps_defaults(st: bool = True) -> dict[str, Any]:
    p = "st_" if st else ""
    return {
        f"{p}ksp_type": "preonly",
        f"{p}pc_type": "cholesky",
        f"{p}pc_factor_mat_solver_type": "mumps",
        f"{p}mat_mumps_icntl_14": MUMPS_ICNTL14,
    }


@dataclass
class EigenSolution:
    """Eigenpairs of ``A x = lam B x`` nearest the shift, ascending."""

    eigenvalues: np.ndarray  # (n,) rad^2/s^2
    vectors: list  # PETSc.Vec, B-normalised (x^T B x = 1)
    eps: Any  # the SLEPc EPS (its ST holds the MUMPS factorisation of A - sigma B)
    sigma: float

    @property
    def freqs_hz(self) -> np.ndarray:
        return np.sqrt(np.maximum(self.eigenvalues, 0.0)) / (2.0 * np.pi)

    def factor(self):
        """The MUMPS factor of ``A - sigma B`` inside the shift-and-invert transform."""
        return self.eps.getST().getKSP().getPC().getFactorMatrix()


def eigen_solve(
    A,
    B,
    n: int,
    *,
    sigma: float = 0.0,
    prefix: str = "upd_modes_",
    what: str = "modes",
    tol: float = EIGEN_TOL,
) -> EigenSolution:
    """The ``n`` eigenpairs of the symmetric pencil (A, B) closest to ``sigma``.

    A is symmetric; B symmetric positive semi-definite (Dirichlet rows carry
    zero mass and give infinite eigenvalues, which the transform ignores).
    Vectors are returned B-normalised. Raises SolveError (with the pairs
    found in ``partial``) if fewer than ``n`` converge.
    """
    from slepc4py import SLEPc

    eps = SLEPc.EPS().create(A.getComm())
    eps.setOptionsPrefix(prefix)
    eps.setOperators(A, B)
    eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
    eps.setType(SLEPc.EPS.Type.KRYLOVSCHUR)
    eps.setDimensions(n)
    eps.setTarget(sigma)
    eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
    eps.setTolerances(tol, 1000)
    # no purification: it costs one more solve per vector (0.17 s each on the
    # 9 mm rig) and only matters for a singular B whose null space the vectors
    # could pick up; Dirichlet rows are zero rows and columns of A and B here,
    # so every application of the operator already leaves them at zero
    eps.setPurify(False)
    st = eps.getST()
    st.setType(SLEPc.ST.Type.SINVERT)
    st.setShift(sigma)
    with petsc_options(prefix, mumps_defaults()):
        eps.setFromOptions()
        try:
            eps.solve()
        except Exception as e:  # noqa: BLE001 - PETSc.Error carries only an error code
            raise SolveError(
                f"{what}: the eigen solve failed ({e}); for more MUMPS work space try "
                f"PETSC_OPTIONS='-{prefix}st_mat_mumps_icntl_14 200'"
            ) from e
    nconv = eps.getConverged()
    lam = np.array([eps.getEigenvalue(i).real for i in range(nconv)])
    order = np.argsort(np.abs(lam - sigma), kind="stable")[:n]
    order = order[np.argsort(lam[order], kind="stable")]
    vecs = []
    for i in order:
        v = A.createVecs()[0]
        eps.getEigenvector(int(i), v)
        vecs.append(v)
    sol = EigenSolution(eigenvalues=lam[order], vectors=vecs, eps=eps, sigma=sigma)
    for v in vecs:  # B-normalise explicitly (SLEPc's scaling depends on options)
        Bv = B.createVecs()[0]
        B.mult(v, Bv)
        v.scale(1.0 / np.sqrt(abs(v.dot(Bv))))
    if nconv < n:
        raise SolveError(
            f"{what}: only {nconv} of {n} eigenpairs converged (SLEPc reason "
            f"{eps.getConvergedReason()}, {eps.getIterationNumber()} iterations)",
            partial=sol,
        )
    log.debug("%s: %d eigenpairs in %d iterations", what, n, eps.getIterationNumber())
    return sol
