"""The contact element record: which coordinates each element sees, and its parameters.

An element ``e`` sees the local relative displacement ``u_e = [t1, t2, n]``
(damper minus platform, metres; ``n > 0`` opens the contact) through rows
``3e, 3e+1, 3e+2`` of a sparse map ``W`` from the generalised coordinates
``q``::

    u = (W @ q).reshape(n_el, 3)           # rows t1, t2, n of each element
    force on q = W.T @ f.ravel()           # f = [T1, T2, -N] per element

An element with a single tangential DOF, or with no normal DOF, simply has
zero rows in ``W``; an element against the ground has no platform columns.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..errors import InputError, check_choice
from .law_params import own_params
from .laws import LAWS  # every law module of workbench.contact.laws


def _per_element(name: str, value: object, n_el: int, lo: float = 0.0) -> np.ndarray:
    """Broadcast a scalar or check an array of one value per element (finite, >= lo)."""
    a = np.asarray(value, dtype=float)
    if a.ndim == 0:
        a = np.full(n_el, float(a))
    if a.shape != (n_el,):
        raise InputError(
            name, f"array of shape {a.shape}", f"a number or {n_el} values (one per element)"
        )
    bad = ~np.isfinite(a) | (a < lo)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise InputError(f"{name}[{i}]", float(a[i]), f"a finite number >= {lo:g}")
    return a


@dataclass(frozen=True, eq=False)
class ContactElements:
    """Node-to-node friction contact elements (DESIGN.md section 6).

    ``W`` (``3 n_el x n``, scipy.sparse) maps the generalised coordinates to
    each element's local relative displacement ``[t1, t2, n]`` in metres.
    Per element: friction coefficient ``mu`` (-), tangential stiffnesses
    ``kt1``, ``kt2`` (N/m), normal stiffness ``kn`` (N/m) and normal preload
    ``n0`` (N, compressive positive). ``law`` is "decoupled" (two Jenkins
    elements, slip limit ``mu N`` on each tangential axis, as in the study of
    the conical damper), "circular" (one slip limit ``|T| <= mu N`` in the
    tangent plane) or any other law of :mod:`workbench.contact.laws`
    ("dahl": smooth friction). ``law_params``: the values per element of
    each law's own parameters beyond ``mu`` (declared in the law's module,
    :mod:`workbench.contact.law_params`), by name.
    """

    W: sp.csr_matrix
    mu: np.ndarray
    kt1: np.ndarray
    kt2: np.ndarray
    kn: np.ndarray
    n0: np.ndarray
    law: str = "decoupled"
    law_params: dict[str, np.ndarray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        W = sp.csr_matrix(self.W, dtype=float)
        if W.shape[0] % 3:
            raise InputError("contact W", f"{W.shape[0]} rows", "3 rows (t1, t2, n) per element")
        n_el = W.shape[0] // 3
        object.__setattr__(self, "W", W)
        for name in ("mu", "kt1", "kt2", "kn", "n0"):
            object.__setattr__(self, name, _per_element(name, getattr(self, name), n_el))
        own = {k: _per_element(k, v, n_el, -np.inf) for k, v in self.law_params.items()}
        object.__setattr__(self, "law_params", own)
        check_choice("law", self.law, LAWS)
        if not np.all(np.isfinite(W.data)):
            raise InputError("contact W", "non-finite entries", "finite numbers")

    # -- sizes -------------------------------------------------------------
    @property
    def n_el(self) -> int:
        return self.W.shape[0] // 3

    @property
    def n_dofs(self) -> int:
        return self.W.shape[1]

    @property
    def active(self) -> np.ndarray:
        """(n_el, 3) bool: the directions whose row of ``W`` is not zero."""
        rows = np.asarray(abs(self.W).sum(axis=1)).ravel() > 0
        return rows.reshape(self.n_el, 3)

    @property
    def lp(self) -> np.ndarray:
        """(n_el, n_own) the law's own parameters per element, in the order of its
        ``PARAMS`` (the ``lp`` its ``step`` receives; a declared default where
        ``law_params`` has no value; no columns for a law without)."""
        own = own_params(self.law)
        out = np.empty((self.n_el, len(own)))
        for j, p in enumerate(own):
            out[:, j] = self.law_params.get(p.name, p.default)
        return out

    @property
    def law_code(self) -> int:
        return LAWS.index(self.law)

    @property
    def kc(self) -> np.ndarray:
        """(n_el, 3) stiffness of the stuck element [kt1, kt2, kn] in N/m."""
        return np.stack([self.kt1, self.kt2, self.kn], axis=1)

    # -- linear parts --------------------------------------------------------
    def stuck_stiffness(self) -> sp.csr_matrix:
        """``W^T diag(kc) W`` (n x n, N/m): the stiffness of every element stuck and closed."""
        return (self.W.T @ sp.diags(self.kc.ravel()) @ self.W).tocsr()

    def force_at_rest(self) -> np.ndarray:
        """(n_el, 3) local force ``[T1, T2, -N]`` at ``u = 0`` with the slider at rest (N)."""
        f = np.zeros((self.n_el, 3))
        f[:, 2] = -self.n0
        return f

    def balance_force(self) -> np.ndarray:
        """(n,) the constant external force that makes ``u = 0`` the static equilibrium (N).

        It is ``W^T f(0)``: the preloads pressed on the coordinates, which the
        centrifugal load on the damper (and the platform reactions) carry.
        """
        return self.W.T @ self.force_at_rest().ravel()

    # -- builders ----------------------------------------------------------
    @classmethod
    def from_dofs(
        cls,
        n: int,
        dofs: Sequence[Sequence[int]] | np.ndarray,
        *,
        mu: float | np.ndarray,
        kt: float | np.ndarray,
        kn: float | np.ndarray = 0.0,
        n0: float | np.ndarray = 0.0,
        kt2: float | np.ndarray | None = None,
        other: Sequence[Sequence[int]] | np.ndarray | None = None,
        frames: np.ndarray | None = None,
        law: str = "decoupled",
        law_params: dict[str, object] | None = None,
    ) -> ContactElements:
        """Elements from DOF indices of an ``n``-DOF model.

        ``dofs[e]`` lists the DOFs of element ``e``'s (damper) node: one index
        (a single tangential DOF t1), or three ``[a, b, c]``. Without
        ``frames`` the three are the local ``t1, t2, n`` directions themselves
        (``-1`` for a direction the model does not have); with ``frames[e]``
        (3 x 3, rows t1, t2, n) they are the node's x, y, z DOFs and the local
        displacement is ``frames[e] @ [x, y, z]``. ``other[e]`` (same shape)
        names the platform node's DOFs (relative = damper - platform); without
        it the element acts against the ground. ``law_params``: the law's own
        parameters by name (a number or one per element).
        """
        n = int(n)
        d = _dof_table("dofs", dofs, n)
        n_el = d.shape[0]
        o = None if other is None else _dof_table("other", other, n, allow_empty=True)
        if o is not None and o.shape != d.shape:
            raise InputError("other", f"shape {o.shape}", f"the shape of dofs {d.shape}")
        if frames is not None:
            frames = np.asarray(frames, dtype=float)
            if frames.shape != (n_el, 3, 3) or d.shape[1] != 3:
                raise InputError(
                    "frames", f"shape {frames.shape}", f"({n_el}, 3, 3) with three DOFs per element"
                )
        rows, cols, vals = [], [], []
        for e in range(n_el):
            for sign, table in ((1.0, d), (-1.0, o)):
                if table is None:
                    continue
                for j, dof in enumerate(table[e]):
                    if dof < 0:
                        continue
                    if frames is None:
                        rows.append(3 * e + j)
                        cols.append(dof)
                        vals.append(sign)
                    else:
                        for a in range(3):
                            if frames[e, a, j] != 0.0:
                                rows.append(3 * e + a)
                                cols.append(dof)
                                vals.append(sign * frames[e, a, j])
        W = sp.csr_matrix((vals, (rows, cols)), shape=(3 * n_el, n))
        W.sum_duplicates()
        own = dict(law_params or {})
        kt2 = kt if kt2 is None else kt2
        return cls(W=W, mu=mu, kt1=kt, kt2=kt2, kn=kn, n0=n0, law=law, law_params=own)

    @classmethod
    def concat(cls, parts: Sequence[ContactElements]) -> ContactElements:
        """One record from several with the same number of DOFs and the same law."""
        if not parts:
            raise InputError("contact", "[]", "at least one group of elements")
        laws = {p.law for p in parts}
        if len(laws) > 1:
            raise InputError("law", sorted(laws), "one law for every contact element")
        n = {p.n_dofs for p in parts}
        if len(n) > 1:
            raise InputError("contact W", sorted(n), "the same number of columns in every group")
        own = {tuple(sorted(p.law_params)) for p in parts}
        if len(own) > 1:
            raise InputError("law_params", sorted(own), "the same law parameters in every group")
        return cls(
            W=sp.vstack([p.W for p in parts]).tocsr(),
            mu=np.concatenate([p.mu for p in parts]),
            kt1=np.concatenate([p.kt1 for p in parts]),
            kt2=np.concatenate([p.kt2 for p in parts]),
            kn=np.concatenate([p.kn for p in parts]),
            n0=np.concatenate([p.n0 for p in parts]),
            law=parts[0].law,
            law_params={
                k: np.concatenate([p.law_params[k] for p in parts]) for k in parts[0].law_params
            },
        )

    def with_params(self, **changes: object) -> ContactElements:
        """A copy with some of mu, kt1, kt2, kn, n0, law, law_params replaced."""
        kw = dict(
            W=self.W,
            mu=self.mu,
            kt1=self.kt1,
            kt2=self.kt2,
            kn=self.kn,
            n0=self.n0,
            law=self.law,
            law_params=self.law_params,
        )
        for k, v in changes.items():
            if k not in kw or k == "W":
                raise InputError(k, v, "one of mu, kt1, kt2, kn, n0, law, law_params")
            kw[k] = v
        return ContactElements(**kw)


def _dof_table(name: str, dofs: object, n: int, allow_empty: bool = False) -> np.ndarray:
    try:
        a = np.asarray(dofs, dtype=float)
    except (TypeError, ValueError):
        raise InputError(name, dofs, "DOF indices: one or three per element") from None
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2 or a.shape[1] not in (1, 3) or a.shape[0] == 0:
        raise InputError(name, dofs, "a list of elements with one (t1) or three (t1, t2, n) DOFs")
    if np.any(a != np.round(a)):
        raise InputError(name, dofs, "whole numbers")
    a = a.astype(int)
    bad = (a >= n) | (a < -1)
    if bad.any():
        e, j = map(int, np.argwhere(bad)[0])
        raise InputError(
            f"{name}[{e}][{j}]", int(a[e, j]), f"a DOF index 0 <= i < {n} (or -1 for none)"
        )
    if not allow_empty and np.all(a < 0, axis=1).any():
        e = int(np.flatnonzero(np.all(a < 0, axis=1))[0])
        raise InputError(f"{name}[{e}]", a[e].tolist(), "at least one DOF")
    return a
