"""``build_disk_sector``: one bladed-disk sector and its damper, meshed with gmsh.

Files written in ``out_dir``::

    sector.msh     the hub sector, the blade and its two platform halves (P2
                   tetrahedra, metres); the two cyclic faces are meshed
                   periodically (gmsh ``setPeriodic`` with the sector's
                   rotation), so each node of the right face is a node of the
                   left face turned by the sector angle
    damper.msh     the damper seated in the groove between this sector's right
                   platform half and the next sector's left half
    sector.vtu, damper.vtu   the same meshes for ParaView (quadratic tetrahedra)
    disk.h5        the :class:`DiskSector` record (contact pairs, images, ...)

Physical groups of ``sector.msh`` (names are the contract with
:mod:`workbench.fe.cyclic`)::

    3: sector 1
    2: bore 11, contact_face_1 12 (right half), contact_face_2 13 (left half),
       cyclic_left 14, cyclic_right 15
    0: contact_nodes_1 21 (side-0 platform nodes), contact_nodes_2 22 (the
       images in this sector of the side-1 platform nodes), excitation 23,
       response 24

The damper mesh is the rig's damper mesh (:func:`.occ.build_damper`) moved
by the rigid map ``G`` of :mod:`.disk`. Cached like the rig: ``disk.h5``
carries the digest of every input and of the code.
"""

from __future__ import annotations

import json
import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import SolveError
from ..io import atomic_path, digest
from .build import code_version as geometry_code_version
from .disk import DiskLayout, load_disk_params, make_disk_layout, rotation
from .params import load_geometry_params
from .records import ContactSet

log = logging.getLogger(__name__)

MATCH_TOL_M = 1e-9  # periodic nodes and contact points agree to this distance

SECTOR_GROUPS = {
    3: {"sector": 1},
    2: {
        "bore": 11,
        "contact_face_1": 12,
        "contact_face_2": 13,
        "cyclic_left": 14,
        "cyclic_right": 15,
    },
    0: {"contact_nodes_1": 21, "contact_nodes_2": 22, "excitation": 23, "response": 24},
}


@dataclass(frozen=True)
class DiskSector:
    """What :func:`build_disk_sector` returns: meshes and the cyclic contact data (SI).

    ``contact`` holds the damper's pairs in the disk frame (side 0 on this
    sector's right platform half, side 1 on the next sector's left half);
    ``image_points[i]`` is the platform node of pair ``i`` in this sector
    (``contact.points[i]`` for side 0, ``rotation(-alpha) contact.points[i]``
    for side 1).
    """

    damper: str
    n_blades: int
    bore: str  # "clamped" | "free"
    sector_msh: Path
    damper_msh: Path
    contact: ContactSet
    image_points: np.ndarray  # (n_pairs, 3) m
    excitation_point: np.ndarray  # (3,) m, on the blade's left face
    response_point: np.ndarray  # (3,) m
    excitation_direction: np.ndarray  # (3,) unit, tangential (+x)
    material: dict[str, float]
    params: dict[str, Any]
    digest: str
    stats: dict[str, Any] = field(default_factory=dict)

    @property
    def alpha(self) -> float:
        """Sector angle, rad."""
        return 2 * np.pi / self.n_blades

    @property
    def rot(self) -> np.ndarray:
        """(3, 3) rotation by the sector angle about the disk axis y (sector j -> j + 1)."""
        return rotation(self.alpha)

    def save(self, path: str | Path) -> Path:
        import h5py

        path = Path(path)
        with atomic_path(path) as tmp, h5py.File(tmp, "w") as h:
            a = h.attrs
            a["damper"], a["n_blades"], a["bore"] = self.damper, self.n_blades, self.bore
            a["sector_msh"] = Path(self.sector_msh).name
            a["damper_msh"] = Path(self.damper_msh).name
            a["contact_kind"] = self.contact.kind
            a["material"] = json.dumps(self.material)
            a["params"] = json.dumps(self.params)
            a["digest"] = self.digest
            a["stats"] = json.dumps(self.stats, default=float)
            self.contact.write_h5(h.require_group("contact"))
            for name in ("image_points", "excitation_point", "response_point"):
                h[name] = getattr(self, name)
            h["excitation_direction"] = self.excitation_direction
        return path

    @classmethod
    def load(cls, path: str | Path) -> DiskSector:
        import h5py

        path = Path(path)
        with h5py.File(path, "r") as h:
            a = h.attrs
            contact = ContactSet.read_h5(h["contact"], str(a["contact_kind"]))
            return cls(
                damper=str(a["damper"]),
                n_blades=int(a["n_blades"]),
                bore=str(a["bore"]),
                sector_msh=path.parent / str(a["sector_msh"]),
                damper_msh=path.parent / str(a["damper_msh"]),
                contact=contact,
                image_points=h["image_points"][()],
                excitation_point=h["excitation_point"][()],
                response_point=h["response_point"][()],
                excitation_direction=h["excitation_direction"][()],
                material=json.loads(a["material"]),
                params=json.loads(a["params"]),
                digest=str(a["digest"]),
                stats=json.loads(a["stats"]),
            )


