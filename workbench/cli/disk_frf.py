"""``upd disk --frf``: the forced response of one sector under engine-order excitation.

Builds the sector's harmonic-balance model (:mod:`workbench.pipeline.sector`) at
the nodal diameters the harmonics of ``--eo`` live at, follows the response at
``--force`` and writes ``sector_eo<EO>.h5`` (the branch, every dataset with its
unit; the engine order, ND and direction of each harmonic as attributes),
``sector_eo<EO>.csv`` and ``sector_eo<EO>.png`` (the receptance curve).
``upd disk --backbone``: the nonlinear mode of the first family at the ND of
``--eo`` on the same sector model (``sector_backbone_eo<EO>.h5``, ``.csv`` and ``.png``: frequency,
damping ratio, friction energy and contact status against the amplitude).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

HARMONICS = (0, 1, 2, 3)


def sector_model(args, ctx, rec, cp):
    """The sector's harmonic-balance model at the NDs of ``args.eo``'s harmonics."""
    from ..hbm.core.sector import check_engine_order
    from ..log import stage
    from ..pipeline.sector import build_sector_model, nds_for

    eo = check_engine_order(args.eo, rec.n_blades)
    with stage(ctx.timings, "sector_model"):
        return build_sector_model(
            rec, cp, nds_for(eo, rec.n_blades, HARMONICS), n_modes=args.frf_modes
        )


def sector_frf(args, ctx, rec, model) -> dict[str, Any]:
    """Run the sector forced response of ``args`` (eo, force, band_hz) on ``model``."""
    from ..log import stage
    from ..pipeline.sector import sector_forced_response

    eo = args.eo
    with stage(ctx.timings, "sector_frf"):
        band = tuple(args.band_hz) if args.band_hz else None
        br, info = sector_forced_response(model, eo, args.force, band, HARMONICS)
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


def sector_backbone_run(args, ctx, model) -> dict[str, Any]:
    """The sector backbone at ``args.eo`` (the default amplitude range: 0.05..300 times the
    first slip) written to ``sector_backbone_eo<EO>.h5``, ``.csv`` and ``.png``."""
    from ..log import stage
    from ..pipeline.sector import sector_backbone

    eo = args.eo
    with stage(ctx.timings, "sector_backbone"):
        nm = sector_backbone(model, eo, harmonics=HARMONICS)
    summary = {
        "eo": eo,
        "completed": nm.completed,
        "message": nm.message,
        "n_points": nm.n_points,
        "stuck_hz": nm.f_stuck_hz,
        "freq_hz": [float(nm.freq_hz[0]), float(nm.freq_hz[-1])] if nm.n_points else [],
        "damping_ratio_max": float(nm.damping_ratio.max()) if nm.n_points else None,
        "time_s": nm.timings["total"],
    }
    stem = f"sector_backbone_eo{eo}"

    def write(d: Path) -> dict[str, str]:
        from ..render.nlmode_figures import plot_backbones

        png = plot_backbones(
            [(str(args.damper), nm)],
            d / f"{stem}.png",
            unit_scale=1e3,
            unit="mm",
            title=f"{args.damper} damper: nonlinear mode at EO {eo} (one sector's unknowns)",
        )
        return {
            "h5": str(nm.save(d / f"{stem}.h5")),
            "csv": str(nm.to_csv(d / f"{stem}.csv", unit="m")),
            "png": str(png),
        }

    summary["files"] = ctx.write(write)
    return summary
