"""Checks of a model file's matrices, contacts and sizes before any solve.

:mod:`.modelfile` reads a model file of ``upd frf`` / ``upd nlmodes``; the
checks here run on what it read, each refusing with an
:class:`~workbench.errors.InputError` that names the model file's key:

- the matrices (:func:`check_matrices`): real, finite, square, symmetric,
  within double precision's range (:mod:`workbench.matrix_checks`), a
  mass on every DOF;
- each contact element (:func:`check_contact_group`): its directions t1,
  t2, n distinct, its platform node another node than its damper node,
  its frame orthonormal, its stiffness not beyond what the model's own
  stiffness can carry in double precision;
- a contact law's own parameters in a ``[[contact]]`` table (:func:`contact_group`);
- the excitation levels against the contacts' slip forces (:func:`check_levels`);
- the stiffness (:func:`check_stiffness`): no negative stiffness, and a
  stuck system that is regular and not ill-conditioned, with the input
  responsible named;
- the memory the harmonic balance will hold (:func:`check_size`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ...config import load_record
from ...contact.law_params import COMMON, law_params, own_params, params_of
from ...errors import InputError, check_int, check_range
from ...limits import (
    CONTACT_STIFFNESS_RATIO_MAX,
    CONTACT_STIFFNESS_WHY,
    LEVEL_OVER_SLIP_MAX,
    LEVEL_WHY,
    check_memory,
)
from ...matrix_checks import check_matrix, check_vector

EIGEN_CHECK_MAX_DOFS = 2000  # the dense eigenvalue checks cost < 1 s up to this size
SINGULAR_RATIO = 1e-12  # the solver refuses (K_r, M) whose eigenvalues span more than this


def check_matrices(M: Any, K: Any, C: Any, fs: Any, labels: Any) -> tuple:
    """M, K, C (or None) and the static force (or None), checked and named by their key."""
    M = check_matrix(M, "model.mass", symmetric=True)
    n = M.shape[0]
    if n < 1:
        raise InputError("model.mass", "shape (0, 0)", "a square matrix, 1 x 1 or more")
    K = check_matrix(K, "model.stiffness", n=n, symmetric=True)
    C = None if C is None else check_matrix(C, "model.damping", n=n)
    fs = None if fs is None else check_vector(fs, "model.static_force", n)
    d = np.asarray(M.diagonal()).ravel()
    if np.any(d <= 0.0):
        i = int(np.flatnonzero(d <= 0.0)[0])
        where = (
            ""
            if labels is None or labels.labels is None
            else f" (node, component) {labels.labels[i]}"
        )
        raise InputError(
            "model.mass",
            f"M[{i},{i}] = {d[i]:g}{where}",
            "a positive mass on every DOF (a positive definite mass matrix)",
            f"{int(np.count_nonzero(d <= 0.0))} of {n} DOFs have no mass",
        )
    return M, K, C, fs


# [solver] fields without an upper bound in SolverOptions: the bounds of a model file
SOLVER_LIMITS = {
    "max_points": (2, 100_000),
    "n_fine": (16, 1 << 16),
    "refresh_ksp_its": (1, 100_000),
    "single_above": (0, 10_000_000),
}


def check_solver(options: Any) -> None:
    """The [solver] table's whole numbers within the bounds of a model file."""
    for key, (lo, hi) in SOLVER_LIMITS.items():
        check_int(f"solver.{key}", getattr(options, key), lo, hi)


def frames(key: str, value: Any) -> np.ndarray:
    """The ``frames`` of a contact group as an array (the checks are the group's)."""
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(
            key, value, "per element a 3 x 3 table of numbers (rows t1, t2, n)"
        ) from None


# every contact law's own parameters (beyond mu): the keys a [[contact]] table may add
LAW_KEYS = {p.name: p for p in law_params() if p not in COMMON}


