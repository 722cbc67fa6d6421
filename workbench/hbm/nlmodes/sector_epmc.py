"""Nonlinear modes of a tuned bladed disk on one sector's unknowns (EPMC, issue 29 item 3).

The equations are those of :mod:`.backbone` (the extended periodic motion
concept: a negative mass-proportional damping ``-xi M q'`` makes the damped
free motion periodic), written on the harmonic blocks of
:class:`workbench.hbm.core.sector.SectorBalance`: harmonic ``h`` is one
sector's motion at nodal diameter ``h EO mod N`` (a travelling wave for
``0 < EO < N/2``, a standing one at ND 0 and N/2). With block ``b``'s
``(K_b, M_b, V_b)`` (:meth:`SectorBalance.block_operators`: the dynamic
stiffness is ``K_b - (h w)^2 M_b + h w V_b``) and ``V^M_b`` the same velocity
operator built from the mass instead of the damping, the residual per unit
modal amplitude ``a`` is

    R_b = (K_b - (h w)^2 M_b + h w (V_b - xi V^M_b)) psi_b + W_b^T G_b(a psi) / a

(the mean block: ``K_0 psi_0 + W_0^T (G_0 - f(0)) / a``), with the mass
normalisation ``psi_1^T M_1 psi_1 = 1`` of harmonic 1's block and the phase
condition ``phi^T V^M_1 psi_1 = 0`` (``phi`` the block's stuck linear mode;
``V^M_1 psi_1`` is the mass times the time derivative, so this is the
condition ``psi_s^T M phi = 0`` of :class:`.epmc.Epmc`). The contact forces
and their exact Jacobian are the sector's (:meth:`SectorBalance.contact`).
The modal amplitude is one sector's: the whole disk's (every sector moving)
is ``sqrt(N)`` times larger at the same motion; frequency and damping ratio
are the same.

:func:`sector_nonlinear_mode` continues it with the same corrector and path
engine as :func:`.backbone.nonlinear_mode` and returns a :class:`.record.NlModeBranch`
whose ``psi`` rows are in the layout of the sector's unknowns (``SectorBalance.N``
values, not ``nh * n``: :meth:`NlModeBranch.psi_of` does not apply), and whose
``linear_hz`` are harmonic 1's block stuck frequencies (each once).
"""

from __future__ import annotations

import dataclasses
import time
from types import SimpleNamespace
from typing import Any

import numpy as np
import scipy.linalg as sla

from ...errors import InputError, check_int, check_range
from ..core.aft import work_per_cycle
from ..core.fourier import Fourier
from ..core.loops import loop_dissipation
from ..core.sector import SectorBalance, SectorModel
from ..path.engine import follow
from ..path.step import StepRule
from .epmc import TWO_PI, EpmcHooks
from .problem import Backbone, BackboneCorrector
from .record import NlModeBranch

__all__ = ["SectorEpmc", "sector_nonlinear_mode"]


