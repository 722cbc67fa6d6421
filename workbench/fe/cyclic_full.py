"""The whole disk from N rotated copies of one extended sector: the check of the cyclic modes.

Independent of the cyclic elimination of :mod:`.cyclic`: every sector's
nodes are turned by ``j alpha`` into the global frame, sector matrices are
turned alike (``K_j = Q_j K Q_j^T``, ``Q_j`` the block-diagonal rotation),
and coincident nodes of the bladed disk (the right face of sector ``j`` and
the left face of sector ``j + 1``; the image nodes of sector ``j`` and the
platform nodes of sector ``j + 1``) are merged by their coordinates. Damper
nodes are never merged (a damper node and its platform node share a point).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from ..errors import SolveError
from .cyclic import MATCH_REL_TOL, CyclicSector, _node_dofs


def full_disk_matrices(
    cs: CyclicSector, sector_K: list | None = None
) -> tuple[sp.csr_matrix, sp.csr_matrix, np.ndarray]:
    """``(K, M, coords)`` of the whole disk in the global frame (clamped nodes removed).

    ``sector_K``: optional per-sector stiffness matrices (``N`` of them, each shaped like
    ``cs.K``, sector ``j``'s own frame) instead of ``cs.K`` for every sector: a mistuned disk.
    """
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    from ..geometry.disk import rotation

    N, n = cs.n_blades, cs.n_nodes
    pts = np.vstack([cs.coords @ rotation(j * cs.alpha).T for j in range(N)])
    merge = np.tile(cs.body != 1, N)  # bladed-disk and image nodes merge; damper nodes do not
    size = float(np.ptp(pts, axis=0).max())
    idx = np.flatnonzero(merge)
    pairs = cKDTree(pts[idx]).query_pairs(MATCH_REL_TOL * size, output_type="ndarray")
    G = sp.coo_matrix(
        (np.ones(len(pairs)), (idx[pairs[:, 0]], idx[pairs[:, 1]])), shape=(N * n, N * n)
    )
    n_glob, label = connected_components(G, directed=False)
    counts = np.bincount(label[idx], minlength=n_glob)[label[idx]]
    image = np.tile(cs.body == 2, N)
    if np.any(counts[image[idx]] != 2):
        raise SolveError("full disk: an image node did not land on exactly one platform node")
    fixed_glob = np.unique(label[(np.arange(N)[:, None] * n + cs.fixed[None, :]).ravel()])
    keep = np.ones(n_glob, bool)
    keep[fixed_glob] = False
    new = np.full(n_glob, -1, dtype=np.int64)
    new[keep] = np.arange(keep.sum())
    n_free = int(keep.sum())
    Ks, Ms = [], []
    for j in range(N):
        Q = sp.block_diag([rotation(j * cs.alpha)] * n, format="csr")
        nodes = new[label[j * n : (j + 1) * n]]
        ok = nodes >= 0
        rows = _node_dofs(np.flatnonzero(ok))
        P = sp.csr_matrix(
            (np.ones(len(rows)), (rows, _node_dofs(nodes[ok]))), shape=(3 * n, 3 * n_free)
        )
        Kj = Q @ (cs.K if sector_K is None else sector_K[j]) @ Q.T
        Mj = Q @ cs.M @ Q.T
        Ks.append(P.T @ Kj @ P)
        Ms.append(P.T @ Mj @ P)
    K, M = sum(Ks[1:], Ks[0]), sum(Ms[1:], Ms[0])
    coords = np.zeros((n_glob, 3))
    coords[label] = pts
    return K.tocsr(), M.tocsr(), coords[keep]


def match_spectra(full_hz: np.ndarray, nd_hz: dict[int, np.ndarray], n_blades: int) -> dict:
    """Compare the full disk's lowest frequencies with the union of the cyclic ones.

    ``nd_hz[k]``: the lowest distinct frequencies of nodal diameter k (a pair
    counted twice for 0 < k < N/2). Compared below the lowest frequency that
    every nodal diameter's list still covers. Returns the worst relative
    difference, the number of frequencies compared and the pairs.
    """
    union = []
    for k, f in nd_hz.items():
        mult = 1 if k == 0 or 2 * k == n_blades else 2
        union += [(x, k) for x in f for _ in range(mult)]
    union.sort()
    cover = min(f[-1] for f in nd_hz.values())
    cmp = [(x, k) for x, k in union if x < cover * (1 - 1e-6)]
    m = min(len(cmp), len(full_hz))
    ref = np.array([x for x, _ in cmp[:m]])
    rel = np.abs(np.asarray(full_hz[:m]) - ref) / np.maximum(ref, 1e-300)
    return dict(
        worst_rel=float(rel.max()) if m else math.nan,
        n_compared=m,
        nd=[k for _, k in cmp[:m]],
        cyclic_hz=ref.tolist(),
        full_hz=list(map(float, full_hz[:m])),
    )
