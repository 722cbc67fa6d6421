"""Harmonic balance on one sector of a tuned bladed disk under engine-order excitation.

Under engine order ``EO`` the steady response of a tuned disk of ``N`` sectors
is a travelling wave: sector ``j + 1`` moves as sector ``j`` shifted in phase,
harmonic ``h`` by ``h * 2 pi EO / N``. Harmonic ``h`` therefore lives at nodal
diameter (ND) ``k_h = h EO mod N``; for ``k_h > N/2`` it is the wave of ND
``N - k_h`` travelling the other way (the complex conjugate). The unknowns are
one sector's: per harmonic the reduced coordinates of the sector at its own ND
and the damper's reduced coordinates.

Conventions (docs/DISK.md, docs/DISK_HBM.md). Sector 0's displacement at
harmonic ``h`` is ``c cos(h w t) + s sin(h w t)``, ``Z = c - i s``. For an ND
``k'`` with two copies (``0 < k' < N/2``) the real cyclic field is
``(a; b) = (c; sigma s)`` (``sigma = +1`` forward, ``k_h = k'``; ``-1``
backward, ``k_h = N - k'``), one vector ``q`` of the ND's reduced coordinates
per harmonic, and the time derivative at ``t = 0`` is ``sigma h w J (a; b)``,
``J (a; b) = (b; -a)`` (``J_r`` on the reduced coordinates: the reduced basis
is closed under ``J``). For ``k' = 0`` or ``N/2`` (one copy, a real field) a
harmonic has the usual cos and sin vectors ``q_c``, ``q_s``. The damper is one
body per sector with its own cos and sin vectors.

Contact: pair ``i``'s relative displacement is ``F_i (u_damper - u_platform)``.
On side 0 the platform is this sector's interface node; on side 1 it is the
neighbour's node, ``R`` times its image node's motion shifted by
``phi_h = 2 pi k_h / N``: on each cos/sin pair the real rotation
``(c; s) -> (cos phi c + sin phi s; cos phi s - sin phi c)``. The contact law
and the AFT see the local relative displacements as on the rig; the forces go
back through the transpose of the same linear map (virtual work), so the
Jacobian is exact.

Residual in metres, as :class:`.balance.HarmonicBalance`: per block
``r_p = x_p - A_p^-1 (P_p - W_p^T G_p)`` with ``A_p`` the block's dynamic
stiffness plus the stuck contact stiffness ``W_p^T K_c W_p`` and
``G = f - K_c u``.

Stability: not computed. Hill's method on one sector would only see
perturbations with the same travelling-wave pattern (the harmonic-to-ND
map of this EO); a perturbation at another ND is outside the unknowns.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from ...contact import ContactElements
from ...errors import InputError
from .aft import aft, work_per_cycle
from .balance import Evaluation, PointData
from .fourier import Fourier
from .loops import loop_dissipation, loop_normal_work


@dataclass(frozen=True, eq=False)
class NdBlock:
    """The reduced sector of one ND (real cyclic form).

    ``K``, ``M``, ``C`` (m x m; N/m, kg, N s/m); ``copies`` 1 (ND 0, N/2) or 2;
    the first ``copies * 3 * n_pairs`` coordinates are the platform interface
    DOFs (copy, pair, x/y/z; side 1: the image node's master); ``J`` (m x m,
    two copies) the reduced ``(a; b) -> (b; -a)``; ``exc``, ``out``
    (copies, n_dof, m): rows of the basis at the excitation and output DOFs.
    """

    k: int
    K: np.ndarray
    M: np.ndarray
    C: np.ndarray
    copies: int
    J: np.ndarray | None
    exc: np.ndarray
    out: np.ndarray


@dataclass(frozen=True, eq=False)
class SectorModel:
    """A bladed-disk sector with its damper, reduced per ND, and the contact pairs.

    ``nd``: ``{k: NdBlock}`` for the NDs used; ``Kd, Md, Cd`` the reduced damper,
    ``Bd`` (3 n_pairs, m_d) its contact nodes' displacements; ``rot`` the 3 x 3
    rotation of one sector; ``frames`` (n_pairs, 3, 3) rows t1, t2, n; ``side``;
    contact parameters per pair; ``exc_force`` (n_exc_dof,) N per unit level on
    the excitation DOFs; ``output_names``.
    """

    n_blades: int
    nd: dict[int, NdBlock]
    Kd: np.ndarray
    Md: np.ndarray
    Cd: np.ndarray
    Bd: np.ndarray
    rot: np.ndarray
    frames: np.ndarray
    side: np.ndarray
    mu: np.ndarray
    kt: np.ndarray
    kn: np.ndarray
    n0: np.ndarray
    law: str
    exc_force: np.ndarray
    output_names: tuple[str, ...] = field(default_factory=tuple)

    @property
    def n_pairs(self) -> int:
        return int(len(self.side))


def nd_of_harmonic(h: int, eo: int, n_blades: int) -> tuple[int, int, int]:
    """``(k_h, k', sigma)``: ``k_h = h EO mod N``, its ND ``k' <= N/2`` and the direction
    (``+1`` forward: ``k' = k_h``; ``-1`` backward: ``k' = N - k_h``)."""
    kh = (int(h) * int(eo)) % int(n_blades)
    if 2 * kh <= n_blades:
        return kh, kh, 1
    return kh, n_blades - kh, -1


def wave_of(h: int, eo: int, n_blades: int) -> tuple[int, str]:
    """``(ND, how its wave travels)`` of harmonic ``h`` under engine order ``eo``:
    "standing" at ND 0 and N/2 (a real field), else "forward" (``k_h = h EO mod N <= N/2``)
    or "backward" (its ND is ``N - k_h``)."""
    _, k, sigma = nd_of_harmonic(h, eo, n_blades)
    if k == 0 or 2 * k == n_blades:
        return k, "standing"
    return k, "forward" if sigma > 0 else "backward"


def check_engine_order(eo: object, n_blades: int) -> int:
    """``eo`` as an int >= 0 (one-line error naming ``eo`` otherwise); N >= 2 checked too."""
    if isinstance(n_blades, bool) or not isinstance(n_blades, int | np.integer) or n_blades < 2:
        raise InputError("n_blades", n_blades, "an integer >= 2")
    ok = isinstance(eo, int | np.integer) and not isinstance(eo, bool)
    if not ok and isinstance(eo, float) and eo.is_integer():
        eo, ok = int(eo), True
    if not ok or int(eo) < 0:
        raise InputError("eo", eo, f"an integer >= 0 (0..{n_blades // 2} are the NDs of N)")
    return int(eo)


class _Lin:
    """What the forced response asks of a linear backend: its name."""

    kind = "sector"


class SectorBalance:
    """Residual, exact Jacobian, recovery and energies of the sector problem at one level.

    Offers the methods :class:`workbench.hbm.forced.response.ForcedResponse` and its
    corrector use on :class:`.balance.HarmonicBalance` (dense Jacobian, physical
    space; no Hill's method).
    """

    space = "physical"
    lin = _Lin()

    def __init__(
        self,
        model: SectorModel,
        eo: int,
        fourier: Fourier,
        level: float = 1.0,
        dc_anchor: float = 0.0,
    ):
        if 1 not in fourier.harmonics:
            raise InputError(
                "harmonics", list(fourier.harmonics), "a list that includes 1 (the excitation)"
            )
        self.model, self.fourier = model, fourier
        self.eo = check_engine_order(eo, model.n_blades)
        n_p = model.n_pairs
        self.n_el = n_p
        self.n3 = 3 * n_p
        self.el = ContactElements(
            W=np.eye(self.n3), mu=model.mu, kt1=model.kt, kt2=model.kt, kn=model.kn,
            n0=model.n0, law=model.law,
        )  # fmt: skip
        self.kc = self.el.kc
        # the mean-position anchor of .balance (the damper is held by its contacts alone)
        self.anchor = np.zeros((n_p, 3))
        if fourier.has_dc and dc_anchor > 0:
            self.anchor[:, 0] = dc_anchor * self.el.kt1
            self.anchor[:, 1] = dc_anchor * self.el.kt2
        self.blocks: list[dict] = []
        if fourier.has_dc:
            self.blocks.append(self._block(0, None))
        for h, c, s in fourier.pairs():
            self.blocks.append(self._block(h, (c, s)))
        off = 0
        for b in self.blocks:
            b["sl"] = slice(off, off + b["n"])
            off += b["n"]
        self.N = off
        self.n_s = self.blocks[0]["n"]
        self.nd_of_harmonic = {
            int(h): nd_of_harmonic(h, self.eo, model.n_blades)[1] for h in fourier.harmonics
        }
        self.direction = {
            int(h): nd_of_harmonic(h, self.eo, model.n_blades)[2] for h in fourier.harmonics
        }
        # W: x -> vec(U) (nh * n3), row (component, element, direction)
        self.Wx = np.zeros((fourier.nh * self.n3, self.N))
        for b in self.blocks:
            for r, comp in enumerate(b["rows"]):
                self.Wx[comp * self.n3 : (comp + 1) * self.n3, b["sl"]] = b["W"][
                    r * self.n3 : (r + 1) * self.n3
                ]
        # rigid modes of the damper: which contact rows hold it (lost-contact check)
        lam, vec = sla.eigh(model.Kd, model.Md)
        rig = vec[:, lam <= 1e-10 * max(abs(lam).max(), 1e-300)]
        self.rigid_w = self._damper_rows() @ rig
        self.set_level(level)
        self.stats = dict(
            n_residual=0, t_residual=0.0, n_jacobian=0, t_jacobian=0.0, aft_periods_max=0
        )

    # -- blocks ------------------------------------------------------------------------
    def _damper_rows(self) -> np.ndarray:
        """(n3, m_d): local relative displacement from the damper's coordinates."""
        m = self.model
        out = np.zeros((self.n3, m.Kd.shape[0]))
        for i in range(m.n_pairs):
            out[3 * i : 3 * i + 3] = m.frames[i] @ m.Bd[3 * i : 3 * i + 3]
        return out

    def _block(self, h: int, rows: tuple[int, int] | None) -> dict:
        """One harmonic's unknowns, maps and matrices (``rows``: its cos and sin components)."""
        m = self.model
        kh, k, sigma = nd_of_harmonic(h, self.eo, m.n_blades)
        if k not in m.nd:
            raise InputError("nodal diameter", k, f"one of the model's {sorted(m.nd)}")
        nd = m.nd[k]
        phi = 2 * np.pi * kh / m.n_blades
        n_p, mq, md = m.n_pairs, nd.K.shape[0], m.Kd.shape[0]
        Wd = self._damper_rows()
        R = m.rot
        if rows is None:  # mean: a real ND-0 field, one vector q0 and d0
            n = mq + md
            Pc = np.zeros((3 * n_p, n))
            Pc[:, :mq] = np.eye(3 * n_p, mq)
            W = np.zeros((self.n3, n))
            W[:, mq:] = Wd
            for i in range(n_p):
                plat = Pc[3 * i : 3 * i + 3] if m.side[i] == 0 else R @ Pc[3 * i : 3 * i + 3]
                W[3 * i : 3 * i + 3] -= m.frames[i] @ plat
            return dict(h=0, k=k, sigma=1, n=n, mq=mq, md=md, W=W, rows=(0,), nd=nd, two=False)
        two = nd.copies == 2
        nq = mq if two else 2 * mq
        n = nq + 2 * md
        Pc = np.zeros((3 * n_p, n))  # sector-0 interface cos / sin
        Ps = np.zeros((3 * n_p, n))
        if two:
            Pc[:, : 3 * n_p] = np.eye(3 * n_p)
            Ps[:, 3 * n_p : 6 * n_p] = sigma * np.eye(3 * n_p)
        else:
            Pc[:, : 3 * n_p] = np.eye(3 * n_p)
            Ps[:, mq : mq + 3 * n_p] = np.eye(3 * n_p)
        c, s = np.cos(phi), np.sin(phi)
        W = np.zeros((2 * self.n3, n))
        W[: self.n3, nq : nq + md] = Wd
        W[self.n3 :, nq + md :] = Wd
        for i in range(n_p):
            sl = slice(3 * i, 3 * i + 3)
            if m.side[i] == 0:
                pc, ps = Pc[sl], Ps[sl]
            else:
                pc, ps = R @ (c * Pc[sl] + s * Ps[sl]), R @ (c * Ps[sl] - s * Pc[sl])
            W[sl] -= m.frames[i] @ pc
            W[self.n3 + 3 * i : self.n3 + 3 * i + 3] -= m.frames[i] @ ps
        return dict(
            h=h, k=k, kh=kh, sigma=sigma, n=n, mq=mq, md=md, nq=nq, W=W, rows=rows, nd=nd, two=two
        )

    def _stiffness(self, b: dict, omega: float, deriv: bool = False) -> np.ndarray:
        """The block's dynamic stiffness at ``omega`` (rad/s) with the stuck contacts; with
        ``deriv`` its derivative in ``omega``."""
        m, nd = self.model, b["nd"]
        W = (0.0 if deriv else 1.0) * b["W"]
        if b["rows"] == (0,):
            A = np.zeros((b["n"], b["n"]))
            if not deriv:
                A[: b["mq"], : b["mq"]] = nd.K
                A[b["mq"] :, b["mq"] :] = m.Kd
                A += W.T @ (self.kc.ravel()[:, None] * W)
            return A
        h = b["h"]
        w = h * omega
        dw = float(h)

        def dyn(K, M):
            return -2 * w * dw * M if deriv else K - w**2 * M

        def vis(C):
            return dw * C if deriv else w * C

        A = np.zeros((b["n"], b["n"]))
        mq, md, nq = b["mq"], b["md"], b["nq"]
        if b["two"]:
            A[:mq, :mq] = dyn(nd.K, nd.M) + b["sigma"] * vis(nd.C) @ nd.J
        else:
            q1, q2 = slice(0, mq), slice(mq, 2 * mq)
            A[q1, q1] = A[q2, q2] = dyn(nd.K, nd.M)
            A[q1, q2] = vis(nd.C)
            A[q2, q1] = -vis(nd.C)
        d1, d2 = slice(nq, nq + md), slice(nq + md, nq + 2 * md)
        A[d1, d1] = A[d2, d2] = dyn(m.Kd, m.Md)
        A[d1, d2] = vis(m.Cd)
        A[d2, d1] = -vis(m.Cd)
        if not deriv:
            kc2 = np.concatenate([self.kc.ravel(), self.kc.ravel()])
            A += W.T @ (kc2[:, None] * W)
        return A

    def block_operators(self, i: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(K, M, V)`` of block ``i`` (harmonic ``h``): its dynamic stiffness is
        ``K - (h w)^2 M + h w V`` (``K`` with the stuck contact stiffness, ``V`` the
        velocity operator of the viscous damping; the mean block has ``M = V = 0``)."""
        b = self.blocks[i]
        A0 = self._stiffness(b, 0.0)
        if b["rows"] == (0,):
            z = np.zeros_like(A0)
            return A0, z, z.copy()
        h = b["h"]
        Ap, Am = self._stiffness(b, 1.0 / h), self._stiffness(b, -1.0 / h)
        return A0, A0 - (Ap + Am) / 2, (Ap - Am) / 2

    def contact(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, object]:
        """``(U, G, dG/dU, aft)`` at unknowns x (N,): contact displacement harmonics
        (nh, n3), ``G = f - K_c u`` (nh, n3; mean anchor included), its exact derivative
        (nh n3, nh n3) and the AFT result."""
        U, G, D, res = self._contact(np.asarray(x, dtype=float).ravel())
        return U, G, self._dfull(D), res

    def stuck_frequencies(self, h: int = 1, n: int = 3) -> np.ndarray:
        """The ``n`` lowest frequencies (Hz) of harmonic ``h``'s block with every contact stuck
        and closed, undamped: the linear limit at ND ``k_h`` (each eigenvalue of the real
        block appears twice, the cos/sin pair of one travelling wave)."""
        b = next((b for b in self.blocks if b["h"] == h and b["rows"] != (0,)), None)
        if b is None:
            raise InputError("h", h, f"a harmonic >= 1 of {list(self.fourier.harmonics)}")
        A0, A1, Am = (self._stiffness(b, w) for w in (0.0, 1.0 / h, -1.0 / h))
        M = -(A1 + Am - 2 * A0) / 2
        lam = sla.eigh(A0, 0.5 * (M + M.T), eigvals_only=True)[0::2][:n]
        return np.sqrt(np.clip(lam, 0.0, None)) / (2 * np.pi)

    # -- forcing ---------------------------------------------------------------------
    def set_level(self, level: float) -> None:
        """Excitation level (multiplies the force on the excitation point)."""
        self.level = float(level)
        m = self.model
        P = np.zeros(self.N)
        rest = self.el.force_at_rest().ravel()
        for b in self.blocks:
            if b["rows"] == (0,):
                P[b["sl"]] = b["W"].T @ rest  # the preload balance: u = 0 is the equilibrium
            elif b["h"] == 1:
                g = b["nd"].exc[0].T @ m.exc_force  # copy a (or q_c): the cos force
                P[b["sl"].start : b["sl"].start + b["mq"]] += self.level * g
        self.P = P

    # -- evaluation ------------------------------------------------------------------
    def _solve(self, omega: float, rhs: np.ndarray, deriv_of: np.ndarray | None = None):
        out = np.empty(self.N)
        for b in self.blocks:
            A = self._stiffness(b, omega)
            if deriv_of is not None:  # d(A^-1 rhs)/dw = -A^-1 dA/dw y
                v = -self._stiffness(b, omega, deriv=True) @ deriv_of[b["sl"]]
            else:
                v = rhs[b["sl"]]
            out[b["sl"]] = np.linalg.solve(A, v)
        return out

    def to_u(self, x: np.ndarray) -> np.ndarray:
        """Contact displacement harmonics (nh, n3) of unknowns x (N,)."""
        return (self.Wx @ x).reshape(self.fourier.nh, self.n3)

    def _contact(self, x: np.ndarray):
        f = self.fourier
        U = self.to_u(x)
        res = aft(U.reshape(f.nh, self.n_el, 3), self.el, f)
        self.stats["aft_periods_max"] = max(
            self.stats["aft_periods_max"], int(res.periods.max(initial=0))
        )
        G = res.F - self.kc[None] * U.reshape(f.nh, self.n_el, 3)
        D = res.J.copy()
        hh = np.arange(f.nh)
        for a in range(3):
            D[:, a, hh, a, hh] -= self.kc[:, a][:, None]
        if self.anchor.any():
            G[0] += self.anchor * U.reshape(f.nh, self.n_el, 3)[0]
            for a in range(2):
                D[:, a, 0, a, 0] += self.anchor[:, a]
        return U, G.reshape(f.nh, self.n3), D, res

    def evaluate(self, x: np.ndarray, omega: float) -> Evaluation:
        """The state at unknowns x (N,) and omega (rad/s): AFT and residual (m)."""
        t0 = time.perf_counter()
        x = np.array(x, dtype=float).ravel()
        U, G, D, res = self._contact(x)
        y = self._solve(omega, self.P - self.Wx.T @ G.ravel())
        self.stats["n_residual"] += 1
        self.stats["t_residual"] += time.perf_counter() - t0
        return Evaluation(x, float(omega), self.level, U, G, D, res, y, x - y)

    def at(self, state, omega: float | None = None) -> Evaluation:
        if isinstance(state, Evaluation):
            return state
        return self.evaluate(state, omega)

    def residual(self, x: np.ndarray, omega: float) -> np.ndarray:
        return self.evaluate(x, omega).r

    def residual_omega(self, ev: Evaluation) -> np.ndarray:
        """dr/dw (N,) in m s/rad."""
        return -self._solve(ev.omega, None, deriv_of=ev.Yz)

    def _dfull(self, D: np.ndarray) -> np.ndarray:
        """dG/dU as one (nh n3, nh n3) matrix, rows (component, element, direction)."""
        f = self.fourier
        out = np.zeros((f.nh, self.n_el, 3, f.nh, self.n_el, 3))
        e = np.arange(self.n_el)
        out[:, e, :, :, e, :] = D.transpose(0, 2, 1, 4, 3)
        return out.reshape(f.nh * self.n3, f.nh * self.n3)

    def _hinv_wt(self, omega: float) -> np.ndarray:
        """A^-1 W^T (N, nh n3) block by block."""
        out = np.empty((self.N, self.Wx.shape[0]))
        for b in self.blocks:
            out[b["sl"]] = np.linalg.solve(self._stiffness(b, omega), self.Wx[:, b["sl"]].T)
        return out

    def dense_jacobian(self, ev: Evaluation, dtype=np.float64) -> np.ndarray:
        """dr/dx (N, N), exact: ``I + A^-1 W^T dG/dU W``."""
        t0 = time.perf_counter()
        J = self._hinv_wt(ev.omega) @ (self._dfull(ev.D) @ self.Wx)
        J.flat[:: self.N + 1] += 1.0
        self.stats["n_jacobian"] += 1
        self.stats["t_jacobian"] += time.perf_counter() - t0
        return J.astype(dtype)

    def jvp(self, ev: Evaluation, v: np.ndarray) -> np.ndarray:
        v = np.asarray(v, dtype=float).ravel()
        dG = self._dfull(ev.D) @ (self.Wx @ v)
        return v + self._solve(ev.omega, self.Wx.T @ dG)

    def stuck_solution(self, omega: float) -> np.ndarray:
        """x (N,) of the linear response with every contact stuck and closed."""
        G0 = np.zeros((self.fourier.nh, self.n3))
        if self.fourier.has_dc:
            G0[0] = self.el.force_at_rest().ravel()
        return self._solve(omega, self.P - self.Wx.T @ G0.ravel())

    # -- recovery ---------------------------------------------------------------------
    def outputs(self, x: np.ndarray) -> np.ndarray:
        """Output harmonics (nh, n_out) of sector 0 (m, the sector's frame)."""
        f = self.fourier
        n_out = self.model.nd[self.blocks[0]["k"]].out.shape[1]
        Y = np.zeros((f.nh, n_out))
        for b in self.blocks:
            xb, out, mq = x[b["sl"]], b["nd"].out, b["mq"]
            if b["rows"] == (0,):
                Y[0] = out[0] @ xb[:mq]
            elif b["two"]:
                Y[b["rows"][0]] = out[0] @ xb[:mq]
                Y[b["rows"][1]] = b["sigma"] * out[1] @ xb[:mq]
            else:
                Y[b["rows"][0]] = out[0] @ xb[:mq]
                Y[b["rows"][1]] = out[0] @ xb[mq : 2 * mq]
        return Y

    def _works(self, x: np.ndarray, omega: float) -> tuple[float, float]:
        """(external, viscous) work per cycle on one sector (J)."""
        m = self.model
        w_ext = w_visc = 0.0
        for b in self.blocks:
            if b["rows"] == (0,):
                continue
            xb, mq, md, nq, h = x[b["sl"]], b["mq"], b["md"], b["nq"], b["h"]
            w = h * h * omega  # pi (h omega)^2 / omega per unit x^T C x: h^2 omega
            nd = b["nd"]
            if b["two"]:
                w_visc += np.pi * w * xb[:mq] @ nd.C @ xb[:mq]
            else:
                w_visc += np.pi * w * (xb[:mq] @ nd.C @ xb[:mq] + xb[mq:nq] @ nd.C @ xb[mq:nq])
            for d in (xb[nq : nq + md], xb[nq + md :]):
                w_visc += np.pi * w * d @ m.Cd @ d
            if h == 1:  # pi h (Fc . us - Fs . uc) with Fs = 0 at the excitation point
                exc = nd.exc
                us = b["sigma"] * exc[1] @ xb[:mq] if b["two"] else exc[0] @ xb[mq:nq]
                w_ext += np.pi * self.level * m.exc_force @ us
        return float(w_ext), float(w_visc)

    def point_data(self, state, omega: float | None = None, n_fine: int = 256) -> PointData:
        """Outputs, contact status, friction energies and the energy balance of one sector."""
        f = self.fourier
        ev = self.at(state, omega)
        Y = self.outputs(ev.x)
        work_ext, work_visc = self._works(ev.x, ev.omega)
        Uloc = ev.U.reshape(f.nh, self.n_el, 3)
        wc = work_per_cycle(ev.aft.F, Uloc, f)
        w_f, w_n = float(wc[:, :2].sum()), float(wc[:, 2].sum())
        fric = loop_dissipation(ev.aft.u, ev.aft.f)
        e_loop = float(fric.sum() + loop_normal_work(ev.aft.u, ev.aft.f).sum())
        den = max(abs(work_ext), abs(work_visc) + abs(w_f) + abs(w_n), 1e-300)
        return PointData(
            omega=ev.omega,
            out_harm=Y,
            out_amp=f.amplitude(Y, n_fine),
            out_h1=f.h1_amplitude(Y),
            out_rms=f.rms(Y),
            status=ev.aft.status,
            friction_energy=fric,
            work_ext=work_ext,
            work_visc=work_visc,
            work_friction=w_f,
            work_normal=w_n,
            energy_residual=abs(work_ext - work_visc - w_f - w_n) / den,
            loop_energy=e_loop,
            accuracy=abs(e_loop - w_f - w_n) / den,
            lost_contact=self.lost_contact(ev),
        )

    def lost_contact(self, ev: Evaluation) -> bool:
        """True if at some instant the closed contacts no longer hold the damper."""
        if ev.aft is None or not np.any(ev.aft.n_sep) or self.rigid_w.shape[1] == 0:
            return False
        WV = self.rigid_w
        r = WV.shape[1]
        for pat in np.unique(ev.aft.contact.T, axis=0):
            A = WV[np.repeat(pat, 3)]
            if A.shape[0] < r:
                return True
            s = np.linalg.svd(A, compute_uv=False)
            if s.size < r or s[-1] <= 1e-9 * max(np.abs(WV).max(), 1e-300):
                return True
        return False
