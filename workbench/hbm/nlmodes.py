"""Nonlinear modes by the extended periodic motion concept (EPMC, Krack 2015).

A negative mass-proportional damping term ``-xi M q'`` is added to the
autonomous equation of motion of the reduced model with its friction
contacts,

    M q'' + (C - xi M) q' + K q + W^T f(W q) = f_static,

so that the free motion of a damped mode becomes periodic: ``xi`` (1/s)
supplies exactly the energy the viscous damping and the friction take per
cycle. The periodic motion is expanded in the harmonic list of
:mod:`.fourier` (the same AFT march, contact law and preload balance as the
forced response, :mod:`.balance`) and continued in the modal amplitude
``a`` (sqrt(kg) m): the harmonics are ``Q = a psi`` with the mass
normalisation of the harmonic-1 shape and a phase condition,

    psi_c1^T M psi_c1 + psi_s1^T M psi_s1 = 1,   psi_s1^T M phi = 0

(``phi`` the mass-normalised linear mode with every contact stuck). The
unknowns of one point are ``psi`` (all DOFs, all harmonics), ``omega``
(rad/s) and ``xi``; the modal damping ratio is ``D = xi / (2 omega)``, the
system's own viscous damping included (in the linear limit ``D`` is the
modal ratio ``zeta`` of the mode, and ``omega`` its stuck frequency).

Residual (physical space, per unit modal amplitude), for harmonic ``k``
with ``A = K_r - (k w)^2 M`` and ``B = k w (C - xi M)``::

    Rc_k = A psi_c + B psi_s + W^T Gc_k / a,   Rs_k = A psi_s - B psi_c + W^T Gs_k / a

plus ``K_r psi_0 + W^T (G_0 - f(0)) / a`` for harmonic 0 (``G = f - K_c u``
as in :mod:`.balance`). The Jacobian is analytic (the AFT's exact
derivative for the contacts); each point is solved by PETSc SNES (Newton
with a backtracking line search, a dense LU of the bordered Jacobian).

The result, :class:`NlModeBranch`, holds per point the modal amplitude,
frequency, ``xi``, damping ratio, friction energy per element and per
cycle, contact status, the energy balance of the point, the MAC of the
harmonic-1 shape against the low-amplitude one, the share of the motion in
the higher harmonics, the output amplitudes, and ``psi`` (so that
:mod:`.synthesis` can rebuild the forced response at any force level).
"""

from __future__ import annotations

import json
import logging
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..errors import InputError, SolveError, check_int, check_range
from .aft import aft, work_per_cycle
from .balance import loop_dissipation, observation
from .fourier import Fourier
from .system import System, modal_damping

log = logging.getLogger(__name__)

TWO_PI = 2.0 * np.pi

_ARRAYS = (
    "amplitude",
    "freq_hz",
    "xi",
    "xi_viscous",
    "damping_ratio",
    "friction_energy",
    "status",
    "energy_residual",
    "work_friction",
    "work_viscous",
    "mac",
    "higher_harmonics",
    "out_amp",
    "out_h1",
    "newton_its",
    "psi",
)