def disk_code_version() -> str:
    """The geometry package's code version plus this module and :mod:`.disk`."""
    from ..io import code_version

    here = Path(__file__).resolve().parent
    return geometry_code_version() + code_version(here, ("disk.py", "disk_build.py"))


def build_disk_sector(
    damper: str,
    out_dir: Path,
    *,
    geometry_file: Path | None = None,
    disk_file: Path | None = None,
    n_blades: int | None = None,
    bore: str | None = None,
    size_mm: float | None = None,
    overrides: dict[str, Any] | None = None,
) -> DiskSector:
    """Mesh one sector of the bladed disk and its damper; return the record (cached).

    ``geometry_file`` and ``overrides`` set the rig section and the damper as
    for :func:`workbench.geometry.build_geometry`; ``disk_file`` (table
    ``[disk]``), ``n_blades`` and ``bore`` the disk. Raises InputError before
    gmsh runs if something does not fit, SolveError if gmsh fails. Serial
    (call it on one rank).
    """
    gp = load_geometry_params(damper, geometry_file, overrides, size_mm)
    dp = load_disk_params(disk_file, n_blades=n_blades, bore=bore)
    dl = make_disk_layout(gp, dp)
    params = dict(gp.as_dict(), disk={"n_blades": dp.n_blades, "bore": dp.bore})
    dig = digest({"damper": gp.damper, "params": params, "code": disk_code_version()})
    out_dir = Path(out_dir)
    h5 = out_dir / "disk.h5"
    if h5.is_file():
        try:
            old = DiskSector.load(h5)
            if old.digest == dig and old.sector_msh.is_file() and old.damper_msh.is_file():
                return old
        except (OSError, KeyError, ValueError):
            pass
        h5.unlink()
    out_dir.mkdir(parents=True, exist_ok=True)
    return _build(dl, params, dig, out_dir)


