"""gmsh (OpenCASCADE) builders: draw a :class:`~.layout.Layout` and mesh it.

The rig and the damper are two separate gmsh models, meshed and written
separately (the damper is a separate body). Both carry a mesh vertex at
every contact point: the points are added as CAD points and embedded in
the platform faces (rig) and in the damper's surface, so gmsh must put a
node there. Meshes are second order (10-node tetrahedra), with a global
size and a finer size around the contact points (a Distance + Threshold
field), written in metres (the CAD is drawn in millimetres and scaled on
output, ``Mesh.ScalingFactor``).

Physical groups (names are the contract with the FE stage; the numbers are
the tags the XDMF meshtags carry)::

    rig     3: base 1, blade_1 2, blade_2 3 (a platform belongs to its blade)
            2: clamped 11 (base bottom), contact_face_1 12, contact_face_2 13
            0: contact_nodes_1 21, contact_nodes_2 22, excitation 23, response 24
    damper  3: damper 1
            2: contact_face_1 12, contact_face_2 13 (wedge only: cone and
               cylinder touch along lines, which are not faces)
            0: contact_nodes_1 21, contact_nodes_2 22

Side 1 is the platform of blade 1 (x < 0), side 2 that of blade 2.
"""

from __future__ import annotations

import logging
import math
import os
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import SolveError
from .layout import Layout

log = logging.getLogger(__name__)

GROUPS = {
    "rig": {
        3: {"base": 1, "blade_1": 2, "blade_2": 3},
        2: {"clamped": 11, "contact_face_1": 12, "contact_face_2": 13},
        0: {"contact_nodes_1": 21, "contact_nodes_2": 22, "excitation": 23, "response": 24},
    },
    "damper": {
        3: {"damper": 1},
        2: {"contact_face_1": 12, "contact_face_2": 13},
        0: {"contact_nodes_1": 21, "contact_nodes_2": 22},
    },
}

# Geometric tolerance for recognising CAD faces, mm (the CAD is exact to
# about 1e-7 mm; the faces we look for are millimetres apart).
_TOL = 1e-5


class MeshingError(SolveError):
    """gmsh failed on a geometry that passed the checks (exit code 3)."""


@contextmanager
def gmsh_session() -> Iterator[Any]:
    """Initialise gmsh silently and always finalise it, also on errors.

    Importing gmsh resets the SIGINT handler to the default; the handler
    in place before is restored on exit so Ctrl-C reaches Python again.
    """
    main = threading.current_thread() is threading.main_thread()
    prev = signal.getsignal(signal.SIGINT) if main else None
    import gmsh

    gmsh.initialize(readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.Verbosity", 2)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.logger.start()
        yield gmsh
    finally:
        try:
            gmsh.logger.stop()
        finally:
            gmsh.finalize()
            if main and prev is not None:
                signal.signal(signal.SIGINT, prev)


def _last_errors(gmsh) -> str:
    try:
        msgs = [m for m in gmsh.logger.get() if m.lower().startswith(("error", "warning"))]
    except Exception:  # noqa: BLE001 - only used to enrich a message
        return ""
    return "; ".join(msgs[-3:])


def _plane_faces(gmsh, normal: np.ndarray, point: np.ndarray) -> list[int]:
    """Planar surfaces of the current model lying in the plane (point, normal)."""
    out = []
    for _, s in gmsh.model.getEntities(2):
        if gmsh.model.getType(2, s) != "Plane":
            continue
        com = np.array(gmsh.model.occ.getCenterOfMass(2, s))
        if abs((com - point) @ normal) > _TOL:
            continue
        lo = gmsh.model.getParametrizationBounds(2, s)
        uv = [0.5 * (lo[0][0] + lo[1][0]), 0.5 * (lo[0][1] + lo[1][1])]
        nrm = np.array(gmsh.model.getNormal(s, uv))
        if abs(abs(nrm @ normal) - 1.0) < 1e-8:
            out.append(s)
    return out


def face_containing(gmsh, normal: np.ndarray, pts: np.ndarray, what: str) -> int:
    """The one planar surface that contains all ``pts`` (bounding-box test)."""
    pts = np.atleast_2d(pts)
    for s in _plane_faces(gmsh, normal, pts[0]):
        x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(2, s)
        lo = np.array([x0, y0, z0]) - _TOL
        hi = np.array([x1, y1, z1]) + _TOL
        if np.all((pts >= lo) & (pts <= hi)):
            return s
    raise MeshingError(f"internal: no CAD face found for {what}")


def embed_points(gmsh, pts: np.ndarray, surface: int) -> list[int]:
    occ = gmsh.model.occ
    tags = [occ.addPoint(*map(float, p)) for p in pts]
    occ.synchronize()
    gmsh.model.mesh.embed(0, tags, 2, surface)
    return tags


def size_field(gmsh, point_tags: list[int], h_min: float, h_max: float, dist: float) -> None:
    """Size ``h_min`` within ``h_min`` of the points, growing linearly to ``h_max`` at ``dist``."""
    f = gmsh.model.mesh.field
    fd = f.add("Distance")
    f.setNumbers(fd, "PointsList", point_tags)
    ft = f.add("Threshold")
    f.setNumber(ft, "InField", fd)
    f.setNumber(ft, "SizeMin", h_min)
    f.setNumber(ft, "SizeMax", h_max)
    f.setNumber(ft, "DistMin", h_min)
    f.setNumber(ft, "DistMax", max(dist, 1.01 * h_min))
    f.setAsBackgroundMesh(ft)
    gmsh.option.setNumber("Mesh.MeshSizeMax", h_max)
    gmsh.option.setNumber("Mesh.MeshSizeMin", 0.0)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)


