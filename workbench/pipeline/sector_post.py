"""What a bladed-disk sector model gives besides its forced response (issue 29, item 5).

:func:`nd_screen`: the rig's coupling screen (:mod:`workbench.assembly.screen`)
at one nodal diameter (ND). The sector's harmonic-1 block at that ND (engine
order ``k``, a forward wave; :class:`workbench.hbm.core.sector.SectorBalance`)
is taken in its two linear limits, as on the rig:

* *stuck*: every pair stuck and closed (springs ``kt, kt, kn``);
* *sliding*: the tangential springs removed, the normal springs kept;

and in each the *family* mode is the one with the largest modal receptance
from the excitation to the response point (the rig's rule,
:func:`workbench.assembly.linear.family_frequency`). The real block of a
travelling wave holds each frequency twice (the cos/sin pair), so the
receptance of a frequency is taken over its whole eigenspace: ``|R P f| /
lambda`` with ``P`` the (mass-orthogonal) projector on the space, ``f`` the
cos force, ``R`` the response point's cos and sin rows; for a single mode this
is the rig's ``|r phi| |f phi| / lambda``. Then ``k2/k = 1 - (f_sliding /
f_stuck)^2``, the share of the stuck family mode's modal stiffness the
sticking damper adds.

:func:`peak_field`: the sector's displacement field at a solved point of
:class:`SectorBalance` (its unknowns ``x``), expanded exactly through each
harmonic's ND basis (:func:`workbench.pipeline.sector.nd_basis` and the cyclic
transformation): per harmonic the cos and sin fields of sector 0 on every node
of the sector mesh.

:func:`full_disk_stability`: Hill's stability of one sector solution as a
state of the whole disk (every ND, every damper), which a sector's own Hill
matrix cannot give.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

CLUSTER_REL = 1e-7  # eigenvalues this close (relative) are one frequency of a travelling wave


def _block_matrices(model, k: int):
    """``(K_base, M, W, kc2, f, R)`` of the harmonic-1 block at ND ``k``: the block's
    stiffness without contact springs, its mass, the contact map (cos rows, then sin), the
    stuck springs on those rows, the unit cos force and the response's cos/sin rows."""
    from ..hbm.core.fourier import Fourier, default_nt
    from ..hbm.core.sector import SectorBalance

    hb = SectorBalance(model, int(k), Fourier((1,), default_nt((1,))), 1.0)
    (b,) = hb.blocks
    A0 = hb._stiffness(b, 0.0)
    A1, Am = hb._stiffness(b, 1.0), hb._stiffness(b, -1.0)
    M = -(A1 + Am - 2 * A0) / 2
    kc2 = np.concatenate([hb.kc.ravel(), hb.kc.ravel()])
    W = b["W"]
    K = A0 - W.T @ (kc2[:, None] * W)
    f = hb.P[b["sl"]]
    mq, out = b["mq"], b["nd"].out
    R = np.zeros((2, b["n"]))
    R[0, :mq] = out[0][0]
    if b["two"]:
        R[1, :mq] = b["sigma"] * out[1][0]
    else:
        R[1, mq : 2 * mq] = out[0][0]
    return 0.5 * (K + K.T), 0.5 * (M + M.T), W, kc2, f, R


def _family(K: np.ndarray, M: np.ndarray, f: np.ndarray, R: np.ndarray) -> tuple[float, int]:
    """(frequency in Hz, 1-based number among the distinct elastic frequencies) of the
    eigenspace of ``(K, M)`` with the largest receptance ``|R P f| / lambda``."""
    lam, phi = sla.eigh(K, M)
    lam = np.maximum(lam, 0.0)
    scale = np.sqrt(max(lam.max(), 1e-300))
    elastic = np.flatnonzero(np.sqrt(lam) > 1e-6 * scale)
    best, best_c, number, i = None, -1.0, 0, 0
    while i < len(elastic):
        j = i
        while (
            j + 1 < len(elastic)
            and lam[elastic[j + 1]] - lam[elastic[i]] <= CLUSTER_REL * (lam[elastic[i]])
        ):
            j += 1
        cols = elastic[i : j + 1]
        number += 1
        P = phi[:, cols]
        c = float(np.linalg.norm(R @ (P @ (P.T @ f)))) / lam[elastic[i]]
        if c > best_c:
            best, best_c = (float(np.sqrt(lam[elastic[i]]) / (2 * np.pi)), number), c
        i = j + 1
    if best is None:
        raise ValueError("the block has no elastic mode")
    return best


