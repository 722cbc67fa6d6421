"""Craig-Bampton reduction of the bladed-disk sector per nodal diameter onto the damper's interface.

The interface of nodal diameter ``k`` is the set of master DOFs (see
:mod:`.cyclic`) of the sector's platform contact nodes: the nodes of side 0
on this sector's right platform half and, for side 1, the left-half nodes
whose images (turned by the sector angle, phase-shifted by ``phi``) are the
next sector's platform nodes. For ``0 < k < N/2`` each node carries the
``a`` and the ``b`` field, so the interface has ``2 x 3 x n_pairs`` DOFs;
for ``k = 0`` and ``N/2`` ``3 x n_pairs``.

Reduced coordinates ``q = (u_B, eta)``: the interface DOFs (physical
displacements, in the order of :attr:`CyclicReduced.boundary_dofs`) and
``n_modes`` fixed-interface modal amplitudes. The static (constraint) modes
make the reduced stiffness exact for any static interface load; the
eigenvalues of ``(K_r, M_r)`` lie above the unreduced ones
(Rayleigh-Ritz) and converge to them as ``n_modes`` grows.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ..errors import check_int
from .cyclic import CyclicSector, eigen, nd_matrices


@dataclass(frozen=True)
class CyclicReduced:
    """One nodal diameter's Craig-Bampton model of the sector (SI)."""

    k: int
    n_blades: int
    K: np.ndarray  # (n_b + n_modes, n_b + n_modes) N/m
    M: np.ndarray  # kg
    boundary_nodes: np.ndarray  # (n_pairs,) sector node of each pair (side 1: this sector's image)
    side: np.ndarray  # (n_pairs,)
    copies: int  # 1 (k = 0, N/2: field a) or 2 (fields a then b)
    n_modes: int

    @property
    def n_boundary(self) -> int:
        """Interface DOFs: copies x n_pairs x 3, ordered (copy, pair, x/y/z)."""
        return self.copies * 3 * len(self.boundary_nodes)


def cb_models(cs: CyclicSector, n_modes: int, comm=None) -> dict[int, CyclicReduced]:
    """:func:`reduce_nd` for every ND 0..N/2 (shared round-robin over ``comm``'s ranks)."""
    nds = cs.nodal_diameters()
    rank, size = (0, 1) if comm is None else (comm.rank, comm.size)
    mine = {k: reduce_nd(cs, k, n_modes) for k in nds[rank::size]}
    if comm is not None and size > 1:
        mine = {k: v for d in comm.allgather(mine) for k, v in d.items()}
    return dict(sorted(mine.items()))


def save_reduced(models: dict[int, CyclicReduced], cs: CyclicSector, path) -> Path:
    """Write every ND's reduced model to one HDF5 file (groups ``nd_<k>``; SI units).

    Beside them: ``rot`` (the sector rotation), ``interface_points`` (m, the platform node
    of each pair in this sector), ``side``, ``n_blades``.
    """
    import h5py

    from ..io import atomic_path

    path = Path(path)
    with atomic_path(path) as tmp, h5py.File(tmp, "w") as h:
        h.attrs["n_blades"] = cs.n_blades
        h.attrs["units"] = "K N/m, M kg, points m"
        h["rot"] = cs.rot
        h["interface_points"] = cs.coords[cs.platform_nodes]
        h["side"] = cs.side
        for k, r in models.items():
            g = h.create_group(f"nd_{k}")
            g["K"], g["M"] = r.K, r.M
            g.attrs["copies"], g.attrs["n_modes"] = r.copies, r.n_modes
            g["boundary_nodes"] = r.boundary_nodes
    return path


def load_reduced(path) -> dict[int, CyclicReduced]:
    """The models written by :func:`save_reduced`, by nodal diameter."""
    import h5py

    out = {}
    with h5py.File(path, "r") as h:
        n_b = int(h.attrs["n_blades"])
        side = h["side"][()]
        for name in h:
            if not name.startswith("nd_"):
                continue
            g = h[name]
            k = int(name[3:])
            out[k] = CyclicReduced(
                k=k,
                n_blades=n_b,
                K=g["K"][()],
                M=g["M"][()],
                boundary_nodes=g["boundary_nodes"][()],
                side=side,
                copies=int(g.attrs["copies"]),
                n_modes=int(g.attrs["n_modes"]),
            )
    return dict(sorted(out.items()))


