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
    add_model_values(p)
    p.add_argument("--no-stability", action="store_true", help="skip Hill's method")
    p.add_argument(
        "--no-figures",
        action="store_true",
        help="write no PNG figures (the curves, CSV and summary only: a lean batch run)",
    )


def add_levels_and_band(p, lead: str = "") -> None:
    """--levels and --band: a model file's levels and band from the command line
    (``upd frf`` and ``upd nlmodes``; ``lead`` starts their help)."""
    from ..limits import FRF_BAND_RATIO_MAX, FRF_BAND_WHY
    from .values import Value, add_value

    add_value(
        p,
        "--levels",
        Value("floats", 0.0, None, lo_open=True),
        f"{lead}excitation levels instead of the file's [excitation] levels (at most 10^4 x "
        "the largest slip force mu N0 over the force per unit level)",
        metavar="L1,L2,...",
    )
    band = Value(
        "floats", 0.0, None, lo_open=True, unit="Hz", count=2, ratio=FRF_BAND_RATIO_MAX,
        why=FRF_BAND_WHY,
    )  # fmt: skip
    add_value(p, "--band", band, f"{lead}frequency band F0 < F1 instead of [band]", metavar="F0,F1")


def add_model_values(p: argparse.ArgumentParser) -> None:
    """--levels, --band, --harmonics, --nt: the model file's values from the command line."""
    from ..limits import MAX_HARMONIC, MAX_NT, NT_WHY
    from .values import Value, add_value

    add_levels_and_band(p)
    add_value(
        p,
        "--harmonics",
        Value("ints", 0, MAX_HARMONIC),
        "harmonic list instead of [hbm] harmonics (must include 1)",
        metavar="H0,H1,...",
    )
    add_value(
        p,
        "--nt",
        Value("int", 1, MAX_NT, why=NT_WHY),
        "time samples per period instead of [hbm] nt (omit for automatic)",
        metavar="N",
    )


def overrides(args: argparse.Namespace) -> dict[str, dict[str, Any]]:
    """The model file's keys replaced by the (checked) command-line values."""
    over: dict[str, dict[str, Any]] = {}
    if getattr(args, "levels", None) is not None:
        over.setdefault("excitation", {})["levels"] = list(args.levels)
    if getattr(args, "band", None) is not None:
        over["band"] = {"start_hz": args.band[0], "end_hz": args.band[1]}
    if getattr(args, "harmonics", None) is not None:
        over.setdefault("hbm", {})["harmonics"] = list(args.harmonics)
    if getattr(args, "nt", None) is not None:
        over.setdefault("hbm", {})["nt"] = int(args.nt)
    if getattr(args, "no_stability", False):
        over.setdefault("solver", {})["stability"] = False
    return over


def run(args: argparse.Namespace, ctx: Context) -> dict[str, Any]:
    from ..errors import SolveError
    from ..hbm import frequency_response, load_frf_model
    from ..io import write_json

    model = _load(args.model, overrides(args), load_frf_model)
    ctx.out_dir(f"results/frf/{model.name}")
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
        files = ctx.write(
            lambda out, b=b, i=i, level=level: _curve_files(
                b, i, level, model, out, figures=not args.no_figures
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

        fig = ctx.write(
            lambda out: plot_frf(
                branches,
                out / "frf.png",
                unit_scale=1e3 if mm else 1.0,
                unit="mm" if mm else model.length_unit,
                title=f"{model.name}",
                force_per_level_n=float(abs(model.f1).max()),
            )
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
        "out": "",
        "curves": rows,
    }
    ctx.write(lambda out: write_json(out / "summary.json", ctx.note_rescue(summary)))
    if failures:
        raise SolveError(
            f"{len(failures)} of {len(rows)} curves stopped early ("
            + "; ".join(failures)
            + f"); what was computed is in {ctx.folder}"
        )
    return summary


def _curve_files(b, i: int, level: float, model, out: Path, figures: bool = True) -> dict:
    """curve_<i>.h5, .csv and (``figures``) the status map .png of one level's branch."""
    stem = f"curve_{i}"
    files = {
        "h5": str(b.save(out / f"{stem}.h5")),
        "csv": str(b.to_csv(out / f"{stem}.csv", unit=model.length_unit)),
    }
    if figures and b.n_points and b.status.shape[1]:
        from ..render.curves import plot_status_map

        files["png"] = str(
            plot_status_map(
                b, out / f"{stem}.png", title=f"{model.name}: contact status, level {level:g}"
            )
        )
    return files


def _load(path: Path, over: dict, load_frf_model):
    """The model file with the command line's values; every check is the model file's
    (workbench/hbm/io/modelfile.py, modelcheck.py), errors name the option typed."""
    return load_frf_model(path, over, names=OVERRIDE_NAMES)


# how the errors name a model-file key the command line overrides
OVERRIDE_NAMES = {
    "excitation.levels": "--levels",
    "hbm.harmonics": "--harmonics",
    "hbm.nt": "--nt",
}