def _onsets(model, k: int, f_stuck_hz: float, zeta: float, law: str):
    """``(F_slip, pair, F_sep, pair, r)``: the rig's slip and separation onset forces
    (:func:`workbench.assembly.screen.onset_forces`: per pair ``T(t) = F tau(t)``, ``N(t) =
    N0 + F nu(t)`` from the stuck linear response per newton) on the harmonic-1 block at ND
    ``k``, over the same +-4 half-power bandwidths about the stuck family, and the stuck
    peak receptance ``r`` (m/N, harmonic-1 amplitude at the response point)."""
    from ..assembly.screen import N_FREQ, N_TIME
    from ..hbm.core.fourier import Fourier, default_nt
    from ..hbm.core.sector import SectorBalance

    hb = SectorBalance(model, int(k), Fourier((1,), default_nt((1,))), 1.0)
    (b,) = hb.blocks
    f = hb.P[b["sl"]]
    _, _, W, _, _, R = _block_matrices(model, k)
    n3 = hb.n3
    w0 = 2 * np.pi * f_stuck_hz
    omegas = w0 * (1 + 4 * max(zeta, 1e-4) * np.linspace(-1, 1, N_FREQ))
    X = np.stack([np.linalg.solve(hb._stiffness(b, w), f) for w in omegas])  # (nw, n)
    resp = float(np.hypot(*(R @ X.T)).max())
    uc, us = (X @ W[:n3].T).reshape(len(omegas), -1, 3), (X @ W[n3:].T).reshape(len(omegas), -1, 3)
    th = np.linspace(0, 2 * np.pi, N_TIME, endpoint=False)
    ut = (
        uc[:, :, None, :] * np.cos(th)[None, None, :, None]
        + us[:, :, None, :] * np.sin(th)[None, None, :, None]
    )  # (nw, np, nt, 3)
    kt, kn = model.kt[None, :, None], model.kn[None, :, None]
    t1, t2, nu = kt * ut[..., 0], kt * ut[..., 1], -kn * ut[..., 2]
    tau = np.maximum(np.abs(t1), np.abs(t2)) if law == "decoupled" else np.hypot(t1, t2)
    mu, n0 = model.mu[None, :, None], model.n0[None, :, None]
    den = tau - mu * nu
    with np.errstate(divide="ignore", invalid="ignore"):
        f_slip = np.where(den > 1e-300, mu * n0 / den, np.inf).min(axis=(0, 2))
        f_sep = np.where(-nu > 1e-300, n0 / (-nu), np.inf).min(axis=(0, 2))
    i, j = int(np.argmin(f_slip)), int(np.argmin(f_sep))
    return float(f_slip[i]), i, float(f_sep[j]), j, resp


def nd_screen(model, k: int, zeta: float | None = None) -> dict:
    """The coupling screen at ND ``k`` (module docstring): ``{"nd", "stuck_hz",
    "sliding_hz", "k2_over_k", "stuck_over_sliding", "stuck_mode", "sliding_mode"}``
    (``*_mode``: which distinct elastic frequency of the block is the family, 1 = lowest).
    With ``zeta`` (the sector's modal damping ratio) also the rig's onset forces per blade
    (N; None: never): ``f_slip_n`` (the first pair reaches mu N(t) in the stuck linear
    response), ``f_sep_n`` (the first normal load reaches zero), their pairs, ``f_cap_n =
    (4 / pi) Q k2/k f_slip_n`` with ``Q = 1 / (2 zeta)``, and ``stuck_peak_m_per_n``."""
    K, M, W, kc2, f, R = _block_matrices(model, k)
    kn_only = kc2.copy().reshape(-1, 3)
    kn_only[:, :2] = 0.0
    kn_only = kn_only.ravel()
    f_st, i_st = _family(K + W.T @ (kc2[:, None] * W), M, f, R)
    f_sl, i_sl = _family(K + W.T @ (kn_only[:, None] * W), M, f, R)
    k2k = 1.0 - (f_sl / f_st) ** 2
    out = {
        "nd": int(k),
        "stuck_hz": f_st,
        "sliding_hz": f_sl,
        "k2_over_k": k2k,
        "stuck_over_sliding": f_st / f_sl,
        "stuck_mode": i_st,
        "sliding_mode": i_sl,
    }
    if zeta is not None:
        fs, i_s, fp, i_p, r = _onsets(model, k, f_st, zeta, model.law)
        fin = np.isfinite
        out.update(
            stuck_peak_m_per_n=r,
            f_slip_n=fs if fin(fs) else None,
            slip_pair=i_s if fin(fs) else -1,
            f_sep_n=fp if fin(fp) else None,
            sep_pair=i_p if fin(fp) else -1,
            # the rig's single-mode estimate of the force up to which the peak stays level
            f_cap_n=(4 / np.pi) / (2 * zeta) * max(k2k, 0.0) * fs if fin(fs) else None,
        )
    return out


