"""Contact pads: tie the nodes around each contact point to it, so a pair loads a patch.

A contact pair acts on one mesh node. Refined around that node, a 3-D
elastic body gives under it without limit (a point load's displacement
grows as 1/h; a line of points acts as a line load, log(1/h)), so the
contact's effective stiffness, its frequencies and its friction energy
follow the mesh (docs/notes/energy_convergence.md). A pad of a fixed size
removes that: the nodes of the body inside the pad and the contact node
move as one rigid body (a penalty on their motion that is not rigid, added
to ``K`` before the reduction), so the pair loads a patch of fixed size
whose compliance converges as the mesh resolves it.

The pad of a pair, in its frame (t1, t2, n) at its point p:

* line contacts: along the line, the pair's tributary length times
  ``FILL`` (so neighbouring pads never touch); across the line and in
  depth, within ``width / 2`` of the line;
* face contacts: a square of the pair's tributary area times ``FILL``
  (side ``FILL sqrt(area)``) in the face; in depth, within ``width / 2``.

The pad translates and rotates freely (a body's rigid motions keep zero
stiffness). ``width = 0``: no pad (the point alone, the default).
"""

from __future__ import annotations

import numpy as np

FILL = 0.9  # the share of the tributary length (area side) a pad covers along the contact
# the tie's stiffness, relative to the body's median diagonal stiffness: 1e5 made the reduced
# wedge's eigenvalues span 1.2e13, beyond the 1e12 the harmonic balance resolves
ALPHA = 1e3


def pad_members(
    coords: np.ndarray,
    points: np.ndarray,
    frames: np.ndarray,
    weight: np.ndarray,
    kind: str,
    width: float,
) -> list[np.ndarray]:
    """Per contact point, the indices into ``coords`` (n, 3) of the nodes in its pad.

    ``points`` (m, 3), ``frames`` (m, 3, 3) rows t1, t2, n, ``weight`` (m,) tributary
    length (m, lines) or area (m^2, faces), ``width`` m. The contact node itself is
    excluded (the caller ties the others to it); lines run along the principal axis of
    the points of each line (t1 and t2 need not follow it).
    """
    from scipy.spatial import cKDTree

    out: list[np.ndarray] = []
    if width <= 0 or len(coords) == 0:
        return [np.zeros(0, dtype=np.int64) for _ in range(len(points))]
    tree = cKDTree(coords)
    for i, p in enumerate(points):
        n = frames[i, 2] / np.linalg.norm(frames[i, 2])
        if kind == "line":
            half_len = 0.5 * FILL * float(weight[i])
            d = _line_direction(points, frames, i)
            reach = np.hypot(half_len, 0.5 * width)
            cand = np.asarray(tree.query_ball_point(p, reach), dtype=np.int64)
            r = coords[cand] - p
            along = r @ d
            across = np.linalg.norm(r - np.outer(along, d), axis=1)
            keep = (np.abs(along) <= half_len) & (across <= 0.5 * width)
        else:
            half = 0.5 * FILL * float(np.sqrt(weight[i]))
            t1 = frames[i, 0] / np.linalg.norm(frames[i, 0])
            t2 = np.cross(n, t1)
            reach = float(np.sqrt(2 * half**2 + (0.5 * width) ** 2))
            cand = np.asarray(tree.query_ball_point(p, reach), dtype=np.int64)
            r = coords[cand] - p
            keep = (
                (np.abs(r @ t1) <= half) & (np.abs(r @ t2) <= half) & (np.abs(r @ n) <= 0.5 * width)
            )
        sel = cand[keep]
        dist = np.linalg.norm(coords[sel] - p, axis=1)
        out.append(np.sort(sel[dist > 1e-12]))
    return out


def _line_direction(points: np.ndarray, frames: np.ndarray, i: int) -> np.ndarray:
    """The unit direction of the contact line through point i: the principal axis of the
    points lying on a common line with it (same normal, within 1e-6 of that line)."""
    n = frames[i, 2] / np.linalg.norm(frames[i, 2])
    same = np.flatnonzero(np.abs(frames[:, 2] @ n - 1.0) < 1e-9)
    pts = points[same]
    if len(pts) < 2:
        return frames[i, 0] / np.linalg.norm(frames[i, 0])
    c = pts.mean(axis=0)
    _, _, vt = np.linalg.svd(pts - c)
    return vt[0]


def rigid_penalty(r: np.ndarray) -> np.ndarray:
    """(3k, 3k) ``I - R (R^T R)^+ R^T``: the part of the k nodes' displacements that is not a
    rigid motion of them (``r`` (k, 3): positions about any point). A pad tied with it moves
    as a rigid body, free to translate and rotate, so it adds no stiffness to a body's own
    rigid motions.

    Nodes on one line (two nodes, or a pad at a coarse contact size whose nodes all lie
    on the contact line) do not feel the rotation about that line: their rigid motions
    span five directions, not six. The basis of the rigid motions is therefore the range
    of ``R`` as its singular values reveal it (relative tolerance ``1e-9``); a plain QR
    of the rank-deficient ``R`` added an arbitrary sixth direction, set by round-off,
    which left two-node pads untied and made mirror-image pads tie differently."""
    k = len(r)
    R = np.zeros((3 * k, 6))
    for j, (x, y, z) in enumerate(r):
        R[3 * j : 3 * j + 3, :3] = np.eye(3)
        # u = theta x r
        R[3 * j : 3 * j + 3, 3:] = [[0.0, z, -y], [-z, 0.0, x], [y, -x, 0.0]]
    # rotations in metres-scaled columns: scale them to the translations' before the rank
    scale = max(float(np.abs(r).max()), 1e-300)
    R[:, 3:] /= scale
    U, sv, _ = np.linalg.svd(R, full_matrices=False)
    Q = U[:, : int(np.sum(sv > 1e-9 * sv[0]))]
    return np.eye(3 * k) - Q @ Q.T