def contact_group(section: type, table: Any, i: int) -> tuple[Any, dict[str, float]]:
    """A ``[[contact]]`` table as (its ``section`` record, its law's own parameters).

    The keys named after a law's own parameter are the law's, not the record's: the
    table's law reads its own (a declared default where not given, range-checked), a
    parameter of another law is refused.
    """
    where = f"contact[{i}]"
    given, rest = {}, table
    if isinstance(table, dict):
        given = {k: v for k, v in table.items() if k in LAW_KEYS}
        rest = {k: v for k, v in table.items() if k not in LAW_KEYS}
    rec = load_record(section, rest, f"{where}.")
    own = {p.name: p for p in own_params(rec.law)}
    for k, v in given.items():
        if k not in own:
            reads = "it reads " + ", ".join(p.name for p in params_of(rec.law))
            raise InputError(f"{where}.{k}", v, f"a parameter of the {rec.law} law ({reads})")
    values = {
        k: check_range(f"{where}.{k}", given.get(k, p.default), p.lo, p.hi, lo_open=p.lo_open)
        for k, p in own.items()
    }
    return rec, values


def _dense(A: Any) -> np.ndarray:
    return A.toarray() if sp.issparse(A) else np.asarray(A, dtype=float)


def check_contact_group(where: str, part: Any, dofs: list, frames: Any, K: Any) -> None:
    """The elements of one ``[[contact]]`` group are not degenerate.

    Each direction the element lists (a DOF >= 0, or a frame row on its DOFs)
    must move: a zero row of ``W`` is a node against itself (its relative
    displacement is zero); the listed directions must be independent (t1
    and n on the same DOF, or two equal frame rows, are one direction).
    """
    if frames is not None:
        F = np.asarray(frames, dtype=float)
        if not np.all(np.isfinite(F)):
            raise InputError(f"{where}.frames", "NaN or infinite values", "finite numbers")
        for e in range(F.shape[0]):
            err = float(np.abs(F[e] @ F[e].T - np.eye(3)).max())
            if err > 1e-4:
                raise InputError(
                    f"{where}.frames[{e}]",
                    F[e].tolist(),
                    "rows t1, t2, n of unit length and at right angles (orthonormal)",
                    f"off by {err:.2g}",
                )
    W = part.W.tocsr()
    for e, el in enumerate(dofs):
        el = el if isinstance(el, list) else [el]
        listed = [j for j, dof in enumerate(el) if dof >= 0]
        if frames is not None:
            F = np.asarray(frames, dtype=float)[e]
            listed = [a for a in range(3) if any(F[a, j] != 0.0 for j in listed)]
        rows = W[3 * e : 3 * e + 3].toarray()
        names = ("t1", "t2", "n")
        for a in listed:
            if not np.any(rows[a]):
                raise InputError(
                    f"{where}.dofs[{e}]",
                    el,
                    "an element whose platform node is another node than its damper node",
                    f"its relative displacement along {names[a]} is zero: the node is "
                    "against itself",
                )
        sub = rows[listed]
        if len(listed) > 1 and np.linalg.matrix_rank(sub, tol=1e-9 * np.abs(sub).max()) < len(
            listed
        ):
            same = [
                (names[a], names[b])
                for i, a in enumerate(listed)
                for b in listed[i + 1 :]
                if np.linalg.matrix_rank(rows[[a, b]]) < 2
            ]
            pair = (
                f"{same[0][0]} and {same[0][1]} are the same direction"
                if same
                else ("its directions are not independent")
            )
            raise InputError(
                f"{where}.dofs[{e}]",
                el,
                "three distinct directions t1, t2, n (distinct DOFs, or independent frame rows)",
                pair,
            )
    kmax = float(np.abs(np.asarray(_dense_diag(K))).max())
    for key, k in (("kt_n_per_m", part.kt1), ("kt2_n_per_m", part.kt2), ("kn_n_per_m", part.kn)):
        top = float(np.max(k)) if np.size(k) else 0.0
        if kmax > 0 and top > CONTACT_STIFFNESS_RATIO_MAX * kmax:
            raise InputError(
                f"{where}.{key}",
                top,
                f"<= {CONTACT_STIFFNESS_RATIO_MAX:g} x the largest diagonal stiffness of "
                f"model.stiffness ({kmax:.3g})",
                CONTACT_STIFFNESS_WHY,
            )


def _dense_diag(K: Any) -> np.ndarray:
    return np.asarray(K.diagonal()).ravel()