def peak_field(cs, model, eo: int, harmonics: tuple[int, ...], x: np.ndarray, n_modes: int):
    """The sector's displacement harmonics at the unknowns ``x`` of a
    :class:`~workbench.hbm.core.sector.SectorBalance` of ``model`` at engine order ``eo``:
    ``{h: (cos, sin)}``, each (n_nodes, 3) in m on the nodes of ``cs`` (the sector alone,
    ``assemble_sector(rec, with_damper=False)``; clamped nodes zero). Harmonic 0 has only a
    cos (mean) field. ``n_modes``: the fixed-interface modes per ND the model was built with
    (the basis is rebuilt, :func:`workbench.pipeline.sector.nd_basis`, deterministic)."""
    from ..fe.cyclic import transformation
    from ..hbm.core.fourier import Fourier, default_nt
    from ..hbm.core.sector import SectorBalance
    from .sector import nd_basis

    hs = tuple(int(h) for h in harmonics)
    hb = SectorBalance(model, eo, Fourier(hs, default_nt(hs)), 1.0)
    x = np.asarray(x, dtype=float)
    if x.shape != (hb.N,):
        raise ValueError(f"x has {x.shape} entries, the sector problem {hb.N}")
    bases: dict[int, np.ndarray] = {}
    n = cs.n_nodes
    out = {}
    for b in hb.blocks:
        k = b["k"]
        if k not in bases:
            Phi, _, _ = nd_basis(cs, k, n_modes)
            bases[k] = transformation(cs, k) @ Phi  # extended-sector fields, (copies 3n, m)
        TP = bases[k]
        xb, mq = x[b["sl"]], b["mq"]
        if b["rows"] == (0,):
            out[0] = ((TP @ xb[:mq]).reshape(n, 3), np.zeros((n, 3)))
        elif b["two"]:
            ab = TP @ xb[:mq]
            out[b["h"]] = (ab[: 3 * n].reshape(n, 3), b["sigma"] * ab[3 * n :].reshape(n, 3))
        else:
            out[b["h"]] = (
                (TP @ xb[:mq]).reshape(n, 3),
                (TP @ xb[mq : 2 * mq]).reshape(n, 3),
            )
    return out


def sector_vtk(rec, coords: np.ndarray | None = None):
    """``(points, cells, celltypes)`` of a DiskSector's mesh as VTK arrays (quadratic
    tetrahedra), its points in the order of the sector's P2 nodes (``assemble_sector``'s
    node numbering); ``coords`` (that sector's node coordinates) are checked against them."""
    from dolfinx import fem, plot
    from mpi4py import MPI

    from ..fe.mesh import read_msh

    mesh = read_msh(rec.sector_msh, MPI.COMM_SELF).mesh
    V = fem.VectorFunctionSpace(mesh, ("CG", 2))
    cells, types, x = plot.create_vtk_mesh(V)
    x = np.asarray(x, dtype=float)
    if coords is not None:
        c = np.asarray(coords)[: len(x)]
        if c.shape != x.shape or np.abs(c - x).max() > 1e-9 * np.ptp(x, axis=0).max():
            raise ValueError("the VTK points are not the sector's nodes in order")
    return x, np.asarray(cells, dtype=np.int64), np.asarray(types, dtype=np.uint8)


def period_max(fields: dict, n_t: int = 64) -> np.ndarray:
    """Per node the largest ``|u(t)|`` (m) over ``n_t`` instants of the period of the
    harmonics ``fields`` (``{h: (cos, sin)}``, each (n, 3), as :func:`peak_field`)."""
    t = 2 * np.pi * np.arange(n_t) / n_t
    best = np.zeros(next(iter(fields.values()))[0].shape[0])
    for tj in t:
        u = sum(c * np.cos(h * tj) + s * np.sin(h * tj) for h, (c, s) in fields.items())
        best = np.maximum(best, np.linalg.norm(u, axis=1))
    return best


HILL_EXPONENTS = 600  # ARPACK's cap on the exponents of the whole disk's Hill problem