@dataclass
class NlModeBranch:
    """A backbone: one nonlinear mode against its modal amplitude (arrays per point).

    ``amplitude`` (sqrt(kg) m: the harmonic-1 motion is ``a psi_1`` with
    ``psi_1^H M psi_1 = 1``), ``freq_hz``, ``xi`` (1/s), ``damping_ratio``
    (``xi / 2 omega``), ``xi_viscous`` (1/s: ``psi_1^H C psi_1``, the viscous
    share of ``xi``), ``friction_energy`` (n_el, J per cycle), ``status``
    (n_el: 0 stuck, 1 stick-slip, 2 partial, 3 full separation),
    ``energy_residual`` (relative: energy fed by ``xi`` against viscous +
    contact work), ``work_friction`` / ``work_viscous`` (J per cycle),
    ``mac`` (of the harmonic-1 shape against the first point, mass
    weighted), ``higher_harmonics`` (share of the kinetic-energy norm in
    harmonics other than 1), ``out_amp`` / ``out_h1`` (n_out: the largest
    ``|y(t)|`` and the harmonic-1 amplitude of each output, model length
    unit), ``newton_its``, ``psi`` (nh * n: the harmonics per unit modal
    amplitude, layout of :mod:`.fourier`).
    """

    mode: int
    f_stuck_hz: float
    linear_hz: np.ndarray  # every linear (stuck) frequency of the model, Hz
    harmonics: tuple[int, ...]
    nt: int
    n: int
    output_names: tuple[str, ...]
    amplitude: np.ndarray = field(default_factory=lambda: np.zeros(0))
    freq_hz: np.ndarray = field(default_factory=lambda: np.zeros(0))
    xi: np.ndarray = field(default_factory=lambda: np.zeros(0))
    xi_viscous: np.ndarray = field(default_factory=lambda: np.zeros(0))
    damping_ratio: np.ndarray = field(default_factory=lambda: np.zeros(0))
    friction_energy: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    status: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), np.int8))
    energy_residual: np.ndarray = field(default_factory=lambda: np.zeros(0))
    work_friction: np.ndarray = field(default_factory=lambda: np.zeros(0))
    work_viscous: np.ndarray = field(default_factory=lambda: np.zeros(0))
    mac: np.ndarray = field(default_factory=lambda: np.zeros(0))
    higher_harmonics: np.ndarray = field(default_factory=lambda: np.zeros(0))
    out_amp: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    out_h1: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    newton_its: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    psi: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    completed: bool = False
    failed: bool = False
    message: str = ""
    timings: dict[str, float] = field(default_factory=dict)
    label: str = ""
    # the linear (stuck) modes, for the other modes' share of a synthesised response
    lin_phi: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # (n, n_m)
    lin_c: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (n_m,) 2 zeta w, 1/s
    obs: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))  # (n_out, n)

    @property
    def n_points(self) -> int:
        return int(self.amplitude.size)

    def other_modes_response(self, f1: np.ndarray, freq_hz: float) -> np.ndarray:
        """(n_out,) complex: the stuck linear response of every mode but the followed one to
        ``f1`` at ``freq_hz`` (what a single-mode synthesis leaves out), m per unit level."""
        if not self.lin_phi.size:
            return np.zeros(self.obs.shape[0] if self.obs.size else 1, complex)
        W = 2 * np.pi * freq_hz
        wn = 2 * np.pi * self.linear_hz
        d = 1.0 / (wn**2 - W**2 + 1j * W * self.lin_c)
        d[self.mode] = 0.0
        return (self.obs @ self.lin_phi) @ (d * (self.lin_phi.T @ np.asarray(f1, complex)))

    @property
    def fourier(self) -> Fourier:
        return Fourier(self.harmonics, self.nt)

    def psi_of(self, i: int) -> np.ndarray:
        """(nh, n) harmonics per unit modal amplitude at point ``i``."""
        return self.psi[i].reshape(len(self.fourier.k), self.n)

    def psi1(self) -> np.ndarray:
        """(n_points, n) complex harmonic-1 shapes ``psi_c1 - i psi_s1``."""
        f = self.fourier
        c = f.index(1, "c")
        P = self.psi.reshape(self.n_points, f.nh, self.n)
        return P[:, c] - 1j * P[:, c + 1]

    def summary(self) -> dict[str, Any]:
        """The numbers the CLI prints for this backbone."""
        if not self.n_points:
            return dict(mode=self.mode, n_points=0, completed=self.completed,
                        failed=self.failed, message=self.message)
        i = int(np.argmax(self.damping_ratio))
        return dict(
            mode=self.mode,
            f_stuck_hz=self.f_stuck_hz,
            freq_first_hz=float(self.freq_hz[0]),
            freq_last_hz=float(self.freq_hz[-1]),
            damping_first=float(self.damping_ratio[0]),
            damping_max=float(self.damping_ratio[i]),
            amplitude_at_damping_max=float(self.amplitude[i]),
            freq_at_damping_max_hz=float(self.freq_hz[i]),
            amplitude_range=[float(self.amplitude[0]), float(self.amplitude[-1])],
            mac_min=float(self.mac.min()),
            energy_residual_max=float(self.energy_residual.max()),
            n_points=self.n_points,
            newton_its=int(self.newton_its.sum()),
            wall_s=round(float(self.timings.get("total", 0.0)), 4),
            completed=self.completed,
            failed=self.failed,
            message=self.message,
        )

    # -- files -------------------------------------------------------------------
    def save(self, path: str | Path) -> Path:
        """Write to HDF5 atomically."""
        import h5py

        from ..io import atomic_path

        path = Path(path)
        with atomic_path(path) as tmp, h5py.File(tmp, "w") as h:
            for name in _ARRAYS:
                h.create_dataset(name, data=getattr(self, name))
            for name in ("linear_hz", "lin_phi", "lin_c", "obs"):
                h.create_dataset(name, data=getattr(self, name))
            a = h.attrs
            for name in ("mode", "f_stuck_hz", "nt", "n", "completed", "failed", "message",
                         "label"):
                a[name] = getattr(self, name)
            a["harmonics"] = np.asarray(self.harmonics, dtype=int)
            a["output_names"] = json.dumps(list(self.output_names))
            a["timings"] = json.dumps(self.timings)
        return path

    @classmethod
    def load(cls, path: str | Path) -> NlModeBranch:
        import h5py

        with h5py.File(path, "r") as h:
            kw = {name: h[name][()] for name in _ARRAYS}
            a = h.attrs
            return cls(
                mode=int(a["mode"]), f_stuck_hz=float(a["f_stuck_hz"]),
                linear_hz=h["linear_hz"][()],
                **{k: h[k][()] for k in ("lin_phi", "lin_c", "obs") if k in h},
                harmonics=tuple(int(v) for v in a["harmonics"]),
                nt=int(a["nt"]), n=int(a["n"]),
                output_names=tuple(json.loads(a["output_names"])),
                completed=bool(a["completed"]), failed=bool(a["failed"]),
                message=str(a["message"]), label=str(a["label"]),
                timings=json.loads(a["timings"]), **kw)

    def to_csv(self, path: str | Path, unit: str = "m") -> Path:
        """One row per point: amplitude, frequency, damping, energy, status counts, outputs."""
        from ..post.tables import write_rows_csv

        rows = []
        for i in range(self.n_points):
            st = self.status[i] if self.status.size else np.zeros(0, int)
            row = {
                "modal_amplitude": float(self.amplitude[i]),
                "freq_hz": float(self.freq_hz[i]),
                "damping_ratio": float(self.damping_ratio[i]),
                "xi_per_s": float(self.xi[i]),
                "friction_energy_j": float(self.friction_energy[i].sum()),
                "n_stuck": int(np.sum(st == 0)),
                "n_stick_slip": int(np.sum(st == 1)),
                "n_partial_sep": int(np.sum(st == 2)),
                "n_separated": int(np.sum(st == 3)),
                "mac": float(self.mac[i]),
                "higher_harmonics": float(self.higher_harmonics[i]),
                "energy_residual": float(self.energy_residual[i]),
            }
            for j, nm in enumerate(self.output_names):
                row[f"{nm}_amp_{unit}"] = float(self.out_amp[i, j])
            rows.append(row)
        return write_rows_csv(path, rows)


