"""Interface nodes: find the P2 node at each requested point, on whichever rank owns it.

An interface point (a contact point, an excitation or a response point) must
be a mesh vertex: the geometry stage embeds it. Each rank searches the P2
nodes it owns; the closest one within a tight tolerance wins, so exactly one
rank owns each interface node and the result does not depend on how the
mesh is partitioned. The DOFs of point ``i`` are the PETSc global rows
``global_dofs[i] = (3 b, 3 b + 1, 3 b + 2)`` (x, y, z) of its node ``b``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .elasticity import ElasticBody
from .parallel import allmax, allmin, allsum

REL_TOL = 1e-7  # of the body's size: gmsh writes coordinates to 16 digits


@dataclass(frozen=True)
class InterfaceNodes:
    """Where the interface points of one body live (identical on every rank)."""

    points: np.ndarray  # (n, 3) requested coordinates, m
    owner: np.ndarray  # (n,) rank that owns the node
    global_dofs: np.ndarray  # (n, 3) PETSc global rows of x, y, z
    local_block: np.ndarray  # (n,) owned local node index on this rank, -1 if not owner
    distance: np.ndarray  # (n,) distance from the point to the node found, m

    @property
    def n(self) -> int:
        return int(self.points.shape[0])

    def dofs(self) -> np.ndarray:
        """(3 n,) global rows in interface order, node-major x, y, z."""
        return self.global_dofs.reshape(-1)


def locate_nodes(
    body: ElasticBody,
    points: np.ndarray,
    *,
    what: str = "interface point",
    labels: list[str] | None = None,
) -> InterfaceNodes:
    """Locate the nodes of ``body`` at ``points``; InputError if a point is not a node."""
    from scipy.spatial import cKDTree

    comm = body.comm
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    n = pts.shape[0]
    xs = body.owned_node_coords()
    lo = allmin(comm, xs.min(axis=0) if len(xs) else np.full(3, np.inf))
    hi = allmax(comm, xs.max(axis=0) if len(xs) else np.full(3, -np.inf))
    size = float(np.linalg.norm(hi - lo))
    tol = REL_TOL * size
    if len(xs):
        dist, idx = cKDTree(xs).query(pts)
    else:
        dist, idx = np.full(n, np.inf), np.zeros(n, dtype=int)
    # the closest node over all ranks; ties go to the lowest rank
    pairs = np.stack([dist, np.full(n, comm.rank, dtype=float)], axis=1)
    all_pairs = comm.allgather(pairs)
    best = (
        np.array([min((p[i, 0], p[i, 1]) for p in all_pairs) for i in range(n)])
        if n
        else np.zeros((0, 2))
    )
    dmin = best[:, 0] if n else np.zeros(0)
    owner = best[:, 1].astype(int) if n else np.zeros(0, dtype=int)
    bad = np.flatnonzero(dmin > tol)
    if len(bad):
        i = int(bad[0])
        name = labels[i] if labels else f"{what} {i}"
        raise InputError(
            f"{body.name} {name}",
            [round(float(c), 9) for c in pts[i]],
            f"a node of the {body.name} mesh (within {tol:.1e} m)",
            f"the nearest node is {dmin[i]:.3e} m away; {len(bad)} of {n} points are not "
            "mesh nodes: the geometry stage must embed them",
        )
    mine = owner == comm.rank
    offset = body.V.dofmap.index_map.local_range[0]
    gblock = np.where(mine, offset + idx, 0).astype(np.int64)
    gblock = np.rint(allsum(comm, gblock)).astype(np.int64)
    local_block = np.where(mine, idx, -1).astype(np.int64)
    global_dofs = 3 * gblock[:, None] + np.arange(3)[None, :]
    uniq, first, counts = np.unique(gblock, return_index=True, return_counts=True)
    if len(uniq) != n:
        j = int(np.flatnonzero(counts > 1)[0])
        i = int(first[j])
        name = labels[i] if labels else f"{what} {i}"
        raise InputError(
            f"{body.name} {name}",
            [round(float(c), 9) for c in pts[i]],
            "a point that no other interface point shares a node with",
            "two interface points fall on the same mesh node",
        )
    return InterfaceNodes(
        points=pts, owner=owner, global_dofs=global_dofs, local_block=local_block, distance=dmin
    )


def interface_points(geom, body: str) -> tuple[np.ndarray, dict[str, np.ndarray], list[str]]:
    """Interface points of ``body`` of a BuiltGeometry, in the ReducedModel order.

    rig: the contact points (ContactSet order), the excitation points of
    blades 1, 2, the response points of blades 1, 2; damper: the contact
    points. A point equal to an earlier one (say an excitation point that is
    also the response point) is not repeated: its node set points at the
    earlier node. Returns ``(coords (n, 3) m, node_sets, labels)``.
    """
    groups = [("contact", np.asarray(geom.contact.points, dtype=float))]
    if body == "rig":
        groups += [
            ("excitation", np.asarray(geom.excitation_points, dtype=float)),
            ("response", np.asarray(geom.response_points, dtype=float)),
        ]
    elif body != "damper":
        raise InputError("body", body, "one of rig, damper")
    coords: list[np.ndarray] = []
    labels: list[str] = []
    sets: dict[str, np.ndarray] = {}
    scale = max(float(np.ptp(np.vstack([g for _, g in groups]), axis=0).max()), 1e-3)
    for name, pts in groups:
        idx = []
        for k, p in enumerate(pts.reshape(-1, 3)):
            hit = [j for j, c in enumerate(coords) if np.linalg.norm(c - p) <= REL_TOL * scale]
            if hit:
                idx.append(hit[0])
            else:
                idx.append(len(coords))
                coords.append(p)
                labels.append(f"{name} point {k}")
        sets[name] = np.asarray(idx, dtype=np.int64)
    return np.array(coords).reshape(-1, 3), sets, labels
