"""The fast kernels of the Craig-Bampton reduction against the plain PETSc products.

* :func:`workbench.fe.parallel.sparse_solve` (MUMPS with sparse right-hand
  sides) gives the constraint modes of :func:`dense_solve` to round-off;
* :func:`workbench.fe.craig_bampton.node_mass` finds ``M_ii = m (x) I_3`` on a
  vector P2 body and :func:`mass_mult` equals PETSc's ``M_ii X``; a matrix
  that couples the components is refused (None), so the PETSc path is used.
"""

from __future__ import annotations

import numpy as np
import pytest
from mpi4py import MPI

from workbench.fe.craig_bampton import interior_factor, mass_mult, node_mass, split_interface
from workbench.fe.interface import interface_points, locate_nodes
from workbench.fe.modes import load_bodies
from workbench.fe.parallel import dense_mult, dense_solve, sparse_solve
from workbench.fe.samples import toy_rig


@pytest.fixture(scope="module")
def split(tmp_path_factory):
    geom = toy_rig(tmp_path_factory.mktemp("toy") / "geometry", lc=0.004)
    comm = MPI.COMM_SELF
    body = load_bodies(geom, comm, which=("rig",))["rig"]
    pts, _, labels = interface_points(geom, "rig")
    nodes = locate_nodes(body, pts, labels=labels)
    return split_interface(body, nodes), comm


def test_sparse_right_hand_sides_give_the_dense_constraint_modes(split):
    sp_, comm = split
    _, _, F, keep = interior_factor(sp_, 0, "rig", comm)
    B = -sp_.Kib
    assert B.shape[1] >= 6 and B.nnz > 0
    X_sparse = sparse_solve(F, B, sp_.n_i, comm)
    X_dense = dense_solve(F, B.toarray(), sp_.n_i, comm)
    keep.destroy()
    scale = np.abs(X_dense).max()
    assert scale > 0
    # the same factor, the same elimination: only the order of a few sums differs
    assert np.abs(X_sparse - X_dense).max() <= 1e-13 * scale
    # and it solves K_ii X = B (the residual of a direct solve: round-off of the factor)
    Kx = dense_mult(sp_.K_ii, X_sparse, sp_.n_i, comm)
    assert np.abs(Kx - B.toarray()).max() <= 1e-9 * np.abs(B).max()


def test_node_mass_product_equals_the_petsc_product(split):
    sp_, comm = split
    m = node_mass(sp_.M_ii, comm)
    assert m is not None and m.shape[0] * 3 == sp_.n_i
    # a third of M_ii's rows, a ninth of its entries (the component blocks are diagonal)
    assert m.nnz * 9 <= sp_.M_ii.getInfo()["nz_used"] + 1
    X = np.random.default_rng(0).standard_normal((sp_.n_i, 7))
    ref = dense_mult(sp_.M_ii, X, sp_.n_i, comm)
    got = mass_mult(m, sp_.M_ii, X[:, :], sp_.n_i, comm)
    assert np.abs(got - ref).max() <= 1e-14 * np.abs(ref).max()
    # a non-contiguous block of columns (the projection's slices) is handled too
    got2 = mass_mult(m, sp_.M_ii, X[:, 1:6], sp_.n_i, comm)
    assert np.abs(got2 - ref[:, 1:6]).max() <= 1e-14 * np.abs(ref).max()


def test_a_mass_that_couples_the_components_is_refused(split):
    sp_, comm = split
    A = sp_.K_ii  # stiffness couples x, y and z: not m (x) I_3
    assert node_mass(A, comm) is None
