"""How soft the structure is at each contact pair, against the pair's own spring.

A contact pair joins one node of the platform to one node of the damper
through springs ``kt, kt, kn`` (directions t1, t2, n of its frame). In the
harmonic balance the pair's spring sees, in series, the structure around
the two nodes: the bodies' global compliance and the local compliance of
the mesh under a force on a single node. For a force on a node the local
part grows without bound as the mesh around that node is refined (a point
load on an elastic body has an unbounded displacement), so when it is not
small against the spring's own ``1 / k`` the effective contact stiffness,
the slip onset and the friction energy follow the mesh rather than the
contact law (docs/notes/energy_convergence.md measures it on the
paper-like rig).

With every pair stuck the stiffness of the generalised coordinates is
``K_s = K + W^T Kc W`` (``Kc`` the diagonal of the springs, ``W`` the map
from the coordinates to the pairs' relative displacements), and
``G = W K_s^-1 W^T`` is the flexibility of the relative displacements.
Taking pair i's own spring out of its diagonal entry (Sherman-Morrison)
leaves the flexibility of the structure that this spring sees, the other
pairs held by theirs::

    g_i = G_ii / (1 - k_i G_ii)

The ratio ``k_i g_i`` is returned: 0 for a rigid structure (the spring
alone sets the contact stiffness); 1 when the structure is as compliant as
the spring (the pair is half as stiff as its law says).

Plain numpy; the coordinates' stiffness must be positive definite once
the springs are added (a free damper held by its contacts is).
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError


def structure_to_spring(K, W, kc) -> np.ndarray:
    """``k_i g_i`` for every spring i (see the module docstring), dimensionless.

    ``K``: (n, n) stiffness of the generalised coordinates (dense or with
    ``toarray``); ``W``: (m, n) map to the relative displacements (dense or
    sparse); ``kc``: (m,) spring stiffness of each row of ``W``, N/m, > 0.
    """
    K = np.asarray(K.toarray() if hasattr(K, "toarray") else K, dtype=float)
    W = np.asarray(W.toarray() if hasattr(W, "toarray") else W, dtype=float)
    kc = np.asarray(kc, dtype=float).ravel()
    n = K.shape[0]
    if K.shape != (n, n):
        raise InputError("K", K.shape, "a square matrix")
    if W.ndim != 2 or W.shape[1] != n:
        raise InputError("W", W.shape, f"a matrix with {n} columns (the coordinates of K)")
    if kc.shape != (W.shape[0],) or not np.all(kc > 0):
        raise InputError("kc", kc.shape, f"{W.shape[0]} positive spring stiffnesses (N/m)")
    Ks = K + W.T @ (kc[:, None] * W)
    try:
        G = W @ np.linalg.solve(Ks, W.T)
    except np.linalg.LinAlgError as exc:
        raise InputError(
            "K", "singular", "a structure held by its springs (K + W^T Kc W invertible)"
        ) from exc
    d = np.diag(G)
    return kc * d / (1.0 - kc * d)


def pair_structure_to_spring(assembled) -> np.ndarray:
    """(n_pairs, 3) ``k g`` of an :class:`~workbench.assembly.model.AssembledModel`'s pairs,
    columns t1, t2, n."""
    kc = np.column_stack([assembled.kt, assembled.kt, assembled.kn]).ravel()
    return structure_to_spring(assembled.K, assembled.W, kc).reshape(-1, 3)


__all__ = ["pair_structure_to_spring", "structure_to_spring"]
