"""The harmonic balance residual, its analytic Jacobian and the recovery of every DOF.

Unknowns. Either the harmonics of the active relative contact DOFs
("condensed": the rows of ``W`` that are not zero, ``n_s = n_act``) or of
all generalised coordinates ("physical": ``n_s = n``), whichever is
smaller (or as chosen). With ``S`` the map from ``q`` to the unknowns
(``W_act`` or ``I``), ``V`` the map from the unknowns to the contact
displacements (selection or ``W``) and ``H`` the receptance of the
regularised system, the residual in metres is

    r(X, w) = X - S H(w) (P - W^T G(V X)),   G(u) = f(u) - K_c u

(``P``: the excitation and static force harmonics), with the Jacobian
``dr/dX = I + S H W^T D V`` (``D = dG/du`` from the AFT, per element) and
``dr/dw = -S (dH/dw) (P - W^T G)``. ``X`` has shape (nh, n_s) in the layout
of :mod:`.fourier`; flattened it is the solver's vector. Every DOF follows
from ``q = H (P - W^T G)``.

Energy balance per cycle (:meth:`HarmonicBalance.point_data`): the work of
the excitation equals the viscous dissipation plus the work of the contact
forces. The contact work is computed from the force harmonics (equal to
the sum over the AFT samples of ``f(t_j) u'(t_j) dt``), so for a solution it
closes to the Newton tolerance: its tangential part is the friction
dissipation; its normal part is the quadrature error of the (conservative)
unilateral spring where the contact opens, stored as ``work_normal``
(zero without separation).

The friction energy reported per element is the trapezoid rule on its
converged loop, ``sum_j (T_j + T_j+1) / 2 . (u_j+1 - u_j)`` over the AFT
samples (DESIGN.md section 6): the dissipation of the law for the sampled
motion (a loop that hardly opens, under a varying normal load, can come
out slightly negative from the sampling; summaries report a negative total
as 0 with a note). It agrees with the harmonic work of the same
element to O(1/nt^2) while the normal load stays positive; where the
contact opens and the force jumps, the harmonic work (the quantity that
balances the excitation) can differ from it and even change sign.

Accuracy indicator (``PointData.accuracy``): the energy balance closes at
any converged point however coarse the sampling, so the indicator compares
two estimates of the contact work that agree only when the sampling
resolves the loop: ``|E_loop - W_harm| / |W_ext|`` (trapezoid on the loops
against the harmonic work). It falls as O(1/nt^2) for a slipping loop.

Mean-position anchor: when a body is held by its contacts alone (rigid-body
modes in ``K``) and every contact holding it slips at some instant, the
mean of its tangential position no longer changes the forces (the loop
forgets it) and the Jacobian is singular. ``dc_anchor`` adds a spring of
``dc_anchor * kt`` on the mean tangential displacement of each element
(harmonic 0 only: it does no work and leaves the vibration untouched) to
pick the solution nearest the static equilibrium.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ...errors import InputError
from .aft import AftResult, aft, work_per_cycle
from .fourier import Fourier
from .linear import make_linear
from .loops import loop_dissipation, loop_normal_work
from .ports import excitation_vector, observation
from .system import System

# observation, excitation_vector (ports.py) and the loop work (loops.py) stay importable here
__all__ = [
    "Evaluation",
    "HarmonicBalance",
    "HillParts",
    "PointData",
]


@dataclass
class PointData:
    """Everything kept about one converged periodic solution."""

    omega: float
    out_harm: np.ndarray  # (nh, n_out) output harmonics, m
    out_amp: np.ndarray  # (n_out,) max over the period of |y(t)|, m
    out_h1: np.ndarray  # (n_out,) harmonic-1 amplitude, m
    out_rms: np.ndarray  # (n_out,) RMS of y(t) over the period, m
    status: np.ndarray  # (n_el,) int8
    friction_energy: np.ndarray  # (n_el,) J per cycle
    work_ext: float  # J per cycle
    work_visc: float
    work_friction: float
    work_normal: float
    energy_residual: float
    loop_energy: float  # J per cycle: trapezoid on the contact loops (tangential + normal)
    accuracy: float  # |loop_energy - harmonic contact work| / |work_ext| (-)
    lost_contact: bool


@dataclass(frozen=True, eq=False)
class Evaluation:
    """One evaluation of the harmonic balance at unknowns ``x`` and ``omega``: the state record.

    Returned by :meth:`HarmonicBalance.evaluate`; the Jacobian, the point data,
    the recovery of every DOF and Hill's method take it as input, so nothing
    is cached on the :class:`HarmonicBalance` itself.
    """

    x: np.ndarray  # (N,) unknowns, m
    omega: float  # rad/s
    level: float  # excitation level it was evaluated at
    U: np.ndarray  # (nh, n3) contact displacement harmonics, m
    G: np.ndarray  # (nh, n3) regularised contact force harmonics f - K_c u, N
    D: np.ndarray  # (n_el, 3, nh, 3, nh) dG/dU, N/m
    aft: AftResult | None  # the contact march (None without contacts)
    Yz: np.ndarray  # (nh, n_z) response on the linear coordinates
    r: np.ndarray  # (N,) residual, m

    def key(self) -> tuple[bytes, float, float]:
        """What identifies the evaluation: unknowns, frequency and level."""
        return (np.asarray(self.x, dtype=float).tobytes(), float(self.omega), float(self.level))


@dataclass(frozen=True, eq=False)
class HillParts:
    """Frequency-independent Kronecker blocks of Hill's dense matrices (z coordinates)."""

    K: np.ndarray
    C: np.ndarray
    M: np.ndarray
    NC: np.ndarray
    NM: np.ndarray
    NNM: np.ndarray
    B: np.ndarray


