"""The structure's flexibility seen by a contact spring (workbench/assembly/flexibility.py)."""

import numpy as np
import pytest

from workbench.assembly.flexibility import structure_to_spring
from workbench.errors import InputError


def test_two_bodies_in_series_with_the_contact():
    """ground -k1- x1 =kc= x2 -k2- ground: the contact sees k1 and k2 in series."""
    k1, k2, kc = 3.0e8, 5.0e7, 1.0e8
    K = np.diag([k1, k2])
    W = np.array([[-1.0, 1.0]])  # relative displacement x2 - x1
    kg = structure_to_spring(K, W, [kc])
    assert kg[0] == pytest.approx(kc * (1 / k1 + 1 / k2), rel=1e-12)


def test_other_springs_stay_in_place():
    """Two contacts in parallel between a grounded node and a free node: each sees only
    the other contact's spring (an equal and opposite pair of forces does not load the
    ground spring)."""
    k1, ka, kb = 2.0e8, 1.0e8, 4.0e8
    K = np.diag([k1, 0.0])  # the second node is free: held by the contacts only
    W = np.array([[-1.0, 1.0], [-1.0, 1.0]])
    kg = structure_to_spring(K, W, [ka, kb])
    assert kg[0] == pytest.approx(ka / kb, rel=1e-9)
    assert kg[1] == pytest.approx(kb / ka, rel=1e-9)


def test_a_node_of_a_refined_bar_has_a_mesh_independent_flexibility():
    """A node on a bar of n elements fixed at both ends: the structure's flexibility at the
    midpoint is L / (4 E A), independent of n (1D has no point-load singularity), so the
    ratio converges; checked at three refinements."""
    EA, L, kc = 2.0e6, 1.0, 1.0e6
    for n in (2, 8, 32):
        k = EA / (L / n)
        K = np.zeros((n + 1, n + 1))
        for e in range(n):
            K[e : e + 2, e : e + 2] += k * np.array([[1, -1], [-1, 1]])
        K = K[1:-1, 1:-1]  # both ends fixed
        # a contact between the bar's midpoint and a rigid ground point (one extra dof)
        Kt = np.zeros((n, n))
        Kt[: n - 1, : n - 1] = K
        W = np.zeros((1, n))
        W[0, n // 2 - 1] = -1.0
        W[0, -1] = 1.0
        Kt[-1, -1] = 1e20  # the ground point: rigid
        kg = structure_to_spring(Kt, W, [kc])
        assert kg[0] == pytest.approx(kc * L / (4 * EA), rel=1e-9)


def test_bad_input_names_the_parameter():
    with pytest.raises(InputError, match="kc"):
        structure_to_spring(np.eye(2), np.ones((1, 2)), [-1.0])
    with pytest.raises(InputError, match="W"):
        structure_to_spring(np.eye(2), np.ones((1, 3)), [1.0])
