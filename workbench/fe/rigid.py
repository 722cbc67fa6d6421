"""The rigid 6-DOF damper: mass and inertia integrated over its mesh.

Generalised coordinates ``q = [u_ref (3, m); theta (3, rad)]`` about the
centroid ``ref``; a material point at ``x`` moves by
``u = u_ref + theta x (x - ref) = u_ref - skew(x - ref) theta``, so each
interface node contributes the rows ``[I, -skew(x_i - ref)]`` of ``T``.
About the centroid the kinetic energy separates::

    M = [[m I, 0], [0, J]],   J = int rho (|r|^2 I - r r^T) dV,  r = x - ref
    K = 0

It is the cheap alternative to the Craig-Bampton damper and gives the same
stuck frequencies where the damper is much stiffer than its contacts.
"""

from __future__ import annotations

import numpy as np

from .mesh import FEMesh

QUAD_DEGREE = 8  # x_i x_j det(J) on curved P2 tetrahedra is of degree 7


def skew(a: np.ndarray) -> np.ndarray:
    """The matrix of ``b -> a x b``."""
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def mass_properties(femesh: FEMesh, rho: float) -> tuple[float, np.ndarray, np.ndarray]:
    """(mass kg, centroid m, inertia tensor about the centroid kg m^2) of a mesh."""
    import ufl
    from dolfinx import fem

    from .parallel import allsum

    mesh = femesh.mesh
    comm = mesh.comm
    dx = ufl.dx(domain=mesh, metadata={"quadrature_degree": QUAD_DEGREE})
    x = ufl.SpatialCoordinate(mesh)
    # three compiled forms, re-assembled with different constant directions a, b
    a = fem.Constant(mesh, np.zeros(3))
    b = fem.Constant(mesh, np.zeros(3))
    c0 = fem.Constant(mesh, np.zeros(3))
    r = x - c0
    rho = fem.Constant(mesh, float(rho))
    f_mass = fem.form(rho * dx)
    f_first = fem.form(rho * ufl.dot(a, x) * dx)
    f_second = fem.form(rho * ufl.dot(a, r) * ufl.dot(b, r) * dx)
    e = np.eye(3)

    def integral(form) -> float:
        return float(allsum(comm, fem.assemble_scalar(form)))

    m = integral(f_mass)
    first = []
    for i in range(3):
        a.value[:] = e[i]
        first.append(integral(f_first))
    c = np.array(first) / m
    c0.value[:] = c
    S = np.zeros((3, 3))
    for i in range(3):
        for j in range(i, 3):
            a.value[:] = e[i]
            b.value[:] = e[j]
            S[i, j] = S[j, i] = integral(f_second)
    S = 0.5 * (S + S.T)
    J = np.trace(S) * np.eye(3) - S
    return m, c, J


def rigid_matrices(
    mass: float, inertia: np.ndarray, ref: np.ndarray, points: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """K (zero), M and T of a rigid body about its centroid ``ref`` for interface ``points``."""
    M = np.zeros((6, 6))
    M[:3, :3] = mass * np.eye(3)
    M[3:, 3:] = inertia
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    T = np.zeros((3 * len(pts), 6))
    for i, p in enumerate(pts):
        T[3 * i : 3 * i + 3, :3] = np.eye(3)
        T[3 * i : 3 * i + 3, 3:] = -skew(p - ref)
    return np.zeros((6, 6)), M, T
