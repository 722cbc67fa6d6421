"""The EPMC problem of one nonlinear mode: residual and analytic Jacobian of a point.

:class:`Epmc` works on every DOF of the reduced model;
:class:`~.epmc_condensed.EpmcCondensed` (its own module) on the contact
displacements and the followed mode (modal damping only), and converts its
solution to the same mass normalisation; :func:`.backbone.make_problem` picks
one.
The equations are given in :mod:`.backbone`, which continues the points
into a backbone.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ...errors import InputError, SolveError, check_int
from ..core.aft import aft, work_per_cycle
from ..core.fourier import Fourier
from ..core.loops import loop_dissipation
from ..core.ports import observation
from ..core.system import System

TWO_PI = 2.0 * np.pi


class EpmcHooks:
    """The hooks the backbone's corrector and loop call, shared by every EPMC form.

    The unknowns are ``[x (N), w, xi]``: ``N + 2`` of them, ``w`` and ``xi``
    scaled by the linear frequency ``w_lin``. A form whose residual rows are
    forces scales them by ``w_lin^2`` times its largest modal mass
    (:meth:`_force_rows`).
    """

    N: int
    w_lin: float

    @property
    def n_unknowns(self) -> int:
        return self.N + 2

    def var_scale(self) -> np.ndarray:
        """Scale of each unknown (x as it is; w and xi by the linear frequency)."""
        sc = np.ones(self.N + 2)
        sc[self.N :] = self.w_lin
        return sc

    def _force_rows(self, M: np.ndarray) -> np.ndarray:
        """Row scales for force residuals with the mass matrix ``M`` (the two condition
        rows as they are)."""
        rs = np.ones(self.N + 2)
        rs[: self.N] = 1.0 / (self.w_lin**2 * max(np.abs(np.diag(M)).max(), 1e-300))
        return rs


class Epmc(EpmcHooks):
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
        self.C = system.damping_matrix()
        lam, phi = sla.eigh(self.Kr, self.M)
        if lam.min() <= 1e-12 * max(abs(lam).max(), 1e-300):
            raise SolveError(
                "the linear system with every contact stuck is singular: a rigid-body mode is "
                "held by no support and no contact element"
            )
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
            e, a, h, b, c = np.meshgrid(
                np.arange(self.n_el),
                np.arange(3),
                np.arange(nh),
                np.arange(3),
                np.arange(nh),
                indexing="ij",
            )
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
            D = sp.csr_matrix(
                (J.ravel(), (self._drow, self._dcol)), shape=(f.nh * self.n3, f.nh * self.n3)
            )
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
        return sp.csr_matrix(
            (J.ravel(), (self._drow, self._dcol)), shape=(f.nh * self.n3, f.nh * self.n3)
        )

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
        J[N, c * n : (c + 1) * n] = 2 * (self.M @ psi[c])
        J[N, (c + 1) * n : (c + 2) * n] = 2 * (self.M @ psi[c + 1])
        J[N + 1, (c + 1) * n : (c + 2) * n] = self.Mphi
        return r, res, J

    # hooks (with EpmcHooks'): the corrector and the loop see only these
    def row_scale(self) -> np.ndarray:
        return self._force_rows(self.M)

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
        y[self.c1 * self.n : (self.c1 + 1) * self.n] = self.phi
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
        mac = float(
            abs(np.conj(ref) @ self.M @ p1) ** 2
            / (np.real(np.conj(ref) @ self.M @ ref) * np.real(np.conj(p1) @ self.M @ p1))
        )
        ke = [
            float(psi[c_] @ self.M @ psi[c_] + psi[s] @ self.M @ psi[s]) * k * k
            for k, c_, s in f.pairs()
        ]
        hk = [k for k, _, _ in f.pairs()]
        total = sum(ke)
        higher = (total - ke[hk.index(1)]) / total if total > 0 else 0.0
        Y = Q @ self.O.T
        return dict(
            amplitude=a,
            freq_hz=w / TWO_PI,
            xi=xi,
            damping_ratio=xi / (2 * w),
            xi_viscous=float(np.real(np.conj(p1) @ self.C @ p1)),
            friction_energy=fric,
            status=status,
            energy_residual=e_res,
            work_friction=w_fric,
            work_viscous=w_visc,
            mac=mac,
            higher_harmonics=higher,
            out_amp=f.amplitude(Y),
            out_h1=f.h1_amplitude(Y),
            psi=y[: self.N].copy(),
            lost=self.lost_contact(res),
            phi1=p1,
        )
