"""Craig-Bampton reduction of one body onto its interface DOFs (PETSc/MUMPS, MPI).

Partition the DOFs into interface ``b`` (x, y, z of every interface node)
and interior ``i``. With the interface held fixed, the interior has the
fixed-interface modes ``K_ii phi_k = w_k^2 M_ii phi_k`` (``phi_k^T M_ii
phi_k = 1``, by block shift-and-invert Krylov on MUMPS multi-right-hand-side
solves, :mod:`.block_eigen`); the static constraint modes are ``Psi =
-K_ii^{-1} K_ib`` (the same MUMPS factorisation of ``K_ii`` and one
sparse multi-right-hand-side solve per block of columns). The body's DOFs are
approximated by::

    u = [u_b; u_i] = [[I, 0], [Psi, Phi]] [u_b; eta]

so that, with ``q = [u_b (3 n_nodes, node-major x,y,z); eta (m)]``::

    K_cb = [[K_bb + K_ib^T Psi, 0], [0, diag(w_k^2)]]
    M_cb = [[M_bb + M_ib^T Psi + Psi^T M_ib + Psi^T M_ii Psi, M_be], [M_be^T, I]]
    M_be = M_ib^T Phi + Psi^T M_ii Phi

A free-free body is reduced the same way: the fixed interface pins its
rigid-body motion, and the constraint modes contain that motion exactly,
so ``K_cb`` keeps six zero eigenvalues.

Parallel layout: every rank owns the interior rows it owns in the body's
numbering; the small reduced blocks are sums of per-rank products
(``allreduce``), then put in interface order, so they do not depend on the
number of ranks beyond round-off. Mode signs are fixed by a smooth
coordinate-dependent weight, not by the partition.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, SolveError
from ..log import progress_bar, stage
from .block_eigen import block_eigen
from .elasticity import ElasticBody
from .interface import InterfaceNodes
from .parallel import allrows, allsum, dense_mult, info, sparse_solve
from .solvers import mumps_defaults, petsc_options

log = logging.getLogger(__name__)

RHS_BLOCK = 96  # right-hand sides per MUMPS multi-RHS solve (memory: n_dofs x 96 doubles)


@dataclass(frozen=True)
class CBMatrices:
    """Reduced matrices of one body, in interface order (identical on every rank)."""

    K: np.ndarray  # (3 n_nodes + m, 3 n_nodes + m) N/m
    M: np.ndarray  # kg
    mode_freqs_hz: np.ndarray  # (m,) fixed-interface frequencies
    n_b: int  # interface DOFs (3 n_nodes)


def sign_weight(coords: np.ndarray, comp: np.ndarray) -> np.ndarray:
    """A smooth, partition-independent weight used to fix the sign of mode shapes."""
    x = coords * 100.0  # the rig is about 0.1 m: a few periods over it
    return np.cos(3.311 * x[:, 0] + 5.173 * x[:, 1] + 7.279 * x[:, 2] + 0.9 * comp + 0.3)


def node_mass(M_ii, comm):
    """The scalar mass matrix ``m`` with ``M_ii = m (x) I_3``, or None (MPI, or not that form).

    The consistent mass of a vector P2 space couples each component only with
    itself, and the interior DOFs come in whole x, y, z triples (the interface
    takes whole nodes), so ``M_ii Psi`` is ``m`` applied to ``Psi`` with each
    node's three rows side by side: a ninth of the entries of ``M_ii`` (two
    thirds of which are stored zeros) and contiguous rows; 2.5-3.5x faster than
    PETSc's sparse-dense product on the 9 mm rigs, same sums. Checked here on a
    random vector; serial only (in parallel the rows of other ranks are needed).
    """
    if comm.size != 1:
        return None
    n = M_ii.getSize()[0]
    if n % 3:
        return None
    A = _local_csr(M_ii, n)
    m = A[0::3, 0::3].tocsr()
    v = np.random.default_rng(3).standard_normal(n)
    ref = A @ v
    got = (m @ v.reshape(-1, 3)).ravel()
    if np.abs(got - ref).max() > 1e-12 * max(np.abs(ref).max(), 1e-300):
        return None
    return m


def mass_mult(m, M_ii, X: np.ndarray, n_i: int, comm) -> np.ndarray:
    """``M_ii X`` (this rank's rows): by the node mass ``m`` when given, else by PETSc."""
    if m is None:
        return dense_mult(M_ii, X, n_i, comm)
    Xc = np.ascontiguousarray(X)
    return (m @ Xc.reshape(n_i // 3, -1)).reshape(n_i, -1)


def _local_csr(A, n_cols: int):
    """This rank's rows of a PETSc AIJ matrix as a scipy CSR matrix with global columns."""
    import scipy.sparse as sp

    indptr, indices, data = A.getValuesCSR()
    n_rows = A.getLocalSize()[0]
    return sp.csr_matrix((data, indices, indptr), shape=(n_rows, n_cols))


@dataclass
class InterfaceSplit:
    """A body's DOFs split into interface (b) and interior (i) rows, this rank's share.

    ``mine``: positions (interface order) of this rank's interface DOFs, in the
    sorted order PETSc's index set holds them; ``is_order``: the same over all
    ranks (index-set position -> interface position); ``Kib``/``Mib``: this
    rank's interior rows, columns in index-set order.
    """

    mine: np.ndarray
    my_b: np.ndarray
    is_order: np.ndarray
    interior: np.ndarray
    n_i: int
    is_b: object
    K_ii: object
    M_ii: object
    Kib: object
    Mib: object
    sign_w: np.ndarray
    m_node: object  # M_ii = m_node (x) I_3 (serial), else None: see node_mass


def split_interface(body: ElasticBody, nodes: InterfaceNodes) -> InterfaceSplit:
    """Index sets and sub-matrices of ``body`` for the interface ``nodes`` (collective)."""
    from petsc4py import PETSc

    comm = body.comm
    K, M = body.K, body.M
    off, nloc = body.dof_offset, body.n_local
    b_dofs = nodes.dofs()  # interface order
    nb = len(b_dofs)
    mine = np.flatnonzero((b_dofs >= off) & (b_dofs < off + nloc))  # positions in iface order
    my_b = b_dofs[mine]
    order = np.argsort(my_b, kind="stable")  # PETSc wants sorted index sets
    mine, my_b = mine[order], my_b[order]
    is_order = np.concatenate(comm.allgather(mine)).astype(int)  # IS position -> iface pos
    interior = np.setdiff1d(np.arange(off, off + nloc, dtype=np.int64), my_b)
    is_b = PETSc.IS().createGeneral(my_b.astype(PETSc.IntType), comm=comm)
    is_i = PETSc.IS().createGeneral(interior.astype(PETSc.IntType), comm=comm)
    # weights for the sign of the modes: coordinates of the interior DOFs
    ld = interior - off
    xyz = body.owned_node_coords()[ld // 3]
    M_ii = M.createSubMatrix(is_i, is_i)
    return InterfaceSplit(
        mine=mine,
        my_b=my_b,
        is_order=is_order,
        interior=interior,
        n_i=comm.allreduce(len(interior)),
        is_b=is_b,
        K_ii=K.createSubMatrix(is_i, is_i),
        M_ii=M_ii,
        Kib=_local_csr(K.createSubMatrix(is_i, is_b), nb),
        Mib=_local_csr(M.createSubMatrix(is_i, is_b), nb),
        sign_w=sign_weight(xyz, ld % 3),
        m_node=node_mass(M_ii, comm),
    )


def interior_factor(sp_: InterfaceSplit, n_modes: int, name: str, comm):
    """``(Phi, lam, F, keep)``: the fixed-interface modes (columns, this rank's interior
    rows, signs fixed) and eigenvalues (none for ``n_modes == 0``), the MUMPS factor F of
    K_ii and the PETSc KSP that holds it (``keep.destroy()`` releases it).

    One factorisation serves the eigen solve (block shift-and-invert Krylov,
    :mod:`.block_eigen`) and the constraint modes.
    """
    from petsc4py import PETSc

    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix("upd_cb_")
    ksp.setOperators(sp_.K_ii)
    # ICNTL(27): right-hand sides MUMPS treats together in its solve phase; 128
    # against the default 32 takes the constraint modes' blocks of RHS_BLOCK at once
    # (wedge rig, 9 mm: 26 -> 20 ms a dense column)
    with petsc_options("upd_cb_", {**mumps_defaults(st=False), "mat_mumps_icntl_27": 128}):
        ksp.setFromOptions()
        try:
            ksp.setUp()
        except Exception as e:  # noqa: BLE001 - PETSc.Error carries only an error code
            raise SolveError(
                f"{name}: the factorisation of the interior stiffness failed ({e}); for more "
                "MUMPS work space try PETSC_OPTIONS='-upd_cb_mat_mumps_icntl_14 200'"
            ) from e
    F = ksp.getPC().getFactorMatrix()
    if n_modes == 0:
        return np.zeros((len(sp_.interior), 0)), np.zeros(0), F, ksp
    lam, Phi, _ = block_eigen(
        sp_.K_ii,
        sp_.M_ii,
        F,
        n_modes,
        comm,
        what=f"{name} fixed-interface modes",
        b_mult=lambda X: mass_mult(sp_.m_node, sp_.M_ii, X, sp_.n_i, comm),
    )
    for k in range(Phi.shape[1]):
        if comm.allreduce(float(sp_.sign_w @ Phi[:, k])) < 0:
            Phi[:, k] = -Phi[:, k]
    return Phi, lam, F, ksp


def craig_bampton(
    body: ElasticBody,
    nodes: InterfaceNodes,
    n_modes: int,
    *,
    timings: dict[str, float] | None = None,
) -> CBMatrices:
    """Reduce ``body`` onto the DOFs of ``nodes`` plus ``n_modes`` fixed-interface modes."""

    comm = body.comm
    K, M = body.K, body.M
    nb = 3 * nodes.n
    if n_modes < 0:
        raise InputError("n_modes", n_modes, "a whole number >= 0")

    with stage(timings, "partition"):
        sp_ = split_interface(body, nodes)
    is_order, interior, n_i = sp_.is_order, sp_.interior, sp_.n_i
    K_ii, M_ii, Kib, Mib = sp_.K_ii, sp_.M_ii, sp_.Kib, sp_.Mib
    K_bb = allrows(comm, _local_csr(K.createSubMatrix(sp_.is_b, sp_.is_b), nb).toarray())
    M_bb = allrows(comm, _local_csr(M.createSubMatrix(sp_.is_b, sp_.is_b), nb).toarray())

    # fixed-interface modes; the shift-and-invert transform factorises K_ii once
    with stage(timings, "eigen"):
        Phi, lam, F, keep = interior_factor(sp_, n_modes, body.name, comm)
    if n_modes and np.any(lam <= 0):
        raise SolveError(
            f"{body.name}: fixed-interface problem is singular "
            f"(eigenvalue {lam.min():.3e}); the interface does not hold the body"
        )

    # static constraint modes, a block of right-hand sides at a time
    Psi = np.empty((len(interior), nb))
    with (
        stage(timings, "constraint_modes"),
        progress_bar(f"{body.name} constraint modes", total=nb, unit="rhs") as bar,
    ):
        for c0 in range(0, nb, RHS_BLOCK):
            c1 = min(nb, c0 + RHS_BLOCK)
            Psi[:, c0:c1] = sparse_solve(F, -Kib[:, c0:c1], n_i, comm)
            bar.update(c1 - c0)
        # check the factorisation shared with the eigen solve really is the one of K_ii
        j = nb // 2
        r = K_ii.createVecs()[0]
        x = K_ii.createVecs()[0]
        x.setArray(Psi[:, j])
        K_ii.mult(x, r)
        rhs = -Kib[:, j].toarray().ravel()
        res = np.sqrt(comm.allreduce(float(np.sum((r.getArray() - rhs) ** 2))))
        ref = np.sqrt(comm.allreduce(float(np.sum(rhs**2)))) or 1.0
        if res / ref > 1e-6:
            raise SolveError(f"{body.name}: constraint modes inaccurate (residual {res / ref:.1e})")
    # release the factorisation (the largest allocation) before the projections
    del F
    keep.destroy()  # the KSP holding it

    with stage(timings, "projection"):
        Khat = K_bb + allsum(comm, Kib.T @ Psi)
        MibPsi = allsum(comm, Mib.T @ Psi)
        # Psi^T M_ii Psi is symmetric: each block of columns only needs its rows from the
        # block's first column down (half the products); the upper triangle is mirrored
        m_node = sp_.m_node
        PMP = np.zeros((nb, nb))
        for c0 in range(0, nb, RHS_BLOCK):
            c1 = min(nb, c0 + RHS_BLOCK)
            Y = mass_mult(m_node, M_ii, Psi[:, c0:c1], n_i, comm)
            PMP[c0:, c0:c1] = allsum(comm, Psi[:, c0:].T @ Y)
        PMP = np.tril(PMP) + np.tril(PMP, -1).T
        Mhat = M_bb + MibPsi + MibPsi.T + PMP
        if n_modes:
            MPhi = mass_mult(m_node, M_ii, Phi, n_i, comm)
            Mbe = allsum(comm, Mib.T @ Phi + Psi.T @ MPhi)
            ortho = allsum(comm, Phi.T @ MPhi)
            err = np.abs(ortho - np.eye(n_modes)).max()
            if err > 1e-6:
                log.warning("%s: fixed-interface modes M-orthonormal to %.1e only", body.name, err)
        else:
            Mbe = np.zeros((nb, 0))

    # interface order
    inv = np.empty(nb, dtype=int)
    inv[is_order] = np.arange(nb)
    Khat = Khat[np.ix_(inv, inv)]
    Mhat = Mhat[np.ix_(inv, inv)]
    Mbe = Mbe[inv]
    m = n_modes
    Kr = np.zeros((nb + m, nb + m))
    Mr = np.zeros((nb + m, nb + m))
    Kr[:nb, :nb] = 0.5 * (Khat + Khat.T)
    Kr[nb:, nb:] = np.diag(lam)
    Mr[:nb, :nb] = 0.5 * (Mhat + Mhat.T)
    Mr[:nb, nb:] = Mbe
    Mr[nb:, :nb] = Mbe.T
    Mr[nb:, nb:] = np.eye(m)
    freqs = np.sqrt(lam) / (2 * np.pi)
    for A in (K_ii, M_ii):
        A.destroy()
    comm.Barrier()
    info(
        log,
        comm,
        "%s: Craig-Bampton %d interface DOFs + %d modes (%s Hz)",
        body.name,
        nb,
        m,
        ", ".join(f"{f:.0f}" for f in freqs[:4]) + (" ..." if m > 4 else ""),
    )
    return CBMatrices(K=Kr, M=Mr, mode_freqs_hz=freqs, n_b=nb)