def full_disk_stability(
    model, eo: int, harmonics: tuple[int, ...], force_n: float, x: np.ndarray, freq_hz: float
) -> dict:
    """Hill's stability of one sector solution as a state of the whole disk.

    The sector's unknowns ``x`` (a :class:`~workbench.hbm.core.sector.SectorBalance`
    solution at ``freq_hz``, engine order ``eo``) give sector 0's contact motion; damper
    ``j``'s is the same turned by ``j phi_h`` on each harmonic ``h`` (``phi_h = 2 pi k_h /
    N``), the travelling wave. On the whole disk of :func:`.sector.full_disk_system` (every
    ND, ``N`` dampers; the ordinary :class:`~workbench.hbm.core.balance.HarmonicBalance`,
    condensed on the contact DOFs) that state is polished by Newton (the AFT samples the
    period at ``default_nt`` instants, which a sector shift of ``2 pi EO / N`` need not
    fall on: the two discrete problems differ by the AFT's sampling, about 1e-4 relative),
    then Hill's method decides (ARPACK, up to :data:`HILL_EXPONENTS` exponents). Every
    perturbation of the disk is seen, not only the sector's own travelling wave.

    Returns a dict: ``verdict`` ("stable", "unstable" or "unknown"), ``max_real`` (1/s)
    and ``max_real_over_w``, ``count_ok``, ``note``, ``mapped_residual`` and
    ``polished_residual`` (largest residual entry over the largest unknown), ``disk_peak_m``
    (the response point's amplitude on the polished state) and the time it took."""
    import dataclasses
    import time

    from ..hbm.core.balance import HarmonicBalance
    from ..hbm.core.fourier import Fourier, default_nt
    from ..hbm.core.options import SolverOptions
    from ..hbm.core.sector import SectorBalance, nd_of_harmonic
    from ..hbm.forced.small import make_corrector
    from ..hbm.stability.along_path import StabilityPath
    from ..hbm.stability.hill import STABLE, UNSTABLE
    from .sector import full_disk_system

    t0 = time.perf_counter()
    hs = tuple(int(h) for h in harmonics)
    fo = Fourier(hs, default_nt(hs))
    opts = dataclasses.replace(
        SolverOptions(), n_floquet=60, n_floquet_max=HILL_EXPONENTS, hill_dense_limit=0
    )
    sec = SectorBalance(model, eo, fo, force_n, opts.dc_anchor)
    U = sec.to_u(np.asarray(x, dtype=float))  # (nh, 3 n_pairs), sector 0
    n_b, k = model.n_blades, [int(v) for v in fo.k]
    Uf = np.zeros((fo.nh, n_b, sec.n3))
    for j in range(n_b):
        for h in hs:
            r = k.index(h)
            if h == 0:
                Uf[r, j] = U[r]
                continue
            ph = 2 * np.pi * nd_of_harmonic(h, eo, n_b)[0] * j / n_b
            c, s = U[r], U[r + 1]
            Uf[r, j] = np.cos(ph) * c + np.sin(ph) * s
            Uf[r + 1, j] = np.cos(ph) * s - np.sin(ph) * c
    system, f1, O = full_disk_system(model, eo)
    hf = HarmonicBalance(system, f1, fo, O, force_n, "condensed", "auto", opts.dc_anchor)
    xf = Uf.reshape(fo.nh, -1)[:, hf.act].ravel()
    w = 2 * np.pi * float(freq_hz)
    scale = max(np.abs(xf).max(), 1e-300)
    ev = hf.evaluate(xf, w)
    mapped = float(np.abs(ev.r).max() / scale)
    for _ in range(30):
        if np.abs(ev.r).max() <= 1e-12 * scale:
            break
        xf = xf - np.linalg.solve(hf.dense_jacobian(ev), ev.r)
        ev = hf.evaluate(xf, w)
    polished = float(np.abs(ev.r).max() / scale)
    st = StabilityPath(hf, make_corrector(hf, opts, scale, w), opts).check(ev)
    verdict = {STABLE: "stable", UNSTABLE: "unstable"}.get(st.verdict, "unknown")
    if polished > 1e-8:
        verdict, note = "unknown", f"Newton did not converge on the disk ({polished:.1e})"
    else:
        note = st.note
    return {
        "verdict": verdict,
        "max_real": float(st.max_real),
        "max_real_over_w": float(st.max_real) / w,
        "count_ok": bool(st.count_ok),
        "note": note,
        "mapped_residual": mapped,
        "polished_residual": polished,
        "disk_peak_m": float(hf.point_data(ev).out_amp[0]),
        "wall_s": time.perf_counter() - t0,
    }
