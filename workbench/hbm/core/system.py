"""The linear reduced system with its friction contacts: what the harmonic balance solves.

Equation of motion in the generalised coordinates ``q`` (n):

    M q'' + C q' + K q + W^T f(W q) = p(t) + f_static

with ``f`` the contact law of :mod:`workbench.contact`. ``u = 0`` is the
static equilibrium of the preloaded assembly: with ``balance=True`` (the
default) ``f_static`` includes ``W^T f(0)``, the constant force that
carries the preloads (the centrifugal load on the damper and the platform
reactions, DESIGN.md section 6).

Regularisation. A damper is a free-free body held only by its contacts, so
``K`` alone may be singular. The solver works with the stuck stiffness
added, ``K_r = K + W^T K_c W`` (``K_c = diag(kt1, kt2, kn)``), and subtracts
``K_c u`` from the contact force; nothing changes physically, and the
linear system with every contact stuck and closed is regular.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ...contact import ContactElements
from ...errors import InputError
from ...matrix_checks import csr_from_parts, real_values


def as_dense(A: object, name: str, n: int | None = None) -> np.ndarray:
    """A dense float matrix (from ndarray or scipy.sparse), square and finite."""
    if A is None:
        raise InputError(name, None, "a square matrix")
    if sp.issparse(A):  # its structure checked first: a bad index would crash SciPy
        A = A.tocsr()
        A = csr_from_parts(A.data, A.indices, A.indptr, A.shape, name).toarray()
    try:
        A = real_values(np.asarray(A), name)  # complex is refused, never cast
    except (TypeError, ValueError) as e:
        if isinstance(e, InputError):
            raise
        raise InputError(name, type(A).__name__, "a real square matrix") from None
    if A.ndim != 2 or A.shape[0] != A.shape[1]:
        raise InputError(name, f"shape {A.shape}", "a square matrix")
    if n is not None and A.shape[0] != n:
        raise InputError(name, f"shape {A.shape}", f"({n}, {n}) like M")
    if not np.all(np.isfinite(A)):
        raise InputError(name, "non-finite entries", "finite numbers")
    return A


def _check_symmetric(A: np.ndarray, name: str) -> None:
    scale = max(np.abs(A).max(), 1e-300)
    asym = np.abs(A - A.T).max() / scale
    if asym > 1e-8:
        raise InputError(
            name, f"asymmetry {asym:.2e}", "a symmetric matrix (relative asymmetry <= 1e-8)"
        )


@dataclass(frozen=True, eq=False)
class System:
    """Mass, damping and stiffness of a reduced model with friction contacts.

    ``M``, ``K`` (n x n; kg and N/m, dense or scipy.sparse); damping either as
    a viscous matrix ``C`` (N s/m) or as modal damping ratios ``zeta`` (a
    number, or one per mode in ascending frequency) on the modes of the
    linear system with stuck contacts; ``contacts`` (:class:`ContactElements`,
    may be None for a linear system); ``static_force`` (n, N) a constant
    external force; ``balance`` adds the force that carries the preloads so
    that ``u = 0`` is the static equilibrium. ``rigid_tol``: eigenvalues of
    ``(K, M)`` below ``rigid_tol * max`` count as rigid-body modes (a body
    held only by its contacts), used to detect a lost contact.
    """

    M: np.ndarray
    K: np.ndarray
    C: np.ndarray | None = None
    zeta: float | np.ndarray | None = None
    contacts: ContactElements | None = None
    static_force: np.ndarray | None = None
    balance: bool = True
    rigid_tol: float = 1e-10
    dof_names: tuple[str, ...] = field(default_factory=tuple)

    def __post_init__(self) -> None:
        M = as_dense(self.M, "M")
        n = M.shape[0]
        K = as_dense(self.K, "K", n)
        _check_symmetric(M, "M")
        _check_symmetric(K, "K")
        try:
            np.linalg.cholesky(M)
        except np.linalg.LinAlgError:
            raise InputError(
                "M", "not positive definite", "a positive definite mass matrix"
            ) from None
        object.__setattr__(self, "M", M)
        object.__setattr__(self, "K", K)
        if self.C is not None and self.zeta is not None:
            raise InputError("damping", "both C and zeta", "either a matrix C or modal ratios zeta")
        if self.C is not None:
            object.__setattr__(self, "C", as_dense(self.C, "C", n))
        if self.zeta is not None:
            z = np.atleast_1d(np.asarray(self.zeta, dtype=float))
            if z.ndim != 1 or z.size == 0 or z.size > n or np.any(~np.isfinite(z)) or np.any(z < 0):
                raise InputError(
                    "zeta", self.zeta, f"a number >= 0 or up to {n} per-mode ratios >= 0"
                )
            object.__setattr__(self, "zeta", z)
        if self.contacts is not None:
            if not isinstance(self.contacts, ContactElements):
                raise InputError(
                    "contacts", type(self.contacts).__name__, "a ContactElements record"
                )
            if self.contacts.n_dofs != n:
                raise InputError(
                    "contacts.W",
                    f"{self.contacts.n_dofs} columns",
                    f"{n} columns (one per DOF of M)",
                )
        if self.static_force is not None:
            fs = np.asarray(self.static_force, dtype=float).ravel()
            if fs.shape != (n,) or not np.all(np.isfinite(fs)):
                raise InputError("static_force", f"shape {fs.shape}", f"{n} finite values (N)")
            object.__setattr__(self, "static_force", fs)
        if self.dof_names and len(self.dof_names) != n:
            raise InputError("dof_names", len(self.dof_names), f"{n} names")

    @property
    def n(self) -> int:
        return int(self.M.shape[0])

    @property
    def n_el(self) -> int:
        return 0 if self.contacts is None else self.contacts.n_el

    def regularised_stiffness(self) -> np.ndarray:
        """``K_r = K + W^T K_c W`` (n x n, N/m): every contact stuck and closed."""
        if self.contacts is None:
            return self.K.copy()
        return self.K + self.contacts.stuck_stiffness().toarray()

    def total_static_force(self) -> np.ndarray:
        """The constant external force (N): ``static_force`` plus the preload balance."""
        f = np.zeros(self.n) if self.static_force is None else self.static_force.copy()
        if self.balance and self.contacts is not None:
            f += self.contacts.balance_force()
        return f

    def damping_matrix(self) -> np.ndarray:
        """The viscous matrix (n x n, N s/m): ``C``, else modal damping ``zeta``, else zero."""
        if self.C is not None:
            return self.C
        if self.zeta is not None:
            return modal_damping(self.M, self.K, self.zeta, self.contacts)
        return np.zeros((self.n, self.n))

    def rigid_modes(self) -> np.ndarray:
        """(n, r) the rigid-body modes of ``K`` alone (bodies held only by contacts)."""
        lam, vec = sla.eigh(self.K, self.M)
        top = max(abs(lam).max(), 1e-300)
        return vec[:, lam <= self.rigid_tol * top]


def modal_damping(
    M: np.ndarray, K: np.ndarray, zeta: float | np.ndarray, contacts: ContactElements | None = None
) -> np.ndarray:
    """Viscous matrix ``C`` (N s/m) giving modal damping ratios ``zeta``.

    The modes are those of ``K + W^T K_c W`` (the contacts stuck and closed)
    when ``contacts`` is given, so a free-free damper held by its contacts
    is fine although ``K`` alone is singular. ``zeta`` is one ratio for all
    modes or one per mode (ascending frequency; missing trailing modes take
    the last value). ``C = M Phi diag(2 zeta_j w_j) Phi^T M`` with ``Phi``
    mass-normalised.
    """
    M = as_dense(M, "M")
    K = as_dense(K, "K", M.shape[0])
    Kr = K if contacts is None else K + contacts.stuck_stiffness().toarray()
    lam, phi = sla.eigh(Kr, M)
    if lam.min() <= -1e-9 * max(abs(lam).max(), 1e-300):
        raise InputError(
            "K", f"lowest eigenvalue {lam.min():.3e}", "a positive semi-definite stiffness"
        )
    wn = np.sqrt(np.clip(lam, 0.0, None))
    z = np.atleast_1d(np.asarray(zeta, dtype=float))
    if np.any(z < 0) or not np.all(np.isfinite(z)):
        raise InputError("zeta", zeta, "damping ratios >= 0")
    zz = np.full(wn.size, z[-1])
    zz[: min(z.size, wn.size)] = z[: wn.size]
    MP = M @ phi
    return (MP * (2 * zz * wn)) @ MP.T
