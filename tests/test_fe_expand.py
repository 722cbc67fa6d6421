"""Full-mesh fields rebuilt from reduced coordinates (workbench/fe/expand.py).

The expansion must give back the Craig-Bampton basis itself: for a field
``u = Phi_cb q`` the full FE energies equal the reduced ones, ``u^T K u =
q^T K_r q`` and ``u^T M u = q^T M_r q``, because ``K_r = Phi_cb^T K Phi_cb``.
A wrong sign or a rotated pair of fixed-interface modes breaks the mass
identity (the modal coordinates couple to the interface through ``M_be``),
so the reduced model's own eigenvectors, which mix every coordinate, are
the test fields. A rigid damper's field is a rigid motion (no strain
energy) with the rigid model's kinetic energy.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sl

from workbench.errors import SolveError
from workbench.fe.expand import expand_body
from workbench.fe.modes import load_bodies
from workbench.fe.reduce import reduce_body
from workbench.fe.samples import toy_rig


@pytest.fixture(scope="module")
def toy(tmp_path_factory):
    out = tmp_path_factory.mktemp("toy_expand")
    geom = toy_rig(out / "geometry", lc=0.004)
    return geom, {
        "rig": reduce_body(geom, "rig", n_modes=6),
        "damper": reduce_body(geom, "damper", n_modes=6),
        "rigid": reduce_body(geom, "damper", rigid=True),
    }


def _full_energies(geom, body, shapes):
    """u^T K u and u^T M u of each expanded field on the full (unreduced) FE model."""
    from mpi4py import MPI

    eb = load_bodies(geom, MPI.COMM_SELF, which=(body,))[body]
    # the gathered fields are in the P2 space's local order (serial: the DOF order)
    out = []
    x, y = eb.K.createVecs()
    d = eb.K.getDiagonal().getArray()
    for u in shapes.disp:
        x.setArray(u.ravel())
        eb.K.mult(x, y)
        k = x.dot(y)
        eb.M.mult(x, y)
        # sum diag(K) u^2: the size a strain energy of this field would have
        out.append((k, x.dot(y), float(d @ u.ravel() ** 2)))
    return np.array(out)


@pytest.mark.parametrize("body", ["rig", "damper"])
def test_craig_bampton_field_carries_the_reduced_energies(toy, body):
    geom, models = toy
    rm = models[body]
    lam, Y = sl.eigh(rm.K, rm.M)
    keep = [k for k in range(len(lam)) if lam[k] > 1e-6 * lam[-1]][:4]  # elastic modes
    Q = Y[:, keep]
    shapes = expand_body(geom, body, rm, Q)
    e = _full_energies(geom, body, shapes)
    kr = np.einsum("ij,ik,kj->j", Q, rm.K, Q)
    mr = np.einsum("ij,ik,kj->j", Q, rm.M, Q)
    np.testing.assert_allclose(e[:, 0], kr, rtol=1e-7)
    np.testing.assert_allclose(e[:, 1], mr, rtol=1e-7)
    # the interface DOFs are the reduced ones, at the interface nodes
    assert shapes.disp.shape == (len(keep), len(shapes.points), 3)


def test_wrong_modes_are_refused(toy):
    """Swapping two modal coordinates of the cached model is caught by the M_be match."""
    import dataclasses

    geom, models = toy
    rm = models["rig"]
    nb = rm.T.shape[0]
    M = rm.M.copy()
    M[:nb, [nb, nb + 2]] = M[:nb, [nb + 2, nb]]
    M[[nb, nb + 2], :nb] = M[[nb + 2, nb], :nb]
    bad = dataclasses.replace(rm, M=M)
    with pytest.raises(SolveError, match="do not match the cached model"):
        expand_body(geom, "rig", bad, np.eye(rm.K.shape[0])[:, :1])


def test_rigid_damper_field_is_a_rigid_motion(toy):
    geom, models = toy
    rm = models["rigid"]
    Q = np.eye(6)
    shapes = expand_body(geom, "damper", rm, Q)
    e = _full_energies(geom, "damper", shapes)
    # no strain energy: round-off of the sum of K's rows (about 1e-16 of its scale)
    assert np.all(np.abs(e[:, 0]) < 1e-12 * e[:, 2]), e[:, 0] / e[:, 2]
    np.testing.assert_allclose(e[:, 1], np.diag(rm.M), rtol=1e-9)
