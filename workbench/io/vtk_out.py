"""ParaView-ready output: VTU files (and PVD collections) that meshio, pyvista and ParaView read.

The dolfinx XDMF files stay (they keep the mesh tags); these are written
beside them because meshio and pyvista cannot read the XDMF tag-grid layout.

Files and what they hold (coordinates in m, like the meshes)::

    <mesh dir>/rig.vtu, damper.vtu       second-order tetrahedra (VTK type 24);
                                         cell data "region" = gmsh volume tag
    <modes dir>/modes_<body>.pvd         a collection with "time" = mode number
                                         (1-based, as the mode pictures)
    <modes dir>/modes_<body>/mode_NN.vtu point data "mode_shape" (mass-normalised,
                                         m/sqrt(kg)); field data "mode" (1-based),
                                         "freq_hz" (labels: modes.json)
    <study>/cases/<case>_peak.vtu        one vertex per contact pair at the peak:
                                         "status" (0 stuck .. 3 full separation),
                                         "friction_energy_mj" (per cycle),
                                         "side" (0/1), and when the model is at
                                         hand "rel_disp_cos_mm", "rel_disp_sin_mm"
                                         (damper minus platform, x y z, harmonic 1:
                                         u(t) = cos part cos(wt) + sin part sin(wt))
                                         and "rel_disp_amp_mm" (t1, t2, n amplitude);
                                         field data "freq_hz", "force_n", "n_pairs",
                                         "digest48" (first 12 hex digits of the
                                         case digest, as an integer)

Field data are numbers only: meshio 5 refuses string arrays. Only rank 0
writes. Heavy imports (pyvista) stay inside the functions.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np

from . import atomic_path

log = logging.getLogger(__name__)

VTK_VERTEX = 1
VTK_QUADRATIC_TETRA = 24


def _grid(points: np.ndarray, cells: np.ndarray, celltypes: np.ndarray):
    import pyvista as pv

    return pv.UnstructuredGrid(
        np.asarray(cells, dtype=np.int64).ravel(),
        np.asarray(celltypes, dtype=np.uint8),
        np.asarray(points, dtype=float),
    )


def write_vtu(
    path: str | Path,
    points: np.ndarray,
    cells: np.ndarray | None = None,
    celltypes: np.ndarray | None = None,
    point_data: dict[str, np.ndarray] | None = None,
    cell_data: dict[str, np.ndarray] | None = None,
    field_data: dict[str, Any] | None = None,
) -> Path:
    """One VTU file (binary, atomic). Without ``cells`` every point is a vertex cell."""
    path = Path(path)
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    if cells is None:
        n = len(points)
        cells = np.column_stack([np.ones(n, np.int64), np.arange(n)]).ravel()
        celltypes = np.full(n, VTK_VERTEX, np.uint8)
    g = _grid(points, cells, celltypes)
    for k, v in (point_data or {}).items():
        g.point_data[k] = np.asarray(v)
    for k, v in (cell_data or {}).items():
        g.cell_data[k] = np.asarray(v)
    for k, v in (field_data or {}).items():
        g.field_data[k] = np.atleast_1d(np.asarray(v))
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        # pyvista chooses the writer from the suffix; the temporary name keeps it last
        real = tmp.with_name(tmp.name + ".vtu")
        g.save(str(real), binary=True)
        real.replace(tmp)
    return path


def write_pvd(path: str | Path, entries: list[tuple[float, str]], comment: str = "") -> Path:
    """A ParaView collection: ``entries`` are ``(timestep, file relative to the PVD)``."""
    path = Path(path)
    rows = [
        f'    <DataSet timestep="{t:g}" group="" part="0" file={quoteattr(f)}/>' for t, f in entries
    ]
    note = f"<!-- {comment.replace('--', '-')} -->\n" if comment else ""
    text = (
        '<?xml version="1.0"?>\n'
        + note
        + '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
        "  <Collection>\n" + "\n".join(rows) + "\n  </Collection>\n</VTKFile>\n"
    )
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return path


def write_mesh_vtu(msh_path: str | Path, vtu_path: str | Path) -> Path:
    """A gmsh second-order tetrahedral mesh as VTU (quadratic tetrahedra, region tags)."""
    from ..geometry.mshio import GMSH_TO_VTK_TET10, TET10
    from ..geometry.occ import gmsh_session

    with gmsh_session() as gmsh:
        gmsh.open(str(msh_path))
        tags, x, _ = gmsh.model.mesh.getNodes()
        x = x.reshape(-1, 3)
        order = np.argsort(tags)
        tags, x = tags[order], x[order]
        conn, region = [], []
        for dim, ent in gmsh.model.getEntities(3):
            types, _, enodes = gmsh.model.mesh.getElements(dim, ent)
            for t, en in zip(types, enodes, strict=True):
                if t != TET10:
                    continue
                c = np.searchsorted(tags, en).reshape(-1, 10)
                conn.append(c)
                phys = gmsh.model.getPhysicalGroupsForEntity(dim, ent)
                region.append(np.full(len(c), int(phys[0]) if len(phys) else ent, np.int32))
    c = np.vstack(conn)[:, GMSH_TO_VTK_TET10]
    cells = np.column_stack([np.full(len(c), 10, np.int64), c])
    return write_vtu(
        vtu_path,
        x,
        cells,
        np.full(len(c), VTK_QUADRATIC_TETRA, np.uint8),
        cell_data={"region": np.concatenate(region)},
    )


def write_modes(
    out_dir: str | Path, body: str, shapes, freqs_hz: np.ndarray, labels: list[str] | None = None
) -> Path:
    """``modes_<body>.pvd`` and one VTU per mode (numbered from 1, frequency in field data).

    ``shapes`` is a :class:`workbench.fe.modes.BodyShapes` (P2 points, VTK
    cells, mass-normalised displacements).
    """
    out = Path(out_dir)
    sub = out / f"modes_{body}"
    entries = []
    for k, u in enumerate(shapes.disp):
        f = float(freqs_hz[k]) if k < len(freqs_hz) else float("nan")
        name = f"mode_{k + 1:02d}.vtu"
        write_vtu(
            sub / name,
            shapes.points,
            shapes.cells,
            shapes.celltypes,
            point_data={"mode_shape": u},
            field_data={"mode": k + 1, "freq_hz": f},
        )
        entries.append((k + 1, f"{sub.name}/{name}"))
    comment = "time = mode number; " + ", ".join(
        f"mode {k + 1}: {float(f):.3f} Hz"
        + (f" ({labels[k]})" if labels and k < len(labels) and labels[k] else "")
        for k, f in enumerate(freqs_hz[: len(entries)])
    )
    return write_pvd(out / f"modes_{body}.pvd", entries, comment)


def peak_relative_motion(case, system) -> np.ndarray | None:
    """(n_pairs, 3) complex harmonic-1 relative displacement (pair frame t1, t2, n), m.

    Read from the solved unknowns at the peak (``Branch.x``, the layout of
    :mod:`workbench.hbm.core.balance`): in the "condensed" space they are the
    harmonics of the active relative contact DOFs themselves (the non-zero
    rows of the contacts' ``W``), in the "physical" space those of every
    coordinate, mapped by ``W``. No solve is repeated. None when the branch
    has no point.
    """
    from ..hbm.core.fourier import Fourier

    b = case.branch
    i = case.peak_index
    if i < 0:
        return None
    el = system.contacts
    fourier = Fourier(tuple(b.harmonics), b.nt)
    X = np.asarray(b.x[i]).reshape(fourier.nh, -1)
    k1 = int(np.flatnonzero(np.asarray(fourier.k) == 1)[0])  # Qc_1, then Qs_1
    x1 = X[k1] - 1j * X[k1 + 1]
    if b.space == "condensed":
        act = np.flatnonzero(np.asarray(el.active).ravel())
        u = np.zeros(3 * el.n_el, complex)
        u[act] = x1
    else:
        u = np.asarray(el.W @ x1)
    return u.reshape(-1, 3)


def write_case_peak(
    path: str | Path,
    case,
    rel_pair_frame: np.ndarray | None = None,
    frames: np.ndarray | None = None,
) -> Path:
    """The contact pairs of one case at its peak as VTU point data (see the module doc)."""
    i = case.peak_index
    n = len(case.points)
    pd: dict[str, np.ndarray] = {"side": np.asarray(case.side, np.int32)}
    if i >= 0:
        pd["status"] = np.asarray(case.branch.status[i], np.int32)
        pd["friction_energy_mj"] = np.asarray(case.energy_mj[i], float)
    if rel_pair_frame is not None and frames is not None:
        # back to x, y, z: u_xyz = R^T u_frame (frames rows are t1, t2, n)
        g = np.einsum("pji,pj->pi", np.asarray(frames), rel_pair_frame)
        pd["rel_disp_cos_mm"] = g.real * 1e3
        pd["rel_disp_sin_mm"] = -g.imag * 1e3
        pd["rel_disp_amp_mm"] = np.abs(rel_pair_frame) * 1e3
    fd = {
        "digest48": _digest48(case.digest),
        "freq_hz": float(case.freq_hz[i]) if i >= 0 else float("nan"),
        "force_n": float(case.force_n),
        "n_pairs": n,
    }
    return write_vtu(path, case.points, point_data=pd, field_data=fd)


def write_case_field(path: str | Path, case, rig, damper, fields: dict[str, list]) -> Path:
    """Rig and damper meshes with a case's peak displacement (workbench/studies/engine/fields.py).

    ``rig``/``damper``: BodyShapes (points, VTK cells); ``fields``: "cos",
    "sin" and optionally "mean", each [rig (n, 3), damper (n, 3)] in m.
    """
    n_r = len(rig.points)
    npc = int(damper.cells[0]) + 1  # count, then the nodes of each cell
    cells_d = np.asarray(damper.cells, dtype=np.int64).reshape(-1, npc).copy()
    cells_d[:, 1:] += n_r
    pd = {
        f"disp_{k}_mm": np.vstack(v) * 1e3 for k, v in fields.items() if k in ("cos", "sin", "mean")
    }
    pd["disp_amp_mm"] = np.hypot(pd["disp_cos_mm"], pd["disp_sin_mm"])
    pd["body"] = np.r_[np.zeros(n_r, np.int32), np.ones(len(damper.points), np.int32)]
    i = case.peak_index
    return write_vtu(
        path,
        np.vstack([rig.points, damper.points]),
        np.r_[np.asarray(rig.cells, np.int64), cells_d.ravel()],
        np.r_[rig.celltypes, damper.celltypes].astype(np.uint8),
        point_data=pd,
        field_data={
            "digest48": _digest48(case.digest),
            "freq_hz": float(case.freq_hz[i]),
            "force_n": float(case.force_n),
        },
    )


def _read_if_digest(path: Path, digest: str):
    """The grid of ``path`` when it is a readable VTU carrying this case digest, else None."""
    if not path.is_file():
        return None
    try:
        import pyvista as pv

        g = pv.read(str(path))
        ok = int(np.atleast_1d(g.field_data["digest48"])[0]) == _digest48(digest)
    except Exception:  # noqa: BLE001 - an unreadable file is rewritten
        return None
    return g if ok else None


def has_digest(path: Path, digest: str) -> bool:
    """True when ``path`` is a readable VTU whose field data carry this case digest."""
    return _read_if_digest(path, digest) is not None


def has_shape(path: Path, digest: str) -> bool:
    """True when ``path`` is a peak file of this digest that carries the relative motion."""
    g = _read_if_digest(path, digest)
    return g is not None and "rel_disp_amp_mm" in g.point_data


def _digest48(digest: str) -> int:
    try:
        return int((digest or "0")[:12], 16)
    except ValueError:
        return 0


def write_study_peaks(
    results, out: str | Path, prepared: dict[str, Any], model_of: dict[str, str]
) -> list[Path]:
    """``cases/<case>_peak.vtu`` for every case of a study.

    ``prepared`` holds the models by model digest and ``model_of`` maps a
    case digest to its model digest. The relative motion needs the case's
    model; for a case reused from the cache without its model, a file that
    already has it is kept, else status and energy alone are written.
    """
    out = Path(out)
    paths = []
    for c in results.cases:
        p = out / "cases" / f"{c.case_id}_peak.vtu"
        prep = prepared.get(model_of.get(c.digest, ""))
        rel = None
        if prep is not None:
            try:
                rel = peak_relative_motion(c, prep.system)
            except Exception as e:  # noqa: BLE001 - the file is a by-product; keep going
                log.warning("%s: peak shape not recovered (%s)", c.case_id, e)
        if rel is None and has_shape(p, c.digest):
            paths.append(p)
            continue
        frames = prep.assembled.contact.frames if prep is not None else None
        paths.append(write_case_peak(p, c, rel, frames))
    return paths
