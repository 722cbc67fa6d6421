"""The EPMC point problem on the contact coordinates and the followed mode (modal damping).

:class:`EpmcCondensed` solves the same equations as :class:`.epmc.Epmc`
with far fewer unknowns when the damping is modal and the contacts see
fewer coordinates than the model has; :meth:`EpmcCondensed.physical`
converts a solution to :class:`.epmc.Epmc`'s mass normalisation.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..core.fourier import Fourier
from ..core.system import System
from .epmc import Epmc, EpmcHooks


class EpmcCondensed(EpmcHooks):
    """The same problem on the contact displacements and the followed mode (modal damping).

    With the mass-normalised modes ``Phi`` of ``(K_r, M)`` diagonalising
    ``C`` (modal damping), the coordinates are split into the followed mode
    ``j`` (modal coordinate ``eta``, every harmonic) and the receptance of
    all the others, ``H'_k = sum_{i != j} phi_i phi_i^T / (w_i^2 - (k w)^2 +
    i k w (c_i - xi))``, which stays regular on the backbone (the followed
    mode alone is singular at its linear limit). Unknowns per unit ``a``:
    the active contact displacements ``X`` (nh, n_s), ``eta`` except its
    harmonic-1 parts (``eta_c1 = 1``, ``eta_s1 = 0``: amplitude and phase),
    ``w`` and ``xi``; residuals ``X - W (phi_j eta + H' (P - W^T G)) / a``
    and the followed mode's own equation. ``a`` here is the amplitude of the
    linear mode's coordinate; :meth:`physical` converts a solution to the
    mass normalisation of :class:`Epmc` (``psi_1^H M psi_1 = 1``), so both
    give the same backbone. The Jacobian costs a few products with the
    contact Jacobian (sparse per element) instead of a dense system on every
    DOF: the size is ``nh (n_s + 1)`` instead of ``nh n``.
    """

    def __init__(
        self,
        system: System,
        fourier: Fourier,
        mode: int,
        outputs: object = None,
        dc_anchor: float = 1e-3,
    ):
        self.phys = Epmc(system, fourier, mode, outputs, dc_anchor)
        ph = self.phys
        self.system, self.fourier = system, fourier
        self.mode, self.w_lin, self.xi_lin, self.wn = ph.mode, ph.w_lin, ph.xi_lin, ph.wn
        self.stats = ph.stats
        lam, Phi = sla.eigh(ph.Kr, ph.M)
        self.Phi = Phi
        Cm = Phi.T @ ph.C @ Phi
        self.cm = np.diag(Cm).copy()  # 2 zeta_i w_i
        self.el = system.contacts
        self.n_el = ph.n_el
        self.act = np.flatnonzero(self.el.active.ravel())
        self.n_s = self.act.size
        B = np.asarray(self.el.W @ Phi)  # (n3, n_m)
        self.Bs = B[self.act]
        self.bj = self.Bs[:, mode].copy()
        self.nh = fourier.nh
        self.Ns = self.nh * self.n_s
        c1 = fourier.index(1, "c")
        self.c1 = c1
        self.keep_eta = np.array([h for h in range(self.nh) if h not in (c1, c1 + 1)], int)
        self.N = self.Ns + self.keep_eta.size  # unknowns besides w and xi
        self.pm = np.zeros((self.nh, Phi.shape[1]))  # modal static force (per unit a: / a)
        if fourier.has_dc:
            f0 = system.total_static_force()
            self.pm[0] = Phi.T @ f0
        # the contact Jacobian pattern restricted to the active rows
        pos = -np.ones(3 * self.n_el, int)
        pos[self.act] = np.arange(self.n_s)
        self._pos = pos
        self.mask_other = np.ones(Phi.shape[1])
        self.mask_other[mode] = 0.0

    # hooks (with EpmcHooks') ----------------------------------------------------------
    def row_scale(self) -> np.ndarray:
        return np.ones(self.N + 2)

    def dc_mask(self) -> np.ndarray:
        m = np.zeros(self.N + 2, bool)
        if self.fourier.has_dc:
            m[: self.n_s] = True
            m[self.Ns + int(np.flatnonzero(self.keep_eta == 0)[0])] = True
        return m

    def _split(self, y: np.ndarray):
        X = y[: self.Ns].reshape(self.nh, self.n_s)
        eta = np.zeros(self.nh)
        eta[self.keep_eta] = y[self.Ns : self.N]
        eta[self.c1] = 1.0
        return X, eta, float(y[self.N]), float(y[self.N + 1])

    def linear_guess(self) -> np.ndarray:
        y = np.zeros(self.N + 2)
        X = np.zeros((self.nh, self.n_s))
        X[self.c1] = self.bj
        y[: self.Ns] = X.ravel()
        y[self.N] = self.w_lin
        y[self.N + 1] = self.xi_lin
        return y

    def _coef(self, w: float, xi: float):
        """Per harmonic component row: the modal receptances d (nh_k, n_m) complex, and
        their derivatives in w and xi (mode j excluded)."""
        f = self.fourier
        k = np.asarray(f.harmonics, float)[:, None]
        wn2 = self.wn[None, :] ** 2
        den = wn2 - (k * w) ** 2 + 1j * k * w * (self.cm[None, :] - xi)
        den[:, self.mode] = 1.0  # the followed mode is not in H' (and is singular there)
        d = self.mask_other / den
        dd_w = -(-2 * k * k * w + 1j * k * (self.cm[None, :] - xi)) * d / den
        dd_xi = -(-1j * k * w) * d / den
        return d, dd_w, dd_xi

    def _apply(self, coef: np.ndarray, F: np.ndarray) -> np.ndarray:
        """Multiply each complex harmonic of F (nh, m) by coef rows (one per harmonic)."""
        from ..core.linear import _combine

        return _combine(self.fourier, F, coef)

    def _contact(self, X: np.ndarray, a: float, want_jac: bool):
        U = np.zeros((self.nh, 3 * self.n_el))
        U[:, self.act] = X * a
        G, D, res = self.phys.contact_local(U, want_jac)
        return G[:, self.act] / a, D, res

    def residual(self, y: np.ndarray, a: float, want_jac: bool | str = False):
        """The point's residual (and with ``want_jac`` its Jacobian in ``y``; "operator":
        :class:`CondensedTangent` in ``[y, ln a]``)."""
        f = self.fourier
        X, eta, w, xi = self._split(y)
        Ga, D, res = self._contact(X, a, bool(want_jac))  # (nh, n_s) per unit a
        Fm = self.pm / a - Ga @ self.Bs  # (nh, n_m) modal force per unit a
        d, dd_w, dd_xi = self._coef(w, xi)
        z = self._apply(d, Fm)  # other modes
        ru = X - (z @ self.Bs.T + eta[:, None] * self.bj[None, :])
        # the followed mode's equation, divided by w_j^2
        j = self.mode
        cj = self.cm[j]
        w2 = self.w_lin**2
        re = np.empty(self.nh)
        if f.has_dc:
            re[0] = (w2 * eta[0] - Fm[0, j]) / w2
        for k, c, s_ in f.pairs():
            A = w2 - (k * w) ** 2
            Bk = k * w * (cj - xi)
            re[c] = (A * eta[c] + Bk * eta[s_] - Fm[c, j]) / w2
            re[s_] = (A * eta[s_] - Bk * eta[c] - Fm[s_, j]) / w2
        r = np.concatenate([ru.ravel(), re])
        self.stats["n_residual"] += 1
        if not want_jac:
            return r, res
        self.stats["n_jacobian"] += 1
        T = CondensedTangent(self, X, eta, w, xi, a, Ga, self._dact(D), Fm, d, dd_w, dd_xi)
        if want_jac == "operator":
            return r, res, T
        return r, res, T.dense()[:, : self.N + 2]

    def tangent(self, y: np.ndarray, a: float):
        """``(r, res, T)``: the residual and its Jacobian in ``[y, ln a]`` as an operator
        (:class:`CondensedTangent`: products without forming it, or the dense matrix)."""
        return self.residual(y, a, want_jac="operator")

    def _dact(self, D) -> sp.csr_matrix:
        """The contact Jacobian on the active unknowns (Ns, Ns), from the full sparse one."""
        if D is None:
            return sp.csr_matrix((self.Ns, self.Ns))
        n3 = 3 * self.n_el
        idx = (np.arange(self.nh)[:, None] * n3 + self.act[None, :]).ravel()
        return D[idx][:, idx].tocsr()

    def full_modal(self, y: np.ndarray, a: float) -> np.ndarray:
        """Modal coordinates (nh, n_m) per unit ``a`` of a solution (all modes)."""
        X, eta, w, xi = self._split(y)
        Ga, _, _ = self._contact(X, a, False)
        Fm = self.pm / a - Ga @ self.Bs
        d, _, _ = self._coef(w, xi)
        z = self._apply(d, Fm)
        z[:, self.mode] = eta
        return z

    def physical(self, y: np.ndarray, a: float) -> tuple[np.ndarray, float]:
        """The solution as ``([psi, w, xi], a_M)`` with ``psi_1^H M psi_1 = 1``."""
        z = self.full_modal(y, a)
        c = self.c1
        m_eff = float(np.sum(z[c] ** 2 + z[c + 1] ** 2))
        s = np.sqrt(m_eff)
        psi = (z @ self.Phi.T) / s
        return np.concatenate([psi.ravel(), [y[self.N], y[self.N + 1]]]), a * s

    def point(self, y: np.ndarray, a: float, phi1_ref):
        return self.phys.point(y, a, phi1_ref)


class CondensedTangent:
    """The Jacobian of :meth:`EpmcCondensed.residual` in ``[y, ln a]`` at one point.

    The contact block is ``I + R D``: ``D`` the contact Jacobian on the active
    coordinates (sparse, element blocks coupling the harmonics) and ``R`` the
    receptance of the other modes, ``R g = (d_k (g B_s)) B_s^T`` per harmonic
    (diagonal in the modes). :meth:`matvec` applies it with those products
    (a few ``n_s x n_m`` products per harmonic); :meth:`dense` forms it, one
    harmonic block of ``R`` at a time (``R`` couples no harmonics), for a
    factorisation. The ``ln a`` column is exact: ``d(G/a)/d ln a = D X - G/a``.
    """

    def __init__(self, p: EpmcCondensed, X, eta, w, xi, a, Ga, Dact, Fm, d, dd_w, dd_xi):
        f = p.fourier
        nh, n_s, Ns, N = p.nh, p.n_s, p.Ns, p.N
        self.p, self.Dact, self.d = p, Dact, d
        self.w2 = w2 = p.w_lin**2
        j, cj = p.mode, p.cm[p.mode]
        Bs = p.Bs
        nk = p.keep_eta.size
        # the columns of eta (kept components), w, xi and ln a, for the contact rows ...
        U = np.zeros((Ns, nk + 3))
        for q, h in enumerate(p.keep_eta):
            U[h * n_s : (h + 1) * n_s, q] = -p.bj
        U[:, nk] = -(p._apply(dd_w, Fm) @ Bs.T).ravel()
        U[:, nk + 1] = -(p._apply(dd_xi, Fm) @ Bs.T).ravel()
        dGa = (Dact @ X.ravel()).reshape(nh, n_s) - Ga  # d(G/a)/d ln a
        dFm = -p.pm / a - dGa @ Bs
        U[:, nk + 2] = -(p._apply(d, dFm) @ Bs.T).ravel()
        # ... and for the followed mode's rows (divided by w_j^2)
        Ee = np.zeros((nh, nh))
        dw, dxi = np.zeros(nh), np.zeros(nh)
        if f.has_dc:
            Ee[0, 0] = w2
        for k, c, s_ in f.pairs():
            A = w2 - (k * w) ** 2
            Bk = k * w * (cj - xi)
            Ee[c, c], Ee[c, s_] = A, Bk
            Ee[s_, c], Ee[s_, s_] = -Bk, A
            dA, dB = -2 * k * k * w, k * (cj - xi)
            dw[c] = dA * eta[c] + dB * eta[s_]
            dw[s_] = dA * eta[s_] - dB * eta[c]
            dxi[c] = -k * w * eta[s_]
            dxi[s_] = k * w * eta[c]
        E = np.zeros((nh, nk + 3))
        E[:, :nk] = Ee[:, p.keep_eta]
        E[:, nk], E[:, nk + 1], E[:, nk + 2] = dw, dxi, -dFm[:, j]
        self.U, self.E = U, E / w2
        self.shape = (N + 2, N + 3)

    def matvec(self, v: np.ndarray) -> np.ndarray:
        """``J v`` for ``v`` over ``[y, ln a]``."""
        p = self.p
        Ns = p.Ns
        vo = v[Ns:]
        g = (self.Dact @ v[:Ns]).reshape(p.nh, p.n_s)
        ru = v[:Ns] + (p._apply(self.d, g @ p.Bs) @ p.Bs.T).ravel() + self.U @ vo
        re = (g @ p.bj) / self.w2 + self.E @ vo
        return np.concatenate([ru, re])

    def dense(self) -> np.ndarray:
        """The Jacobian as a dense ``(N + 2, N + 3)`` array."""
        p, f = self.p, self.p.fourier
        n_s, Ns = p.n_s, p.Ns
        J = np.zeros(self.shape)
        Dr = self.Dact.tocsr()
        for i, kk in enumerate(f.harmonics):
            Rk = (p.Bs * self.d[i]) @ p.Bs.T
            if kk == 0:
                R, rows = Rk.real, slice(0, n_s)
            else:
                c = f.index(kk, "c")
                R = np.block([[Rk.real, Rk.imag], [-Rk.imag, Rk.real]])
                rows = slice(c * n_s, (c + 2) * n_s)
            J[rows, :Ns] = (Dr[rows].T @ R.T).T  # R (dense) times the rows of D (sparse)
        J[np.arange(Ns), np.arange(Ns)] += 1.0
        J[:Ns, Ns:] = self.U
        J[Ns:, :Ns] = (Dr.T @ np.kron(np.eye(p.nh), p.bj[:, None])).T / self.w2
        J[Ns:, Ns:] = self.E
        return J
