"""The EPMC problem of one nonlinear mode: residual and analytic Jacobian of a point.

:class:`Epmc` works on every DOF of the reduced model; :class:`EpmcCondensed`
on the contact displacements and the followed mode (modal damping only),
and converts its solution to the same mass normalisation; :func:`make_problem`
picks one. The equations are given in :mod:`.nlmodes`, which continues the
points into a backbone.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..errors import InputError, SolveError, check_int
from .aft import aft, work_per_cycle
from .balance import loop_dissipation, observation
from .fourier import Fourier
from .system import System, modal_damping

TWO_PI = 2.0 * np.pi


class Epmc:
    """Residual and Jacobian of the extended periodic motion concept for one linear mode."""

    def __init__(
        self,
        system: System,
        fourier: Fourier,
        mode: int,
        outputs: object = None,
        dc_anchor: float = 1e-3,
    ):
        if 1 not in fourier.harmonics:
            raise InputError("harmonics", list(fourier.harmonics), "a list that includes 1")
        self.system, self.fourier = system, fourier
        n = self.n = system.n
        self.M = system.M
        self.Kr = system.regularised_stiffness()
        if system.C is not None:
            self.C = system.C
        elif system.zeta is not None:
            self.C = modal_damping(system.M, system.K, system.zeta, system.contacts)
        else:
            self.C = np.zeros((n, n))
        lam, phi = sla.eigh(self.Kr, self.M)
        if lam.min() <= 1e-12 * max(abs(lam).max(), 1e-300):
            raise SolveError(
                "the linear system with every contact stuck is singular: a rigid-body mode is "
                "held by no support and no contact element")
        self.wn = np.sqrt(lam)
        self.phi_all = phi
        self.c_all = np.einsum("ij,ik,kj->j", phi, self.C, phi)  # 2 zeta w (diagonal part)
        mode = check_int("mode", mode, 0, n - 1)
        self.mode = mode
        self.phi = phi[:, mode]
        self.Mphi = self.M @ self.phi
        self.w_lin = float(self.wn[mode])
        self.xi_lin = float(self.phi @ self.C @ self.phi)
        self.el = system.contacts
        self.n_el = system.n_el
        self.n3 = 3 * self.n_el
        nh = fourier.nh
        self.nh = nh
        self.N = nh * n
        if self.n_el:
            self.W = self.el.W
            self.kc = self.el.kc
            self.Wh = sp.kron(sp.identity(nh, format="csr"), self.W, format="csr")
            self.f_rest = self.el.force_at_rest().ravel()
        else:
            self.W = sp.csr_matrix((0, n))
            self.kc = np.zeros((0, 3))
            self.Wh = sp.csr_matrix((0, self.N))
            self.f_rest = np.zeros(0)
        self.anchor = np.zeros((self.n_el, 3))
        self._rigid = system.rigid_modes()
        if self.n_el and dc_anchor > 0 and self._rigid.shape[1]:
            self.anchor[:, 0] = dc_anchor * self.el.kt1
            self.anchor[:, 1] = dc_anchor * self.el.kt2
        self.O = observation(system, outputs)
        self.c1 = fourier.index(1, "c")
        # sparse pattern of the contact Jacobian (rows (h, e, a), cols (c, e, b))
        if self.n_el:
            e, a, h, b, c = np.meshgrid(np.arange(self.n_el), np.arange(3), np.arange(nh),
                                        np.arange(3), np.arange(nh), indexing="ij")
            self._drow = (h * self.n3 + 3 * e + a).ravel()
            self._dcol = (c * self.n3 + 3 * e + b).ravel()
        self._lin_cache: tuple | None = None
        self.stats = dict(n_residual=0, n_jacobian=0, t_aft=0.0)

    # -- pieces ----------------------------------------------------------------------
    def contact(self, Q: np.ndarray, want_jac: bool = True):
        """(G (nh, n3), D sparse or None, AftResult) at the harmonics Q (nh, n)."""
        f = self.fourier
        if not self.n_el:
            return np.zeros((f.nh, 0)), None, None
        t0 = time.perf_counter()
        U = np.asarray((self.W @ Q.T).T)  # (nh, n3)
        Uloc = U.reshape(f.nh, self.n_el, 3)
        res = aft(Uloc, self.el, f, want_jac=want_jac)
        G = res.F - self.kc[None] * Uloc
        if f.has_dc and self.anchor.any():
            G[0] += self.anchor * Uloc[0]
        D = None
        if want_jac:
            J = res.J.copy()
            hh = np.arange(f.nh)
            for a in range(3):
                J[:, a, hh, a, hh] -= self.kc[:, a][:, None]
            if f.has_dc:
                for a in range(2):
                    J[:, a, 0, a, 0] += self.anchor[:, a]
            D = sp.csr_matrix((J.ravel(), (self._drow, self._dcol)),
                              shape=(f.nh * self.n3, f.nh * self.n3))
        self.stats["t_aft"] += time.perf_counter() - t0
        return G.reshape(f.nh, self.n3), D, res

    def contact_local(self, U: np.ndarray, want_jac: bool = True):
        """Like :meth:`contact` from the contact displacement harmonics U (nh, n3) directly."""
        f = self.fourier
        t0 = time.perf_counter()
        Uloc = U.reshape(f.nh, self.n_el, 3)
        res = aft(Uloc, self.el, f, want_jac=want_jac)
        G = res.F - self.kc[None] * Uloc
        if f.has_dc and self.anchor.any():
            G[0] += self.anchor * Uloc[0]
        D = None
        if want_jac:
            D = self._jac_sparse(res.J)
        self.stats["t_aft"] += time.perf_counter() - t0
        return G.reshape(f.nh, self.n3), D, res

    def _jac_sparse(self, J0: np.ndarray) -> sp.csr_matrix:
        """dG/dU as a sparse (nh n3, nh n3) matrix from the AFT's per-element blocks."""
        f = self.fourier
        J = J0.copy()
        hh = np.arange(f.nh)
        for a in range(3):
            J[:, a, hh, a, hh] -= self.kc[:, a][:, None]
        if f.has_dc:
            for a in range(2):
                J[:, a, 0, a, 0] += self.anchor[:, a]
        return sp.csr_matrix((J.ravel(), (self._drow, self._dcol)),
                             shape=(f.nh * self.n3, f.nh * self.n3))

    def _linear(self, P: np.ndarray, w: float, xi: float) -> np.ndarray:
        """The linear part on harmonics P (nh, n): K_r P0; A Pc + B Ps; A Ps - B Pc."""
        f = self.fourier
        out = np.empty_like(P)
        if f.has_dc:
            out[0] = self.Kr @ P[0]
        Cx = self.C - xi * self.M
        for k, c, s in f.pairs():
            A_c = self.Kr @ P[c] - (k * w) ** 2 * (self.M @ P[c])
            A_s = self.Kr @ P[s] - (k * w) ** 2 * (self.M @ P[s])
            B_c = k * w * (Cx @ P[c])
            B_s = k * w * (Cx @ P[s])
            out[c] = A_c + B_s
            out[s] = A_s - B_c
        return out

    def residual(self, y: np.ndarray, a: float, want_jac: bool = False):
        """Residual (N + 2,) at ``y = [psi, w, xi]`` and modal amplitude ``a`` (and Jacobian)."""
        f, n = self.fourier, self.n
        psi = y[: self.N].reshape(f.nh, n)
        w, xi = float(y[self.N]), float(y[self.N + 1])
        G, D, res = self.contact(a * psi, want_jac)
        R = self._linear(psi, w, xi)
        if self.n_el:
            Gs = G.copy()
            if f.has_dc:
                Gs[0] = Gs[0] - self.f_rest
            R = R + np.asarray((self.W.T @ Gs.T).T) / a
        if f.has_dc and self.system.static_force is not None:
            R[0] = R[0] - self.system.static_force / a
        c = self.c1
        amp = float(psi[c] @ self.M @ psi[c] + psi[c + 1] @ self.M @ psi[c + 1]) - 1.0
        phase = float(psi[c + 1] @ self.Mphi)
        r = np.concatenate([R.ravel(), [amp, phase]])
        self.stats["n_residual"] += 1
        if not want_jac:
            return r, res
        self.stats["n_jacobian"] += 1
        N = self.N
        J = np.zeros((N + 2, N + 2))
        Cx = self.C - xi * self.M
        if f.has_dc:
            J[:n, :n] = self.Kr
        dw = np.zeros((f.nh, n))
        dxi = np.zeros((f.nh, n))
        for k, c_, s in f.pairs():
            A = self.Kr - (k * w) ** 2 * self.M
            B = k * w * Cx
            rc, rs = slice(c_ * n, (c_ + 1) * n), slice(s * n, (s + 1) * n)
            J[rc, rc] = A
            J[rc, rs] = B
            J[rs, rc] = -B
            J[rs, rs] = A
            dA = -2 * k * k * w * self.M
            dB = k * Cx
            dw[c_] = dA @ psi[c_] + dB @ psi[s]
            dw[s] = dA @ psi[s] - dB @ psi[c_]
            dxi[c_] = -k * w * (self.M @ psi[s])
            dxi[s] = k * w * (self.M @ psi[c_])
        if self.n_el:
            J[:N, :N] += (self.Wh.T @ D @ self.Wh).toarray()
        J[:N, N] = dw.ravel()
        J[:N, N + 1] = dxi.ravel()
        J[N, c * n:(c + 1) * n] = 2 * (self.M @ psi[c])
        J[N, (c + 1) * n:(c + 2) * n] = 2 * (self.M @ psi[c + 1])
        J[N + 1, (c + 1) * n:(c + 2) * n] = self.Mphi
        return r, res, J

    # hooks shared with the condensed form (the corrector and the loop see only these)
    @property
    def n_unknowns(self) -> int:
        return self.N + 2

    def var_scale(self) -> np.ndarray:
        """Scale of each unknown (psi as it is; w and xi by the linear frequency)."""
        sc = np.ones(self.N + 2)
        sc[self.N:] = self.w_lin
        return sc

    def row_scale(self) -> np.ndarray:
        rs = np.ones(self.N + 2)
        rs[: self.N] = 1.0 / (self.w_lin**2 * max(np.abs(np.diag(self.M)).max(), 1e-300))
        return rs

    def dc_mask(self) -> np.ndarray:
        m = np.zeros(self.N + 2, bool)
        if self.fourier.has_dc:
            m[: self.n] = True
        return m

    def physical(self, y: np.ndarray, a: float) -> tuple[np.ndarray, float]:
        """``([psi, w, xi], a)`` in the mass normalisation (here the unknowns themselves)."""
        return y, a

    def linear_guess(self) -> np.ndarray:
        """``y`` of the linear mode with every contact stuck (exact as ``a -> 0``)."""
        y = np.zeros(self.N + 2)
        y[self.c1 * self.n:(self.c1 + 1) * self.n] = self.phi
        y[self.N] = self.w_lin
        y[self.N + 1] = self.xi_lin
        return y

    def lost_contact(self, res) -> bool:
        """True if at some instant the closed contacts no longer hold a body held only by them."""
        if res is None or not np.any(res.n_sep) or not self._rigid.shape[1]:
            return False
        WV = np.asarray(self.W @ self._rigid)
        r = WV.shape[1]
        for pat in np.unique(res.contact.T, axis=0):
            A = WV[np.repeat(pat, 3)]
            if A.shape[0] < r:
                return True
            s = np.linalg.svd(A, compute_uv=False)
            if s.size < r or s[-1] <= 1e-9 * max(np.abs(WV).max(), 1e-300):
                return True
        return False

    def point(self, y: np.ndarray, a: float, phi1_ref: np.ndarray | None) -> dict[str, Any]:
        """Everything kept about one converged point."""
        f, n = self.fourier, self.n
        psi = y[: self.N].reshape(f.nh, n)
        w, xi = float(y[self.N]), float(y[self.N + 1])
        Q = a * psi
        G, _, res = self.contact(Q, want_jac=False)
        nabla = f.nabla(w)
        V = nabla @ Q  # velocity harmonics
        # energy fed by -xi M q' and taken by C q' per cycle: pi/w * sum over harmonics
        def quad(A: np.ndarray) -> float:
            tot = 0.0
            for _k, c_, s in f.pairs():
                tot += float(V[c_] @ A @ V[c_] + V[s] @ A @ V[s])
            return np.pi / w * tot

        w_in = xi * quad(self.M)
        w_visc = quad(self.C)
        if self.n_el:
            Uloc = np.asarray((self.W @ Q.T).T).reshape(f.nh, self.n_el, 3)
            wc = work_per_cycle(res.F, Uloc, f)
            w_contact = float(wc.sum())
            w_fric = float(wc[:, :2].sum())
            fric = loop_dissipation(res.u, res.f)
            status = res.status
        else:
            w_contact = w_fric = 0.0
            fric, status = np.zeros(0), np.zeros(0, np.int8)
        den = max(abs(w_in), abs(w_visc) + abs(w_contact), 1e-300)
        e_res = abs(w_in - w_visc - w_contact) / den
        c = self.c1
        p1 = psi[c] - 1j * psi[c + 1]
        ref = p1 if phi1_ref is None else phi1_ref
        mac = float(abs(np.conj(ref) @ self.M @ p1) ** 2
                    / (np.real(np.conj(ref) @ self.M @ ref) * np.real(np.conj(p1) @ self.M @ p1)))
        ke = [float(psi[c_] @ self.M @ psi[c_] + psi[s] @ self.M @ psi[s]) * k * k
              for k, c_, s in f.pairs()]
        hk = [k for k, _, _ in f.pairs()]
        total = sum(ke)
        higher = (total - ke[hk.index(1)]) / total if total > 0 else 0.0
        Y = Q @ self.O.T
        return dict(
            amplitude=a, freq_hz=w / TWO_PI, xi=xi, damping_ratio=xi / (2 * w),
            xi_viscous=float(np.real(np.conj(p1) @ self.C @ p1)),
            friction_energy=fric, status=status, energy_residual=e_res, work_friction=w_fric,
            work_viscous=w_visc, mac=mac, higher_harmonics=higher,
            out_amp=f.amplitude(Y), out_h1=f.h1_amplitude(Y), psi=y[: self.N].copy(),
            lost=self.lost_contact(res), phi1=p1,
        )


