"""``build_geometry``: parameters -> checked layout -> gmsh meshes -> BuiltGeometry.

Files written in ``out_dir``::

    rig.msh, damper.msh        second-order gmsh meshes (MSH 4.1, binary, metres)
    rig.xdmf/.h5, damper.xdmf/.h5   the same meshes for ParaView/dolfinx, one
                               meshtags per physical group, named after it
    geometry.h5                the BuiltGeometry record (contact pairs, frames, ...)

The build is cached: ``geometry.h5`` carries the digest of every input and
of the code that made it; a second call with the same inputs loads it
without meshing. Under MPI, rank 0 meshes while the others wait, then every
rank loads the record.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import SolveError, run_on_root
from ..io import code_version as _code_version
from ..io import digest
from ..log import mpi_size
from .layout import Layout, make_layout
from .params import GeometryParams, load_geometry_params
from .records import BuiltGeometry, ContactSet

log = logging.getLogger(__name__)

_SOURCES = (
    "build.py",
    "layout.py",
    "occ.py",
    "mirror.py",
    "mshio.py",
    "params.py",
    "records.py",
    "seat_tools.py",
)
MATCH_TOL_M = 1e-9  # a contact point must be a vertex of both meshes to this distance


def code_version() -> str:
    """Package version plus a hash of this sub-package's sources (the cache key's code part)."""
    here = Path(__file__).resolve().parent
    shapes = tuple(f"shapes/{p.name}" for p in sorted((here / "shapes").glob("*.py")))
    return _code_version(here, _SOURCES + shapes)


def geometry_digest(gp: GeometryParams) -> str:
    """The cache key of a build: damper, resolved parameters, code version."""
    return digest({"damper": gp.damper, "params": gp.as_dict(), "code": code_version()})


def build_geometry(
    damper: str,
    out_dir: Path,
    *,
    geometry_file: Path | None = None,
    size_mm: float | None = None,
    overrides: Mapping[str, Any] | None = None,
    comm: Any = None,
) -> BuiltGeometry:
    """Mesh the rig and one damper seated in its groove; return the record.

    Parameters
    ----------
    damper : a registered shape (:mod:`.shapes`): "cone", "cylinder", "wedge", ...
    out_dir : folder for the meshes and ``geometry.h5`` (created).
    geometry_file : a TOML overriding any table of the defaults
        ([rig...], [cone], [cylinder], [wedge]).
    size_mm : the global element size of the rig, mm (``rig.mesh.size_mm``).
    overrides : nested dict with the same keys as the files, e.g.
        ``{"cone": {"semi_angle_deg": 12}}``.
    comm : the ranks that build together (default: COMM_WORLD under mpirun);
        ``MPI.COMM_SELF`` lets one rank build alone.

    Raises InputError (bad or non-fitting parameters, before gmsh runs) or
    SolveError (gmsh failed; ``partial`` holds what was built).
    """
    gp = load_geometry_params(damper, geometry_file, overrides, size_mm)
    lay = make_layout(gp)  # every rank checks, so every rank raises the same InputError
    dig = geometry_digest(gp)
    out_dir = Path(out_dir)
    if comm is None and mpi_size() > 1:
        from mpi4py import MPI

        comm = MPI.COMM_WORLD
    if comm is not None and comm.size > 1:
        return _build_mpi(comm, lay, dig, out_dir)
    return _build_or_reuse(lay, dig, out_dir)


def cached_geometry(
    damper: str,
    out_dir: Path,
    *,
    geometry_file: Path | None = None,
    size_mm: float | None = None,
    overrides: Mapping[str, Any] | None = None,
) -> BuiltGeometry | None:
    """The record of a finished :func:`build_geometry` in ``out_dir`` with these inputs, else None.

    Cheap (no gmsh); raises InputError for bad parameters as the build would.
    """
    gp = load_geometry_params(damper, geometry_file, overrides, size_mm)
    make_layout(gp)
    return _reusable(Path(out_dir) / "geometry.h5", geometry_digest(gp))


def _build_mpi(comm: Any, lay: Layout, dig: str, out_dir: Path) -> BuiltGeometry:
    """Rank 0 builds; the others wait and load. An error on rank 0 is raised on every rank.

    dolfinx (used by rank 0 to write the XDMF files) is imported on every rank
    first: importing it initialises PETSc, which is collective on
    COMM_WORLD; done on rank 0 alone it would collide with the broadcast the
    other ranks are waiting in.
    """
    import dolfinx  # noqa: F401 - collective PETSc initialisation, see above

    rec = run_on_root(comm, lambda: _build_or_reuse(lay, dig, out_dir), "geometry build")
    if comm.rank == 0:
        return rec  # type: ignore[return-value]
    return BuiltGeometry.load(out_dir / "geometry.h5")


def _reusable(h5: Path, dig: str) -> BuiltGeometry | None:
    if not h5.is_file():
        return None
    try:
        old = BuiltGeometry.load(h5)
    except (OSError, KeyError, ValueError) as e:
        log.warning(
            "geometry: cached %s is unreadable (%s: %s); rebuilding it", h5, type(e).__name__, e
        )
        return None
    needed = [old.rig_msh, old.damper_msh] + [
        h5.parent / f"{b}.{ext}" for b in ("rig", "damper") for ext in ("xdmf", "h5")
    ]
    if old.digest == dig and all(p.is_file() for p in needed):
        return old
    return None


def _build_or_reuse(lay: Layout, dig: str, out_dir: Path) -> BuiltGeometry:
    h5 = out_dir / "geometry.h5"
    old = _reusable(h5, dig)
    if old is not None:
        log.info("geometry: reusing %s (digest %s)", h5, dig)
        _write_vtu(out_dir)  # a folder built before the VTU files existed gets them
        return old
    out_dir.mkdir(parents=True, exist_ok=True)
    if h5.exists():
        h5.unlink()  # the record marks a complete build; remove it before rebuilding
    return _build(lay, dig, out_dir)


def _build(lay: Layout, dig: str, out_dir: Path) -> BuiltGeometry:
    from .mshio import mesh_file_info, write_xdmf
    from .occ import build_damper, build_rig, gmsh_session

    gp = lay.params
    timings: dict[str, float] = {}
    rig_msh, damper_msh = out_dir / "rig.msh", out_dir / "damper.msh"
    done: dict[str, Any] = {"layout": lay}
    t0 = time.perf_counter()
    what = "rig"
    try:
        with gmsh_session() as gmsh:
            log.info(
                "geometry: meshing the rig (size %g mm, %g mm at the contacts)",
                gp.rig.mesh.size_mm,
                min(gp.rig.mesh.contact_size_mm, lay.contact_spacing),
            )
            build_rig(gmsh, lay, rig_msh)
            done["rig_msh"] = rig_msh
            timings["mesh_rig_s"] = time.perf_counter() - t0
            t1 = time.perf_counter()
            what = f"{gp.damper} damper"
            log.info("geometry: meshing the %s", what)
            build_damper(gmsh, lay, damper_msh)
            done["damper_msh"] = damper_msh
            timings["mesh_damper_s"] = time.perf_counter() - t1
    except SolveError as e:
        raise SolveError(str(e), partial=done) from None
    except Exception as e:  # noqa: BLE001 - gmsh raises bare Exceptions; report them in one line
        raise SolveError(
            f"gmsh failed while building the {what}: {e} (the inputs passed the "
            "fit checks; please report this case)",
            partial=done,
        ) from None
    t1 = time.perf_counter()
    rig_info, damper_info = mesh_file_info(rig_msh), mesh_file_info(damper_msh)
    timings["read_back_s"] = time.perf_counter() - t1

    pts = lay.points * 1e-3
    stats = _match_stats(pts, lay, rig_info, damper_info)
    if stats["max_point_offset_m"] > MATCH_TOL_M:
        raise SolveError(
            f"a contact point is {stats['max_point_offset_m']:.3g} m from the nearest mesh vertex "
            f"(allowed {MATCH_TOL_M:g} m): the meshes do not match node to node",
            partial=dict(done, stats=stats),
        )
    t1 = time.perf_counter()
    write_xdmf(rig_msh, out_dir / "rig.xdmf", "rig")
    write_xdmf(damper_msh, out_dir / "damper.xdmf", "damper")
    _write_vtu(out_dir)
    timings["xdmf_s"] = time.perf_counter() - t1

    rho = gp.rig.material.rho_kg_m3
    vol_exact = lay.volume * 1e-9
    stats.update(
        rig_n_nodes=rig_info.n_nodes,
        rig_n_cells=rig_info.n_cells,
        damper_n_nodes=damper_info.n_nodes,
        damper_n_cells=damper_info.n_cells,
        n_nodes=rig_info.n_nodes + damper_info.n_nodes,
        n_cells=rig_info.n_cells + damper_info.n_cells,
        n_contact_pairs=lay.n_pairs,
        rig_volume_m3=rig_info.volume,
        damper_volume_exact_m3=vol_exact,
        damper_volume_rel_error=(damper_info.volume - vol_exact) / vol_exact,
        damper_centroid_exact_m=(lay.centroid * 1e-3).tolist(),
        element_order=2,
        size_mm=gp.rig.mesh.size_mm,
        contact_size_mm=min(gp.rig.mesh.contact_size_mm, lay.contact_spacing, gp.rig.mesh.size_mm),
        damper_size_mm=min(gp.rig.mesh.damper_size_mm, gp.rig.mesh.size_mm),
        code_version=code_version(),
        timings_s={k: round(v, 3) for k, v in timings.items()},
        **{
            k: (float(v) if isinstance(v, (float, np.floating)) else v)
            for k, v in lay.notes.items()
        },
    )
    scale = 1e-3 if lay.kind == "line" else 1e-6
    contact = ContactSet(
        points=pts,
        frames=lay.frames.copy(),
        side=lay.side.astype(np.int64),
        weight=lay.weight * scale,
        kind=lay.kind,
    )
    rec = BuiltGeometry(
        damper=gp.damper,
        rig_msh=rig_msh,
        damper_msh=damper_msh,
        contact=contact,
        excitation_points=lay.excitation * 1e-3,
        response_points=lay.response * 1e-3,
        excitation_direction=np.array([1.0, 0.0, 0.0]),
        response_direction=np.array([1.0, 0.0, 0.0]),
        damper_volume_m3=damper_info.volume,
        damper_mass_kg=rho * damper_info.volume,
        damper_centroid=damper_info.centroid,
        material=gp.rig.material.as_si(),
        params=gp.as_dict(),
        digest=dig,
        stats=stats,
    )
    rec.save(out_dir / "geometry.h5")
    log.info(
        "geometry: %d + %d nodes, %d contact pairs, max pair gap %.3g m, written to %s",
        rig_info.n_nodes,
        damper_info.n_nodes,
        lay.n_pairs,
        stats["max_pair_gap_m"],
        out_dir,
    )
    return rec


def _write_vtu(out_dir: Path) -> None:
    """rig.vtu and damper.vtu beside the XDMF files (meshio, pyvista and ParaView read them)."""
    from ..io.vtk_out import write_mesh_vtu

    for body in ("rig", "damper"):
        vtu, msh = out_dir / f"{body}.vtu", out_dir / f"{body}.msh"
        if not vtu.is_file() or vtu.stat().st_mtime_ns < msh.stat().st_mtime_ns:
            write_mesh_vtu(msh, vtu)


def _match_stats(pts: np.ndarray, lay: Layout, rig_info: Any, damper_info: Any) -> dict[str, Any]:
    """Pair gaps from the actual mesh vertices: nearest vertex of each mesh to each point."""
    from scipy.spatial import cKDTree

    d_rig, i_rig = cKDTree(rig_info.vertices).query(pts)
    d_dam, i_dam = cKDTree(damper_info.vertices).query(pts)
    gap = np.linalg.norm(rig_info.vertices[i_rig] - damper_info.vertices[i_dam], axis=1)
    named = np.vstack([lay.excitation, lay.response]) * 1e-3
    d_named, _ = cKDTree(rig_info.vertices).query(named)
    return dict(
        max_pair_gap_m=float(gap.max()),
        max_point_offset_m=float(max(d_rig.max(), d_dam.max())),
        max_named_point_offset_m=float(d_named.max()),
    )
