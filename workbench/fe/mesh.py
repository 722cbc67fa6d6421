"""A distributed dolfinx mesh with its physical groups by name.

The reading itself is the geometry stage's :func:`workbench.geometry.read_msh`
(dolfinx 0.5.2's ``gmshio.read_from_msh`` is broken); :class:`FEMesh` adds
lookups by name that fail with an InputError naming the groups that exist.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class FEMesh:
    """A distributed dolfinx mesh with its tags and physical group names."""

    mesh: Any  # dolfinx.mesh.Mesh
    cell_tags: Any  # dolfinx MeshTags of the volumes
    facet_tags: Any  # dolfinx MeshTags of the surfaces
    groups: dict[str, tuple[int, int]]  # physical name -> (dim, tag)
    path: Path

    @property
    def comm(self):
        return self.mesh.comm

    def group(self, name: str, dim: int) -> int:
        """Tag of the physical group ``name`` of dimension ``dim``; InputError if absent."""
        if name not in self.groups or self.groups[name][0] != dim:
            have = sorted(n for n, (d, _) in self.groups.items() if d == dim)
            raise InputError(
                f"physical group of {self.path.name}",
                name,
                f"one of the {dim}-D groups {have}",
                "the mesh file does not define it",
            )
        return self.groups[name][1]

    def facets(self, name: str) -> np.ndarray:
        """Local indices of the facets in the surface group ``name``."""
        return self.facet_tags.find(self.group(name, 2))

    def cells(self, name: str) -> np.ndarray:
        """Local indices of the cells in the volume group ``name``."""
        return self.cell_tags.find(self.group(name, 3))


def read_msh(path: str | Path, comm=None) -> FEMesh:
    """Read a gmsh mesh file (read on rank 0, distributed over ``comm``).

    Delegates to :func:`workbench.geometry.read_msh` after checking, on every
    rank at once, that the file exists (a missing file would otherwise stop
    rank 0 inside gmsh while the others wait). Only the elements of physical
    groups become cells/facets (gmshio's rule).
    """
    from mpi4py import MPI

    from ..geometry import read_msh as geometry_read_msh

    comm = MPI.COMM_WORLD if comm is None else comm
    path = Path(path)
    ok = comm.bcast(path.is_file() if comm.rank == 0 else None, root=0)
    if not ok:
        raise InputError("mesh file", str(path), "an existing gmsh .msh file")
    d = geometry_read_msh(path, comm)
    if not any(dim == 3 for dim, _ in d.groups.values()):
        raise InputError("mesh file", str(path), "a mesh with a physical volume group")
    n_cells = comm.allreduce(d.mesh.topology.index_map(3).size_local)
    log.debug(
        "read %s: %d cells, order %d, groups %s",
        path.name,
        n_cells,
        d.mesh.geometry.cmap.degree,
        sorted(d.groups),
    )
    return FEMesh(
        mesh=d.mesh,
        cell_tags=d.cell_tags,
        facet_tags=d.facet_tags,
        groups=dict(d.groups),
        path=path,
    )