class SectorEpmc(EpmcHooks):
    """Residual and analytic Jacobian of the EPMC on one sector (the PathProblem side of
    :class:`.problem.Backbone`, as :class:`.epmc.Epmc`)."""

    def __init__(
        self, model: SectorModel, eo: int, fourier: Fourier, mode: int = 0, dc_anchor=1e-3
    ):
        self.hb = hb = SectorBalance(model, eo, fourier, 0.0, dc_anchor)
        as_mass = dataclasses.replace(
            model,
            nd={k: dataclasses.replace(b, C=b.M) for k, b in model.nd.items()},
            Cd=model.Md,
        )
        hm = SectorBalance(as_mass, eo, fourier, 0.0, dc_anchor)
        self.fourier = fourier
        self.N = hb.N
        self.ops = []  # per block: (sl, h, K, M, V, VM)
        for i, b in enumerate(hb.blocks):
            K, M, V = hb.block_operators(i)
            VM = hm.block_operators(i)[2]
            self.ops.append((b["sl"], b["h"], K, M, V, VM))
        i1 = next(i for i, b in enumerate(hb.blocks) if b["h"] == 1)
        self.sl1 = hb.blocks[i1]["sl"]
        _, _, K1, M1, V1, VM1 = self.ops[i1]
        self.M1 = 0.5 * (M1 + M1.T)
        b1 = hb.blocks[i1]
        if b1["two"]:
            lam, vec = sla.eigh(K1, self.M1)
            lam, vec = lam[0::2], vec[:, 0::2]  # each travelling wave twice (a (v, J v) pair)
        else:  # a standing wave: its cos and sin halves are uncoupled; the cos one (as Epmc)
            mq, md, nq = b1["mq"], b1["md"], b1["nq"]
            ic = np.r_[0:mq, nq : nq + md]
            lam, vc = sla.eigh(K1[np.ix_(ic, ic)], self.M1[np.ix_(ic, ic)])
            vec = np.zeros((K1.shape[0], lam.size))
            vec[ic] = vc
        mode = check_int("mode", mode, 0, lam.size - 1)
        self.mode = mode
        self.wn = np.sqrt(np.clip(lam, 0.0, None))
        self.w_lin = float(self.wn[mode])
        self.phi = vec[:, mode]
        self.phase_row = self.phi @ VM1
        # the damping matrix of the block: V = C T with T = M^-1 V^M (T^2 = -I)
        T = np.linalg.solve(self.M1, VM1)
        self.C1 = -V1 @ T
        self.xi_lin = float(self.phi @ self.C1 @ self.phi)
        self.phi_all = vec
        self.c_all = np.einsum("ij,ik,kj->j", vec, self.C1, vec)
        self.f_rest = hb.el.force_at_rest().ravel()
        self.stats = dict(n_residual=0, n_jacobian=0, t_aft=0.0)

    # -- the point equations -------------------------------------------------------
    def _contact(self, x: np.ndarray):
        t0 = time.perf_counter()
        out = self.hb.contact(x)
        self.stats["t_aft"] += time.perf_counter() - t0
        return out

    def residual(self, y: np.ndarray, a: float, want_jac: bool = False):
        """Residual (N + 2,) at ``y = [psi, w, xi]`` and modal amplitude ``a`` (and Jacobian)."""
        N = self.N
        psi = np.asarray(y[:N], dtype=float)
        w, xi = float(y[N]), float(y[N + 1])
        U, G, D, res = self._contact(a * psi)
        if self.fourier.has_dc:
            G = G.copy()
            G[0] -= self.f_rest
        R = self.hb.Wx.T @ G.ravel() / a
        J = np.zeros((N + 2, N + 2)) if want_jac else None
        for sl, h, K, M, V, VM in self.ops:
            A = K - (h * w) ** 2 * M + h * w * (V - xi * VM)
            R[sl] += A @ psi[sl]
            if want_jac:
                J[sl, sl] = A
                J[sl, N] = (-2 * h * h * w * M + h * (V - xi * VM)) @ psi[sl]
                J[sl, N + 1] = -h * w * (VM @ psi[sl])
        p1 = psi[self.sl1]
        r = np.concatenate([R, [p1 @ self.M1 @ p1 - 1.0, self.phase_row @ p1]])
        self.stats["n_residual"] += 1
        if not want_jac:
            return r, res
        self.stats["n_jacobian"] += 1
        J[:N, :N] += self.hb.Wx.T @ D @ self.hb.Wx
        J[N, self.sl1] = 2 * (self.M1 @ p1)
        J[N + 1, self.sl1] = self.phase_row
        return r, res, J

    def row_scale(self) -> np.ndarray:
        return self._force_rows(self.M1)

    def dc_mask(self) -> np.ndarray:
        m = np.zeros(self.N + 2, bool)
        if self.fourier.has_dc:
            m[self.hb.blocks[0]["sl"]] = True
        return m

    def physical(self, y: np.ndarray, a: float) -> tuple[np.ndarray, float]:
        return y, a

    def linear_guess(self) -> np.ndarray:
        y = np.zeros(self.N + 2)
        y[self.sl1] = self.phi
        y[self.N], y[self.N + 1] = self.w_lin, self.xi_lin
        return y

    def lost_contact(self, res) -> bool:
        return res is not None and self.hb.lost_contact(SimpleNamespace(aft=res))

    def slip_amplitude(self) -> float:
        """Modal amplitude at which the first contact slips or lifts in the stuck mode."""
        el, hb = self.hb.el, self.hb
        x = np.zeros(self.N)
        x[self.sl1] = self.phi
        U = hb.to_u(x).reshape(self.fourier.nh, hb.n_el, 3)
        c = self.fourier.index(1, "c")
        u = np.hypot(U[c], U[c + 1])
        with np.errstate(divide="ignore", invalid="ignore"):
            cand = np.concatenate(
                [
                    el.mu * el.n0 / (el.kt1 * u[:, 0]),
                    el.mu * el.n0 / (el.kt2 * u[:, 1]),
                    el.n0 / (el.kn * u[:, 2]),
                ]
            )
        cand = cand[np.isfinite(cand) & (cand > 0)]
        return float(cand.min()) if cand.size else 1.0

    def point(self, y: np.ndarray, a: float, phi1_ref: np.ndarray | None) -> dict[str, Any]:
        """Everything kept about one converged point (one sector's energies)."""
        f, N = self.fourier, self.N
        psi = y[:N]
        w, xi = float(y[N]), float(y[N + 1])
        U, _, _, res = self._contact(a * psi)
        kin = damp = 0.0
        ke = {}
        for sl, h, _K, M, V, VM in self.ops:
            if h == 0:
                continue
            T = np.linalg.solve(M, VM)
            Cb = -V @ T
            ke[h] = h * h * float(psi[sl] @ M @ psi[sl])
            kin += ke[h]
            damp += h * h * float(psi[sl] @ Cb @ psi[sl])
        w_in = xi * np.pi * w * a * a * kin
        w_visc = np.pi * w * a * a * damp
        wc = work_per_cycle(res.F, U.reshape(f.nh, self.hb.n_el, 3), f)
        w_contact, w_fric = float(wc.sum()), float(wc[:, :2].sum())
        den = max(abs(w_in), abs(w_visc) + abs(w_contact), 1e-300)
        p1 = psi[self.sl1].astype(complex)
        ref = p1 if phi1_ref is None else phi1_ref
        mac = float(
            abs(np.conj(ref) @ self.M1 @ p1) ** 2
            / (np.real(np.conj(ref) @ self.M1 @ ref) * np.real(np.conj(p1) @ self.M1 @ p1))
        )
        Y = self.hb.outputs(a * psi)
        return dict(
            amplitude=a,
            freq_hz=w / TWO_PI,
            xi=xi,
            damping_ratio=xi / (2 * w),
            xi_viscous=float(psi[self.sl1] @ self.C1 @ psi[self.sl1]),
            friction_energy=loop_dissipation(res.u, res.f),
            status=res.status,
            energy_residual=abs(w_in - w_visc - w_contact) / den,
            work_friction=w_fric,
            work_viscous=w_visc,
            mac=mac,
            higher_harmonics=(kin - ke[1]) / kin if kin > 0 else 0.0,
            out_amp=f.amplitude(Y),
            out_h1=f.h1_amplitude(Y),
            psi=psi.copy(),
            lost=self.lost_contact(res),
            phi1=p1,
        )


