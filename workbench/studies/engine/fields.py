"""Full-mesh forced-response fields at each case's peak (study option ``field-shapes``).

``cases/<case>_peak_field.vtu``: the rig and the damper meshes (quadratic
tetrahedra) with the displacement at the peak of the case's curve, point
data in mm::

    disp_cos_mm, disp_sin_mm   harmonic 1: u(t) = cos part cos(wt) + sin part sin(wt)
    disp_amp_mm                per component, sqrt(cos^2 + sin^2)
    disp_mean_mm               harmonic 0 (the mean position), when solved for
    body                       0 rig, 1 damper

field data ``freq_hz``, ``force_n``, ``digest48`` (as the ``_peak.vtu`` files).
The generalised coordinates come from the solved unknowns (one evaluation
of the harmonic balance at the stored peak point, no new solve); the
full-mesh basis is rebuilt per model by :mod:`workbench.fe.expand` (about
one reduction's eigen solve: 20-30 s per damper on the 9 mm rig), by every
MPI rank together.
A case whose file already matches its digest is skipped; a failure is
logged and the study goes on (the file is a by-product).
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np

log = logging.getLogger(__name__)


def peak_coordinates(case, prep) -> tuple[np.ndarray, dict[str, int]]:
    """(nh, n) harmonics of the generalised coordinates at the case's peak, and row indices."""
    from ...hbm.core.balance import HarmonicBalance
    from ...hbm.core.fourier import Fourier
    from ...hbm.core.options import SolverOptions

    b, i = case.branch, case.peak_index
    opts = SolverOptions()
    fourier = Fourier(tuple(b.harmonics), b.nt)
    hb = HarmonicBalance(
        prep.system,
        prep.assembled.excitation(case.phase_deg),
        fourier,
        None,
        case.force_n,
        b.space,
        opts.backend,
        opts.dc_anchor,
    )
    q = hb.response(np.asarray(b.x[i]), 2 * np.pi * float(b.freq_hz[i]))
    k = np.asarray(fourier.k)
    rows = {"cos": int(np.flatnonzero(k == 1)[0])}
    rows["sin"] = rows["cos"] + 1
    if 0 in fourier.harmonics:
        rows["mean"] = int(np.flatnonzero(k == 0)[0])
    return q, rows


def field_path(out: Path, case) -> Path:
    from ...post.results import case_id

    return Path(out) / "cases" / f"{case_id(case)}_peak_field.vtu"


def missing_fields(cases: list, out: Path, comm=None) -> list[int]:
    """Indices of the planned cases whose field file is absent or stale (rank 0 reads the
    files, every rank of ``comm`` gets the list)."""
    from ...io.vtk_out import has_digest

    missing = None
    if comm is None or comm.rank == 0:
        missing = [k for k, c in enumerate(cases) if not has_digest(field_path(out, c), c.digest)]
    return comm.bcast(missing, root=0) if comm is not None else missing


def write_study_fields(
    results,
    out: str | Path,
    prepared: dict[str, Any],
    model_of: dict[str, str],
    missing: list[int],
    comm=None,
) -> list[Path]:
    """The ``_peak_field.vtu`` of the cases ``missing`` (indices, :func:`missing_fields`,
    the same on every rank) that have a peak point.

    Collective over ``comm`` (default COMM_WORLD): every rank takes part in
    the FE expansion (a rank-0-only PETSc session left objects whose
    clean-up at exit waited for the other ranks); rank 0 writes the files.
    """
    from mpi4py import MPI

    from ...fe.expand import expand_body
    from ...log import progress_bar

    comm = MPI.COMM_WORLD if comm is None else comm
    out = Path(out)
    todo = [k for k in missing if results.cases[k].peak_index >= 0]
    groups: dict[str, list] = {}
    for k in todo:
        c = results.cases[k]
        groups.setdefault(model_of.get(c.digest, ""), []).append(c)
    paths = []
    with progress_bar("peak fields", total=len(groups), unit="model") as bar:
        for md, cases in groups.items():
            prep = prepared.get(md)
            if prep is None or not prep.reduced:
                log.warning("peak fields: no model at hand for %d case(s); skipped", len(cases))
                bar.update(1)
                continue
            try:
                paths += _model_fields(out, cases, prep, expand_body, comm)
            except Exception as e:  # noqa: BLE001 - a by-product: report and go on
                log.warning("peak fields of %s not written (%s)", cases[0].damper, e)
            bar.update(1)
    return paths


def _model_fields(out: Path, cases: list, prep, expand_body, comm) -> list[Path]:
    from ...io.vtk_out import write_case_field

    n_rig = prep.assembled.n_rig
    cols, meta = [], []
    for c in cases:
        q, rows = peak_coordinates(c, prep)
        names = [r for r in ("cos", "sin", "mean") if r in rows]
        meta.append((c, names, len(cols)))
        cols += [q[rows[r]] for r in names]
    Q = np.column_stack(cols)
    geom = prep.geometry
    shapes = {
        "rig": expand_body(geom, "rig", prep.reduced["rig"], Q[:n_rig], comm),
        "damper": expand_body(geom, "damper", prep.reduced["damper"], Q[n_rig:], comm),
    }
    paths = []
    if comm.rank != 0:  # the gathered fields are on rank 0
        return paths
    for c, names, j0 in meta:
        fields = {
            r: [shapes[b].disp[j0 + k] for b in ("rig", "damper")] for k, r in enumerate(names)
        }
        paths.append(
            write_case_field(field_path(out, c), c, shapes["rig"], shapes["damper"], fields)
        )
    return paths
