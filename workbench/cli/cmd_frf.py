"""``upd frf``: frequency response curves of a reduced model with friction contacts."""

from __future__ import annotations

import argparse
import logging
import math
from pathlib import Path
from typing import Any

from .main import Context

HELP = "frequency response of reduced matrices with friction contacts (harmonic balance)"
DESCRIPTION = """\
Compute the forced response of a linear reduced model (matrices from any FE code,
.npz or HDF5) with 3-D friction contact elements, by the multi-harmonic balance
method with pseudo-arc-length continuation and Hill stability, one curve per
excitation level of the model file.

For each level it writes curve_<i>.h5 (the branch), curve_<i>.csv and
curve_<i>.png (status map), plus frf.png (all levels) and summary.json to --out
(--no-figures: no PNG),
and prints per level: peak_frequency_hz and peak_amplitude (largest |y(t)| over
the period of the first output DOF, in the model's length unit),
h1_peak_frequency_hz and h1_amplitude (the harmonic-1 amplitude at its own
peak), rms_peak_frequency_hz and rms_amplitude, peak_stability (stable,
unstable or unknown), n_points, wall_s, the worst energy-balance residual and
the accuracy indicator (accuracy_max, accuracy_warning). With
length_unit = "1" (a dimensionless model) the frequencies are also given in
rad/s (*_rad_s) and no *_mm keys are written. Examples: studies/examples/*.toml.
"""

log = logging.getLogger(__name__)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("model", type=Path, help="model file (TOML; see studies/examples)")
    p.add_argument(
        "--levels",
        metavar="L1,L2,...",
        help="excitation levels instead of the file's [excitation] levels",
    )
    p.add_argument("--band", metavar="F0,F1", help="frequency band in Hz instead of [band]")
    p.add_argument("--harmonics", metavar="H0,H1,...", help="harmonic list instead of [hbm]")
    p.add_argument("--nt", metavar="N", help="time samples per period instead of [hbm] nt")
    p.add_argument("--no-stability", action="store_true", help="skip Hill's method")
    p.add_argument(
        "--no-figures",
        action="store_true",
        help="write no PNG figures (the curves, CSV and summary only: a lean batch run)",
    )


def _list(text: str | None, name: str, cast) -> list | None:
    from ..errors import InputError

    if text is None:
        return None
    try:
        vals = [cast(v) for v in text.replace(" ", "").split(",") if v]
    except ValueError:
        raise InputError(name, text, "a comma-separated list of numbers") from None
    if not vals:
        raise InputError(name, text, "a comma-separated list of at least one number")
    return vals