def check_levels(key: str, levels: list[float], f1: np.ndarray, groups: list) -> None:
    """Excitation levels that leave the contacts a part to play.

    ``groups``: (where, ContactElements) per group; with a preload the
    largest slip force is ``max(mu N0)``; a force beyond
    ``LEVEL_OVER_SLIP_MAX`` times it is refused.
    """
    slip = max((float(np.max(p.mu * p.n0)) for _, p in groups if p.n_el), default=0.0)
    fmax = float(np.abs(f1).max())
    if slip <= 0.0 or fmax <= 0.0:
        return
    top = LEVEL_OVER_SLIP_MAX * slip / fmax
    for i, lv in enumerate(levels):
        if lv > top:
            raise InputError(
                f"{key}[{i}]",
                lv,
                f"a level <= {top:g} (a force of at most {LEVEL_OVER_SLIP_MAX:g} x the largest "
                f"slip force mu N0 = {slip:g})",
                LEVEL_WHY,
            )


def check_stiffness(M: Any, K: Any, contacts: Any, groups: list) -> None:
    """No negative stiffness; the stuck system regular, or the input responsible named.

    Dense eigenvalues, so only up to ``EIGEN_CHECK_MAX_DOFS`` DOFs (larger
    models are checked by the solver itself).
    """
    n = M.shape[0]
    d = _dense_diag(K)
    if d.size and d.min() < 0:
        i = int(np.argmin(d))
        raise InputError(
            "model.stiffness",
            f"K[{i},{i}] = {d[i]:g}",
            "a stiffness matrix without negative stiffness (no negative diagonal entry)",
        )
    if n > EIGEN_CHECK_MAX_DOFS:
        return
    Kd, Md = _dense(K), _dense(M)
    lam = np.linalg.eigvalsh(0.5 * (Kd + Kd.T))
    if lam[0] < -1e-9 * max(1.0, float(np.abs(lam).max())):
        raise InputError(
            "model.stiffness",
            f"lowest eigenvalue {lam[0]:.4g}",
            "a positive semi-definite stiffness matrix (no negative stiffness)",
        )
    Kr = Kd if contacts is None else Kd + contacts.stuck_stiffness().toarray()
    try:
        mu = sla.eigvalsh(Kr, Md)
    except (np.linalg.LinAlgError, ValueError):
        raise InputError(
            "model.mass", "not positive definite", "a positive definite mass matrix"
        ) from None
    top = max(float(np.abs(mu).max()), 1e-300)
    low = float(mu.min())
    if low > SINGULAR_RATIO * top:
        return
    kmax = max(float(np.abs(d).max()), 1e-300)
    springs = [
        (f"{w}.{key}", float(np.max(k)))
        for w, p in groups
        if p.n_el
        for key, k in (("kt_n_per_m", p.kt1), ("kt2_n_per_m", p.kt2), ("kn_n_per_m", p.kn))
    ]
    stiff = max(springs, key=lambda t: t[1], default=None)
    if low <= 100 * np.finfo(float).eps * top:
        raise InputError(
            "model.stiffness",
            f"lowest eigenvalue {low:.3g} of the stuck system (K + contact springs, M)",
            "a model held by supports or contact elements (no free rigid-body mode)",
            "a rigid-body mode is held by no support and no contact element; add contact "
            "elements or supports",
        )
    if stiff is not None and stiff[1] > 1e3 * kmax:
        raise InputError(
            stiff[0],
            stiff[1],
            f"a contact stiffness nearer the model's own (largest diagonal of K {kmax:.3g})",
            f"with it the eigenvalues of the stuck system span {top / low:.2g}; the solver "
            f"needs less than {1 / SINGULAR_RATIO:.0e}",
        )
    raise InputError(
        "model.stiffness",
        f"eigenvalues of the stuck system from {low:.3g} to {top:.3g}",
        f"a spread below {1 / SINGULAR_RATIO:.0e} (a well-conditioned model)",
        "check the units of model.stiffness and model.mass",
    )


def check_size(harmonics: tuple[int, ...], nt: int, n: int, n_el: int, param: str) -> None:
    """Refuse a harmonic balance whose arrays would not fit in the memory available."""
    from ..core.fourier import default_nt, memory_estimate

    nt_used = nt or default_nt(tuple(harmonics))
    need = memory_estimate(tuple(harmonics), nt_used, n, n_el)
    check_memory(
        need,
        param,
        nt if param.endswith("nt") else list(harmonics),
        f"{len(harmonics)} harmonics with {nt_used} samples per period on {n} DOFs and "
        f"{n_el} contact elements",
    )