class EpmcCondensed:
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

    def __init__(self, system: System, fourier: Fourier, mode: int, outputs: object = None,
                 dc_anchor: float = 1e-3):
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

    # hooks ----------------------------------------------------------------------------
    @property
    def n_unknowns(self) -> int:
        return self.N + 2

    def var_scale(self) -> np.ndarray:
        sc = np.ones(self.N + 2)
        sc[self.N:] = self.w_lin
        return sc

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
        eta[self.keep_eta] = y[self.Ns: self.N]
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
        from .linear import _combine

        return _combine(self.fourier, F, coef)

    def _contact(self, X: np.ndarray, a: float, want_jac: bool):
        U = np.zeros((self.nh, 3 * self.n_el))
        U[:, self.act] = X * a
        G, D, res = self.phys.contact_local(U, want_jac)
        return G[:, self.act] / a, D, res

    def residual(self, y: np.ndarray, a: float, want_jac: bool = False):
        f = self.fourier
        X, eta, w, xi = self._split(y)
        Ga, D, res = self._contact(X, a, want_jac)  # (nh, n_s) per unit a
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
        nh, n_s, Ns, N = self.nh, self.n_s, self.Ns, self.N
        J = np.zeros((N + 2, N + 2))
        # dr_u/dX = I + R D,  R = blocks of Bs H'_k Bs^T (real form)
        Dact = self._dact(D)  # sparse (Ns, Ns): dG_act / dX (per unit a: the same)
        R = np.zeros((Ns, Ns))
        for i, kk in enumerate(f.harmonics):
            Rk = (self.Bs * d[i]) @ self.Bs.T
            if kk == 0:
                R[:n_s, :n_s] = Rk.real
            else:
                c = f.index(kk, "c")
                rc, rs = slice(c * n_s, (c + 1) * n_s), slice((c + 1) * n_s, (c + 2) * n_s)
                R[rc, rc] = Rk.real
                R[rc, rs] = Rk.imag
                R[rs, rc] = -Rk.imag
                R[rs, rs] = Rk.real
        J[:Ns, :Ns] = np.asarray((Dact.T @ R.T).T)
        J[np.arange(Ns), np.arange(Ns)] += 1.0
        # dr_u/deta = -b_j in each component
        for q, h in enumerate(self.keep_eta):
            J[h * n_s:(h + 1) * n_s, Ns + q] = -self.bj
        # d/dw, d/dxi of r_u through H'
        J[:Ns, N] = -(self._apply(dd_w, Fm) @ self.Bs.T).ravel()
        J[:Ns, N + 1] = -(self._apply(dd_xi, Fm) @ self.Bs.T).ravel()
        # the followed mode's rows: -dFm_j/dX = b_j^T dG/dX
        bD = np.asarray((Dact.T @ np.kron(np.eye(nh), self.bj[None, :]).T).T)  # (nh, Ns)
        Je = np.zeros((nh, N + 2))
        Je[:, :Ns] = bD
        Ee = np.zeros((nh, nh))  # d re / d eta
        dw = np.zeros(nh)
        dxi = np.zeros(nh)
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
        Je[:, Ns:N] = Ee[:, self.keep_eta]
        Je[:, N] = dw
        Je[:, N + 1] = dxi
        J[Ns:N + 2] = Je / w2
        return r, res, J

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


def make_problem(system: System, fourier: Fourier, mode: int, outputs: object = None,
                 dc_anchor: float = 1e-3, space: str = "auto"):
    """:class:`EpmcCondensed` when the damping is modal and the contacts see fewer
    coordinates than the model has ("auto"), else :class:`Epmc` (all DOFs)."""
    from ..errors import check_choice

    check_choice("space", space, ("auto", "condensed", "physical"))
    if space == "physical" or not system.n_el:
        return Epmc(system, fourier, mode, outputs, dc_anchor)
    n_s = int(system.contacts.active.sum())
    modal = system.C is None
    if not modal:
        from .linear import ModalLinear

        _, modal = ModalLinear.is_modal(system.M, system.regularised_stiffness(), system.C)
    if space == "condensed" or (modal and n_s + 1 < system.n):
        if not modal:
            raise InputError("space", space, "physical (the damping is not modal)")
        return EpmcCondensed(system, fourier, mode, outputs, dc_anchor)
    return Epmc(system, fourier, mode, outputs, dc_anchor)
