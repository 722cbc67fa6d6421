"""Linear elasticity of one body: P2 displacement space, stiffness and mass.

::

    K = int sigma(u) : eps(v) dx      sigma = 2 mu eps + lambda tr(eps) I
    M = int rho u . v dx

Units: SI throughout (Pa, kg/m^3, m), so K is in N/m and M in kg.
Clamped DOFs (a surface group, e.g. ``"clamped"`` at the rig's base) are
Dirichlet rows: K carries 1 and M carries 0 on their diagonal, so they add
only infinite eigenvalues that a shift-and-invert solve never sees.

PETSc numbering: the space has block size 3; the global row of component
``c`` of block (node) ``b`` is ``3 b + c``.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import check_range
from ..log import stage
from .mesh import FEMesh
from .parallel import info

log = logging.getLogger(__name__)

QUADRATURE_DEGREE = 4  # exact for the P2 mass matrix on straight-sided cells


@dataclass(frozen=True)
class Material:
    """Isotropic linear elastic material (SI units)."""

    E_pa: float
    nu: float
    rho_kg_m3: float

    @classmethod
    def from_dict(cls, d: dict[str, float]) -> Material:
        """From ``BuiltGeometry.material`` (keys E_pa, nu, rho_kg_m3), checked."""
        return cls(
            E_pa=check_range("material.E_pa", d.get("E_pa"), 0.0, lo_open=True, unit="Pa"),
            nu=check_range("material.nu", d.get("nu"), -1.0, 0.5, lo_open=True, hi_open=True),
            rho_kg_m3=check_range(
                "material.rho_kg_m3", d.get("rho_kg_m3"), 0.0, lo_open=True, unit="kg/m^3"
            ),
        )

    @property
    def lame(self) -> tuple[float, float]:
        """(mu, lambda) in Pa."""
        mu = self.E_pa / (2.0 * (1.0 + self.nu))
        lmb = self.E_pa * self.nu / ((1.0 + self.nu) * (1.0 - 2.0 * self.nu))
        return mu, lmb


@dataclass(frozen=True)
class ElasticBody:
    """Assembled stiffness and mass of one body on its distributed mesh."""

    name: str
    femesh: FEMesh
    V: Any  # dolfinx VectorFunctionSpace, P2
    K: Any  # PETSc.Mat, N/m, Dirichlet rows with 1 on the diagonal
    M: Any  # PETSc.Mat, kg, Dirichlet rows with 0 on the diagonal
    material: Material
    clamped_blocks: np.ndarray  # local block indices of the clamped nodes (owned + ghost)

    @property
    def comm(self):
        return self.femesh.comm

    @property
    def n_dofs(self) -> int:
        """Global number of DOFs (3 per P2 node, clamped ones included)."""
        im = self.V.dofmap.index_map
        return int(im.size_global * self.V.dofmap.index_map_bs)

    @property
    def n_local(self) -> int:
        """Number of DOFs owned by this rank."""
        return int(self.V.dofmap.index_map.size_local * self.V.dofmap.index_map_bs)

    @property
    def dof_offset(self) -> int:
        """Global index of this rank's first owned DOF."""
        return int(self.V.dofmap.index_map.local_range[0] * self.V.dofmap.index_map_bs)

    def owned_node_coords(self) -> np.ndarray:
        """(n_owned_nodes, 3) coordinates of the owned P2 nodes, m."""
        n = self.V.dofmap.index_map.size_local
        return self.V.tabulate_dof_coordinates()[:n]


def assemble_body(
    femesh: FEMesh,
    material: Material,
    *,
    name: str,
    clamped: str | None = None,
    degree: int = 2,
    timings: dict[str, float] | None = None,
) -> ElasticBody:
    """Assemble K and M of a body with Lagrange elements of ``degree`` (default P2).

    ``clamped`` names a surface group whose nodes are fixed (None: free body).
    """
    import dolfinx.fem.petsc  # noqa: F401 - registers fem.petsc
    import ufl
    from dolfinx import fem
    from petsc4py import PETSc

    local: dict[str, float] = {}
    with stage(local, "assembly"):
        mesh = femesh.mesh
        V = fem.VectorFunctionSpace(mesh, ("CG", degree))
        mu, lmb = material.lame
        u, v = ufl.TrialFunction(V), ufl.TestFunction(V)

        def eps(w):
            return ufl.sym(ufl.grad(w))

        def sigma(w):
            return 2.0 * mu * eps(w) + lmb * ufl.tr(eps(w)) * ufl.Identity(3)

        dx = ufl.dx(metadata={"quadrature_degree": QUADRATURE_DEGREE})
        a = fem.form(ufl.inner(sigma(u), eps(v)) * dx)
        m = fem.form(material.rho_kg_m3 * ufl.inner(u, v) * dx)
        bcs = []
        blocks = np.zeros(0, dtype=np.int32)
        if clamped is not None:
            facets = femesh.facets(clamped)
            mesh.topology.create_connectivity(2, 3)
            blocks = fem.locate_dofs_topological(V, 2, facets)
            n_clamped = femesh.comm.allreduce(int(np.sum(blocks < V.dofmap.index_map.size_local)))
            if n_clamped == 0:
                from ..errors import InputError

                raise InputError(
                    f"{name} clamped group",
                    clamped,
                    "a surface with mesh nodes",
                    "no node found on it",
                )
            bcs = [fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType), blocks, V)]
        K = fem.petsc.assemble_matrix(a, bcs=bcs, diagonal=1.0)
        K.assemble()
        M = fem.petsc.assemble_matrix(m, bcs=bcs, diagonal=0.0)
        M.assemble()
    body = ElasticBody(
        name=name,
        femesh=femesh,
        V=V,
        K=K,
        M=M,
        material=material,
        clamped_blocks=np.asarray(blocks),
    )
    if timings is not None:
        timings["assembly"] = timings.get("assembly", 0.0) + local["assembly"]
    info(
        log,
        femesh.comm,
        "%s: %d DOFs (P%d), assembled in %.1f s",
        name,
        body.n_dofs,
        degree,
        local["assembly"],
    )
    return body
