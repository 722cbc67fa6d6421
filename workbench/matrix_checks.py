"""Checks of matrices read from files, before any compiled code sees them.

A matrix from a user's file reaches LAPACK, SciPy's sparse kernels and
PETSc; a wrong index there is a segmentation fault, a complex value is
cast to real with a warning, a NaN or a 1e300 ends as a failed solve
blamed on the physics. Every matrix read from a file passes through
:func:`check_matrix` (or :func:`csr_from_parts` for CSR parts), which
refuses with an :class:`~workbench.errors.InputError` naming the file's
parameter:

- a sparse structure with an index out of range, a row pointer that is not
  non-decreasing from 0 to the number of stored values, or parts of
  different lengths;
- a shape that is not square (or not ``n x n`` like the mass matrix);
- a value that is not a real number (complex with a non-zero imaginary
  part, text, booleans), NaN or infinite;
- entries whose magnitude is beyond ``ENTRY_MAX`` (or a matrix whose largest
  entry is below ``ENTRY_MIN``): products overflow double precision;
- an asymmetric matrix where symmetry is required (mass, stiffness).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

from .errors import InputError
from .limits import ENTRY_MAX, ENTRY_MIN, ENTRY_WHY

SYMMETRY_TOL = 1e-8  # relative asymmetry accepted (round-off of an FE export)


def real_values(a: Any, param: str, what: str = "the matrix") -> np.ndarray:
    """``a`` as a float array; complex values with a non-zero imaginary part, text,
    booleans and objects are refused (never cast silently)."""
    arr = np.asarray(a)
    kind = arr.dtype.kind
    if kind in "iuf":
        return arr.astype(float, copy=False)
    if kind == "c":
        imag = float(np.abs(arr.imag).max()) if arr.size else 0.0
        if imag != 0.0:
            raise InputError(
                param,
                f"complex values (imaginary part up to {imag:.3g})",
                "real numbers",
                f"{what} is complex; a structural matrix is real and is not cast silently",
            )
        return arr.real.astype(float)
    raise InputError(
        param, f"values of type {arr.dtype}", "real numbers", f"{what} holds no numbers"
    )


def _whole(a: Any, param: str, label: str) -> np.ndarray:
    arr = np.asarray(a)
    if arr.dtype.kind in "iu":
        return arr.astype(np.int64).ravel()
    if (
        arr.dtype.kind == "f"
        and arr.size
        and np.all(np.isfinite(arr))
        and np.all(arr == np.round(arr))
    ):
        return arr.astype(np.int64).ravel()
    if arr.dtype.kind == "f" and arr.size == 0:
        return arr.astype(np.int64).ravel()
    raise InputError(param, f"{label} of type {arr.dtype}", f"whole numbers in {label}")


def csr_from_parts(data: Any, indices: Any, indptr: Any, shape: Any, param: str) -> sp.csr_matrix:
    """A CSR matrix from its stored parts, each checked before SciPy is called.

    ``shape``: (rows, columns); ``indptr``: rows + 1 non-decreasing offsets
    from 0 to the number of stored values; ``indices``: a column index
    ``0 <= j < columns`` per stored value; ``data``: the real values.
    """
    shp = _whole(shape, param, "shape")
    if shp.size != 2 or np.any(shp < 0):
        raise InputError(param, f"shape {np.asarray(shape).tolist()}", "two whole numbers >= 0")
    nr, nc = int(shp[0]), int(shp[1])
    ptr = _whole(indptr, param, "indptr")
    idx = _whole(indices, param, "indices")
    vals = real_values(np.asarray(data).ravel(), param)
    if ptr.size != nr + 1:
        raise InputError(param, f"{ptr.size} row offsets (indptr)", f"{nr + 1} (rows + 1)")
    if ptr[0] != 0 or np.any(np.diff(ptr) < 0):
        raise InputError(param, "indptr", "row offsets rising from 0 (non-decreasing)")
    if idx.size != vals.size or ptr[-1] != vals.size:
        raise InputError(
            param,
            f"{vals.size} values, {idx.size} column indices, last row offset {ptr[-1]}",
            "as many values as column indices, and the last row offset equal to them",
        )
    if idx.size and (idx.min() < 0 or idx.max() >= nc):
        bad = int(idx[(idx < 0) | (idx >= nc)][0])
        raise InputError(param, f"column index {bad}", f"column indices 0 <= j < {nc}")
    return sp.csr_matrix((vals, idx, ptr), shape=(nr, nc))


def check_matrix(
    A: Any, param: str, *, n: int | None = None, symmetric: bool = False, square: bool = True
) -> Any:
    """``A`` (dense or scipy.sparse) checked and as floats (CSR stays CSR).

    ``n``: the required size (that of the mass matrix); ``symmetric``:
    relative asymmetry at most :data:`SYMMETRY_TOL`.
    """
    if A is None:
        raise InputError(param, None, "a matrix")
    if sp.issparse(A):
        A = A.tocsr()
        A = csr_from_parts(A.data, A.indices, A.indptr, A.shape, param)
        vals = A.data
    else:
        A = real_values(A, param)
        vals = A
    if A.ndim != 2 or A.size == 0:
        raise InputError(param, f"shape {A.shape}", "a matrix (two dimensions), 1 x 1 or more")
    if square and A.shape[0] != A.shape[1]:
        raise InputError(param, f"shape {A.shape}", "a square matrix")
    if n is not None and A.shape[0] != n:
        raise InputError(param, f"shape {A.shape}", f"({n}, {n}), the size of the mass matrix")
    if vals.size and not np.all(np.isfinite(vals)):
        bad = int(np.count_nonzero(~np.isfinite(vals)))
        raise InputError(param, f"{bad} NaN or infinite entries", "finite numbers")
    top = float(np.abs(vals).max()) if vals.size else 0.0
    if top > ENTRY_MAX or 0.0 < top < ENTRY_MIN:
        raise InputError(
            param,
            f"largest entry {top:.3g}",
            f"{ENTRY_MIN:g} <= largest |entry| <= {ENTRY_MAX:g}",
            ENTRY_WHY,
        )
    if symmetric and top > 0.0:
        D = A - A.T
        asym = float(abs(D).max()) / top
        if asym > SYMMETRY_TOL:
            raise InputError(
                param,
                f"asymmetry {asym:.2e}",
                f"a symmetric matrix (relative asymmetry <= {SYMMETRY_TOL:g})",
            )
    return A


def check_vector(v: Any, param: str, n: int) -> np.ndarray:
    """A real finite vector of ``n`` values."""
    a = real_values(v, param, "the vector").ravel()
    if a.size != n:
        raise InputError(param, f"{a.size} values", f"{n} values (one per DOF)")
    if not np.all(np.isfinite(a)):
        raise InputError(param, "NaN or infinite values", "finite numbers")
    if a.size and float(np.abs(a).max()) > ENTRY_MAX:
        raise InputError(
            param, f"largest value {np.abs(a).max():.3g}", f"|value| <= {ENTRY_MAX:g}", ENTRY_WHY
        )
    return a
