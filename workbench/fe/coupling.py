"""Stuck contact: each pair tied by springs kt (t1, t2) and kn (n) in its own frame.

For pair ``i`` with frame ``R_i`` (rows t1, t2, n) and stiffnesses from
:meth:`ContactParams.pair_stiffness`, the spring energy is::

    1/2 (u_d - u_p)^T S_i (u_d - u_p),   S_i = R_i^T diag(kt_i, kt_i, kn_i) R_i

with ``u_d`` the damper node and ``u_p`` the platform node. This is the
linear limit of the friction contact when nothing slips or separates, so
the stuck modes of the full FE model, of the reduced models and of the
harmonic balance at vanishing excitation all describe the same system.

Two assemblies of the same springs:

* :func:`stuck_fe_system`: the unreduced rig and damper FE matrices coupled
  in one PETSc system (a MatNest converted to AIJ; the rig block first on
  every rank, then the damper block);
* :func:`stuck_reduced_system`: two :class:`~workbench.reduced.ReducedModel`
  coupled in numpy (no dolfinx needed).
"""

from __future__ import annotations

import numpy as np

from ..assembly.params import ContactParams
from ..geometry.records import ContactSet
from ..reduced import ReducedModel


def pair_springs(contact: ContactSet, params: ContactParams) -> np.ndarray:
    """(n_pairs, 3, 3) spring matrices S_i in global axes, N/m."""
    kt, kn = params.pair_stiffness(contact.kind, contact.weight)
    d = np.stack([kt, kt, kn], axis=1)  # (n, 3)
    R = np.asarray(contact.frames, dtype=float)
    return np.einsum("nki,nk,nkj->nij", R, d, R)


def stuck_reduced_system(
    rig: ReducedModel, damper: ReducedModel, contact: ContactSet, params: ContactParams
) -> tuple[np.ndarray, np.ndarray]:
    """K, M of rig + damper (q = [q_rig; q_damper]) with every contact pair stuck."""
    S = pair_springs(contact, params)
    n_p = contact.n_pairs
    rc = np.asarray(rig.node_sets["contact"])
    dc = np.asarray(damper.node_sets["contact"])
    if len(rc) != n_p or len(dc) != n_p:
        raise ValueError(f"contact node sets ({len(rc)}, {len(dc)}) do not match {n_p} pairs")
    Gp = rig.T[rig.node_dofs(rc)]  # (3 n_p, n_r): platform displacements
    Gd = damper.T[damper.node_dofs(dc)]  # (3 n_p, n_d): damper displacements
    Sb = np.zeros((3 * n_p, 3 * n_p))
    for i in range(n_p):
        Sb[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] = S[i]
    G = np.hstack([-Gp, Gd])
    nr, nd = rig.n, damper.n
    K = np.zeros((nr + nd, nr + nd))
    M = np.zeros_like(K)
    K[:nr, :nr], K[nr:, nr:] = rig.K, damper.K
    M[:nr, :nr], M[nr:, nr:] = rig.M, damper.M
    K += G.T @ Sb @ G
    return 0.5 * (K + K.T), M


def stuck_fe_system(rig, damper, p_nodes, d_nodes, S: np.ndarray):
    """The unreduced rig + damper system with the stuck springs (PETSc, MPI).

    ``rig``/``damper`` are :class:`~workbench.fe.elasticity.ElasticBody`,
    ``p_nodes``/``d_nodes`` the :class:`~workbench.fe.interface.InterfaceNodes`
    of the platform and damper node of each pair. Returns ``(K, M, is_rig,
    is_damper)``: AIJ matrices and the index sets of each body's DOFs in
    the coupled numbering.
    """
    from petsc4py import PETSc

    comm = rig.comm
    rank = comm.rank
    add = PETSc.InsertMode.ADD_VALUES
    Krr = rig.K.copy()
    Kdd = damper.K.copy()
    Krd = PETSc.Mat().createAIJ(
        ((rig.n_local, rig.n_dofs), (damper.n_local, damper.n_dofs)), nnz=(3, 3), comm=comm
    )
    Krd.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
    Krd.setUp()
    for i in range(len(S)):
        gp = p_nodes.global_dofs[i].astype(PETSc.IntType)
        gd = d_nodes.global_dofs[i].astype(PETSc.IntType)
        if p_nodes.owner[i] == rank:
            Krr.setValues(gp, gp, S[i].ravel(), addv=add)
            Krd.setValues(gp, gd, (-S[i]).ravel(), addv=add)
        if d_nodes.owner[i] == rank:
            Kdd.setValues(gd, gd, S[i].ravel(), addv=add)
    for A in (Krr, Kdd, Krd):
        A.assemble()
    Kdr = Krd.transpose(PETSc.Mat())
    Knest = PETSc.Mat().createNest([[Krr, Krd], [Kdr, Kdd]], comm=comm)
    Mnest = PETSc.Mat().createNest([[rig.M, None], [None, damper.M]], comm=comm)
    is_rig, is_damper = Knest.getNestISs()[0]
    K = Knest.convert("aij")
    M = Mnest.convert("aij")
    return K, M, is_rig, is_damper