def _build(dl: DiskLayout, params: dict, dig: str, out_dir: Path) -> DiskSector:
    from .mshio import mesh_file_info
    from .occ import build_damper, gmsh_session

    gp = dl.rig.params
    sector_msh, damper_msh = out_dir / "sector.msh", out_dir / "damper.msh"
    what = "disk sector"
    try:
        with gmsh_session() as gmsh:
            _draw_and_mesh_sector(gmsh, dl, sector_msh)
            what = f"{gp.damper} damper"
            rig_frame = out_dir / ".damper_rig_frame.msh"
            build_damper(gmsh, dl.rig, rig_frame)
            _move_mesh(gmsh, rig_frame, damper_msh, dl)
            rig_frame.unlink()
    except SolveError:
        raise
    except Exception as e:  # noqa: BLE001 - gmsh raises bare Exceptions; one line
        raise SolveError(f"gmsh failed while building the {what}: {e}") from None
    s_info, d_info = mesh_file_info(sector_msh), mesh_file_info(damper_msh)
    pts, img = dl.points * 1e-3, dl.image_points * 1e-3
    from scipy.spatial import cKDTree

    d_dam, _ = cKDTree(d_info.vertices).query(pts)
    d_sec, _ = cKDTree(s_info.vertices).query(img)
    offset = float(max(d_dam.max(), d_sec.max()))
    if offset > MATCH_TOL_M:
        raise SolveError(
            f"a contact point is {offset:.3g} m from the nearest mesh vertex "
            f"(allowed {MATCH_TOL_M:g} m): the meshes do not match node to node"
        )
    scale = 1e-3 if dl.rig.kind == "line" else 1e-6
    contact = ContactSet(
        points=pts,
        frames=dl.frames.copy(),
        side=dl.side.copy(),
        weight=dl.rig.weight * scale,
        kind=dl.rig.kind,
    )
    rho = gp.rig.material.rho_kg_m3
    stats = dict(
        sector_n_nodes=s_info.n_nodes,
        sector_n_cells=s_info.n_cells,
        damper_n_nodes=d_info.n_nodes,
        damper_n_cells=d_info.n_cells,
        n_contact_pairs=int(len(pts)),
        max_point_offset_m=offset,
        sector_volume_m3=s_info.volume,
        damper_mass_kg=rho * d_info.volume,
        r_bore_m=dl.r_in * 1e-3,
        r_root_m=dl.r_root * 1e-3,
        r_tip_m=dl.r_tip * 1e-3,
        sector_angle_deg=float(np.degrees(dl.alpha)),
        size_mm=gp.rig.mesh.size_mm,
    )
    rec = DiskSector(
        damper=gp.damper,
        n_blades=dl.n_blades,
        bore=dl.disk.bore,
        sector_msh=sector_msh,
        damper_msh=damper_msh,
        contact=contact,
        image_points=img,
        excitation_point=dl.excitation * 1e-3,
        response_point=dl.response * 1e-3,
        excitation_direction=np.array([1.0, 0.0, 0.0]),
        material=gp.rig.material.as_si(),
        params=params,
        digest=dig,
        stats=stats,
    )
    from ..io.vtk_out import write_mesh_vtu

    for msh in (sector_msh, damper_msh):
        write_mesh_vtu(msh, msh.with_suffix(".vtu"))
    rec.save(out_dir / "disk.h5")
    log.info(
        "disk: %d blades, sector %d nodes, damper %d nodes, %d pairs, written to %s",
        dl.n_blades,
        s_info.n_nodes,
        d_info.n_nodes,
        len(pts),
        out_dir,
    )
    return rec


