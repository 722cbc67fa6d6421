"""The linear part of the harmonic balance: receptances of the regularised system per harmonic.

For harmonic ``k`` at angular frequency ``w`` the dynamic stiffness is
``Z_k = K_r - (k w)^2 M + i k w C`` and the receptance ``H_k = Z_k^{-1}``.
Two backends work in their own coordinates ``z``:

* :class:`ModalLinear` (modal or proportional damping): ``z`` are the
  modal coordinates of ``(K_r, M)`` (mass-normalised ``Phi``), where
  ``H_k`` is diagonal: ``d_j = 1 / (w_j^2 - (k w)^2 + 2 i zeta_j w_j k w)``.
  Applying a receptance costs two thin matrix products; no factorisation.
* :class:`DirectLinear` (any viscous ``C``): ``z = q``; one complex LU of
  ``Z_k`` per harmonic and frequency, cached for the last frequency.

Both take and return real harmonic arrays ``(nh, m)`` in the layout of
:mod:`workbench.hbm.core.fourier`.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ...errors import SolveError
from .fourier import Fourier

SPREAD_MAX = 1e12  # eigenvalues of (K_r, M) spread wider lose the receptances' digits


def check_regular(lam: np.ndarray) -> None:
    """The stuck system ``(K_r, M)`` is regular and well-conditioned, else a SolveError
    that says which: a rigid-body mode (lowest eigenvalue at round-off) is singular; a
    positive lowest eigenvalue far below the highest is ill-conditioning, and names the
    inputs that cause it."""
    top = max(float(np.abs(lam).max()), 1e-300)
    low = float(lam.min())
    if low > top / SPREAD_MAX:
        return
    if low > 100 * np.finfo(float).eps * top:
        raise SolveError(
            "the linear system with every contact stuck is ill-conditioned: the eigenvalues "
            f"of (K_r, M) span {top / low:.3g} (from {low:.4g} to {top:.4g}; at most "
            f"{SPREAD_MAX:.0e} is resolved). K_r is the stiffness plus the contact springs: "
            "a contact stiffness far above the structure's own (kt-line, kn-line, kt-face, "
            "kn-face of a study; kt_n_per_m, kn_n_per_m of a model file) or matrices in mixed "
            "units cause it; lower the contact stiffness or check the units"
        )
    raise SolveError(
        "the linear system with every contact stuck is singular (lowest eigenvalue "
        f"{low:.3e} of (K_r, M), at round-off of the highest {top:.3e}): a rigid-body mode is "
        "held by no support and no contact element; add contact elements or supports"
    )


def _combine(fourier: Fourier, T: np.ndarray, coef: np.ndarray) -> np.ndarray:
    """Multiply each complex harmonic of T (nh, m) by ``coef`` (one row (m,) per harmonic of
    the list, complex), return real (nh, m)."""
    Y = np.empty_like(T)
    if fourier.has_dc:
        Y[0] = T[0] * coef[0].real
    c = coef[fourier.pair_row]
    a, b = c.real, c.imag
    Tc, Ts = T[fourier.ic], T[fourier.is_]
    # (Tc - i Ts)(a + i b) = (a Tc + b Ts) - i (a Ts - b Tc)
    Y[fourier.ic] = a * Tc + b * Ts
    Y[fourier.is_] = a * Ts - b * Tc
    return Y


class ModalLinear:
    """Receptances from the real modes of ``(K_r, M)`` with modal damping ratios."""

    kind = "modal"

    def __init__(
        self,
        M: np.ndarray,
        Kr: np.ndarray,
        fourier: Fourier,
        zeta: np.ndarray | None = None,
        C: np.ndarray | None = None,
        modes: tuple[np.ndarray, np.ndarray] | None = None,
    ):
        self.fourier = fourier
        lam, phi = modes if modes is not None else sla.eigh(Kr, M)
        check_regular(lam)
        self.phi = phi
        self.wn = np.sqrt(lam)
        if C is not None:
            Cm = phi.T @ C @ phi
            self.zeta = np.diag(Cm) / (2 * self.wn)
        elif zeta is not None:
            z = np.atleast_1d(zeta)
            self.zeta = np.full(self.wn.size, z[-1])
            self.zeta[: min(z.size, self.wn.size)] = z[: self.wn.size]
        else:
            self.zeta = np.zeros(self.wn.size)
        self.M = M
        self.n = M.shape[0]
        self.n_z = self.wn.size
        self._cache: tuple[float, dict, dict] | None = None

    @staticmethod
    def is_modal(M: np.ndarray, Kr: np.ndarray, C: np.ndarray, tol: float = 1e-9):
        """The modes of (K_r, M) and whether they diagonalise C (relative off-diagonal <= tol)."""
        lam, phi = sla.eigh(Kr, M)
        Cm = phi.T @ C @ phi
        off = Cm - np.diag(np.diag(Cm))
        scale = max(np.abs(np.diag(Cm)).max(), 1e-300)
        return (lam, phi), bool(np.abs(off).max() <= tol * scale)

    def coef(self, omega: float) -> tuple[np.ndarray, np.ndarray]:
        """Diagonal receptances ``d_k`` and ``d d_k / d w``, one row per harmonic (cached)."""
        if self._cache is not None and self._cache[0] == omega:
            return self._cache[1], self._cache[2]
        k = np.asarray(self.fourier.harmonics, dtype=float)[:, None]
        den = self.wn**2 - (k * omega) ** 2 + 2j * (self.zeta * self.wn) * (k * omega)
        d = 1.0 / den
        dd = -(-2 * k * k * omega + 2j * (self.zeta * self.wn) * k) * d * d
        self._cache = (omega, d, dd)
        return d, dd

    # coordinates ------------------------------------------------------------
    def to_z(self, X: np.ndarray) -> np.ndarray:
        """Physical harmonics (nh, n) -> the right-hand side in z: ``Phi^T X``."""
        return X @ self.phi

    def from_z(self, Y: np.ndarray) -> np.ndarray:
        return Y @ self.phi.T

    def q_to_z(self, Q: np.ndarray) -> np.ndarray:
        """Coordinates q (nh, n) -> modal coordinates ``Phi^T M q``."""
        return Q @ self.M @ self.phi

    def map_z(self, S: np.ndarray | sp.spmatrix) -> np.ndarray:
        """A map ``S`` acting on q expressed on z: ``S Phi`` (dense)."""
        return np.asarray(S @ self.phi)

    def solve(self, omega: float, Xz: np.ndarray, deriv: bool = False) -> np.ndarray:
        """``H_k`` (or ``dH_k/dw``) applied to each harmonic of Xz (nh, n_z)."""
        d, dd = self.coef(omega)
        return _combine(self.fourier, Xz, dd if deriv else d)

    def dense_receptance(
        self,
        omega: float,
        left: np.ndarray,
        right: np.ndarray,
        harmonics: tuple[int, ...] | None = None,
    ):
        """``{k: left H_k right^T}`` (complex; real for k = 0) for maps given on z."""
        harmonics = self.fourier.harmonics if harmonics is None else harmonics
        d, _ = self.coef(omega)
        out = {}
        for i, k in enumerate(self.fourier.harmonics):
            if k not in harmonics:
                continue
            dr, di = d[i].real.astype(left.dtype), d[i].imag.astype(left.dtype)
            if k == 0:
                out[0] = (left * dr) @ right.T
            else:
                out[k] = (left * dr) @ right.T + 1j * ((left * di) @ right.T)
        return out

    def viscous_work(self, omega: float, Yz: np.ndarray) -> float:
        """Viscous dissipation per cycle (J) of the response Yz (nh, n_z)."""
        c = 2 * self.zeta * self.wn
        w = 0.0
        for k, ic, is_ in self.fourier.pairs():
            w += np.pi * k * k * omega * float(np.sum(c * (Yz[ic] ** 2 + Yz[is_] ** 2)))
        return w

    # Hill's method in z ---------------------------------------------------
    def hill_blocks(self):
        """(Mz, Cz, Kz) as dense matrices on z."""
        return (np.eye(self.n_z), np.diag(2 * self.zeta * self.wn), np.diag(self.wn**2))

    def apply_M(self, X: np.ndarray) -> np.ndarray:
        return X

    def apply_C(self, X: np.ndarray) -> np.ndarray:
        return X * (2 * self.zeta * self.wn)


class DirectLinear:
    """Receptances by complex LU of ``Z_k`` (any viscous damping matrix)."""

    kind = "direct"

    def __init__(self, M: np.ndarray, Kr: np.ndarray, C: np.ndarray | None, fourier: Fourier):
        self.fourier = fourier
        self.M, self.Kr = M, Kr
        self.C = np.zeros_like(M) if C is None else C
        self.n = self.n_z = M.shape[0]
        self._omega: float | None = None
        self._lu: dict[int, tuple] = {}
        try:
            self._lu0 = sla.lu_factor(Kr, check_finite=False) if fourier.has_dc else None
        except sla.LinAlgError:
            self._lu0 = None
        check_regular(sla.eigvalsh(Kr, M))

    def _factor(self, omega: float) -> None:
        if self._omega == omega:
            return
        self._lu = {}
        for k, _, _ in self.fourier.pairs():
            Z = self.Kr - (k * omega) ** 2 * self.M + 1j * k * omega * self.C
            self._lu[k] = sla.lu_factor(Z, check_finite=False)
        self._omega = omega

    def to_z(self, X: np.ndarray) -> np.ndarray:
        return X

    def from_z(self, Y: np.ndarray) -> np.ndarray:
        return Y

    def q_to_z(self, Q: np.ndarray) -> np.ndarray:
        return Q

    def map_z(self, S):
        return S

    def solve(self, omega: float, Xz: np.ndarray, deriv: bool = False) -> np.ndarray:
        self._factor(omega)
        f = self.fourier
        Y = np.empty_like(Xz)
        if f.has_dc:
            Y[0] = 0.0 if deriv else sla.lu_solve(self._lu0, Xz[0].T).T
        for k, c, s in f.pairs():
            rhs = (Xz[c] - 1j * Xz[s]).T
            sol = sla.lu_solve(self._lu[k], rhs)
            if deriv:
                dZ = -2 * k * k * omega * self.M + 1j * k * self.C
                sol = -sla.lu_solve(self._lu[k], dZ @ sol)
            Y[c] = sol.real.T
            Y[s] = -sol.imag.T
        return Y

    def dense_receptance(self, omega: float, left, right, harmonics=None):
        harmonics = self.fourier.harmonics if harmonics is None else harmonics
        if any(k > 0 for k in harmonics):
            self._factor(omega)
        R = right.toarray() if sp.issparse(right) else np.asarray(right)
        out = {}
        for k in harmonics:
            lu = self._lu0 if k == 0 else self._lu[k]
            sol = sla.lu_solve(lu, R.T.astype(complex) if k else R.T)
            out[k] = left @ sol
        return out

    def viscous_work(self, omega: float, Yz: np.ndarray) -> float:
        w = 0.0
        for k, ic, is_ in self.fourier.pairs():
            w += (
                np.pi
                * k
                * k
                * omega
                * float(
                    np.einsum("i,ij,j->", Yz[ic], self.C, Yz[ic])
                    + np.einsum("i,ij,j->", Yz[is_], self.C, Yz[is_])
                )
            )
        return w

    def hill_blocks(self):
        return (self.M, self.C, self.Kr)

    def apply_M(self, X: np.ndarray) -> np.ndarray:
        return X @ self.M.T

    def apply_C(self, X: np.ndarray) -> np.ndarray:
        return X @ self.C.T


def make_linear(M, Kr, C, zeta, fourier: Fourier, backend: str = "auto"):
    """The cheapest exact backend: modal when ``C`` is diagonal on the modes of (K_r, M)."""
    if backend == "direct":
        Cd = C
        if C is None and zeta is not None:
            from .system import modal_damping

            Cd = modal_damping(M, Kr, zeta)
        return DirectLinear(M, Kr, Cd, fourier)
    if C is None:
        return ModalLinear(M, Kr, fourier, zeta=zeta)
    modes, diagonal = ModalLinear.is_modal(M, Kr, C)
    if diagonal or backend == "modal":
        return ModalLinear(M, Kr, fourier, C=C, modes=modes)
    return DirectLinear(M, Kr, C, fourier)
