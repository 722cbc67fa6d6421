"""``upd disk --frf``: the forced response of one sector under engine-order excitation.

Builds the sector's harmonic-balance model (:mod:`workbench.pipeline.sector`) at
the nodal diameters the harmonics of ``--eo`` live at, follows the response at
``--force`` and writes ``sector_eo<EO>.h5`` (the branch, every dataset with its
unit; the engine order, ND and direction of each harmonic as attributes),
``sector_eo<EO>.csv`` and ``sector_eo<EO>.png`` (the receptance curve).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any


def sector_frf(args, ctx, rec, cp, out: Path) -> dict[str, Any]:
    """Run the sector forced response of ``args`` (eo, force, frf_modes, band_hz) on ``rec``."""
    from ..hbm.core.sector import check_engine_order
    from ..log import stage
    from ..pipeline.sector import build_sector_model, nds_for, sector_forced_response

    harmonics = (0, 1, 2, 3)
    eo = check_engine_order(args.eo, rec.n_blades)
    with stage(ctx.timings, "sector_model"):
        model = build_sector_model(
            rec, cp, nds_for(eo, rec.n_blades, harmonics), n_modes=args.frf_modes
        )
    with stage(ctx.timings, "sector_frf"):
        band = tuple(args.band_hz) if args.band_hz else None
        br, info = sector_forced_response(model, eo, args.force, band, harmonics)
    i = int(br.out_amp[:, 0].argmax()) if len(br.freq_hz) else -1
    summary = {
        **info,
        "force_n": args.force,
        "completed": br.completed,
        "message": br.message,
        "n_points": len(br.freq_hz),
        "peak_hz": float(br.freq_hz[i]) if i >= 0 else None,
        "peak_m": float(br.out_amp[i, 0]) if i >= 0 else None,
        "friction_energy_at_peak_j": float(br.friction_energy[i].sum()) if i >= 0 else None,
    }

    def write(folder: Path) -> dict[str, str]:
        import h5py

        from ..io.units import BRANCH_UNITS, annotate
        from ..render.sector_figures import plot_sector_frf

        stem = folder / f"sector_eo{eo}"
        h5 = br.save(stem.with_suffix(".h5"))
        with h5py.File(h5, "a") as h:
            annotate(h, BRANCH_UNITS)
            h.attrs["problem"] = json.dumps({"kind": "sector", "force_n": args.force, **info})
        csv = br.to_csv(stem.with_suffix(".csv"))
        png = plot_sector_frf(br, info, args.force, rec.damper, stem.with_suffix(".png"))
        return {"sector_h5": str(h5), "sector_csv": str(csv), "sector_png": str(png)}

    summary["files"] = ctx.write(write)
    return summary