def _draw_and_mesh_sector(gmsh: Any, dl: DiskLayout, path: Path) -> None:
    """Hub sector + blade + platform halves, fused; points embedded; periodic cyclic faces."""
    from .occ import MeshingError, embed_points, face_containing, mesh_and_write, size_field

    occ = gmsh.model.occ
    gmsh.model.add("sector")
    rig = dl.rig.params.rig
    ha = dl.alpha / 2
    w, y0 = dl.width, -dl.width / 2

    def pt(r: float, th: float) -> int:
        return occ.addPoint(r * np.sin(th), y0, r * np.cos(th))

    centre = occ.addPoint(0.0, y0, 0.0)
    a, b = pt(dl.r_in, -ha), pt(dl.r_root, -ha)
    c, d = pt(dl.r_root, ha), pt(dl.r_in, ha)
    loop = [
        occ.addLine(a, b),
        occ.addCircleArc(b, centre, c),
        occ.addLine(c, d),
        occ.addCircleArc(d, centre, a),
    ]
    face = occ.addPlaneSurface([occ.addCurveLoop(loop)])
    hub = [t for dd, t in occ.extrude([(2, face)], 0.0, w, 0.0) if dd == 3]
    occ.remove([(0, centre)])
    t, bw = rig.blade.thickness_mm, rig.blade.width_mm
    blade = occ.addBox(-t / 2, -bw / 2, dl.blade_z0, t, bw, dl.r_tip - dl.blade_z0)
    py0, py1 = dl.rig.platform_y
    halves = []
    for poly in (dl.platform_right, dl.platform_right[::-1] * np.array([-1.0, 1.0])):
        corners = [occ.addPoint(float(x), py0, float(z)) for x, z in poly]
        n = len(corners)
        lines = [occ.addLine(corners[i], corners[(i + 1) % n]) for i in range(n)]
        f = occ.addPlaneSurface([occ.addCurveLoop(lines)])
        halves += [(3, t_) for dd, t_ in occ.extrude([(2, f)], 0.0, py1 - py0, 0.0) if dd == 3]
    occ.fuse([(3, h) for h in hub], [(3, blade)] + halves)
    occ.synchronize()
    vols = gmsh.model.getEntities(3)
    if len(vols) != 1:
        raise MeshingError(f"internal: the disk sector CAD has {len(vols)} volumes, expected 1")
    members: dict[str, list[int]] = {"sector": [vols[0][1]]}
    mid = 0.5 * (dl.r_in + dl.r_root)
    left_pt = np.array([[mid * np.sin(-ha), 0.0, mid * np.cos(-ha)]])
    right_pt = np.array([[mid * np.sin(ha), 0.0, mid * np.cos(ha)]])
    n_left = np.array([np.cos(ha), 0.0, np.sin(ha)])
    n_right = np.array([np.cos(ha), 0.0, -np.sin(ha)])
    members["cyclic_left"] = [face_containing(gmsh, n_left, left_pt, "the left cyclic face")]
    members["cyclic_right"] = [face_containing(gmsh, n_right, right_pt, "the right cyclic face")]
    bore = []
    for _, s in gmsh.model.getEntities(2):
        if gmsh.model.getType(2, s) != "Cylinder":
            continue
        lo, hi = gmsh.model.getParametrizationBounds(2, s)
        x, _, z = gmsh.model.getValue(2, s, [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])])
        if abs(np.hypot(x, z) - dl.r_in) < 1e-5:
            bore.append(s)
    if len(bore) != 1:
        raise MeshingError(f"internal: found {len(bore)} bore faces, expected 1")
    members["bore"] = bore
    n0 = dl.frames[dl.side == 0][0, 2]
    n1 = n0 * np.array([-1.0, 1.0, 1.0])  # the left half is the mirror image
    point_tags: list[int] = []
    for k, normal in ((0, n0), (1, n1)):
        pts = dl.image_points[dl.side == k]
        f = face_containing(gmsh, normal, pts, f"the platform face of side {k}")
        members[f"contact_face_{k + 1}"] = [f]
        tags = embed_points(gmsh, pts, f)
        members[f"contact_nodes_{k + 1}"] = tags
        point_tags += tags
    for name, p in (("excitation", dl.excitation), ("response", dl.response)):
        f = face_containing(gmsh, np.array([1.0, 0.0, 0.0]), p, f"the {name} point")
        members[name] = embed_points(gmsh, p[None, :], f)
    for dim, names in SECTOR_GROUPS.items():
        for name, tag in names.items():
            gmsh.model.addPhysicalGroup(dim, members[name], tag)
            gmsh.model.setPhysicalName(dim, tag, name)
    R = rotation(dl.alpha)  # left face -> right face
    affine = np.eye(4)
    affine[:3, :3] = R
    gmsh.model.mesh.setPeriodic(
        2, members["cyclic_right"], members["cyclic_left"], affine.ravel().tolist()
    )
    ms = rig.mesh
    h_c = min(ms.contact_size_mm, dl.rig.contact_spacing, ms.size_mm)
    size_field(gmsh, point_tags, h_c, ms.size_mm, ms.refine_distance_mm)
    mesh_and_write(gmsh, path, "disk sector")


def _move_mesh(gmsh: Any, src: Path, dst: Path, dl: DiskLayout) -> None:
    """Open a mesh written in the rig frame (metres), move every node by G, write it."""
    gmsh.clear()
    gmsh.open(str(src))
    tags, x, _ = gmsh.model.mesh.getNodes()
    x = x.reshape(-1, 3) * 1e3
    moved = dl.to_disk(x) * 1e-3
    for tag, p in zip(tags, moved, strict=True):
        gmsh.model.mesh.setNode(int(tag), p.tolist(), [])
    gmsh.option.setNumber("Mesh.ScalingFactor", 1.0)  # already in metres
    gmsh.option.setNumber("Mesh.Binary", 1)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.write(str(dst))
