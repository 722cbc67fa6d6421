"""The bladed-disk sector's harmonic-balance model and its full-disk reference (issue 29).

:func:`build_sector_model` turns a :class:`workbench.geometry.disk_build.DiskSector`
into a :class:`workbench.hbm.core.sector.SectorModel`: per nodal diameter (ND)
a Craig-Bampton reduction of the bladed sector (no damper) onto the platform
contact nodes' master DOFs, the damper reduced onto its contact nodes, the
contact pairs with the rig's stiffness and preload rules.

The fixed-interface modes of an ND with two copies are made closed under
``J (a; b) = (b; -a)`` (the quarter-period shift of a travelling wave): the
modes returned by the eigen solver are completed by their ``J`` images and
re-orthonormalised, so the reduced basis holds every travelling wave it holds
a standing wave of. Without that the reduced sector would not be a tuned disk
and the one-sector harmonic balance would not be exact for it.

:func:`full_disk_system` assembles the whole disk on the cyclic basis: every
ND's reduced coordinates (energy ``N/2 q^T K_k q`` for two copies, ``N q^T K_k
q`` for one) and ``N`` dampers, each tied to sector ``j``'s and ``j + 1``'s
platforms. It is the same discretisation as the sector model, solved by the
ordinary :class:`workbench.hbm.core.balance.HarmonicBalance`: the verification
reference of tests/test_sector_hbm.py.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..contact import ContactElements
from ..errors import InputError
from ..hbm.core.sector import (
    NdBlock,
    SectorModel,
    check_engine_order,
    nd_of_harmonic,
    wave_of,
)
from ..hbm.core.system import System, modal_damping


def _node_of(coords: np.ndarray, p: np.ndarray, what: str) -> int:
    d = np.linalg.norm(coords - np.asarray(p)[None, :], axis=1)
    i = int(np.argmin(d))
    if d[i] > 1e-9 * max(float(np.ptp(coords, axis=0).max()), 1e-300):
        raise InputError(what, f"{d[i]:.3g} m from the nearest node", "a node of the sector mesh")
    return i


def _j_perm(idx: np.ndarray, n_m: int) -> tuple[np.ndarray, np.ndarray]:
    """(partner, sign) of ``J`` on the DOF subset ``idx`` of ``(a; b)`` (n_m DOFs a copy)."""
    pos = {int(g): i for i, g in enumerate(idx)}
    partner = np.array([pos[int(g) + n_m] if g < n_m else pos[int(g) - n_m] for g in idx])
    sign = np.where(idx < n_m, 1.0, -1.0)
    return partner, sign


def nd_basis(cs, k: int, n_modes: int, mats=None) -> tuple[np.ndarray, np.ndarray, int]:
    """The J-closed Craig-Bampton basis of ND ``k``: ``(Phi, pos, copies)``.

    ``Phi`` (copies * n_m, m) maps the reduced coordinates to the master DOFs of
    :func:`workbench.fe.cyclic.nd_matrices` (``(a_M; b_M)`` for two copies); the first
    ``copies * 3 * n_pairs`` columns are the platform interface DOFs (copy, pair, x/y/z),
    the rest the fixed-interface modes. ``pos[g]``: the master index of sector DOF ``g``
    (-1: clamped or slave). The extended sector's field is ``transformation(cs, k) @ Phi
    @ q``. ``mats``: ``nd_matrices(cs, k)`` when at hand.
    """
    from scipy.sparse.linalg import splu

    from ..fe.cyclic import eigen, nd_matrices

    Kk, Mk, T = mats or nd_matrices(cs, k)
    mdofs = cs.master_dofs()
    n_m = len(mdofs)
    copies = T.shape[0] // (3 * cs.n_nodes)
    pos = np.full(3 * cs.n_nodes, -1, dtype=np.int64)
    pos[mdofs] = np.arange(n_m)
    nodes = np.asarray(cs.platform_nodes)
    b_one = pos[(3 * nodes[:, None] + np.arange(3)[None, :]).ravel()]
    b = np.concatenate([b_one + c * n_m for c in range(copies)])
    n = Kk.shape[0]
    inner = np.setdiff1d(np.arange(n), b)
    Kii, Mii = Kk[inner][:, inner].tocsc(), Mk[inner][:, inner].tocsc()
    psi = -splu(Kii).solve(Kk[inner][:, b].toarray())
    _, V = eigen(Kii, Mii, n_modes)
    if copies == 2:  # complete the modes by their J images, then orthonormalise
        partner, sign = _j_perm(inner, n_m)
        W = np.hstack([V, sign[:, None] * V[partner]])
        Mw = W.T @ (Mii @ W)
        s, U = sla.eigh(0.5 * (Mw + Mw.T))
        keep = s > 1e-9 * s.max()
        Wn = W @ (U[:, keep] / np.sqrt(s[keep]))
        Kw = Wn.T @ (Kii @ Wn)
        _, Y = sla.eigh(0.5 * (Kw + Kw.T))
        V = Wn @ Y
    nb = len(b)
    Phi = np.zeros((n, nb + V.shape[1]))
    Phi[b, :nb] = np.eye(nb)
    Phi[inner, :nb] = psi
    Phi[inner, nb:] = V
    return Phi, pos, copies


def reduce_nd_closed(
    cs, k: int, n_modes: int, exc_node: int, out_rows: np.ndarray, basis_out: dict | None = None
):
    """Craig-Bampton of ND ``k`` with a J-closed modal basis: ``(K, M, J, exc, out)``.

    Interface: the platform contact nodes' master DOFs (copy, pair, x/y/z) as in
    :func:`workbench.fe.cyclic_cb.reduce_nd`. ``exc``: (copies, 3, m) rows of the
    basis at ``exc_node``; ``out``: (copies, n_out, m) the rows ``out_rows``
    (n_out, 3) applied to the response node's DOFs (``out_rows`` holds the node).
    The basis: :func:`nd_basis`. ``basis_out``: if a dict, ``basis_out[k]`` receives
    ``T Phi``, the basis on the extended sector (``(a; b)`` stacked for two copies; the
    mistuning projection uses it).
    """
    from ..fe.cyclic import nd_matrices

    mats = nd_matrices(cs, k)
    Kk, Mk, T = mats
    Phi, pos, copies = nd_basis(cs, k, n_modes, mats)
    n_m = int((pos >= 0).sum())
    n = Kk.shape[0]
    K = Phi.T @ (Kk @ Phi)
    M = Phi.T @ (Mk @ Phi)
    if basis_out is not None:
        basis_out[k] = np.asarray(T @ Phi)
    J = None
    if copies == 2:
        partner, sign = _j_perm(np.arange(n), n_m)
        JPhi = sign[:, None] * Phi[partner]
        J = sla.lstsq(Phi, JPhi)[0]
        err = np.abs(Phi @ J - JPhi).max() / max(np.abs(Phi).max(), 1e-300)
        if err > 1e-8:
            raise ValueError(f"the reduced basis of ND {k} is not closed under J ({err:.2e})")
    exc_d = pos[3 * exc_node + np.arange(3)]
    out_nodes = out_rows["dofs"]
    out_d = pos[out_nodes]
    if np.any(exc_d < 0) or np.any(out_d < 0):
        raise ValueError("the excitation or response node is not a master node")
    exc = np.stack([Phi[exc_d + c * n_m] for c in range(copies)])
    out = np.stack([out_rows["rows"] @ Phi[out_d + c * n_m] for c in range(copies)])
    return 0.5 * (K + K.T), 0.5 * (M + M.T), J, exc, out, copies


def _reduce_damper(Kd: sp.spmatrix, Md: sp.spmatrix, dnode: np.ndarray, n_modes: int):
    """Craig-Bampton of the free damper onto its contact nodes: ``(K, M, Bd)``."""
    from scipy.sparse.linalg import splu

    from ..fe.cyclic import eigen

    n = Kd.shape[0]
    b = (3 * np.asarray(dnode)[:, None] + np.arange(3)[None, :]).ravel()
    ub, inv = np.unique(b, return_inverse=True)
    inner = np.setdiff1d(np.arange(n), ub)
    Kd, Md = Kd.tocsr(), Md.tocsr()
    Kii, Mii = Kd[inner][:, inner].tocsc(), Md[inner][:, inner].tocsc()
    psi = -splu(Kii).solve(Kd[inner][:, ub].toarray())
    _, V = eigen(Kii, Mii, n_modes) if n_modes else (None, np.zeros((len(inner), 0)))
    Phi = np.zeros((n, len(ub) + V.shape[1]))
    Phi[ub, : len(ub)] = np.eye(len(ub))
    Phi[inner, : len(ub)] = psi
    Phi[inner, len(ub) :] = V
    K, M = Phi.T @ (Kd @ Phi), Phi.T @ (Md @ Phi)
    Bd = np.zeros((len(b), Phi.shape[1]))
    Bd[np.arange(len(b)), inv] = 1.0
    return 0.5 * (K + K.T), 0.5 * (M + M.T), Bd


def build_sector_model(
    rec,
    contact_params,
    nds: list[int] | None = None,
    n_modes: int = 10,
    n_damper_modes: int = 6,
    zeta: float = 0.005,
    law: str = "decoupled",
    keep_basis: dict | None = None,
) -> SectorModel:
    """The sector harmonic-balance model of a DiskSector ``rec`` at the NDs ``nds``
    (default every ND 0..N/2).

    ``contact_params``: a :class:`workbench.assembly.params.ContactParams` (pair
    stiffness, friction coefficient, centrifugal load); ``zeta``: modal damping
    ratio of the bladed sector's reduced modes of each ND (the damper undamped).
    The excitation is a unit force along ``rec.excitation_direction`` at the
    excitation point; the output the response point's displacement along it.
    ``keep_basis``: if a dict, it receives ``"sector"`` (the bladed sector's
    :class:`~workbench.fe.cyclic.CyclicSector`) and ``"basis"`` (per ND the reduced
    basis on the extended sector, :func:`reduce_nd_closed`'s ``basis_out``).
    """
    from ..assembly.model import preloads
    from ..fe.cyclic import assemble_sector, damper_matrices

    n_b = int(rec.n_blades)
    cs = assemble_sector(rec, with_damper=False)
    nds = list(range(n_b // 2 + 1)) if nds is None else sorted(set(int(k) for k in nds))
    d = np.asarray(rec.excitation_direction, dtype=float)
    exc_node = _node_of(cs.coords, rec.excitation_point, "excitation point")
    resp_node = _node_of(cs.coords, rec.response_point, "response point")
    out_rows = dict(dofs=3 * resp_node + np.arange(3), rows=d[None, :])
    blocks = {}
    bases = None if keep_basis is None else keep_basis.setdefault("basis", {})
    if keep_basis is not None:
        keep_basis["sector"] = cs
    for k in nds:
        K, M, J, exc, out, copies = reduce_nd_closed(cs, k, n_modes, exc_node, out_rows, bases)
        C = modal_damping(M, K, zeta)
        blocks[k] = NdBlock(k, K, M, 0.5 * (C + C.T), copies, J, exc, out)
    Kd, Md, _, dnode = damper_matrices(rec)
    Kdr, Mdr, Bd = _reduce_damper(Kd, Md, dnode, n_damper_modes)
    c = rec.contact
    kt, kn = contact_params.pair_stiffness(c.kind, c.weight)
    beta = float(rec.params["rig"]["platform"]["angle_deg"])
    n0 = preloads(c, contact_params.cf_n, contact_params.mu, beta)
    return SectorModel(
        n_blades=n_b,
        nd=blocks,
        Kd=Kdr,
        Md=Mdr,
        Cd=np.zeros_like(Kdr),
        Bd=Bd,
        rot=np.asarray(cs.rot),
        frames=np.asarray(c.frames, dtype=float),
        side=np.asarray(c.side),
        mu=np.full(c.n_pairs, float(contact_params.mu)),
        kt=np.asarray(kt, dtype=float),
        kn=np.asarray(kn, dtype=float),
        n0=np.asarray(n0, dtype=float),
        law=law,
        exc_force=d,
        output_names=("response_t",),
    )


def nds_for(eo: int, n_blades: int, harmonics: tuple[int, ...]) -> list[int]:
    """The NDs the harmonics of engine order ``eo`` live at (``0`` for the mean)."""
    eo = check_engine_order(eo, n_blades)
    return sorted({nd_of_harmonic(h, eo, n_blades)[1] for h in harmonics})


def full_disk_system(model: SectorModel, eo: int) -> tuple[System, np.ndarray, np.ndarray]:
    """The whole disk on the cyclic basis of ``model`` (every ND 0..N/2 in ``model.nd``):
    ``(System, f1, O)`` with the engine-order-``eo`` force (``f1``, complex, on every
    sector with phase ``j 2 pi eo / N``) and sector 0's output rows ``O``.

    Coordinates: each ND's reduced coordinates in turn, then the ``N`` dampers'.
    Sector ``j``'s interface DOFs are ``sum_k cos(j phi_k) q_k[a] + sin(j phi_k) q_k[b]``.
    """
    n_b = model.n_blades
    eo = check_engine_order(eo, n_b)
    missing = set(range(n_b // 2 + 1)) - set(model.nd)
    if missing:
        raise InputError("model.nd", sorted(model.nd), f"every ND 0..{n_b // 2}")
    n_p, md = model.n_pairs, model.Kd.shape[0]
    offs, off = {}, 0
    for k in sorted(model.nd):
        offs[k] = off
        off += model.nd[k].K.shape[0]
    n_sec = off
    n = n_sec + n_b * md
    K, M, C = np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n))
    iface = []  # iface[j]: (3 n_p, n) sector j's interface DOFs
    for j in range(n_b):
        A = np.zeros((3 * n_p, n))
        for k, blk in model.nd.items():
            ph = 2 * math.pi * k * j / n_b
            o = offs[k]
            A[:, o : o + 3 * n_p] += math.cos(ph) * np.eye(3 * n_p)
            if blk.copies == 2:
                A[:, o + 3 * n_p : o + 6 * n_p] += math.sin(ph) * np.eye(3 * n_p)
        iface.append(A)
    f1 = np.zeros(n, dtype=complex)
    O = np.zeros((model.nd[0].out.shape[1], n))
    for k, blk in model.nd.items():
        o, m = offs[k], blk.K.shape[0]
        s = n_b / 2 if blk.copies == 2 else n_b
        sl = slice(o, o + m)
        K[sl, sl], M[sl, sl], C[sl, sl] = s * blk.K, s * blk.M, s * blk.C
        O[:, sl] = blk.out[0]
        for j in range(n_b):
            ph = 2 * math.pi * k * j / n_b
            rows = math.cos(ph) * blk.exc[0]
            if blk.copies == 2:
                rows = rows + math.sin(ph) * blk.exc[1]
            f1[sl] += np.exp(2j * math.pi * eo * j / n_b) * (rows.T @ model.exc_force)
    W = np.zeros((3 * n_p * n_b, n))
    for j in range(n_b):
        sl = slice(n_sec + j * md, n_sec + (j + 1) * md)
        K[sl, sl], M[sl, sl], C[sl, sl] = model.Kd, model.Md, model.Cd
        for i in range(n_p):
            r = slice(3 * (j * n_p + i), 3 * (j * n_p + i) + 3)
            F = model.frames[i]
            W[r, sl] += F @ model.Bd[3 * i : 3 * i + 3]
            if model.side[i] == 0:
                plat = iface[j][3 * i : 3 * i + 3]
            else:
                plat = model.rot @ iface[(j + 1) % n_b][3 * i : 3 * i + 3]
            W[r] -= F @ plat
    tile = np.tile
    contacts = ContactElements(
        W=sp.csr_matrix(W),
        mu=tile(model.mu, n_b),
        kt1=tile(model.kt, n_b),
        kt2=tile(model.kt, n_b),
        kn=tile(model.kn, n_b),
        n0=tile(model.n0, n_b),
        law=model.law,
    )
    return System(M=M, K=K, C=C, contacts=contacts), f1, O


def sector_forced_response(
    model: SectorModel,
    eo: int,
    force_n: float,
    band_hz: tuple[float, float] | None = None,
    harmonics: tuple[int, ...] = (0, 1, 2, 3),
    nt: int | None = None,
    options=None,
    label: str = "",
):
    """The forced response of one sector under engine order ``eo``: a
    :class:`workbench.hbm.forced.branch.Branch` (output 0: the response point's
    displacement along the excitation direction, m) and a dict saying at which ND
    each harmonic lives and in which direction (forward/backward).

    ``force_n``: the harmonic-1 force amplitude (N) on the excitation point of every
    sector, sector ``j`` lagging by ``j 2 pi eo / N``. ``band_hz`` defaults to 0.9..1.1
    times the first stuck frequency at ``eo``'s ND. No Hill's stability (the branch's
    ``stability`` is "unknown"): see :mod:`workbench.hbm.core.sector`.
    """
    import dataclasses

    from ..errors import check_range
    from ..hbm.core.fourier import Fourier, default_nt
    from ..hbm.core.options import SolverOptions
    from ..hbm.core.sector import SectorBalance
    from ..hbm.forced.response import follow_balance

    eo = check_engine_order(eo, model.n_blades)
    force_n = check_range("force", force_n, 0.0, lo_open=True, unit="N")
    opts = dataclasses.replace(options or SolverOptions(), stability=False)
    fourier = Fourier(tuple(harmonics), nt or default_nt(tuple(harmonics)))
    hb = SectorBalance(model, eo, fourier, force_n, opts.dc_anchor)
    if band_hz is None:
        f0 = float(hb.stuck_frequencies(1, 1)[0])
        band_hz = (0.9 * f0, 1.1 * f0)
    lo, hi = (float(v) for v in band_hz)
    check_range("band_hz[0]", lo, 0.0, lo_open=True, unit="Hz")
    check_range("band_hz[1]", hi, lo, lo_open=True, unit="Hz")
    br = follow_balance(hb, (lo, hi), opts, model.output_names, label=label or f"EO {eo}")
    info = {
        "n_blades": model.n_blades,
        "eo": eo,
        "nd_of_harmonic": {str(h): hb.nd_of_harmonic[h] for h in fourier.harmonics},
        "direction_of_harmonic": {
            str(h): wave_of(h, eo, model.n_blades)[1] for h in fourier.harmonics
        },
        "stuck_hz": hb.stuck_frequencies(1, 3).tolist(),
        "stability": "not computed (one sector's Hill matrix only sees its own travelling wave)",
    }
    return br, info


def sector_backbone(
    model: SectorModel,
    eo: int,
    amplitude_range: tuple[float, float] | None = None,
    relative_range: tuple[float, float] = (0.05, 300.0),
    harmonics: tuple[int, ...] = (0, 1, 2, 3),
    nt: int | None = None,
    mode: int = 0,
    **options,
):
    """The nonlinear mode (EPMC backbone) of the tuned disk's family ``mode`` (0: the first)
    at engine order ``eo``'s ND, on one sector's unknowns: a
    :class:`workbench.hbm.nlmodes.record.NlModeBranch` (amplitude: one sector's modal
    amplitude, sqrt(kg) m; the whole disk's is ``sqrt(N)`` times larger). ``options``: those
    of :func:`workbench.hbm.nlmodes.sector_epmc.sector_nonlinear_mode`."""
    from ..hbm.core.fourier import default_nt
    from ..hbm.nlmodes.sector_epmc import sector_nonlinear_mode

    eo = check_engine_order(eo, model.n_blades)
    h = tuple(harmonics)
    return sector_nonlinear_mode(
        model, eo, mode, amplitude_range, relative_range, h, nt or default_nt(h), **options
    )