# -- the problem ---------------------------------------------------------------------
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


# -- the corrector: PETSc SNES with the dense analytic Jacobian ------------------------
class _Snes:
    """Newton (SNES, backtracking line search, dense LU) on the bordered system.

    Unknowns ``Y = [y / scale, s]`` with ``s = ln a``; equations
    ``[r(y; e^s) * row_scale, c . (Y - Yp)]``: the constraint ``c`` is ``e_s``
    for a point at a given amplitude, or the secant for a pseudo-arc-length
    step (which passes a fold of the backbone in amplitude).
    """

    def __init__(self, prob: Epmc, tol: float, tol_stall: float, max_it: int,
                 line_search: str = "bt"):
        from petsc4py import PETSc

        self.prob = prob
        N = prob.n_unknowns
        n = N + 1
        self.n = n
        comm = PETSc.COMM_SELF
        self.snes = PETSc.SNES().create(comm)
        prefix = f"upd_epmc{id(self)}_"
        self.snes.setOptionsPrefix(prefix)
        po = PETSc.Options()
        po[f"{prefix}snes_linesearch_type"] = line_search
        self.F = PETSc.Vec().createSeq(n, comm=comm)
        self.X = PETSc.Vec().createSeq(n, comm=comm)
        self.J = PETSc.Mat().createDense((n, n), comm=comm)
        self.J.setUp()
        self.s = prob.var_scale()
        self.rs = prob.row_scale()
        self.c = np.zeros(n)
        self.c[-1] = 1.0
        self.c0 = 0.0
        me = self

        def function(snes, X, F):
            Y = X.getArray(readonly=True)
            r, _ = me.prob.residual(Y[:N] * me.s, float(np.exp(Y[N])))
            out = F.getArray()
            out[:N] = r * me.rs
            out[N] = me.c @ Y - me.c0
            if not np.all(np.isfinite(out)):
                out[:] = np.inf

        def jacobian(snes, X, A, P):
            Y = X.getArray(readonly=True)
            a = float(np.exp(Y[N]))
            y = Y[:N] * me.s
            r0, _, Jd = me.prob.residual(y, a, want_jac=True)
            Jf = np.empty((n, n))
            Jf[:N, :N] = (Jd * me.rs[:, None]) * me.s[None, :]
            h = 1e-6  # d r / d ln a: one more residual (the contact term alone depends on a)
            r1, _ = me.prob.residual(y, a * np.exp(h))
            Jf[:N, N] = (r1 - r0) / h * me.rs
            Jf[N] = me.c
            A.setValues(range(n), range(n), Jf.ravel())  # row-major
            A.assemble()

        self.snes.setFunction(function, self.F)
        self.snes.setJacobian(jacobian, self.J, self.J)
        ksp = self.snes.getKSP()
        ksp.setType("preonly")
        ksp.getPC().setType("lu")
        reasons = PETSc.SNES.ConvergedReason
        hist: list[float] = []
        self.ok = False

        def converged(snes, it, norms):
            F = snes.getFunction()[0].getArray(readonly=True)
            X = snes.getSolution().getArray(readonly=True)
            if not np.all(np.isfinite(F)):
                return reasons.DIVERGED_FNORM_NAN
            rn = float(np.abs(F[:N]).max())
            scale = max(float(np.abs(X[: N - 2]).max()), 1.0)
            if it == 0:
                hist.clear()
            hist.append(rn)
            c_ok = abs(F[N]) <= 1e-9
            if rn <= tol * scale and c_ok:
                me.ok = True
                return reasons.CONVERGED_FNORM_ABS
            if len(hist) > 4 and hist[-1] > 0.5 * hist[-5] and rn <= tol_stall * scale and c_ok:
                me.ok = True  # Newton stalls on a kink (stick/slip transition)
                return reasons.CONVERGED_SNORM_RELATIVE
            if it >= max_it:
                return reasons.DIVERGED_MAX_IT
            return reasons.ITERATING

        self.snes.setConvergenceTest(converged)
        self.snes.setTolerances(max_it=max_it + 1)
        self.snes.setMaxLinearSolveFailures(10**6)
        self.snes.setFromOptions()
        del po[f"{prefix}snes_linesearch_type"]

    def scaled(self, y: np.ndarray, s: float) -> np.ndarray:
        return np.concatenate([y / self.s, [s]])

    def unscaled(self, Y: np.ndarray) -> tuple[np.ndarray, float]:
        return Y[:-1] * self.s, float(Y[-1])

    def solve(self, Y0: np.ndarray, c: np.ndarray | None = None,
              Yp: np.ndarray | None = None) -> tuple[np.ndarray, bool, int]:
        """From ``Y0`` with the constraint ``c . (Y - Yp) = 0`` (default: ``s = Y0[-1]``)."""
        if c is None:
            self.c = np.zeros(self.n)
            self.c[-1] = 1.0
            self.c0 = float(Y0[-1])
        else:
            self.c = np.asarray(c, float)
            self.c0 = float(self.c @ (Y0 if Yp is None else Yp))
        self.X.getArray()[:] = Y0
        self.ok = False
        try:
            self.snes.solve(None, self.X)
        except Exception as e:  # noqa: BLE001 - a PETSc/numerical failure is a failed step
            log.debug("EPMC corrector: %s", e)
            return Y0, False, 0
        Y = self.X.getArray(readonly=True).copy()
        ok = bool(self.snes.getConvergedReason() > 0 and self.ok and np.all(np.isfinite(Y)))
        return Y, ok, int(self.snes.getIterationNumber())

    def destroy(self) -> None:
        for o in (self.snes, self.F, self.X, self.J):
            o.destroy()


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