def sector_nonlinear_mode(
    model: SectorModel,
    eo: int,
    mode: int = 0,
    amplitude_range: tuple[float, float] | None = None,
    relative_range: tuple[float, float] = (0.05, 300.0),
    harmonics: tuple[int, ...] = (0, 1, 2, 3),
    nt: int | None = None,
    n_steps: int = 40,
    max_points: int = 400,
    tol: float = 1e-10,
    tol_stall: float = 1e-7,
    max_newton: int = 12,
    max_change: float = 0.25,
    dc_anchor: float = 1e-3,
    max_fold_points: int = 80,
    jacobian_lag: int = 1,
    label: str = "",
) -> NlModeBranch:
    """The backbone of the tuned disk's mode ``mode`` (0: the first family) at the ND of
    engine order ``eo``, continued in one sector's modal amplitude (sqrt(kg) m).

    The options mean what they mean in :func:`.backbone.nonlinear_mode`
    (``relative_range``: times the modal amplitude of the first slip or lift-off in
    the stuck mode); the dense LU corrector, by default rebuilt at every iteration
    (``jacobian_lag`` 1: one sector's Jacobian is small, and the chord iterations of a
    lagged one failed on the travelling waves' stick-slip). Never raises for a failed solve.
    """
    t_start = time.perf_counter()
    fourier = Fourier(tuple(harmonics), nt or 0)
    prob = SectorEpmc(model, eo, fourier, mode, dc_anchor)
    a_slip = prob.slip_amplitude()
    if amplitude_range is None:
        lo, hi = (float(v) for v in relative_range)
        check_range("relative_range[0]", lo, 0.0, lo_open=True)
        check_range("relative_range[1]", hi, lo, lo_open=True)
        amplitude_range = (lo * a_slip, hi * a_slip)
    if len(amplitude_range) != 2:
        raise InputError("amplitude_range", amplitude_range, "two amplitudes (sqrt(kg) m)")
    a0, a1 = (float(v) for v in amplitude_range)
    check_range("amplitude_range[0]", a0, 0.0, lo_open=True)
    check_range("amplitude_range[1]", a1, a0, lo_open=True)
    n_steps = check_int("n_steps", n_steps, 1)
    lag = check_int("jacobian_lag", jacobian_lag, 1)
    snes = BackboneCorrector(prob, tol, tol_stall, max_newton, lag=lag, linear="dense")
    its_scale = 1.0 if lag == 1 else 2.5
    snes.set_max_it(round(max_newton * its_scale))
    rule = StepRule.backbone(n_steps, max_points, max_change, max_fold_points, its_scale)

    from ...log import progress_bar

    span = np.log(a1) - np.log(a0)
    tag = label or f"EO {prob.hb.eo}"
    with progress_bar(f"sector nlmode {tag}", total=round(span, 6), unit="ln a") as bar:
        bb = Backbone(prob, snes, (a0, a1), 0.0, None, float(np.log(0.999 * a_slip)), 0, rule, bar)
        try:
            out = follow(bb, rule)
        finally:
            snes.destroy()
    n_el, n_out = prob.hb.n_el, len(model.output_names) or 1
    shapes = dict(
        friction_energy=(0, n_el),
        status=(0, n_el),
        out_amp=(0, n_out),
        out_h1=(0, n_out),
        psi=(0, prob.N),
    )
    arr = bb.rows.arrays(shapes, dict(status=np.int8, newton_its=int))
    return NlModeBranch(
        mode=prob.mode,
        f_stuck_hz=prob.w_lin / TWO_PI,
        linear_hz=prob.wn / TWO_PI,
        harmonics=fourier.harmonics,
        nt=fourier.nt,
        n=prob.N,
        output_names=tuple(model.output_names) or ("y0",),
        completed=out.completed,
        failed=out.failed,
        message=out.message or ("reached the largest amplitude" if out.completed else ""),
        timings=dict(
            total=time.perf_counter() - t_start,
            aft=prob.stats["t_aft"],
            factorisations=snes.n_factor,
            krylov_its=snes.n_krylov,
        ),
        label=tag,
        lin_phi=prob.phi_all,
        lin_c=prob.c_all,
        **arr,
    )
