"""Reading the written meshes back: statistics (gmsh) and dolfinx meshes (XDMF).

:func:`read_msh` is the way the FE stage should load ``rig.msh`` and
``damper.msh`` into dolfinx: ``dolfinx.io.gmshio.read_from_msh`` in the
Debian build of dolfinx 0.5.2 is broken (it returns an undefined name on
the reading rank and passes an unknown ``partitioner`` argument on the
others), so this does what it was meant to do: read the file with gmsh on
one rank and call ``gmshio.model_to_mesh``. It also returns the physical
group names and the coordinates of the point groups, which dolfinx drops.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .occ import gmsh_session

TET10 = 11  # gmsh element type of the 10-node tetrahedron


@dataclass(frozen=True)
class MeshFileInfo:
    """What a written ``.msh`` holds, read back with gmsh (coordinates in metres)."""

    n_nodes: int
    n_cells: int
    vertices: np.ndarray  # (n_vertices, 3) corner nodes of the tetrahedra
    volume: float  # m^3, integrated over the (curved, second-order) elements
    centroid: np.ndarray  # (3,) m
    groups: dict[str, tuple[int, int]]  # name -> (dim, tag)
    point_groups: dict[str, np.ndarray] = field(default_factory=dict)  # name -> (k, 3) m


def mesh_file_info(path: str | Path) -> MeshFileInfo:
    """Nodes, cells, tetrahedron corners, volume and groups of a written mesh."""
    with gmsh_session() as gmsh:
        gmsh.open(str(path))
        tags, x, _ = gmsh.model.mesh.getNodes()
        x = x.reshape(-1, 3)
        order = np.argsort(tags)
        tags, x = tags[order], x[order]
        _, enodes = gmsh.model.mesh.getElementsByType(TET10)
        conn = enodes.reshape(-1, 10)
        corners = np.unique(conn[:, :4])
        vert = x[np.searchsorted(tags, corners)]
        pts, w = gmsh.model.mesh.getIntegrationPoints(TET10, "Gauss4")  # det J is cubic
        _, det, coord = gmsh.model.mesh.getJacobians(TET10, pts)
        det = det.reshape(-1, len(w))
        coord = coord.reshape(-1, len(w), 3)
        dv = det * w[None, :]
        volume = float(dv.sum())
        centroid = np.einsum("eq,eqi->i", dv, coord) / volume
        groups, point_groups = {}, {}
        for dim, tag in gmsh.model.getPhysicalGroups():
            name = gmsh.model.getPhysicalName(dim, tag)
            groups[name] = (int(dim), int(tag))
            if dim == 0:
                _, c = gmsh.model.mesh.getNodesForPhysicalGroup(0, tag)
                point_groups[name] = np.asarray(c).reshape(-1, 3)
        return MeshFileInfo(
            n_nodes=int(len(tags)),
            n_cells=int(conn.shape[0]),
            vertices=vert,
            volume=volume,
            centroid=centroid,
            groups=groups,
            point_groups=point_groups,
        )


@dataclass
class DolfinxMesh:
    """A mesh read into dolfinx with its tags and the names of its physical groups."""

    mesh: Any  # dolfinx.mesh.Mesh
    cell_tags: Any  # MeshTags of dimension 3 (values: physical tags)
    facet_tags: Any  # MeshTags of dimension 2
    groups: dict[str, tuple[int, int]]  # name -> (dim, tag)
    point_groups: dict[str, np.ndarray]  # name -> (k, 3) coordinates, m


def import_gmshio() -> Any:
    """``dolfinx.io.gmshio``, imported without losing the SIGINT handler.

    Importing it imports gmsh, which sets SIGINT to ``SIG_DFL``: a Ctrl-C
    would then kill the process silently instead of raising
    KeyboardInterrupt (and :func:`~workbench.geometry.occ.gmsh_session`
    would record and restore ``SIG_DFL``). The handler in place before the
    import is put back.
    """
    import signal
    import threading

    main = threading.current_thread() is threading.main_thread()
    prev = signal.getsignal(signal.SIGINT) if main else None
    try:
        from dolfinx.io import gmshio
    finally:
        if main and prev is not None:
            signal.signal(signal.SIGINT, prev)
    return gmshio


def read_msh(path: str | Path, comm: Any = None, rank: int = 0) -> DolfinxMesh:
    """Read a ``.msh`` written by the geometry stage into a (distributed) dolfinx mesh.

    ``comm`` defaults to ``MPI.COMM_WORLD``; gmsh reads the file on ``rank``
    and dolfinx distributes the mesh. Cell and facet tags carry the physical
    tags; ``groups`` maps the names to them.
    """
    from mpi4py import MPI

    gmshio = import_gmshio()
    comm = MPI.COMM_WORLD if comm is None else comm
    if comm.rank == rank:
        with gmsh_session() as gmsh:
            gmsh.open(str(path))
            groups, point_groups = {}, {}
            for dim, tag in gmsh.model.getPhysicalGroups():
                name = gmsh.model.getPhysicalName(dim, tag)
                groups[name] = (int(dim), int(tag))
                if dim == 0:
                    _, c = gmsh.model.mesh.getNodesForPhysicalGroup(0, tag)
                    point_groups[name] = np.asarray(c).reshape(-1, 3)
            mesh, ct, ft = gmshio.model_to_mesh(gmsh.model, comm, rank, gdim=3)
        comm.bcast((groups, point_groups), root=rank)
    else:
        import gmsh

        mesh, ct, ft = gmshio.model_to_mesh(gmsh.model, comm, rank, gdim=3)
        groups, point_groups = comm.bcast(None, root=rank)
    return DolfinxMesh(mesh, ct, ft, groups, point_groups)


def write_xdmf(msh_path: str | Path, xdmf_path: str | Path, name: str) -> Path:
    """Write a mesh and one meshtags per physical group (named after it) as XDMF.

    Serial (``MPI.COMM_SELF``): called by the rank that meshed. Point groups
    become vertex meshtags located by coordinates (within 1e-12 m).
    """
    from dolfinx.io import XDMFFile
    from dolfinx.mesh import meshtags
    from mpi4py import MPI
    from scipy.spatial import cKDTree

    d = read_msh(msh_path, MPI.COMM_SELF)
    mesh = d.mesh
    mesh.name = name
    xdmf_path = Path(xdmf_path)
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(0, tdim)
    n_vert = mesh.topology.index_map(0).size_local
    # the geometry node of each vertex (P2 geometry: vertices are a subset of the nodes)
    from dolfinx.cpp.mesh import entities_to_geometry

    cpp_mesh = getattr(mesh, "_mesh", mesh)  # dolfinx 0.5.2 wraps the C++ mesh
    vgeo = entities_to_geometry(cpp_mesh, 0, np.arange(n_vert, dtype=np.int32), False).ravel()
    vx = mesh.geometry.x[vgeo]
    tree = cKDTree(vx)
    geom = f"/Xdmf/Domain/Grid[@Name='{name}']/Geometry"
    with XDMFFile(MPI.COMM_SELF, str(xdmf_path), "w") as f:
        f.write_mesh(mesh)
        for gname, (dim, tag) in sorted(d.groups.items(), key=lambda kv: (-kv[1][0], kv[1][1])):
            if dim == tdim:
                idx = d.cell_tags.indices[d.cell_tags.values == tag]
            elif dim == tdim - 1:
                idx = d.facet_tags.indices[d.facet_tags.values == tag]
            else:
                dist, idx = tree.query(d.point_groups[gname])
                if dist.max() > 1e-12:
                    raise RuntimeError(f"{gname}: a point is {dist.max():.3g} m from any vertex")
            idx = np.unique(np.asarray(idx, dtype=np.int32))
            mt = meshtags(mesh, dim, idx, np.full(idx.size, tag, dtype=np.int32))
            mt.name = gname
            f.write_meshtags(mt, geometry_xpath=geom)
    return xdmf_path


# gmsh 10-node tetrahedron -> VTK quadratic tetrahedron node order (the last
# two edge nodes are swapped: gmsh 8 = edge 2-3, 9 = edge 1-3).
GMSH_TO_VTK_TET10 = np.array([0, 1, 2, 3, 4, 5, 6, 7, 9, 8])


def read_tet10(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Node coordinates (N, 3) in m and 10-node tetrahedra (M, 10), 0-based, gmsh order."""
    with gmsh_session() as gmsh:
        gmsh.open(str(path))
        tags, x, _ = gmsh.model.mesh.getNodes()
        x = x.reshape(-1, 3)
        order = np.argsort(tags)
        tags, x = tags[order], x[order]
        _, enodes = gmsh.model.mesh.getElementsByType(TET10)
        conn = np.searchsorted(tags, enodes).reshape(-1, 10)
    return x, conn