# -- choosing the mode and the amplitude range -------------------------------------------
def linear_modes(system: System) -> tuple[np.ndarray, np.ndarray]:
    """(w (rad/s), Phi mass-normalised) of the linear system with every contact stuck."""
    lam, phi = sla.eigh(system.regularised_stiffness(), system.M)
    return np.sqrt(np.clip(lam, 0.0, None)), phi


def pick_mode(system: System, f1: object, band_hz: tuple[float, float] | None = None) -> int:
    """The stuck mode the excitation ``f1`` drives most (in ``band_hz`` if given).

    Score ``|phi_j^H f1| / w_j^2``: the static modal response to the force.
    """
    w, phi = linear_modes(system)
    a = np.asarray(f1, dtype=complex).ravel()
    if a.shape != (system.n,):
        raise InputError("f1", f"shape {a.shape}", f"{system.n} complex amplitudes (N)")
    score = np.abs(phi.T @ a) / np.maximum(w, 1e-300) ** 2
    if band_hz is not None:
        f = w / TWO_PI
        inside = (f >= band_hz[0]) & (f <= band_hz[1])
        if inside.any():
            score = np.where(inside, score, -1.0)
    return int(np.argmax(score))


def slip_amplitude(system: System, mode: int) -> float:
    """Modal amplitude (sqrt(kg) m) at which the first element slips or lifts in the stuck mode."""
    if system.contacts is None or not system.n_el:
        return 1.0
    _, phi = linear_modes(system)
    el = system.contacts
    u = np.asarray(el.W @ phi[:, mode]).reshape(el.n_el, 3)
    cand = []
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = el.mu * el.n0 / (el.kt1 * np.abs(u[:, 0]))
        t2 = el.mu * el.n0 / (el.kt2 * np.abs(u[:, 1]))
        nn = el.n0 / (el.kn * np.abs(u[:, 2]))
    for v in (t1, t2, nn):
        v = v[np.isfinite(v) & (v > 0)]
        if v.size:
            cand.append(float(v.min()))
    return min(cand) if cand else 1.0


