"""Modes of the rig with the damper stuck (or free), with the first bending pair named.

``contact="stuck"``: the unreduced rig (base clamped) and damper (free)
meshes coupled by the stuck springs of every contact pair
(:mod:`workbench.fe.coupling`), one generalised eigenproblem.
``contact="free"``: the damper does not touch the platforms; the rig's
modes are those of the blades alone, and the damper's own free-free
elastic frequencies are reported beside them.

First bending (DESIGN.md section 3) is bending in x. It is recognised from
the computed shapes, not prescribed: at the two response points (one per
blade) the x-displacement must dominate and both blades must move; the
lowest such mode with the same sign on both blades is the in-phase mode,
the lowest with opposite signs the out-of-phase mode.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..assembly.params import ContactParams, load_contact_params
from ..errors import check_choice, check_int
from ..log import stage
from .elasticity import ElasticBody, Material, assemble_body
from .interface import InterfaceNodes, locate_nodes
from .mesh import read_msh
from .parallel import info

log = logging.getLogger(__name__)

X_DOMINANCE = 0.7  # |u_x| / |u| at both response points for a bending-in-x mode
PARTICIPATION = 0.2  # min(|u_x1|, |u_x2|) / max(...) for a mode of both blades
DAMPER_MODE_SHARE = 0.9  # a mode whose modal mass is this much damper is the damper's
FREE_SHIFT_HZ = 10.0  # shift below zero for problems that may have rigid-body modes


@dataclass(frozen=True)
class BodyShapes:
    """Mode shapes of one body as plain arrays for plotting (on rank 0)."""

    points: np.ndarray  # (N, 3) P2 node coordinates, m
    cells: np.ndarray  # VTK connectivity, flat: [10, i0, ..., i9, 10, ...]
    celltypes: np.ndarray  # (n_cells,) VTK cell type (24: quadratic tetrahedron)
    disp: np.ndarray  # (n_modes, N, 3) displacement, mass-normalised (m / sqrt(kg))


@dataclass(frozen=True)
class ModesResult:
    """Frequencies and named modes of the rig with a damper."""

    damper: str
    contact: str  # "stuck" | "free"
    freqs_hz: np.ndarray  # (n,)
    labels: list[str]  # per mode: "first bending in-phase", ... or ""
    in_phase: int | None  # index of the first bending in-phase mode
    out_of_phase: int | None  # index of the first bending out-of-phase mode
    response_disp: np.ndarray  # (n, 2, 3) displacement of the response points
    damper_share: np.ndarray  # (n,) the damper's share of the modal mass (0 when free)
    damper_freqs_hz: np.ndarray  # free-free elastic frequencies of the damper ("free")
    n_dofs: dict[str, int]
    shapes: dict[str, BodyShapes] = field(default_factory=dict)  # rank 0 only
    files: dict[str, str] = field(default_factory=dict)
    timings: dict[str, float] = field(default_factory=dict)

    def summary(self) -> dict[str, Any]:
        """A JSON-able summary; mode numbers are 1-based (as in the PNG names)."""

        def named(i):
            if i is None:
                return None
            return {"mode": i + 1, "freq_hz": round(float(self.freqs_hz[i]), 3)}

        return {
            "damper": self.damper,
            "contact": self.contact,
            "freqs_hz": [round(float(x), 3) for x in self.freqs_hz],
            "first_bending_in_phase": named(self.in_phase),
            "first_bending_out_of_phase": named(self.out_of_phase),
            "modes": [
                {
                    "mode": k + 1,
                    "freq_hz": round(float(f), 3),
                    "label": lab or "-",
                    "damper_mass_share": round(float(sh), 3),
                }
                for k, (f, lab, sh) in enumerate(
                    zip(self.freqs_hz, self.labels, self.damper_share, strict=True)
                )
            ],
            "damper_free_free_hz": [round(float(x), 1) for x in self.damper_freqs_hz],
            "n_dofs": self.n_dofs,
            "files": self.files,
            "timings_s": {k: round(v, 3) for k, v in self.timings.items()},
        }


def classify_bending(
    response_disp: np.ndarray,
    excitation_disp: np.ndarray | None = None,
) -> tuple[list[str], int | None, int | None]:
    """Name the first bending in-phase and out-of-phase modes from point displacements.

    ``response_disp`` is (n_modes, 2, 3): the displacement of the response
    point of blade 1 and blade 2 in each mode; ``excitation_disp`` the same
    at the excitation points (lower on the blades). A blade *moves* in a mode
    if its response point moves at least PARTICIPATION of the larger of the
    two. A mode bends in x if x dominates the motion of every moving blade's
    response point (X_DOMINANCE); it is a *first* bending mode if, in
    addition, the excitation point of each moving blade moves the same way
    in x as its response point (no node along the span: the second
    cantilever mode changes sign near 0.78 of the span). Returns the labels
    and the indices of the lowest in-phase and out-of-phase first bending
    modes in which both blades move (None if there is none, e.g. when the
    blades are uncoupled and each mode is one blade's alone).
    """
    u = np.asarray(response_disp, dtype=float)
    e = None if excitation_disp is None else np.asarray(excitation_disp, dtype=float)
    labels = [""] * len(u)
    in_phase = out_phase = None
    for k, uk in enumerate(u):
        mag = np.linalg.norm(uk, axis=1)
        if mag.max() == 0:
            continue
        moving = np.flatnonzero(mag >= PARTICIPATION * mag.max())
        ux = uk[:, 0]
        if not np.all(np.abs(ux[moving]) >= X_DOMINANCE * mag[moving]):
            continue
        first = e is None or bool(np.all(e[k, moving, 0] * ux[moving] > 0))
        order = "first bending" if first else "bending in x"
        if len(moving) == 1:
            labels[k] = f"{order}, blade {moving[0] + 1} alone"
        else:
            phase = "in-phase" if ux[0] * ux[1] > 0 else "out-of-phase"
            if first and phase == "in-phase" and in_phase is None:
                in_phase = k
            elif first and phase == "out-of-phase" and out_phase is None:
                out_phase = k
            elif first:
                order = "first-bending shape"
                phase += " (higher branch)"
            labels[k] = f"{order} {phase}"
    return labels, in_phase, out_phase


def load_bodies(
    geom,
    comm=None,
    timings: dict[str, float] | None = None,
    which: tuple[str, ...] = ("rig", "damper"),
) -> dict[str, ElasticBody]:
    """Read and assemble the rig (base clamped) and/or the damper (free) of ``geom``."""
    from mpi4py import MPI

    comm = MPI.COMM_WORLD if comm is None else comm
    mat = Material.from_dict(geom.material)
    out = {}
    for name in which:
        with stage(timings, "read_mesh"):
            fm = read_msh(geom.rig_msh if name == "rig" else geom.damper_msh, comm)
        out[name] = assemble_body(
            fm, mat, name=name, clamped="clamped" if name == "rig" else None, timings=timings
        )
    return out


def _vec_to_function(V, local: np.ndarray):
    from dolfinx import fem

    u = fem.Function(V)
    n = len(local)
    u.x.array[:n] = local
    u.x.scatter_forward()
    return u


def _values_at(nodes: InterfaceNodes, local: np.ndarray, comm) -> np.ndarray:
    """(n_nodes, 3) values of an owned-DOF array at interface nodes, on every rank."""
    from .parallel import allsum

    v = np.zeros((nodes.n, 3))
    for i in range(nodes.n):
        b = nodes.local_block[i]
        if b >= 0:
            v[i] = local[3 * b : 3 * b + 3]
    return allsum(comm, v)


def _gather_shapes(V, arrays: list[np.ndarray], comm) -> BodyShapes | None:
    """VTK arrays of the P2 space and the mode shapes, gathered on rank 0."""
    from dolfinx import plot

    cells, types, x = plot.create_vtk_mesh(V)
    npc = int(cells[0]) + 1 if len(cells) else 11
    conn = np.asarray(cells).reshape(-1, npc)
    disp = []
    for a in arrays:
        u = _vec_to_function(V, a)
        disp.append(u.x.array.reshape(-1, 3).copy())
    disp_arr = np.stack(disp) if disp else np.zeros((0, len(x), 3))
    parts = comm.gather((conn, np.asarray(types), np.asarray(x), disp_arr), root=0)
    if comm.rank != 0:
        return None
    off = 0
    cc, tt, xx, dd = [], [], [], []
    for c, t, p, d in parts:
        c = c.copy()
        c[:, 1:] += off
        off += len(p)
        cc.append(c)
        tt.append(t)
        xx.append(p)
        dd.append(d)
    return BodyShapes(
        points=np.vstack(xx),
        cells=np.vstack(cc).ravel(),
        celltypes=np.concatenate(tt),
        disp=np.concatenate(dd, axis=1),
    )


def _write_xdmf(path: Path, V, arrays: list[np.ndarray], comm) -> Path:
    """Mode shapes as one XDMF time series ("time" = mode number from 1, as the pictures).

    dolfinx's layout, read by ParaView; meshio and pyvista read the VTU/PVD
    files written beside (:func:`workbench.io.vtk_out.write_modes`).
    """
    from dolfinx.io import XDMFFile

    path.parent.mkdir(parents=True, exist_ok=True)
    with XDMFFile(comm, str(path), "w") as f:
        f.write_mesh(V.mesh)
        for k, a in enumerate(arrays):
            u = _vec_to_function(V, a)
            u.name = "mode_shape"
            f.write_function(u, float(k + 1))
    return path


def _write_vtk(
    out: Path, body_shapes, freqs, labels, contact, dmp, damper_elastic, damper_hz, comm
) -> dict[str, str]:
    """modes_rig.pvd and modes_damper.pvd (VTU per mode, 1-based, with frequencies)."""
    from ..io.vtk_out import write_modes

    if contact != "stuck":  # the damper file holds its own free-free elastic modes
        bs = _gather_shapes(dmp.V, damper_elastic, comm)
        if bs is not None:
            body_shapes = dict(body_shapes, damper=bs)
    if comm.rank != 0:
        return {}
    files = {"modes_rig_pvd": str(write_modes(out, "rig", body_shapes["rig"], freqs, labels))}
    dl = labels if contact == "stuck" else ["damper free-free"] * len(damper_hz)
    files["modes_damper_pvd"] = str(
        write_modes(
            out, "damper", body_shapes["damper"], freqs if contact == "stuck" else damper_hz, dl
        )
    )
    return files


def compute_modes(
    geom,
    *,
    contact: str = "stuck",
    n: int = 10,
    contact_params: ContactParams | None = None,
    comm=None,
    out_dir: str | Path | None = None,
    shapes: bool = True,
    timings: dict[str, float] | None = None,
) -> ModesResult:
    """The ``n`` lowest modes of the rig with the damper stuck (springs) or free.

    ``geom`` is a :class:`~workbench.geometry.BuiltGeometry`. With ``out_dir``
    the shapes go to ``modes_rig.xdmf`` and ``modes_damper.xdmf`` there (with
    ``contact="free"`` the damper file holds its free-free elastic modes).
    ``shapes`` gathers the shapes on rank 0 for pictures
    (:func:`workbench.render.modes.render_modes`). A point of the geometry
    that is not a mesh node is an InputError; a failed eigen solve a
    SolveError carrying the converged pairs.
    """
    from mpi4py import MPI

    from .coupling import pair_springs, stuck_fe_system
    from .solvers import eigen_solve

    contact = check_choice("contact", contact, ("stuck", "free"))
    n = check_int("n", n, 1, 200)
    comm = MPI.COMM_WORLD if comm is None else comm
    params = contact_params or load_contact_params()
    timings = {} if timings is None else timings
    bodies = load_bodies(geom, comm, timings)
    rig, dmp = bodies["rig"], bodies["damper"]
    with stage(timings, "locate"):
        pn = locate_nodes(rig, geom.contact.points, what="contact point")
        dn = locate_nodes(dmp, geom.contact.points, what="contact point")
        rn = locate_nodes(rig, geom.response_points, what="response point")
        en = locate_nodes(rig, geom.excitation_points, what="excitation point")
    shift = -((2 * np.pi * FREE_SHIFT_HZ) ** 2)
    damper_hz = np.zeros(0)
    share: list[float] = []
    with stage(timings, "eigen"):
        if contact == "stuck":
            S = pair_springs(geom.contact, params)
            K, M, is_r, is_d = stuck_fe_system(rig, dmp, pn, dn, S)
            sol = eigen_solve(
                K, M, n, sigma=shift, prefix="upd_modes_", what=f"{geom.damper} stuck modes"
            )
            rig_arrays, dmp_arrays = [], []
            tmp = dmp.M.createVecs()[0]
            for v in sol.vectors:
                for iset, dest in ((is_r, rig_arrays), (is_d, dmp_arrays)):
                    sub = v.getSubVector(iset)
                    dest.append(sub.getArray().copy())
                    if iset is is_d:  # the damper's share of the modal mass (v^T M v = 1)
                        dmp.M.mult(sub, tmp)
                        share.append(float(sub.dot(tmp)))
                    v.restoreSubVector(iset, sub)
        else:
            sol = eigen_solve(
                rig.K, rig.M, n, sigma=0.0, prefix="upd_modes_", what="rig modes (damper free)"
            )
            rig_arrays = [v.getArray().copy() for v in sol.vectors]
            dmp_arrays = [np.zeros(dmp.n_local) for _ in rig_arrays]
            dsol = eigen_solve(
                dmp.K,
                dmp.M,
                12,
                sigma=shift,
                prefix="upd_free_",
                what=f"{geom.damper} damper free-free modes",
            )
            damper_hz = dsol.freqs_hz[6:]
            damper_elastic = [v.getArray().copy() for v in dsol.vectors[6:]]
            if dsol.freqs_hz[5] > 1e-3 * dsol.freqs_hz[6] and comm.rank == 0:
                log.warning(
                    "damper: the 6th free-free frequency %.3g Hz is not a rigid mode",
                    dsol.freqs_hz[5],
                )
    freqs = sol.freqs_hz
    # response-point displacements; sign: the larger x-motion of the two response points is +x
    resp = np.zeros((len(freqs), 2, 3))
    exc = np.zeros((len(freqs), 2, 3))
    for k in range(len(freqs)):
        r = _values_at(rn, rig_arrays[k], comm)
        x = _values_at(en, rig_arrays[k], comm)
        j = int(np.argmax(np.abs(r[:, 0])))
        if r[j, 0] < 0:
            rig_arrays[k] *= -1
            dmp_arrays[k] *= -1
            r, x = -r, -x
        resp[k], exc[k] = r, x
    labels, i_in, i_out = classify_bending(resp, exc)
    share_arr = np.array(share) if share else np.zeros(len(freqs))
    for k in range(len(labels)):
        if k not in (i_in, i_out) and share_arr[k] > DAMPER_MODE_SHARE:
            labels[k] = "damper on its contacts"
    files: dict[str, str] = {}
    with stage(timings, "output"):
        if out_dir is not None:
            out = Path(out_dir)
            files["modes_rig_xdmf"] = str(
                _write_xdmf(out / "modes_rig.xdmf", rig.V, rig_arrays, comm)
            )
            # stuck: the damper's part of each mode; free: its own free-free elastic modes
            files["modes_damper_xdmf"] = str(
                _write_xdmf(
                    out / "modes_damper.xdmf",
                    dmp.V,
                    dmp_arrays if contact == "stuck" else damper_elastic,
                    comm,
                )
            )
        body_shapes = {}
        if shapes or out_dir is not None:
            for name, body, arrays in (("rig", rig, rig_arrays), ("damper", dmp, dmp_arrays)):
                bs = _gather_shapes(body.V, arrays, comm)
                if bs is not None:
                    body_shapes[name] = bs
        if out_dir is not None:
            files.update(
                _write_vtk(
                    Path(out_dir),
                    body_shapes,
                    freqs,
                    labels,
                    contact,
                    dmp,
                    None if contact == "stuck" else damper_elastic,
                    damper_hz,
                    comm,
                )
            )
        if not shapes:
            body_shapes = {}
    res = ModesResult(
        damper=geom.damper,
        contact=contact,
        freqs_hz=freqs,
        labels=labels,
        in_phase=i_in,
        out_of_phase=i_out,
        response_disp=resp,
        damper_share=share_arr,
        damper_freqs_hz=damper_hz,
        n_dofs={"rig": rig.n_dofs, "damper": dmp.n_dofs},
        shapes=body_shapes,
        files=files,
        timings=dict(timings),
    )
    info(
        log,
        comm,
        "%s, contact %s: %s Hz; first bending in-phase %s, out-of-phase %s",
        geom.damper,
        contact,
        ", ".join(f"{f:.1f}" for f in freqs),
        "none" if i_in is None else f"{freqs[i_in]:.1f} Hz",
        "none" if i_out is None else f"{freqs[i_out]:.1f} Hz",
    )
    return res