def reduce_nd(cs: CyclicSector, k: int, n_modes: int = 20) -> CyclicReduced:
    """Craig-Bampton reduction of ND ``k`` onto the platform contact nodes' master DOFs."""
    n_modes = check_int("n_modes", n_modes, 1, 2000)
    Kk, Mk, T = nd_matrices(cs, k)
    mdofs = cs.master_dofs()
    copies = T.shape[0] // (3 * cs.n_nodes)
    pos = np.full(3 * cs.n_nodes, -1, dtype=np.int64)
    pos[mdofs] = np.arange(len(mdofs))
    nodes = np.asarray(cs.platform_nodes)
    one = (3 * nodes[:, None] + np.arange(3)[None, :]).ravel()
    b_one = pos[one]
    if np.any(b_one < 0):
        raise ValueError("a platform contact node is not a master node of the cyclic sector")
    b = np.concatenate([b_one + c * len(mdofs) for c in range(copies)])
    n = Kk.shape[0]
    inner = np.setdiff1d(np.arange(n), b)
    Kii = Kk[inner][:, inner].tocsc()
    Kib = Kk[inner][:, b]
    Mii = Mk[inner][:, inner].tocsc()
    from scipy.sparse.linalg import splu

    lu = splu(Kii)
    psi = -lu.solve(Kib.toarray())
    _, phi = eigen(Kii, Mii, n_modes)
    nb = len(b)
    Tcb = np.zeros((n, nb + phi.shape[1]))
    Tcb[b, :nb] = np.eye(nb)
    Tcb[inner, :nb] = psi
    Tcb[inner, nb:] = phi
    Ts = sp.csr_matrix(Tcb)
    Kr = (Ts.T @ (Kk @ Ts)).toarray()
    Mr = (Ts.T @ (Mk @ Ts)).toarray()
    return CyclicReduced(
        k=int(k),
        n_blades=cs.n_blades,
        K=0.5 * (Kr + Kr.T),
        M=0.5 * (Mr + Mr.T),
        boundary_nodes=nodes,
        side=np.asarray(cs.side),
        copies=copies,
        n_modes=int(phi.shape[1]),
    )


def stuck_nd_system(
    red: CyclicReduced,
    Kd: sp.spmatrix,
    Md: sp.spmatrix,
    damper_nodes: np.ndarray,
    springs: np.ndarray,
    rot: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The reduced sector of ND ``red.k`` with its damper stuck: ``(K, M)`` on
    ``(q_sector, d_a[, d_b])`` (the damper's DOFs once per copy).

    The damper node of pair ``i`` is tied by ``springs[i]`` (3 x 3, disk frame) to its
    platform displacement: for side 0 the interface DOFs of pair ``i``; for side 1 the
    neighbour's node, ``R (cos phi u_a + sin phi u_b)`` (copy a) and
    ``R (cos phi u_b - sin phi u_a)`` (copy b), ``u`` the interface DOFs of the image node
    (``k = 0``, ``N/2``: ``+-R u_a``). The linear limit of the sector's harmonic balance.
    """
    import math

    phi = 2 * math.pi * red.k / red.n_blades
    c, s = math.cos(phi), math.sin(phi)
    n_p = len(red.boundary_nodes)
    n_q = red.K.shape[0]
    n_d = Kd.shape[0]
    cp = red.copies
    n = n_q + cp * n_d
    G = np.zeros((cp * 3 * n_p, n))  # relative displacement damper - platform, per copy/pair
    for a in range(cp):
        for i in range(n_p):
            r = slice(3 * (a * n_p + i), 3 * (a * n_p + i) + 3)
            dn = n_q + a * n_d + 3 * int(damper_nodes[i])
            G[r, dn : dn + 3] += np.eye(3)
            own = [3 * (b * n_p + i) for b in range(cp)]
            if red.side[i] == 0:
                G[r, own[a] : own[a] + 3] -= np.eye(3)
            elif cp == 1:
                G[r, own[0] : own[0] + 3] -= c * rot  # c = +-1 at k = 0, N/2
            else:
                other = 1 - a
                sign = 1.0 if a == 0 else -1.0
                G[r, own[a] : own[a] + 3] -= c * rot
                G[r, own[other] : own[other] + 3] -= sign * s * rot
    Sb = np.zeros((cp * 3 * n_p, cp * 3 * n_p))
    for a in range(cp):
        for i in range(n_p):
            j = 3 * (a * n_p + i)
            Sb[j : j + 3, j : j + 3] = springs[i]
    K = np.zeros((n, n))
    M = np.zeros((n, n))
    K[:n_q, :n_q], M[:n_q, :n_q] = red.K, red.M
    Kd_, Md_ = Kd.toarray(), Md.toarray()
    for a in range(cp):
        sl = slice(n_q + a * n_d, n_q + (a + 1) * n_d)
        K[sl, sl], M[sl, sl] = Kd_, Md_
    K += G.T @ Sb @ G
    return 0.5 * (K + K.T), 0.5 * (M + M.T)