def _block_entries(blocks: list[tuple[np.ndarray, np.ndarray]]):
    """``(rows, cols, vals)`` of dense blocks given as ``(dofs, block)`` (COO triplets;
    entries of blocks that share a DOF are summed where the matrix is built)."""
    if not blocks:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0)
    rows = np.concatenate([np.repeat(d, len(d)) for d, _ in blocks])
    cols = np.concatenate([np.tile(d, len(d)) for d, _ in blocks])
    return rows, cols, np.concatenate([b.ravel() for _, b in blocks])


def penalty_alpha(diagonal: np.ndarray) -> float:
    """The tie's stiffness: ``ALPHA`` times the median of the body's positive diagonal
    stiffness entries (clamped rows, set to 1, left out)."""
    pos = diagonal[diagonal > 1.0]
    return ALPHA * (float(np.median(pos)) if len(pos) else 1.0)


def pad_penalty(
    coords: np.ndarray,
    centers: np.ndarray,
    points: np.ndarray,
    frames: np.ndarray,
    weight: np.ndarray,
    kind: str,
    width: float,
    alpha: float,
):
    """The pads' penalty on a body held by one process, a scipy CSR (3n, 3n) matrix.

    ``coords`` (n, 3) the body's nodes (node-major DOFs ``3 node + c``); pair i ties node
    ``centers[i]`` (its contact node, at ``points[i]``) and the nodes of its pad
    (:func:`pad_members`) into one rigid body with ``alpha`` :func:`rigid_penalty`. The
    distributed form for a dolfinx body is :func:`tie_pads`; the cyclic sector's bodies
    (assembled on one process) use this.
    """
    import scipy.sparse as sp

    members = pad_members(coords, points, frames, weight, kind, width)
    blocks = []
    for c, mem in zip(np.asarray(centers, dtype=np.int64), members, strict=True):
        g = np.concatenate([[c], mem[mem != c]])
        if len(g) > 1:
            d = (3 * g[:, None] + np.arange(3)[None, :]).ravel()
            blocks.append((d, alpha * rigid_penalty(coords[g] - coords[c])))
    n = 3 * len(coords)
    rows, cols, vals = _block_entries(blocks)
    return sp.csr_matrix((vals, (rows, cols)), shape=(n, n))


def tie_pads(body, nodes, contact, width_m: float) -> dict[str, float]:
    """Make each contact point's pad rigid in ``body.K`` (PETSc, assembled again).

    ``nodes``: the located interface nodes (the first ``contact.n_pairs`` are the contact
    points, in ContactSet order). The pad's nodes (the contact node and those of
    :func:`pad_members`) get the penalty ``alpha`` :func:`rigid_penalty`: they move as one
    rigid body. Each rank finds the pad nodes it owns and every rank sees every pad; each
    builds the penalty's rows it owns in one preallocated matrix, added to ``K`` once
    (``K + P``: inserting the pads' new entries into ``K`` itself reallocates row after
    row, 90 % of a reduction's time on the paper-like rig). Returns counts.
    """
    import scipy.sparse as sp
    from petsc4py import PETSc

    comm = body.comm
    K = body.K
    coords = body.owned_node_coords()
    m = contact.n_pairs
    members = pad_members(
        coords, contact.points, contact.frames, contact.weight, contact.kind, width_m
    )
    offset = body.V.dofmap.index_map.local_range[0]
    mine = [(offset + mem, coords[mem]) for mem in members]
    every = comm.allgather(mine)
    alpha = max(comm.allgather(penalty_alpha(K.getDiagonal().getArray())))
    centers = nodes.global_dofs[:m] // 3
    lo, hi = K.getOwnershipRange()
    blocks: list[tuple[np.ndarray, np.ndarray]] = []  # (global dofs, dense block)
    n_tied = 0
    for i in range(m):
        g = np.concatenate([[centers[i, 0]]] + [e[i][0] for e in every]).astype(np.int64)
        x = np.vstack([contact.points[i][None, :]] + [e[i][1] for e in every])
        keep = np.concatenate([[True], g[1:] != g[0]])
        g, x = g[keep], x[keep]
        n_tied += len(g) - 1
        if len(g) < 2:
            continue
        dofs = (3 * g[:, None] + np.arange(3)[None, :]).ravel()
        blocks.append((dofs, alpha * rigid_penalty(x - x[0])))
    # the rows this rank owns (CSR, columns sorted, the pads that share an entry summed)
    (rl, rg), (cl, cg) = K.getSizes()
    rows, cols, vals = _block_entries(blocks)
    own = (rows >= lo) & (rows < hi)
    local = sp.csr_matrix((vals[own], (rows[own] - lo, cols[own])), shape=(hi - lo, cg))
    local.sum_duplicates()
    if comm.allreduce(local.nnz) == 0:
        return {"pad_nodes": n_tied, "pad_alpha": alpha, "pad_nodes_per_pair": 0.0}
    P = PETSc.Mat().createAIJ(
        ((rl, rg), (cl, cg)),
        csr=(
            local.indptr.astype(PETSc.IntType),
            local.indices.astype(PETSc.IntType),
            local.data,
        ),
        comm=comm,
    )
    P.assemble()
    K.axpy(1.0, P, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    P.destroy()
    return {"pad_nodes": n_tied, "pad_alpha": alpha, "pad_nodes_per_pair": n_tied / max(m, 1)}


__all__ = [
    "ALPHA",
    "FILL",
    "pad_members",
    "pad_penalty",
    "penalty_alpha",
    "rigid_penalty",
    "tie_pads",
]
