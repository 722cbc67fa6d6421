r"""Cyclic symmetry of a bladed disk: one sector's FE matrices per nodal diameter (real arithmetic).

Conventions (docs/DISK.md). Sector ``j`` is sector 0 turned by ``j alpha``
about the disk axis y, ``alpha = 2 pi / N`` (:func:`workbench.geometry.disk.rotation`).
Each sector's displacement is written in its own frame (global = R(j alpha)
local). A mode of nodal diameter ``k`` has, on sector ``j``::

    u_j = a cos(j phi) + b sin(j phi),   phi = 2 pi k / N

with two real fields ``a``, ``b`` on one sector (complex form: ``U = a - i b``,
``u_j = Re(U e^{i j phi})``, and sector ``j + 1`` carries ``e^{i phi} U``).

The *extended sector* holds every DOF one sector's energy depends on: the
sector body's nodes, its damper's nodes and, for the damper's side-1 pairs,
"image" nodes standing for the next sector's platform nodes. Two kinds of
node are slaves of a node of sector 0 (``master``), seen from sector ``j+1``:

* a node of the right cyclic face is the left-face node ``m`` of the next
  sector: ``p_s = R p_m``;
* an image node is the next sector's platform node, the image of this
  sector's left-half node ``m``: ``p_s = R p_m``.

With ``R = R(alpha)``, shifting ``j -> j + 1`` gives the slave values::

    a_s = R ( cos(phi) a_m + sin(phi) b_m )
    b_s = R ( cos(phi) b_m - sin(phi) a_m )

so ``(a, b)`` on the extended sector is ``T (a_M, b_M)`` on the master DOFs,
and the disk's energy is ``N / 2 (a^T K a + b^T K b)``: the ND-``k`` matrices
are ``K_k = T^T diag(K, K) T``, ``M_k`` alike (real symmetric; each
eigenvalue appears twice, for ``(a, b)`` and ``(-b, a)``). For ``k = 0``
(``phi = 0``) and ``k = N / 2`` (``phi = pi``) the field is real: one copy,
``a_s = +-R a_m``.

Units SI (N/m, kg, Hz). Clamped (bore) DOFs are removed. The assembly
(:func:`assemble_sector`) runs dolfinx on one rank (``COMM_SELF``); the rest
is scipy.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import InputError, check_int

log = logging.getLogger(__name__)

MATCH_REL_TOL = 1e-7  # of the sector's size: gmsh writes coordinates to 16 digits
SHIFT_HZ = 1.0  # shift-and-invert target below every mode (a free bore has rigid modes at 0)


@dataclass(frozen=True)
class CyclicSector:
    """The extended sector's matrices and its cyclic bookkeeping (node-major DOFs 3 b + c)."""

    n_blades: int
    K: sp.csr_matrix  # (3 n, 3 n) N/m, sector + damper + stuck springs (free DOFs kept)
    M: sp.csr_matrix  # kg
    coords: np.ndarray  # (n, 3) m, node coordinates (image nodes: on the next sector)
    body: np.ndarray  # (n,) 0 sector, 1 damper, 2 image node
    fixed: np.ndarray  # node indices clamped (bore)
    slave: np.ndarray  # node indices eliminated (right face, image nodes)
    master: np.ndarray  # the sector-0 node each slave copies (turned by rot)
    platform_nodes: np.ndarray  # (n_pairs,) sector node of each pair's platform (side 1: image)
    damper_nodes: np.ndarray  # (n_pairs,) damper node of each pair (-1 without damper)
    side: np.ndarray  # (n_pairs,)

    @property
    def alpha(self) -> float:
        return 2 * math.pi / self.n_blades

    @property
    def rot(self) -> np.ndarray:
        from ..geometry.disk import rotation

        return rotation(self.alpha)

    @property
    def n_nodes(self) -> int:
        return int(self.coords.shape[0])

    def master_dofs(self) -> np.ndarray:
        """DOFs kept by the cyclic elimination (not slave, not clamped), in order."""
        drop = np.zeros(self.n_nodes, bool)
        drop[self.fixed] = True
        drop[self.slave] = True
        return _node_dofs(np.flatnonzero(~drop))

    def nodal_diameters(self) -> list[int]:
        """0 .. N // 2."""
        return list(range(self.n_blades // 2 + 1))


def _node_dofs(nodes: np.ndarray) -> np.ndarray:
    nodes = np.asarray(nodes, dtype=np.int64)
    return (3 * nodes[:, None] + np.arange(3)[None, :]).ravel()


def _petsc_to_scipy(A) -> sp.csr_matrix:
    ai, aj, av = A.getValuesCSR()
    n = A.getSize()
    return sp.csr_matrix((av, aj, ai), shape=n)


def _match(src: np.ndarray, dst: np.ndarray, tol: float, what: str) -> np.ndarray:
    """Index into ``dst`` of the point matching each ``src`` point; SolveError if any misses."""
    from scipy.spatial import cKDTree

    from ..errors import SolveError

    d, idx = cKDTree(dst).query(src)
    if len(d) and d.max() > tol:
        raise SolveError(f"{what}: a node is {d.max():.3g} m from its match (allowed {tol:.3g} m)")
    return idx


def assemble_sector(rec, contact_params=None, *, with_damper: bool = True) -> CyclicSector:
    """Assemble the extended sector of a :class:`~workbench.geometry.disk_build.DiskSector`.

    ``with_damper``: the damper and its stuck contact springs (``contact_params``,
    a :class:`~workbench.assembly.params.ContactParams`; springs as
    :func:`workbench.fe.coupling.pair_springs`) are part of the sector; False:
    the bladed disk alone. Runs dolfinx on ``COMM_SELF``.
    """
    from mpi4py import MPI

    from .coupling import pair_springs
    from .elasticity import Material, assemble_body
    from .mesh import read_msh

    mat = Material.from_dict(rec.material)
    clamped = "bore" if rec.bore == "clamped" else None
    sec = assemble_body(
        read_msh(rec.sector_msh, MPI.COMM_SELF), mat, name="sector", clamped=clamped
    )
    xs = sec.V.tabulate_dof_coordinates()
    Ks, Ms = _petsc_to_scipy(sec.K), _petsc_to_scipy(sec.M)
    size = float(np.ptp(xs, axis=0).max())
    tol = MATCH_REL_TOL * size
    alpha = 2 * math.pi / rec.n_blades
    ha = alpha / 2
    n_left = np.array([math.cos(ha), 0.0, math.sin(ha)])
    n_right = np.array([math.cos(ha), 0.0, -math.sin(ha)])
    left = np.flatnonzero(np.abs(xs @ n_left) < tol)
    right = np.flatnonzero(np.abs(xs @ n_right) < tol)
    if len(left) != len(right) or len(left) == 0:
        raise InputError("sector mesh", str(rec.sector_msh), "a periodic mesh of the cyclic faces")
    from ..geometry.disk import rotation

    R = rotation(alpha)
    right_of_left = right[_match(xs[left] @ R.T, xs[right], tol, "cyclic faces")]
    platform = _match(rec.image_points, xs, tol, "platform contact nodes")
    fixed = np.asarray(sec.clamped_blocks, dtype=np.int64)
    n_s = xs.shape[0]
    side = np.asarray(rec.contact.side)
    one = np.flatnonzero(side == 1)
    pad = pad_width_m(rec)
    if pad > 0:  # the platform's pads, side-1 pairs' frames turned into this sector
        from .pads import pad_penalty, penalty_alpha

        frames = np.array(rec.contact.frames, dtype=float)
        frames[one] = frames[one] @ R
        c, alpha_pad = rec.contact, penalty_alpha(Ks.diagonal())
        Ks = Ks + pad_penalty(
            xs, platform, rec.image_points, frames, c.weight, c.kind, pad, alpha_pad
        )
    if not with_damper:
        return CyclicSector(
            n_blades=rec.n_blades,
            K=_drop_dirichlet(Ks, fixed),
            M=_drop_dirichlet(Ms, fixed),
            coords=xs,
            body=np.zeros(n_s, np.int64),
            fixed=fixed,
            slave=right_of_left,
            master=left,
            platform_nodes=platform,
            damper_nodes=np.full(len(platform), -1),
            side=side,
        )
    Kd, Md, xd, dnode = damper_matrices(rec)
    n_d = xd.shape[0]
    n_img = len(one)
    n = n_s + n_d + n_img
    # pair i: damper node n_s + dnode[i]; platform node platform[i] (side 0) or an image node
    p_node = platform.copy()
    p_node[one] = n_s + n_d + np.arange(n_img)
    S = pair_springs(rec.contact, contact_params)
    rows, cols, vals = [], [], []
    for i in range(len(S)):
        nodes = (n_s + dnode[i], p_node[i])
        for a, sa in enumerate(nodes):
            for b, sb in enumerate(nodes):
                r = 3 * sa + np.repeat(np.arange(3), 3)
                c = 3 * sb + np.tile(np.arange(3), 3)
                rows.append(r)
                cols.append(c)
                vals.append((S[i] if a == b else -S[i]).ravel())
    Kc = sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(3 * n, 3 * n)
    )
    zero = sp.csr_matrix((3 * n_img, 3 * n_img))
    K = sp.block_diag([_drop_dirichlet(Ks, fixed), Kd, zero], format="csr") + Kc
    M = sp.block_diag([_drop_dirichlet(Ms, fixed), Md, zero], format="csr")
    coords = np.vstack([xs, xd, rec.contact.points[one]])
    body = np.concatenate([np.zeros(n_s), np.ones(n_d), np.full(n_img, 2)]).astype(np.int64)
    d_nodes = n_s + dnode
    return CyclicSector(
        n_blades=rec.n_blades,
        K=K.tocsr(),
        M=M.tocsr(),
        coords=coords,
        body=body,
        fixed=fixed,
        slave=np.concatenate([right_of_left, n_s + n_d + np.arange(n_img)]),
        master=np.concatenate([left, platform[one]]),
        platform_nodes=platform,
        damper_nodes=d_nodes,
        side=side,
    )


def damper_matrices(rec) -> tuple[sp.csr_matrix, sp.csr_matrix, np.ndarray, np.ndarray]:
    """The free damper of a DiskSector: ``(K, M, node coords, contact node of each pair)``."""
    from mpi4py import MPI

    from .elasticity import Material, assemble_body
    from .mesh import read_msh

    mat = Material.from_dict(rec.material)
    dam = assemble_body(read_msh(rec.damper_msh, MPI.COMM_SELF), mat, name="damper")
    xd = dam.V.tabulate_dof_coordinates()
    tol = MATCH_REL_TOL * float(np.ptp(xd, axis=0).max())
    dnode = _match(rec.contact.points, xd, tol, "damper contact nodes")
    Kd = _petsc_to_scipy(dam.K)
    pad = pad_width_m(rec)
    if pad > 0:  # the damper's pads (the pairs' frames are the disk frame's, as its nodes)
        from .pads import pad_penalty, penalty_alpha

        c = rec.contact
        Kd = Kd + pad_penalty(
            xd, dnode, c.points, c.frames, c.weight, c.kind, pad, penalty_alpha(Kd.diagonal())
        )
    return Kd.tocsr(), _petsc_to_scipy(dam.M), xd, dnode


def pad_width_m(rec) -> float:
    """The contact pads' width of a DiskSector, m (``[rig.mesh] pad_mm``; 0: no pads)."""
    return float(rec.params.get("rig", {}).get("mesh", {}).get("pad_mm", 0.0)) * 1e-3


def _drop_dirichlet(A: sp.csr_matrix, fixed_nodes: np.ndarray) -> sp.csr_matrix:
    """Zero the rows and columns of the clamped nodes (they are removed later)."""
    keep = np.ones(A.shape[0])
    keep[_node_dofs(fixed_nodes)] = 0.0
    D = sp.diags(keep)
    return (D @ A @ D).tocsr()


def _slave_map(cs: CyclicSector) -> tuple[sp.csr_matrix, sp.csr_matrix, np.ndarray]:
    """(C, W, masters): C picks the master DOFs, W sends them turned by R to the slave rows."""
    mdofs = cs.master_dofs()
    n = 3 * cs.n_nodes
    col_of = np.full(n, -1, dtype=np.int64)
    col_of[mdofs] = np.arange(len(mdofs))
    C = sp.csr_matrix((np.ones(len(mdofs)), (mdofs, np.arange(len(mdofs)))), shape=(n, len(mdofs)))
    R = cs.rot
    rows, cols, vals = [], [], []
    fixed = set(cs.fixed.tolist())
    for s, m in zip(cs.slave, cs.master, strict=True):
        if int(m) in fixed:
            continue  # a clamped master: the slave is clamped too (the mesh is periodic)
        for r in range(3):
            for c in range(3):
                rows.append(3 * s + r)
                cols.append(col_of[3 * m + c])
                vals.append(R[r, c])
    cols_a = np.asarray(cols)
    if len(cols_a) and cols_a.min() < 0:
        raise InputError("cyclic sector", "a slave node", "a master that is not itself a slave")
    W = sp.csr_matrix((vals, (rows, cols)), shape=(n, len(mdofs)))
    return C.tocsr(), W, mdofs


def transformation(cs: CyclicSector, k: int) -> sp.csr_matrix:
    """T of nodal diameter ``k``: extended-sector fields from the master DOFs.

    ``k = 0`` or ``N/2``: ``a = T a_M`` (one copy). Otherwise ``(a; b) = T (a_M; b_M)``.
    """
    n_b = cs.n_blades
    k = check_int("nodal diameter", k, 0, n_b // 2)
    C, W, _ = _slave_map(cs)
    phi = 2 * math.pi * k / n_b
    if k == 0:
        return (C + W).tocsr()
    if 2 * k == n_b:
        return (C - W).tocsr()
    c, s = math.cos(phi), math.sin(phi)
    return sp.bmat([[C + c * W, s * W], [-s * W, C + c * W]], format="csr")


def complex_nd_matrices(cs: CyclicSector, k: int) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """Hermitian ``(K_c, M_c)`` of nodal diameter ``k`` on the complex amplitude ``U = a - i b``.

    ``T_c = C + e^{i phi} W`` (a slave is ``R e^{i phi}`` times its master), ``K_c = T_c^H K
    T_c``: the form a harmonic balance with complex harmonics uses. Any ``k`` in 0..N-1 is
    accepted (``k`` and ``N - k`` are complex conjugates: the backward and forward waves of
    one nodal diameter). Same eigenvalues as :func:`nd_matrices`, each once.
    """
    k = check_int("nodal diameter", k, 0, cs.n_blades - 1)
    C, W, _ = _slave_map(cs)
    Tc = (C + np.exp(2j * math.pi * k / cs.n_blades) * W).tocsr()
    Kc = (Tc.conj().T @ cs.K @ Tc).tocsr()
    Mc = (Tc.conj().T @ cs.M @ Tc).tocsr()
    return 0.5 * (Kc + Kc.conj().T), 0.5 * (Mc + Mc.conj().T)


def nd_matrices(cs: CyclicSector, k: int) -> tuple[sp.csr_matrix, sp.csr_matrix, sp.csr_matrix]:
    """``(K_k, M_k, T)`` of nodal diameter ``k`` (real symmetric, N/m and kg)."""
    T = transformation(cs, k)
    double = T.shape[0] == 2 * cs.K.shape[0]
    K = sp.block_diag([cs.K, cs.K]) if double else cs.K
    M = sp.block_diag([cs.M, cs.M]) if double else cs.M
    Kk = (T.T @ K @ T).tocsr()
    Mk = (T.T @ M @ T).tocsr()
    return 0.5 * (Kk + Kk.T), 0.5 * (Mk + Mk.T), T


def _to_petsc(A: sp.csr_matrix):
    from petsc4py import PETSc

    A = A.tocsr()
    A.sort_indices()
    P = PETSc.Mat().createAIJ(
        size=A.shape,
        csr=(A.indptr.astype(PETSc.IntType), A.indices.astype(PETSc.IntType), A.data),
        comm=PETSc.COMM_SELF,
    )
    P.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    P.assemble()
    return P


def eigen(K, M, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``n`` lowest eigenpairs of ``K x = lambda M x`` (SLEPc, shift-and-invert, one rank).

    The shift sits below zero (``SHIFT_HZ``), so a free bore's rigid modes are
    found too and ``K - sigma M`` is positive definite. Vectors M-normalised.
    """
    from .solvers import eigen_solve

    n = min(n, K.shape[0] - 2)
    sigma = -((2 * math.pi * SHIFT_HZ) ** 2)
    A, B = _to_petsc(K), _to_petsc(M)
    sol = eigen_solve(A, B, n, sigma=sigma, prefix="upd_cyclic_", what="cyclic modes")
    X = np.column_stack([v.getArray().copy() for v in sol.vectors])
    for obj in (*sol.vectors, sol.eps, A, B):  # free the MUMPS factor now, not at exit
        obj.destroy()
    return sol.eigenvalues, X


def to_hz(lam: np.ndarray) -> np.ndarray:
    """Frequencies (Hz) of eigenvalues omega^2 (tiny negative round-off -> 0)."""
    return np.sqrt(np.clip(lam, 0.0, None)) / (2 * math.pi)


def nd_modes(cs: CyclicSector, k: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``n`` lowest distinct frequencies (Hz) of nodal diameter ``k`` and their shapes.

    For ``0 < k < N/2`` each frequency is a degenerate pair of the real
    formulation; one vector of each pair is returned (as ``(a; b)`` on the
    master DOFs, with :func:`transformation` giving the extended sector).
    """
    Kk, Mk, _ = nd_matrices(cs, k)
    double = 0 < k and 2 * k != cs.n_blades
    lam, X = eigen(Kk, Mk, 2 * n if double else n)
    if double:
        lam, X = 0.5 * (lam[0::2] + lam[1::2]), X[:, 0::2]
    return to_hz(lam), X


def fan(cs: CyclicSector, n_families: int, comm=None) -> np.ndarray:
    """``(N//2 + 1, n_families)`` frequencies (Hz), row k = nodal diameter k.

    Under MPI the nodal diameters are shared round-robin over ``comm``'s
    ranks (each rank holds the whole sector) and gathered on every rank.
    """
    nds = cs.nodal_diameters()
    rank, size = (0, 1) if comm is None else (comm.rank, comm.size)
    import time

    mine = {}
    for k in nds[rank::size]:
        t0 = time.perf_counter()
        mine[k] = nd_modes(cs, k, n_families)[0]
        log.info(
            "ND %d of %d: %s Hz (%.1f s)",
            k,
            nds[-1],
            ", ".join(f"{f:.1f}" for f in mine[k]),
            time.perf_counter() - t0,
        )
    if comm is not None and size > 1:
        allp = comm.allgather(mine)
        mine = {k: v for d in allp for k, v in d.items()}
    return np.array([mine[k] for k in nds])