# -- the continuation ---------------------------------------------------------------------
def nonlinear_mode(
    system: System,
    mode: int | None = None,
    amplitude_range: tuple[float, float] | None = None,
    relative_range: tuple[float, float] = (0.05, 300.0),
    harmonics: tuple[int, ...] = (0, 1, 2, 3),
    nt: int | None = None,
    outputs: object = None,
    output_names: tuple[str, ...] | None = None,
    f1: object = None,
    band_hz: tuple[float, float] | None = None,
    n_steps: int = 40,
    max_points: int = 400,
    tol: float = 1e-10,
    tol_stall: float = 1e-7,
    max_newton: int = 12,
    max_change: float = 0.25,
    dc_anchor: float = 1e-3,
    space: str = "auto",
    levels: object = None,
    max_fold_points: int = 80,
    refine_ratio: float = 1.02,
    label: str = "",
) -> NlModeBranch:
    """The backbone of one nonlinear mode, continued in modal amplitude.

    ``mode``: index of the stuck linear mode to follow (default: the one
    ``f1`` drives most in ``band_hz``, see :func:`pick_mode`, else mode 0).
    ``amplitude_range`` (sqrt(kg) m), or ``relative_range`` times the modal
    amplitude of the first slip (or lift-off) in the stuck mode. ``n_steps``
    sets the first step (``ln(a1/a0) / n_steps``). Steps in ``ln a`` with a
    secant predictor; where they stall (a fold of the backbone in amplitude),
    pseudo-arc-length steps in ``(psi, w, xi, ln a)`` pass it (a step that
    lands back on a point already computed is refused); the step adapts to
    the Newton iterations and to ``max_change`` (largest relative change of
    frequency or damping ratio per step). With ``f1`` and ``levels`` (the
    excitation levels to synthesise), the backbone stops once its dissipation
    ``a xi w`` exceeds twice the largest level's modal force
    ``|psi_1^H f1|``: every level's peak is then inside it. A fold that the
    amplitude does not pass again within ``max_fold_points`` points ends the
    backbone (completed = False). With ``levels``, a point is then solved at
    each level's synthesised peak where the backbone's segment there spans
    more than ``refine_ratio`` in amplitude. Never raises for a failed solve:
    the branch says ``failed`` and keeps its points.
    """
    t_start = time.perf_counter()
    fourier = Fourier(tuple(harmonics), nt or 0)
    if mode is None:
        mode = pick_mode(system, f1, band_hz) if f1 is not None else 0
    O = observation(system, outputs)
    names = tuple(output_names) if output_names else tuple(f"y{j}" for j in range(O.shape[0]))
    if len(names) != O.shape[0]:
        raise InputError("output_names", list(names), f"{O.shape[0]} names (one per output)")
    prob = make_problem(system, fourier, mode, O, dc_anchor, space)
    if amplitude_range is None:
        a_slip = slip_amplitude(system, mode)
        lo, hi = (float(v) for v in relative_range)
        check_range("relative_range[0]", lo, 0.0, lo_open=True)
        check_range("relative_range[1]", hi, lo, lo_open=True)
        amplitude_range = (lo * a_slip, hi * a_slip)
    a_slip = slip_amplitude(system, mode)
    a0, a1 = (float(v) for v in amplitude_range)
    check_range("amplitude_range[0]", a0, 0.0, lo_open=True)
    check_range("amplitude_range[1]", a1, a0, lo_open=True)
    n_steps = check_int("n_steps", n_steps, 1)
    rows: dict[str, list] = {k: [] for k in _ARRAYS}
    snes = _Snes(prob, tol, tol_stall, max_newton)
    message, failed, completed = "", False, False
    s0, s1 = np.log(a0), np.log(a1)
    phi1_ref = None
    f_top = float(max(np.atleast_1d(levels))) if levels is not None and f1 is not None else 0.0
    f1v = np.asarray(f1, complex).ravel() if f1 is not None else None
    s_slip = float(np.log(0.999 * a_slip)) if system.n_el else -np.inf

    ys: list[tuple[np.ndarray, float]] = []  # the unknowns of every recorded point

    def record(y: np.ndarray, a: float, its: int) -> dict[str, Any]:
        nonlocal phi1_ref
        y_unknowns = (y.copy(), float(a))
        y, a = prob.physical(y, a)
        pt = prob.point(y, a, phi1_ref)
        if phi1_ref is None:
            phi1_ref = pt["phi1"]
        if pt["lost"]:
            raise _Stop(f"the damper has lost contact at modal amplitude {a:.4g}: a singular "
                        "state; the backbone ends here", False)
        for k in _ARRAYS:
            if k != "newton_its":
                rows[k].append(pt[k])
        rows["newton_its"].append(its)
        ys.append(y_unknowns)
        if f_top > 0 and a * pt["xi"] * TWO_PI * pt["freq_hz"] > 2.0 * f_top * abs(
                np.conj(pt["phi1"]) @ f1v) and np.any(pt["status"] > 0):
            raise _Stop(f"covers the largest level ({f_top:g}): its peak is below modal "
                        f"amplitude {a:.4g}", False, completed=True)
        return pt

    from ..log import progress_bar

    N = prob.n_unknowns - 2
    span = s1 - s0
    # metric of the arc length: the shape relative to its size, frequency and xi relative to
    # the linear frequency (a change of a third counts as the whole amplitude range), ln a
    # relative to the range
    mw = np.empty(N + 3)
    mw[:N] = 1.0 / max(float(np.linalg.norm(prob.linear_guess()[:N])), 1e-300)
    # the mean position does not count (as dc_weight = 0 in the FRF): a stuck slider's
    # offset jumps where slip starts
    mw[:N][prob.dc_mask()[:N]] = 0.0
    mw[N] = mw[N + 1] = 3.0
    mw[N + 2] = 1.0 / span
    ds = 1.0 / n_steps
    ds_max, ds_min = 2.0 / n_steps, 1e-5
    cos_max = np.cos(np.radians(30.0))

    def norm(v: np.ndarray) -> float:
        return float(np.sqrt(np.sum((mw * v) ** 2)))

    def w_d(Y: np.ndarray) -> tuple[float, float]:
        y, _ = snes.unscaled(Y)
        return y[N], y[N + 1] / (2 * y[N])

    try:
        with progress_bar(f"nlmode {label or mode}", total=round(span, 6), unit="ln a") as bar:
            Y, ok, its = snes.solve(snes.scaled(prob.linear_guess(), s0))
            if not ok:
                raise _Stop(f"the corrector failed at the first amplitude {a0:.4g}", True)
            prev = record(snes.unscaled(Y)[0], a0, its)
            Y_prev: np.ndarray | None = None
            turns = 0
            arc = 0  # > 0: steps left in pseudo-arc-length mode (a fold in amplitude)
            hist = [Y]
            s_top, since_top = float(Y[-1]), 0
            while True:
                if len(rows["amplitude"]) >= max_points:
                    raise _Stop(f"stopped after max_points = {max_points}", False)
                if Y_prev is None:
                    t = np.zeros(N + 3)
                    t[-1] = span  # along ln a: the linear mode does not change
                else:
                    t = (Y - Y_prev) / norm(Y - Y_prev)
                if arc:  # the plane normal to the secant, a predictor along it
                    Yp = Y + ds * t
                    Yn, ok, its = snes.solve(Yp, mw**2 * t, Yp)
                else:  # the next amplitude, the secant extrapolated to it as predictor
                    dsn = ds * span
                    if Y[-1] < s_slip - 1e-9 < Y[-1] + dsn:
                        dsn = s_slip - Y[-1]  # a point just below the first slip (a kink)
                    Yp = Y + t * (dsn / t[-1]) if t[-1] > 1e-12 * span else Y.copy()
                    Yp[-1] = Y[-1] + dsn
                    Yn, ok, its = snes.solve(Yp)
                if ok:
                    (w0, d0), (w1, d1) = w_d(Y), w_d(Yn)
                    change = max(abs(w1 - w0) / w0, abs(d1 - d0) / max(abs(d0), 1e-3))
                    step = Yn - Y
                    cosang = float(np.sum(mw**2 * step * t)) / max(norm(step), 1e-300)
                    if (change > max_change or (arc and cosang < cos_max)) \
                            and ds > 2 * ds_min and turns < 4:
                        ok = False
                        turns += 1
                    elif cosang < 0.0 and Y_prev is not None:
                        ok = False  # back along the branch behind us: never accepted
                    elif len(hist) > 2 and min(norm(Yn - h) for h in hist[:-2]) < 0.3 * ds:
                        ok = False  # retracing the branch already computed
                if not ok:
                    ds *= 0.5
                    if not arc and ds < 1e-3 / n_steps and Y_prev is not None:
                        arc, ds = 8, 1.0 / n_steps  # natural stepping stalls: a fold?
                        continue
                    if ds < ds_min:
                        raise _Stop(
                            f"the corrector failed after modal amplitude "
                            f"{np.exp(Y[-1]):.4g} even with the smallest step; the backbone "
                            "so far is kept", True)
                    continue
                turns = 0
                if Yn[-1] >= s1:  # the last point exactly at the largest amplitude
                    th = (s1 - Y[-1]) / (Yn[-1] - Y[-1])
                    Yg = Y + th * (Yn - Y)
                    Yg[-1] = s1
                    Ye, ok_e, its_e = snes.solve(Yg)
                    if ok_e:
                        record(snes.unscaled(Ye)[0], a1, its_e)
                    break
                if Yn[-1] < s0:
                    raise _Stop("the backbone turned back below the smallest amplitude", False)
                if arc:  # back to stepping in amplitude once it increases again
                    arc = arc - 1 if Yn[-1] > Y[-1] else 8
                    if Yn[-1] < s_top - np.log(2.0):
                        raise _Stop(
                            f"the backbone folds back in amplitude after {np.exp(s_top):.4g} "
                            "and does not turn again within a factor 2 (the mode changes "
                            "character, or the free damper's mean position does): it ends "
                            "here", False)
                if Yn[-1] > s_top:
                    s_top, since_top = float(Yn[-1]), 0
                else:
                    since_top += 1
                    if since_top > max_fold_points:
                        raise _Stop(
                            f"the backbone folds back in amplitude after {np.exp(s_top):.4g} "
                            f"and has not passed it again in {max_fold_points} points (the "
                            "mode changes character, or the free damper's mean position "
                            "does): it ends here", False)
                Y_prev, Y = Y, Yn
                hist.append(Y)
                prev = record(snes.unscaled(Y)[0], float(np.exp(Y[-1])), its)
                bar.n = round(min(max(Y[-1] - s0, 0.0), span), 6)
                bar.set_postfix_str(f"{prev['freq_hz']:.4g} Hz, D {prev['damping_ratio']:.3g}",
                                    refresh=False)
                bar.update(0)
                grow = 1.5 if its <= 4 else (0.7 if its > 8 else 1.0)
                ds = float(np.clip(ds * grow, ds_min, ds_max))
            completed = True
    except _Stop as stop:
        message, failed, completed = str(stop), stop.failed, stop.completed
        (log.warning if failed else log.info)("%s", message)
    except (np.linalg.LinAlgError, FloatingPointError, ArithmeticError, RuntimeError) as e:
        failed = True
        message = f"stopped by a numerical error: {type(e).__name__}: {e}"
        log.warning("%s", message)
    n_el = system.n_el
    prob_phys = prob.phys if isinstance(prob, EpmcCondensed) else prob

    def branch() -> NlModeBranch:
        arr: dict[str, np.ndarray] = {}
        shapes = dict(friction_energy=(0, n_el), status=(0, n_el), out_amp=(0, O.shape[0]),
                      out_h1=(0, O.shape[0]), psi=(0, fourier.nh * system.n))
        for k, v in rows.items():
            arr[k] = np.array(v) if v else np.zeros(shapes.get(k, (0,)))
        arr["status"] = arr["status"].astype(np.int8)
        arr["newton_its"] = arr["newton_its"].astype(int)
        timings = dict(total=time.perf_counter() - t_start, aft=prob.stats["t_aft"])
        return NlModeBranch(
            mode=mode, f_stuck_hz=prob.w_lin / TWO_PI, linear_hz=prob.wn / TWO_PI,
            harmonics=fourier.harmonics, nt=fourier.nt, n=system.n, output_names=names,
            completed=completed, failed=failed,
            message=message or ("reached the largest amplitude" if completed else ""),
            timings=timings, label=label, lin_phi=prob_phys.phi_all, lin_c=prob_phys.c_all,
            obs=O, **arr)

    try:
        if f_top > 0 and len(ys) >= 2:
            _refine_at_peaks(branch, snes, record, rows, ys, f1v, levels, refine_ratio)
    except (_Stop, np.linalg.LinAlgError, FloatingPointError, ArithmeticError,
            RuntimeError) as e:
        log.info("refinement at the peaks stopped: %s", e)
    finally:
        snes.destroy()
    return branch()