def run(args: argparse.Namespace, ctx: Context) -> dict[str, Any]:
    from ..errors import InputError, SolveError
    from ..hbm import frequency_response, load_frf_model
    from ..io import write_json

    over: dict[str, dict[str, Any]] = {}
    lv = _list(args.levels, "--levels", float)
    if lv is not None:
        over.setdefault("excitation", {})["levels"] = lv
    band = _list(args.band, "--band", float)
    if band is not None:
        if len(band) != 2:
            raise InputError("--band", args.band, "two frequencies F0,F1 in Hz")
        over["band"] = {"start_hz": band[0], "end_hz": band[1]}
    hs = _list(args.harmonics, "--harmonics", int)
    if hs is not None:
        over.setdefault("hbm", {})["harmonics"] = hs
    if args.nt is not None:
        nt = _list(args.nt, "--nt", int)
        if len(nt) != 1 or nt[0] < 1:
            # 0 would silently mean "automatic": refuse it, omitting --nt is the way
            raise InputError(
                "--nt", args.nt, "one whole number of samples per period >= 1 (omit for automatic)"
            )
        over.setdefault("hbm", {})["nt"] = nt[0]
    if args.no_stability:
        over.setdefault("solver", {})["stability"] = False
    model = _load(args.model, over, load_frf_model)
    out = ctx.out_dir(f"results/frf/{model.name}")
    mm = model.length_unit == "m"
    dimensionless = model.length_unit == "1"
    branches, rows, failures = [], [], []
    for i, level in enumerate(model.levels):
        b = frequency_response(
            model.system,
            model.f1,
            level,
            model.band_hz,
            model.outputs,
            harmonics=model.harmonics,
            nt=model.nt or None,
            options=model.options,
            output_names=model.output_names,
            label=f"{model.name} level {level:g}",
        )
        branches.append(b)
        stem = f"curve_{i}"
        files = {
            "h5": str(b.save(out / f"{stem}.h5")),
            "csv": str(b.to_csv(out / f"{stem}.csv", unit=model.length_unit)),
        }
        if b.n_points and b.status.shape[1] and not args.no_figures:
            from ..render.curves import plot_status_map

            files["png"] = str(
                plot_status_map(
                    b, out / f"{stem}.png", title=f"{model.name}: contact status, level {level:g}"
                )
            )
        row = b.summary()
        row["peak_amplitude_unit"] = model.length_unit
        if mm and row["peak_amplitude"] is not None:
            for key in ("peak_amplitude", "h1_amplitude", "rms_amplitude"):
                row[f"{key}_mm"] = row[key] * 1e3
        if dimensionless:  # the time unit is the model's too: angular frequencies, rad/s
            for key in ("peak_frequency", "h1_peak_frequency", "rms_peak_frequency"):
                hz = row[f"{key}_hz"]
                row[f"{key}_rad_s"] = None if hz is None else 2 * math.pi * hz
        row["files"] = files
        rows.append(row)
        if b.failed:
            failures.append(f"level {level:g}: {b.message}")
    fig = None
    if not args.no_figures:
        from ..render.curves import plot_frf

        fig = plot_frf(
            branches,
            out / "frf.png",
            unit_scale=1e3 if mm else 1.0,
            unit="mm" if mm else model.length_unit,
            title=f"{model.name}",
            force_per_level_n=float(abs(model.f1).max()),
        )
    summary = {
        "model": str(model.path),
        "name": model.name,
        "n_dofs": model.system.n,
        "n_elements": model.system.n_el,
        "length_unit": model.length_unit,
        "band_hz": list(model.band_hz),
        "harmonics": list(model.harmonics),
        "nt": int(branches[0].nt) if branches else None,
        "figure": str(fig) if fig else None,
        "out": str(out),
        "curves": rows,
    }
    write_json(out / "summary.json", summary)
    if failures:
        raise SolveError(
            f"{len(failures)} of {len(rows)} curves stopped early ("
            + "; ".join(failures)
            + f"); what was computed is in {out}"
        )
    return summary


def _load(path: Path, over: dict, load_frf_model):
    """The model file, with a damaged matrix file or a negative stiffness refused (exit 2)."""
    import zipfile

    import numpy as np

    from ..config import read_toml
    from ..errors import InputError, WorkbenchError

    try:
        model = load_frf_model(path, over)
    except WorkbenchError:
        raise
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile) as e:
        # h5py/numpy on a truncated or corrupt .h5/.npz
        name = (read_toml(path).get("model") or {}).get("matrices", "")
        raise InputError(
            "model.matrices",
            name,
            "a readable .npz or HDF5 file",
            f"{type(e).__name__}: {str(e)[:160]}",
        ) from None
    K = model.system.K
    d = np.asarray(K.diagonal() if hasattr(K, "diagonal") else np.diag(K), dtype=float)
    if d.size and d.min() < 0:
        i = int(np.argmin(d))
        raise InputError(
            "model.stiffness",
            f"K[{i},{i}] = {d[i]:g}",
            "a stiffness matrix without negative stiffness (no negative diagonal entry)",
        )
    if 0 < d.size <= 2000:  # small models: positive semi-definite (round-off allowed)
        Kd = K.toarray() if hasattr(K, "toarray") else np.asarray(K, dtype=float)
        lam = np.linalg.eigvalsh(0.5 * (Kd + Kd.T))
        if lam[0] < -1e-9 * max(1.0, float(np.abs(lam).max())):
            raise InputError(
                "model.stiffness",
                f"lowest eigenvalue {lam[0]:.4g}",
                "a positive semi-definite stiffness matrix (no negative stiffness)",
            )
    return model