def _groups(gmsh, body: str, members: dict[str, list[int]]) -> None:
    for dim, names in GROUPS[body].items():
        for name, tag in names.items():
            ents = members.get(name)
            if ents:
                gmsh.model.addPhysicalGroup(dim, ents, tag)
                gmsh.model.setPhysicalName(dim, tag, name)


def mesh_and_write(gmsh, path: Path, what: str, body: str = "", mirror: bool = False) -> None:
    """Generate the 3-D mesh, raise it to order 2 and write it (metres) atomically.

    ``mirror``: the model is the half x >= 0 of ``body`` ("rig" or "damper"); the mesh
    written is it and its mirror image (:func:`workbench.geometry.mirror.mirror_model`)."""
    try:
        gmsh.model.mesh.generate(3)
        gmsh.model.mesh.setOrder(2)
    except Exception as e:  # gmsh raises a bare Exception with its last error
        raise MeshingError(
            f"gmsh could not mesh the {what}: {e} {_last_errors(gmsh)} (try another "
            f"rig.mesh.size_mm or rig.mesh.contact_size_mm)"
        ) from None
    if mirror:
        from .mirror import mirror_model

        tags = {name: tag for names in GROUPS[body].values() for name, tag in names.items()}
        mirror_model(gmsh, tags, what)
    types, _, _ = gmsh.model.mesh.getElements(3)
    if list(types) != [11]:
        raise MeshingError(
            f"gmsh made element types {list(types)} for the {what}, not 10-node tetrahedra only"
        )
    gmsh.option.setNumber("Mesh.ScalingFactor", 1e-3)  # drawn in mm, written in m
    gmsh.option.setNumber("Mesh.Binary", 1)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.SaveAll", 0)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.part.msh")
    try:
        gmsh.write(str(tmp))
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def sides(lay: Layout) -> tuple[int, ...]:
    """The sides (0: blade 1's, x < 0; 1: blade 2's) a builder draws: both, or blade 2's
    alone where the mesh is mirrored (``[rig.mesh] mirror``)."""
    return (1,) if lay.params.rig.mesh.mirror else (0, 1)


def build_rig(gmsh: Any, lay: Layout, path: Path) -> None:
    """Draw, mesh and write the rig: base, two blades with platforms, embedded points
    (mirrored: the half x >= 0, then its mirror image, :mod:`workbench.geometry.mirror`)."""
    occ = gmsh.model.occ
    gmsh.model.add("rig")
    b = lay.base
    mirror = lay.params.rig.mesh.mirror
    x0 = 0.0 if mirror else b.x0  # the rig is symmetric about x = 0
    base = occ.addBox(x0, b.y0, b.z0, b.x0 + b.dx - x0, b.dy, b.dz)
    blades = []
    y0, y1 = lay.platform_y
    for k in sides(lay):
        bx = lay.blades[k]
        blade = occ.addBox(bx.x0, bx.y0, bx.z0, bx.dx, bx.dy, bx.dz)
        corners = [occ.addPoint(x, y0, z) for x, z in lay.platform_xz[k]]
        lines = [occ.addLine(corners[i], corners[(i + 1) % 4]) for i in range(4)]
        face = occ.addPlaneSurface([occ.addCurveLoop(lines)])
        ext = occ.extrude([(2, face)], 0.0, y1 - y0, 0.0)
        plat = [t for d, t in ext if d == 3]
        fused, _ = occ.fuse([(3, blade)], [(3, t) for t in plat])
        blades.append(fused)
    occ.fragment([(3, base)], [dt for f in blades for dt in f])
    occ.synchronize()
    vols: dict[str, list[int]] = {"base": [], **{f"blade_{k + 1}": [] for k in sides(lay)}}
    for _, v in gmsh.model.getEntities(3):
        x, _, z = occ.getCenterOfMass(3, v)
        if z < lay.base.dz:
            vols["base"].append(v)
        else:
            vols["blade_1" if x < 0 else "blade_2"].append(v)
    if not all(len(v) == 1 for v in vols.values()):
        raise MeshingError(f"internal: the rig CAD has volumes {vols}, expected one of each")
    members: dict[str, list[int]] = {k: v for k, v in vols.items()}
    members["clamped"] = [
        face_containing(
            gmsh, np.array([0.0, 0.0, 1.0]), np.array([[0.0, 0.0, 0.0]]), "the clamped face"
        )
    ]
    point_tags: list[int] = []
    for k in sides(lay):
        pts = lay.points[lay.side == k]
        face = face_containing(gmsh, lay.normals[k], pts, f"the contact face of blade {k + 1}")
        members[f"contact_face_{k + 1}"] = [face]
        tags = embed_points(gmsh, pts, face)
        members[f"contact_nodes_{k + 1}"] = tags
        point_tags += tags
    for name, pts in (("excitation", lay.excitation), ("response", lay.response)):
        members[name] = []
        for k in sides(lay):
            face = face_containing(
                gmsh, np.array([1.0, 0.0, 0.0]), pts[k], f"the {name} point of blade {k + 1}"
            )
            members[name] += embed_points(gmsh, pts[k : k + 1], face)
    _groups(gmsh, "rig", members)
    ms = lay.params.rig.mesh
    h_c = min(ms.contact_size_mm, lay.contact_spacing, ms.size_mm)
    size_field(gmsh, point_tags, h_c, ms.size_mm, ms.refine_distance_mm)
    mesh_and_write(gmsh, path, "rig", "rig", mirror)