def _refine_at_peaks(branch, snes, record, rows, ys, f1v, levels, ratio: float) -> None:
    """Add solved points at the synthesised peak of every level where the backbone is coarse.

    For each level (up to three passes) the peak's modal amplitude is found
    on the current backbone; if its segment spans more than ``ratio`` in
    amplitude and increases monotonically, the point at the peak's
    amplitude is solved (predictor: the segment's unknowns interpolated in
    ``ln a``) and inserted in order. The synthesis is then exact to the
    point solved, not to an interpolation over a coarse segment.
    """
    from .synthesis import synthesize

    for _ in range(3):
        nm = branch()
        added = 0
        for lv in sorted(set(float(v) for v in np.atleast_1d(levels))):
            try:
                s = synthesize(nm, f1v, lv)
            except InputError:
                return
            a = nm.amplitude
            j = int(np.searchsorted(a, s.peak_modal_amplitude))
            if not 0 < j < a.size or a[j] / a[j - 1] <= ratio or np.any(np.diff(a[: j + 1]) <= 0):
                continue
            (y0, p0), (y1, p1) = ys[j - 1], ys[j]
            # the continuation parameter of the target (the physical amplitude is a_M)
            th = np.log(s.peak_modal_amplitude / a[j - 1]) / np.log(a[j] / a[j - 1])
            pt = float(np.exp(np.log(p0) + th * (np.log(p1) - np.log(p0))))
            Yg = snes.scaled(y0 + th * (y1 - y0), np.log(pt))
            Y, ok, its = snes.solve(Yg)
            if not ok:
                continue
            n_before = len(rows["amplitude"])
            record(snes.unscaled(Y)[0], float(np.exp(Y[-1])), its)
            if len(rows["amplitude"]) == n_before:
                continue
            if not a[j - 1] < rows["amplitude"][-1] < a[j]:  # off its segment: dropped
                for key in rows:
                    rows[key].pop()
                ys.pop()
                continue
            for key in rows:  # move the new point into amplitude order
                rows[key].insert(j, rows[key].pop())
            ys.insert(j, ys.pop())
            added += 1
            nm = branch()
        if not added:
            return


class _Stop(Exception):
    def __init__(self, message: str, failed: bool, completed: bool = False):
        super().__init__(message)
        self.failed, self.completed = failed, completed
