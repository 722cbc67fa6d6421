"""Full-mesh displacement fields from reduced coordinates (Craig-Bampton or rigid body).

A reduced model keeps only its matrices: the full-mesh basis (141,000 x
162 numbers for the 9 mm rig) is not stored. To see a forced response on
the whole mesh, the basis is rebuilt here, on demand, for the columns asked:

* Craig-Bampton body, ``q = [u_b; eta]``: the interior is
  ``u_i = -K_ii^-1 K_ib u_b + Phi eta``. ``Phi`` is computed again (one
  factorisation and eigen solve, as in the reduction); the static part is
  one multi-right-hand-side solve with that same factor. The recomputed
  modes are matched to the cached model through its mass coupling block
  ``M_be = M_ib^T Phi + Psi^T M_ii Phi`` (= ``Phi^T M_ib - Lambda^-1 Phi^T K_ib``
  transposed, no constraint modes needed): the orthogonal ``R`` that best
  maps the new block onto the stored one fixes signs and any rotation
  inside a repeated eigenvalue (it may not exchange modes of different
  frequencies). A mismatch over 1e-6 (another mesh, other
  code) is a SolveError, never a silently wrong picture.
* Rigid damper, ``q = [t; theta]`` about its centroid: ``u = t + theta x (x - c)``.

Collective over ``comm``; the fields are gathered on rank 0.
"""

from __future__ import annotations

import logging

import numpy as np

from ..errors import SolveError
from .craig_bampton import interior_factor, split_interface
from .modes import BodyShapes, _gather_shapes, load_bodies
from .parallel import allsum, dense_solve

log = logging.getLogger(__name__)

MATCH_TOL = 1e-6


def expand_body(geom, body: str, rm, Q: np.ndarray, comm=None) -> BodyShapes | None:
    """The full-mesh displacement of ``body`` for each column of ``Q`` (reduced coordinates).

    Returns a BodyShapes on rank 0 (``disp`` of shape (k, n_points, 3), in the
    units of ``Q``), None on the other ranks.
    """
    from mpi4py import MPI

    comm = MPI.COMM_WORLD if comm is None else comm
    Q = np.asarray(Q, dtype=float).reshape(rm.K.shape[0], -1)
    eb = load_bodies(geom, comm, which=(body,))[body]
    if rm.kind == "rigid":
        arrays = _rigid_field(eb, rm, Q)
    else:
        arrays = _cb_field(geom, eb, body, rm, Q, comm)
    return _gather_shapes(eb.V, arrays, comm)


def _rigid_field(eb, rm, Q: np.ndarray) -> list[np.ndarray]:
    x = eb.owned_node_coords() - np.asarray(rm.ref_point)
    out = []
    for j in range(Q.shape[1]):
        t, th = Q[:3, j], Q[3:6, j]
        out.append((t + np.cross(th, x)).ravel())
    return out


def _cb_field(geom, eb, body: str, rm, Q: np.ndarray, comm) -> list[np.ndarray]:
    from .interface import interface_points, locate_nodes

    pts, _, labels = interface_points(geom, body)
    nodes = locate_nodes(eb, pts, labels=labels)
    nb = 3 * nodes.n
    m = rm.K.shape[0] - nb
    if nb != rm.T.shape[0] or m < 0:
        raise SolveError(
            f"{body}: the mesh has {nb} interface DOFs, the reduced model {rm.T.shape[0]}"
        )
    sp_ = split_interface(eb, nodes)
    inv = np.empty(nb, dtype=int)
    inv[sp_.is_order] = np.arange(nb)
    ub, eta = Q[:nb], Q[nb:]
    Phi, lam, F, keep = interior_factor(sp_, m, body, comm)
    R = np.zeros((0, 0))
    if m:
        # M_be^T = Phi^T M_ib - Lambda^-1 Phi^T K_ib (index-set column order)
        MbeT = allsum(comm, sp_.Mib.T @ Phi).T - allsum(comm, sp_.Kib.T @ Phi).T / lam[:, None]
        Mbe_new = MbeT.T[inv]
        Mbe_old = np.asarray(rm.M)[:nb, nb:]
        U, _, Vt = np.linalg.svd(Mbe_new.T @ Mbe_old)
        R = U @ Vt
        ref = max(np.linalg.norm(Mbe_old), 1e-300)
        mismatch = np.linalg.norm(Mbe_new @ R - Mbe_old) / ref
        f_err = np.abs(np.sqrt(lam) / (2 * np.pi) / np.asarray(rm.mode_freqs_hz) - 1).max()
        # R may flip signs and turn a repeated eigenvalue's modes, never exchange two
        # modes of different frequency: R must commute with Lambda
        mixing = np.abs(R * (lam[:, None] - lam[None, :])).max() / lam.max()
        if max(mismatch, f_err, mixing) > MATCH_TOL:
            raise SolveError(
                f"{body}: the recomputed fixed-interface modes do not match the cached model "
                f"(coupling block {mismatch:.1e}, frequencies {f_err:.1e}, mode mixing "
                f"{mixing:.1e}; tolerance {MATCH_TOL:.0e}): was it reduced from another mesh?"
            )
        log.debug("%s: modes matched to the cached model to %.1e", body, mismatch)
    rhs = -(sp_.Kib @ ub[sp_.is_order])
    ui = dense_solve(F, rhs, sp_.n_i, comm) + Phi @ (R @ eta)
    keep.destroy()
    off = eb.dof_offset
    full = np.zeros((eb.n_local, Q.shape[1]))
    full[sp_.interior - off] = ui
    full[sp_.my_b - off] = ub[sp_.mine]
    return [full[:, j].copy() for j in range(Q.shape[1])]