def _rotate_seam_down(gmsh, vol: int, origin: np.ndarray, axis: np.ndarray) -> None:
    """Turn a cone or cylinder about its axis so its CAD seam line is at the bottom.

    OpenCASCADE closes a periodic face with a seam edge along one generator;
    the contact lines must not lie on it (a point cannot be embedded in a
    face's boundary), so the seam goes to the lowest generator, which faces
    neither platform.
    """
    occ = gmsh.model.occ
    lines = [c for _, c in gmsh.model.getEntities(1) if gmsh.model.getType(1, c) == "Line"]
    if len(lines) != 1:
        raise MeshingError(f"internal: expected one seam line on the damper, found {len(lines)}")
    mid = np.array(occ.getCenterOfMass(1, lines[0]))
    r = mid - origin
    r -= (r @ axis) * axis
    down = np.array([0.0, 0.0, -1.0])
    down -= (down @ axis) * axis
    r, down = r / np.linalg.norm(r), down / np.linalg.norm(down)
    ang = math.atan2(np.cross(r, down) @ axis, r @ down)
    if abs(ang) > 1e-12:
        occ.rotate([(3, vol)], *map(float, origin), *map(float, axis), ang)
        occ.synchronize()


def embed_on_lateral_face(
    gmsh: Any,
    lay: Layout,
    vol: int,
    origin: np.ndarray,
    axis: np.ndarray,
    lateral_type: str,
    members: dict[str, list[int]],
    point_tags: list[int],
) -> int:
    """A solid of revolution just added (``vol``): turn its seam down and embed each side's
    contact points in its one lateral face (gmsh type ``lateral_type``: "Cone", "Cylinder").
    Mirrored (``[rig.mesh] mirror``): cut to its half x >= 0 first (the seam, turned down,
    lies in the plane x = 0) and embed side 2's points only. Returns the volume's tag."""
    gmsh.model.occ.synchronize()
    _rotate_seam_down(gmsh, vol, origin, axis)
    if lay.params.rig.mesh.mirror:
        from .mirror import keep_half

        (vol,) = keep_half(gmsh, [(3, vol)])
    lateral = [s for _, s in gmsh.model.getEntities(2) if gmsh.model.getType(2, s) == lateral_type]
    if len(lateral) != 1:
        raise MeshingError(f"internal: the damper has {len(lateral)} {lateral_type} faces")
    for k in sides(lay):
        tags = embed_points(gmsh, lay.points[lay.side == k], lateral[0])
        members[f"contact_nodes_{k + 1}"] = tags
        point_tags += tags
    return vol


def build_damper(gmsh: Any, lay: Layout, path: Path) -> None:
    """Draw, mesh and write the damper with the contact points embedded in its surface.

    The shape's own ``draw`` (:mod:`workbench.geometry.shapes`) makes the
    solid and embeds the points; the groups, sizes and meshing are common.
    """
    from .shapes import get as get_shape

    gmsh.model.add("damper")
    pl = lay.damper
    members: dict[str, list[int]] = {}
    point_tags: list[int] = []
    vol = get_shape(lay.params.damper).draw(gmsh, lay, members, point_tags)
    members["damper"] = [vol]
    _groups(gmsh, "damper", members)
    ms = lay.params.rig.mesh
    h = min(ms.damper_size_mm, ms.size_mm)
    h_c = min(ms.contact_size_mm, lay.contact_spacing, h)
    size_field(gmsh, point_tags, h_c, h, ms.refine_distance_mm)
    mesh_and_write(gmsh, path, f"damper ({pl['kind']})", "damper", ms.mirror)