class HarmonicBalance:
    """Residual, Jacobian, recovery and energies of one system at one excitation level.

    Stateless between calls: :meth:`evaluate` returns an :class:`Evaluation`
    and every derived quantity takes one (``stats`` only counts calls).
    """

    def __init__(
        self,
        system: System,
        f1: object,
        fourier: Fourier,
        outputs: object = None,
        level: float = 1.0,
        space: str = "auto",
        backend: str = "auto",
        dc_anchor: float = 0.0,
    ):
        if 1 not in fourier.harmonics:
            raise InputError(
                "harmonics", list(fourier.harmonics), "a list that includes 1 (the excitation)"
            )
        self.system, self.fourier = system, fourier
        self.el = system.contacts
        self.n = system.n
        self.n_el = system.n_el
        self.n3 = 3 * self.n_el
        Kr = system.regularised_stiffness()
        self.lin = make_linear(system.M, Kr, system.C, system.zeta, fourier, backend)
        if self.n_el:
            self.W = self.el.W
            self.act = np.flatnonzero(self.el.active.ravel())
            self.kc = self.el.kc
        else:
            self.W = sp.csr_matrix((0, self.n))
            self.act = np.zeros(0, dtype=int)
            self.kc = np.zeros((0, 3))
        # rigid-body modes of K (bodies held by their contacts alone) and how they move the
        # contacts: for the anchor below and the lost-contact check
        self.rigid = system.rigid_modes() if self.n_el else np.zeros((self.n, 0))
        self.rigid_w = (
            np.asarray(self.W @ self.rigid) if self.rigid.shape[1] else np.zeros((self.n3, 0))
        )
        # mean-position anchor: only where a body is held by its contacts alone
        self.anchor = np.zeros((self.n_el, 3))
        if self.n_el and dc_anchor > 0 and self.rigid.shape[1]:
            self.anchor[:, 0] = dc_anchor * self.el.kt1
            self.anchor[:, 1] = dc_anchor * self.el.kt2
        if space == "auto" or not self.n_el:  # no contact: a linear system on all DOFs
            space = "condensed" if self.n_el and self.act.size <= self.n else "physical"
        if space not in ("condensed", "physical"):
            raise InputError("space", space, "one of auto, condensed, physical")
        self.space = space
        S = self.W[self.act] if space == "condensed" else sp.identity(self.n, format="csr")
        self.n_s = S.shape[0]
        # position of each contact DOF (3 e + d) among the condensed unknowns (-1: inactive)
        self._pos = -np.ones(self.n3, dtype=int)
        self._pos[self.act] = np.arange(self.act.size)
        self.Sz = self.lin.map_z(S)
        self.Bz = self.lin.map_z(self.W)
        self.O = observation(system, outputs)
        self.Oz = self.lin.map_z(self.O)
        self.f1 = excitation_vector(system, f1)
        self.static = system.total_static_force()
        self.N = fourier.nh * self.n_s
        self.set_level(level)
        # the regularised static flexibility S H_0 W^T (n_s, n3): frequency independent
        self.R0 = None
        if fourier.has_dc and self.n_el:
            Sz = self.Sz.toarray() if sp.issparse(self.Sz) else np.asarray(self.Sz)
            self.R0 = np.asarray(self.lin.dense_receptance(0.0, Sz, self.Bz, (0,))[0]).real
        self.stats = dict(
            n_residual=0, t_residual=0.0, n_jacobian=0, t_jacobian=0.0, aft_periods_max=0
        )

    # -- forcing ---------------------------------------------------------------
    def set_level(self, level: float) -> None:
        """Excitation level (multiplies f1)."""
        f = self.fourier
        P = np.zeros((f.nh, self.n))
        if f.has_dc:
            P[0] = self.static
        c = f.index(1, "c")
        P[c] = (level * self.f1).real
        P[c + 1] = -(level * self.f1).imag
        self.level = float(level)
        self.P = P
        self.Pz = self.lin.to_z(P)

    # -- maps ------------------------------------------------------------------
    @staticmethod
    def _rmul(X: np.ndarray, A) -> np.ndarray:
        """``X @ A`` for dense or sparse A (X is (nh, m))."""
        if sp.issparse(A):
            return np.asarray((A.T @ X.T).T)
        return X @ A

    def to_u(self, X: np.ndarray) -> np.ndarray:
        """Contact displacement harmonics (nh, n3) from unknowns X (nh, n_s)."""
        if self.space == "condensed":
            U = np.zeros((X.shape[0], self.n3))
            U[:, self.act] = X
            return U
        return self._rmul(X, self.W.T)

    def _left(self, Yz: np.ndarray) -> np.ndarray:
        return self._rmul(Yz, self.Sz.T)

    # -- evaluation -------------------------------------------------------------
    def _contact(self, X: np.ndarray):
        """AFT at X: (U (nh, n3), G (nh, n3), D (n_el, 3, nh, 3, nh), AftResult or None)."""
        f = self.fourier
        U = self.to_u(X)
        if not self.n_el:
            return U, np.zeros((f.nh, 0)), np.zeros((0, 3, f.nh, 3, f.nh)), None
        res = aft(U.reshape(f.nh, self.n_el, 3), self.el, f)
        self.stats["aft_periods_max"] = max(
            self.stats["aft_periods_max"], int(res.periods.max(initial=0))
        )
        Uloc = U.reshape(f.nh, self.n_el, 3)
        G = res.F - self.kc[None] * Uloc
        D = res.J.copy()
        h = np.arange(f.nh)
        for a in range(3):
            D[:, a, h, a, h] -= self.kc[:, a][:, None]
        ac = self.el.active  # an inactive direction (zero row of W) never moves: no entries
        D *= (ac[:, :, None] & ac[:, None, :])[:, :, None, :, None]
        if f.has_dc and self.anchor.any():
            G[0] += self.anchor * Uloc[0]
            for a in range(2):
                D[:, a, 0, a, 0] += self.anchor[:, a]
        return U, G.reshape(f.nh, self.n3), D, res

    def evaluate(self, x: np.ndarray, omega: float) -> Evaluation:
        """The state at unknowns x (N,) and angular frequency omega (rad/s): AFT and residual."""
        import time

        t0 = time.perf_counter()
        x = np.array(x, dtype=float).ravel()
        X = x.reshape(self.fourier.nh, self.n_s)
        U, G, D, res = self._contact(X)
        Yz = self.lin.solve(omega, self.Pz - self._rmul(G, self.Bz))
        r = (X - self._left(Yz)).ravel()
        self.stats["n_residual"] += 1
        self.stats["t_residual"] += time.perf_counter() - t0
        return Evaluation(x, float(omega), self.level, U, G, D, res, Yz, r)

    def at(self, state: Evaluation | np.ndarray, omega: float | None = None) -> Evaluation:
        """``state`` itself, or the evaluation at unknowns ``state`` and ``omega``."""
        if isinstance(state, Evaluation):
            return state
        if omega is None:
            raise TypeError("omega is needed with unknowns x")
        return self.evaluate(state, omega)

    def residual(self, x: np.ndarray, omega: float) -> np.ndarray:
        """r (N,) in metres at unknowns x (N,) and angular frequency omega (rad/s)."""
        return self.evaluate(x, omega).r

    def residual_omega(self, ev: Evaluation) -> np.ndarray:
        """dr/dw (N,) in m s/rad at an evaluation."""
        dY = self.lin.solve(ev.omega, self.Pz - self._rmul(ev.G, self.Bz), deriv=True)
        return -self._left(dY).ravel()

    def jvp(self, ev: Evaluation, v: np.ndarray) -> np.ndarray:
        """``dr/dx @ v`` at an evaluation (exact, matrix-free)."""
        f = self.fourier
        V = np.asarray(v, dtype=float).reshape(f.nh, self.n_s)
        dG = self._dG(ev.D, self.to_u(V))
        return (V + self._left(self.lin.solve(ev.omega, self._rmul(dG, self.Bz)))).ravel()

    def _dG(self, D: np.ndarray, dU: np.ndarray) -> np.ndarray:
        """D applied to contact displacement harmonics dU (nh, n3) -> (nh, n3)."""
        f = self.fourier
        if not self.n_el:
            return np.zeros_like(dU)
        loc = dU.reshape(f.nh, self.n_el, 3).transpose(1, 2, 0).reshape(self.n_el, 3 * f.nh, 1)
        out = np.matmul(D.reshape(self.n_el, 3 * f.nh, 3 * f.nh), loc)
        return out.reshape(self.n_el, 3, f.nh).transpose(2, 0, 1).reshape(f.nh, self.n3)

    def dense_jacobian(self, ev: Evaluation, dtype=np.float64) -> np.ndarray:
        """dr/dx (N, N) assembled densely at an evaluation (float32: a single-precision LU)."""
        if not self.n_el:
            return np.eye(self.N, dtype=dtype)
        if self.space == "condensed" and self.act.size == self.n3:
            J = self.jacobian_columns(ev, full=True, dtype=dtype)
        else:
            J = np.zeros((self.N, self.N), dtype=dtype)
            C, cols = self.jacobian_columns(ev, dtype=dtype)
            if self.space == "condensed":
                J[:, cols] = C
            else:
                J += C
        J.flat[:: self.N + 1] += 1.0
        return J

    def element_classes(self, ev: Evaluation) -> tuple[np.ndarray, np.ndarray]:
        """(nonlinear, anchored) element indices at an evaluation.

        An element whose contact Jacobian ``D`` is zero apart from the mean-position
        anchor (stuck and closed all period) only adds the anchor's two constant
        entries; every other element adds full blocks.
        """
        D = ev.D.copy()
        for a in range(2):
            D[:, a, 0, a, 0] -= self.anchor[:, a] if self.fourier.has_dc else 0.0
        # stuck blocks cancel to round-off (the march adds kt dE step by step)
        scale = np.maximum(self.kc.max(axis=1), 1e-300)
        nonlin = np.abs(D.reshape(self.n_el, -1)).max(axis=1) > 1e-9 * scale
        return np.flatnonzero(nonlin), np.flatnonzero(~nonlin)

    def jacobian_columns(
        self,
        ev: Evaluation,
        elements: np.ndarray | None = None,
        full: bool = False,
        dtype=np.float64,
    ):
        """Columns of ``dr/dx - I`` belonging to the contact DOFs of ``elements``.

        Returns ``(C, cols)``: ``C`` (N, m) and the unknown index of each column
        (condensed space); in the physical space ``C`` is the whole ``dr/dx - I``
        (N, N) and ``cols`` is ``arange(N)``. Vectorised over elements and harmonics.
        ``full`` (every contact DOF active, condensed): return ``dr/dx - I`` itself.
        """
        import time

        t0 = time.perf_counter()
        f = self.fourier
        nh, n_s, n_el = f.nh, self.n_s, self.n_el
        omega = ev.omega
        els = (
            np.arange(n_el)
            if elements is None or self.space != "condensed"
            else np.asarray(elements)
        )
        ne = els.size
        Sz = self.Sz.toarray() if sp.issparse(self.Sz) else np.asarray(self.Sz)
        Bz = self._bz_rows(els)
        if dtype == np.float32 and not sp.issparse(Bz):  # half the memory traffic
            Sz, Bz = Sz.astype(np.float32), Bz.astype(np.float32)
        R = self.lin.dense_receptance(omega, Sz, Bz, tuple(k for k in f.harmonics if k > 0))
        if f.has_dc:  # frequency independent: from the cached static flexibility
            R[0] = self.R0[:, (3 * els[:, None] + np.arange(3)).ravel()]
        # D by output component: (nh, ne, 3, 3 nh) with the last axis (d', h')
        Dh = np.ascontiguousarray(ev.D[els].transpose(2, 0, 1, 3, 4), dtype=dtype)
        Dh = Dh.reshape(nh, ne, 3, 3 * nh)
        Jx = np.empty((nh, ne, n_s, 3 * nh), dtype=dtype)  # rows (h, i), cols (e, d', h')

        def blocks(M: np.ndarray) -> np.ndarray:  # (n_s, 3 ne) -> (ne, n_s, 3)
            return np.ascontiguousarray(np.swapaxes(M.reshape(n_s, ne, 3), 0, 1), dtype=dtype)

        if f.has_dc:
            np.matmul(blocks(np.asarray(R[0])), Dh[0], out=Jx[0])
        for p, k in enumerate(f.pair_k):
            Rr, Ri = blocks(R[int(k)].real), blocks(R[int(k)].imag)
            c, s_ = int(f.ic[p]), int(f.is_[p])
            # [Uc; Us] = [[Rr, Ri], [-Ri, Rr]] [Gc; Gs]
            np.matmul(Rr, Dh[c], out=Jx[c])
            Jx[c] += np.matmul(Ri, Dh[s_])
            np.matmul(Rr, Dh[s_], out=Jx[s_])
            Jx[s_] -= np.matmul(Ri, Dh[c])
        # rows (h, i), cols (h', e, d')
        Jt = Jx.reshape(nh, ne, n_s, 3, nh).transpose(0, 2, 4, 1, 3)
        self.stats["n_jacobian"] += 1
        if full:
            out = np.empty((self.N, self.N), dtype=dtype)
            out.reshape(nh, n_s, nh, ne, 3)[...] = Jt
            self.stats["t_jacobian"] += time.perf_counter() - t0
            return out
        Jt = Jt.reshape(self.N, nh, ne * 3)
        if self.space == "condensed":
            pos = self._pos[(3 * els[:, None] + np.arange(3)).ravel()]
            keep = pos >= 0
            cols = (np.arange(nh)[:, None] * n_s + pos[keep][None, :]).ravel()
            C = Jt[:, :, keep].reshape(self.N, -1)
        else:
            C = (Jt @ self.W.toarray()).reshape(self.N, self.N)
            cols = np.arange(self.N)
        self.stats["t_jacobian"] += time.perf_counter() - t0
        return C, cols

    def anchor_columns(self, elements: np.ndarray):
        """Columns of ``dr/dx - I`` for the anchor alone on ``elements`` (mean, tangential)."""
        f = self.fourier
        if not f.has_dc or elements.size == 0 or self.space != "condensed":
            return np.zeros((self.N, 0)), np.zeros(0, dtype=int)
        u = (3 * elements[:, None] + np.arange(2)).ravel()
        a = self.anchor[elements, :2].ravel()
        keep = (self._pos[u] >= 0) & (a != 0)
        u, a = u[keep], a[keep]
        R0 = self.R0[:, u]
        C = np.zeros((self.N, u.size))
        C[: self.n_s] = R0 * a
        return C, self._pos[u]

    def _bz_rows(self, els: np.ndarray):
        """Rows of the contact map on z for the three directions of ``els``."""
        rows = (3 * els[:, None] + np.arange(3)).ravel()
        return self.Bz[rows]

    # -- guesses and recovery ---------------------------------------------------
    def stuck_solution(self, omega: float) -> np.ndarray:
        """x (N,) of the linear response with every contact stuck and closed (exact if stuck)."""
        f = self.fourier
        G0 = np.zeros((f.nh, self.n3))
        if self.n_el and f.has_dc:
            G0[0] = self.el.force_at_rest().ravel()
        Y = self.lin.solve(omega, self.Pz - self._rmul(G0, self.Bz))
        return self._left(Y).ravel()

    def response(self, state: Evaluation | np.ndarray, omega: float | None = None) -> np.ndarray:
        """Harmonics of every generalised coordinate q (nh, n) at a solution.

        ``state``: an :class:`Evaluation`, or the unknowns x with ``omega`` (rad/s).
        """
        return self.lin.from_z(self.at(state, omega).Yz)

    def point_data(
        self, state: Evaluation | np.ndarray, omega: float | None = None, n_fine: int = 256
    ) -> PointData:
        """Outputs, contact status, friction energies and the energy balance at a solution.

        ``state``: an :class:`Evaluation`, or the unknowns x with ``omega`` (rad/s).
        """
        f = self.fourier
        ev = self.at(state, omega)
        omega = ev.omega
        Y = self._rmul(ev.Yz, self.Oz.T)
        out_amp = f.amplitude(Y, n_fine)
        out_h1 = f.h1_amplitude(Y)
        out_rms = f.rms(Y)
        work_ext = float(np.sum(work_per_cycle(self.Pz, ev.Yz, f)))
        work_visc = self.lin.viscous_work(omega, ev.Yz)
        if self.n_el:
            Uloc = ev.U.reshape(f.nh, self.n_el, 3)
            wc = work_per_cycle(ev.aft.F, Uloc, f)  # (n_el, 3)
            w_f = float(wc[:, 0].sum() + wc[:, 1].sum())
            w_n = float(wc[:, 2].sum())
            fric = loop_dissipation(ev.aft.u, ev.aft.f)
            e_loop = float(fric.sum() + loop_normal_work(ev.aft.u, ev.aft.f).sum())
            status = ev.aft.status
            lost = self.lost_contact(ev)
        else:
            fric, w_f, w_n, status, lost = np.zeros(0), 0.0, 0.0, np.zeros(0, np.int8), False
            e_loop = 0.0
        den = max(abs(work_ext), abs(work_visc) + abs(w_f) + abs(w_n), 1e-300)
        resid = abs(work_ext - work_visc - w_f - w_n) / den
        accuracy = abs(e_loop - w_f - w_n) / den
        return PointData(
            omega=omega,
            out_harm=Y,
            out_amp=out_amp,
            out_h1=out_h1,
            out_rms=out_rms,
            status=status,
            friction_energy=fric,
            work_ext=work_ext,
            work_visc=work_visc,
            work_friction=w_f,
            work_normal=w_n,
            energy_residual=resid,
            loop_energy=e_loop,
            accuracy=accuracy,
            lost_contact=lost,
        )

    def lost_contact(self, ev: Evaluation) -> bool:
        """True if at some instant the closed contacts no longer hold a free body.

        A body held only by its contacts (a rigid-body mode of ``K``) is free
        when, at some sample of the period, the rows of ``W`` of the closed
        elements do not constrain that mode: the state is singular.
        """
        if ev.aft is None or not np.any(ev.aft.n_sep):
            return False
        WV = self.rigid_w
        r = WV.shape[1]
        if r == 0:
            return False
        patterns = np.unique(ev.aft.contact.T, axis=0)
        for pat in patterns:
            rows = np.repeat(pat, 3)
            A = WV[rows]
            if A.shape[0] < r:
                return True
            s = np.linalg.svd(A, compute_uv=False)
            if s.size < r or s[-1] <= 1e-9 * max(np.abs(WV).max(), 1e-300):
                return True
        return False

    # -- Hill's method operators -----------------------------------------------
    def hill_parts(self) -> HillParts:
        """The frequency-independent blocks of Hill's dense matrices (build once per branch)."""
        f = self.fourier
        Mz, Cz, Kz = self.lin.hill_blocks()
        I = np.eye(f.nh)
        n1 = f.nabla(1.0)
        B = self.Bz.toarray() if sp.issparse(self.Bz) else np.asarray(self.Bz)
        return HillParts(
            K=np.kron(I, Kz),
            C=np.kron(I, Cz),
            M=np.kron(I, Mz),
            NC=np.kron(n1, Cz),
            NM=np.kron(n1, Mz),
            NNM=np.kron(n1 @ n1, Mz),
            B=np.kron(I, B),
        )

    def hill_dense(self, ev: Evaluation, parts: HillParts | None = None):
        """(Delta0, Delta1, Delta2) of Hill's quadratic eigenproblem on z (dense) at ``ev``.

        ``parts``: :meth:`hill_parts` (built here when not given).
        """
        f = self.fourier
        hp = parts if parts is not None else self.hill_parts()
        omega = ev.omega
        d0 = hp.K + omega * hp.NC + omega**2 * hp.NNM
        if self.n_el:
            Dfull = np.zeros((f.nh, self.n_el, 3, f.nh, self.n_el, 3))
            e = np.arange(self.n_el)
            Dfull[:, e, :, :, e, :] = ev.D.transpose(0, 2, 1, 4, 3)
            Dfull = Dfull.reshape(f.nh * self.n3, f.nh * self.n3)
            d0 = d0 + hp.B.T @ Dfull @ hp.B
        d1 = hp.C + 2 * omega * hp.NM
        return d0, d1, hp.M

    def hill_shift_invert(self, ev: Evaluation, jsolve) -> tuple[int, callable]:
        """Size and action of ``A^-1 B`` for Hill's state-space form.

        ``jsolve(b)`` applies the inverse of the Jacobian dr/dx at the
        solution; by the Woodbury identity it gives ``Delta0^-1`` without
        forming the large Hill matrix.
        """
        f = self.fourier
        nh, nz = f.nh, self.lin.n_z
        omega = ev.omega
        nab = f.nabla(omega)
        lin = self.lin

        def d0_inv(v: np.ndarray) -> np.ndarray:
            a = lin.solve(omega, v)
            if self.space == "condensed":
                b = self._left(a).ravel()
                c = jsolve(b).reshape(nh, self.n_s)
                dG = self._dG(ev.D, self.to_u(c))
                return a - lin.solve(omega, self._rmul(dG, self.Bz))
            q = lin.from_z(a).ravel()
            c = jsolve(q).reshape(nh, self.n)
            return lin.q_to_z(c)

        def op(b: np.ndarray) -> np.ndarray:
            b1 = b[: nh * nz].reshape(nh, nz)
            b2 = b[nh * nz :].reshape(nh, nz)
            c2 = lin.apply_M(b2)
            d1b1 = lin.apply_C(b1) + 2 * lin.apply_M(nab @ b1)
            z1 = -d0_inv(c2 + d1b1)
            return np.concatenate([z1.ravel(), b1.ravel()])

        return 2 * nh * nz, op
