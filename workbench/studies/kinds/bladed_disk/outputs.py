"""The bladed-disk study's files (rank 0): tables (CSV), results (HDF5 with units), figures,
the summary JSON and the report, from the case records and the per-damper screen and
worst-peak fields of ``compute.py``."""

from __future__ import annotations

import logging
from typing import Any

import numpy as np

from ....hbm.core.sector import wave_of
from ....io import write_json
from ....io.csv_rows import write_rows_csv
from ...engine.outputs import write_manifest_and_report

log = logging.getLogger(__name__)


def nd_and_direction(eo: int, n_blades: int) -> tuple[int, str]:
    """The ND the harmonic-1 excitation of ``eo`` lives at and its wave's direction
    (:func:`workbench.hbm.core.sector.wave_of`)."""
    return wave_of(1, eo, n_blades)


def eo_nd(eos: list[int], n_blades: int) -> dict[str, dict[str, Any]]:
    """The summaries' ``eo_nd``: per EO its harmonic-1 ND and the wave's direction."""
    return {
        str(e): dict(zip(("nd", "direction"), wave_of(1, e, n_blades), strict=True)) for e in eos
    }


def write_outputs(spec, out, cases, worst, best, fans, eos, forces, summary, timings) -> None:
    """Tables (CSV), results (HDF5 with units), figures, summary JSON and report (rank 0)."""
    import h5py

    from .figures import (
        plot_energy_vs_eo,
        plot_fan_eo,
        plot_k2k_vs_nd,
        plot_peaks_vs_eo,
        plot_worst_status,
        render_worst_fields,
    )
    from .report import bladed_disk_sections, extra_sections

    n_b = int(spec.bladed_disk.n_blades)
    dampers = list(spec.dampers)
    tables, figs = out / "tables", out / "figures"
    tables.mkdir(parents=True, exist_ok=True)
    figs.mkdir(parents=True, exist_ok=True)
    cols = [
        "damper",
        "eo",
        "nd",
        "direction",
        "force_n",
        "peak_m",
        "peak_hz",
        "friction_energy_j",
        "stuck_hz",
        "peak_at_band_edge",
        "completed",
        "cached",
        "n_points",
        "wall_s",
        "message",
    ]
    write_rows_csv(tables / "bladed_disk_cases.csv", cases, cols)
    write_rows_csv(tables / "bladed_disk_worst.csv", worst)
    write_rows_csv(tables / "bladed_disk_best.csv", best)
    fan_rows = [
        {
            "nodal_diameter": k,
            **{
                f"{d}_family_{j + 1}_hz": float(fans[d][k, j])
                for d in dampers
                for j in range(fans[d].shape[1])
            },
        }
        for k in range(n_b // 2 + 1)
    ]
    write_rows_csv(tables / "bladed_disk_fan.csv", fan_rows)
    screen = summary["screen"]
    write_rows_csv(tables / "bladed_disk_screen.csv", screen)

    shape = (len(dampers), len(forces), len(eos))
    grid = {q: np.full(shape, np.nan) for q in ("peak_m", "peak_hz", "friction_energy_j")}
    lower = np.zeros(shape, dtype=bool)
    for c in cases:
        i, j, k = dampers.index(c["damper"]), forces.index(c["force_n"]), eos.index(c["eo"])
        for q in grid:
            grid[q][i, j, k] = np.nan if c[q] is None else c[q]
        # a curve that stopped early or peaks on its band edge: its peak is a lower bound
        lower[i, j, k] = not c["completed"] or c["peak_at_band_edge"]
    units = {
        "peak_m": (
            "m",
            "peak amplitude of the response point along the excitation [damper, force, eo]",
        ),
        "peak_hz": ("Hz", "frequency of the peak [damper, force, eo]"),
        "friction_energy_j": (
            "J",
            "friction energy per sector and cycle at the peak [damper, force, eo]",
        ),
        "forces_n": ("N", "harmonic-1 force on each blade"),
        "eos": ("1", "engine orders"),
        "nd": ("1", "nodal diameter of the harmonic-1 excitation of each EO"),
        "nodal_diameters": ("1", "nodal diameters of the fan diagram"),
    }
    with h5py.File(out / "bladed_disk.h5", "w") as h:
        for q, a in grid.items():
            h[q] = a
        h["forces_n"] = np.array(forces)
        h["eos"] = np.array(eos)
        h["nd"] = np.array([nd_and_direction(e, n_b)[0] for e in eos])
        h["nodal_diameters"] = np.arange(n_b // 2 + 1)
        h.attrs["dampers"] = json_list(dampers)
        h.attrs["direction"] = json_list([nd_and_direction(e, n_b)[1] for e in eos])
        h.attrs["n_blades"] = n_b
        for d in dampers:
            name = f"fan_stuck_hz/{d}"
            h[name] = fans[d]
            h[name].attrs["unit"] = "Hz"
            h[name].attrs["description"] = (
                "stuck-damper cyclic frequencies [nodal diameter, family]"
            )
        n_nd = n_b // 2 + 1
        for q, u, text in (
            ("stuck_hz", "Hz", "first family, every pair stuck"),
            ("sliding_hz", "Hz", "first family, tangential springs removed"),
            ("k2_over_k", "1", "1 - (sliding / stuck)^2"),
        ):
            a = np.full((len(dampers), n_nd), np.nan)
            for r in screen:
                a[dampers.index(r["damper"]), r["nd"]] = r[q]
            h[f"screen/{q}"] = a
            units[f"screen/{q}"] = (u, f"coupling screen [damper, nodal diameter]: {text}")
        for q, (u, text) in units.items():
            h[q].attrs["unit"] = u
            h[q].attrs["description"] = text

    curves = {(c["damper"], c["force_n"], c["eo"]): c for c in cases}
    paths = {
        "peaks": plot_peaks_vs_eo(
            dampers, forces, eos, grid["peak_m"], n_b, figs / "bladed_disk_peaks.png", lower
        ),
        "energy": plot_energy_vs_eo(
            dampers, forces, eos, grid["friction_energy_j"], figs / "bladed_disk_energy.png", lower
        ),
        "fan": plot_fan_eo(
            fans,
            n_b,
            worst,
            [c for c in curves.values() if c["peak_hz"]],
            figs / "bladed_disk_fan.png",
        ),
    }
    f_max = max(forces)
    wcases = [
        curves[(w["damper"], w["force_n"], w["worst_eo"])] for w in worst if w["force_n"] == f_max
    ]
    wnd = {w["damper"]: w["nd"] for w in worst if w["force_n"] == f_max}
    eo_nds = sorted({nd_and_direction(e, n_b)[0] for e in eos})
    paths["k2k"] = plot_k2k_vs_nd(
        dampers, screen, eo_nds, wnd, figs / "bladed_disk_k2k.png", forces
    )
    if wcases:
        paths["status"] = plot_worst_status(wcases, figs / "bladed_disk_status.png")
    fields = summary["worst_peak_field"]
    if fields:
        try:
            paths["fields"] = render_worst_fields(fields, figs / "bladed_disk_worst_fields.png")
        except Exception as e:  # noqa: BLE001 - a picture is a by-product (no EGL, no GPU)
            log.warning("worst-peak field picture not drawn (%s)", e)
    summary["files"] = {
        "h5": str(out / "bladed_disk.h5"),
        "screen_csv": str(tables / "bladed_disk_screen.csv"),
        "worst_peak_vtu": [f["vtu"] for f in fields],
        "cases_csv": str(tables / "bladed_disk_cases.csv"),
        "worst_csv": str(tables / "bladed_disk_worst.csv"),
        "best_csv": str(tables / "bladed_disk_best.csv"),
        **{f"{k}_png": str(p) for k, p in paths.items()},
    }
    head = [
        f"{w['damper']} at {w['force_n']:g} N: worst EO {w['worst_eo']} (ND {w['nd']}, "
        f"{w['direction']}), peak {w['worst_peak_m']:.4g} m at {w['peak_hz']:.1f} Hz"
        + (f" (branch stopped early at EO {w['stopped_eos']})" if w["stopped_eos"] else "")
        for w in worst
    ]
    summary["headline"] = head
    head += [
        f"{d} k2/k (1 - (f_sliding/f_stuck)^2) at ND 0..{n_b // 2}: "
        + " ".join(f"{r['k2_over_k']:.3f}" for r in screen if r["damper"] == d)
        for d in dampers
    ]
    sections = bladed_disk_sections(
        n_b, eos, summary["eo_nd"], worst, best, summary["failed"], summary["at_band_edge"]
    )
    sections += extra_sections(dampers, screen, fields, wcases, paths)
    write_manifest_and_report(
        out,
        spec,
        f"bladed disk of {n_b} blades: dampers x engine orders x forces,",
        head,
        timings,
        sections,
    )
    write_json(out / "bladed_disk.json", summary)


def json_list(v: list) -> str:
    import json

    return json.dumps(v)
