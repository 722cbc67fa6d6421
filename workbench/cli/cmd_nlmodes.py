"""``upd nlmodes``: nonlinear modes (backbones) and the forced responses synthesised from them."""

from __future__ import annotations

import argparse
import logging
import time
from pathlib import Path
from typing import Any

from .main import Context

HELP = "nonlinear modes: frequency and damping against amplitude, forced responses from them"
DESCRIPTION = """\
Follow one nonlinear mode of a reduced model with friction contacts in its modal
amplitude by the extended periodic motion concept (a negative mass-proportional
damping -xi M q' makes the damped free motion periodic; Krack 2015), with the same
harmonic balance, AFT, contact law and preload balance as `upd frf`. Out come the
frequency, the modal damping ratio D = xi / (2 w) (the model's own viscous damping
included), the friction energy per cycle and the contact status against the modal
amplitude (the backbone). The forced response at any excitation level then follows
from the single-nonlinear-mode synthesis, checked automatically for validity (mode
shape change, a close mode, a backbone that folds back, higher harmonics, heavy
damping).

FILE is either
  a model file of `upd frf` (TOML with [model]): the mode the excitation drives most
    in the band; backbone.h5/.csv, backbone.png, synthesis.png and summary.json in
    --out; per level the synthesised peak and whether it is valid; with --compare
    also the full HBM curve of each level, the peak errors and the time ratio;
  a study file of `upd study` (comparison or sweep): one backbone per damper and
    family on the study's reduced models (same --out: the FE cache and, if the study
    has run, its curves are reused), the syntheses at the study's forces against the
    study's HBM curves where computed; nlmodes.json/.csv and the figures in --out.

examples:
  upd nlmodes studies/examples/two_dof_contact.toml --compare
  upd nlmodes studies/examples/sdof_jenkins.toml --levels 0.2,0.5,1,2 --json
  upd nlmodes tests/studies/tiny.toml --out results/tiny"""

log = logging.getLogger(__name__)


# the nonlinear mode's own options: (flag, dest) used with a model file only
MODEL_ONLY = (
    ("--mode", "mode"),
    ("--amplitudes", "amplitudes"),
    ("--levels", "levels"),
    ("--band", "band"),
    ("--compare", "compare"),
)
# study options that a model file takes too (the others need a study file)
MODEL_STUDY_OPTIONS = ("harmonics", "nt")
RANGE_WHY = (
    "relative to the first slip: below 1e-4 the mode is stuck, beyond 1e5 the contacts play no part"
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    from ..limits import ENTRY_MAX
    from ..studies.engine.spec import add_arguments as add_study_options
    from .cmd_frf import add_levels_and_band
    from .values import Value, add_value

    p.add_argument(
        "file", type=Path, metavar="FILE", help="model file (TOML with [model]) or study file"
    )
    g = p.add_argument_group("nonlinear mode options")
    add_value(
        g,
        "--mode",
        Value("int", 0, 100_000),
        "model file: index of the stuck linear mode to follow, below the model's number of "
        "DOFs (default: the one the excitation drives most in the band)",
        metavar="N",
    )
    add_value(
        g,
        "--range",
        Value("floats", 1e-4, 1e5, count=2, rising=True, why=RANGE_WHY),
        "modal amplitude range relative to the first slip or lift-off in the stuck mode",
        metavar="R0,R1",
        default="0.05,300",
    )
    add_value(
        g,
        "--amplitudes",
        Value("floats", 0.0, ENTRY_MAX, lo_open=True, count=2, rising=True, ratio=1e9),
        "model file: absolute modal amplitude range (sqrt(kg) m) instead of --range",
        metavar="A0,A1",
    )
    add_value(
        g,
        "--steps",
        Value("int", 1, 10_000),
        "first step: the range over N steps",
        metavar="N",
        default="40",
    )
    add_levels_and_band(g, "model file: ")
    g.add_argument(
        "--compare",
        action="store_true",
        help="model file: also compute the full HBM curve of every level",
    )
    add_study_options(p)


def run(args: argparse.Namespace, ctx: Context) -> dict[str, Any]:
    from ..config import read_toml
    from ..errors import InputError
    from ..studies.engine.spec import OPTIONS

    if not args.file.is_file():
        raise InputError("FILE", str(args.file), "an existing model or study file (TOML)")
    data = read_toml(args.file)
    if not data:
        raise InputError(
            "FILE", str(args.file), "a model file ([model]) or a study file", "it is empty"
        )
    if "model" in data:  # a study option the model file would ignore is refused
        for o in OPTIONS:
            if hasattr(args, o.attr) and o.name not in MODEL_STUDY_OPTIONS:
                raise InputError(
                    f"--{o.name}",
                    getattr(args, o.attr),
                    f"no --{o.name} with a model file ([model] in {args.file.name})",
                    "it is a study option; a model file takes --harmonics and --nt",
                )
        return _run_model(args, ctx)
    for flag, dest in MODEL_ONLY:  # ... and so is a model-file option with a study file
        v = getattr(args, dest)
        if v not in (None, False):
            raise InputError(
                flag,
                v,
                f"no {flag} with a study file ({args.file.name} has no [model])",
                "the study's nonlinear modes are its first bending pair, one per damper and family",
            )
    return _run_study(args, ctx)


def _run_model(args: argparse.Namespace, ctx: Context) -> dict[str, Any]:
    from ..errors import SolveError, check_int
    from ..hbm import frequency_response, load_frf_model
    from ..hbm.nlmodes.backbone import nonlinear_mode
    from ..hbm.nlmodes.synthesis import synthesize
    from ..io import write_json
    from ..render.nlmode_figures import plot_backbones, plot_synthesis
    from ..studies.engine.spec import BY_NAME, check_option
    from .cmd_frf import OVERRIDE_NAMES, overrides

    for name in MODEL_STUDY_OPTIONS:  # the study options' own rule
        if hasattr(args, name):
            setattr(args, name, check_option(BY_NAME[name], getattr(args, name)))
    model = load_frf_model(args.file, overrides(args), names=OVERRIDE_NAMES)
    out = ctx.out_dir(f"results/nlmodes/{model.name}")
    mode = None if args.mode is None else check_int("--mode", args.mode, 0, model.system.n - 1)
    amps = None if args.amplitudes is None else tuple(args.amplitudes)
    rel = tuple(args.range)
    steps = args.steps
    nm = nonlinear_mode(
        model.system,
        mode=mode,
        amplitude_range=amps,
        relative_range=rel,
        harmonics=model.harmonics,
        nt=model.nt or None,
        outputs=model.outputs,
        output_names=model.output_names,
        f1=model.f1,
        band_hz=model.band_hz,
        n_steps=steps,
        dc_anchor=model.options.dc_anchor,
        levels=model.levels,
        label=model.name,
    )
    files = ctx.write(
        lambda d: {
            "h5": str(nm.save(d / "backbone.h5")),
            "csv": str(nm.to_csv(d / "backbone.csv", unit=model.length_unit)),
        }
    )
    mm = model.length_unit == "m"
    scale, unit = (1e3, "mm") if mm else (1.0, model.length_unit)
    if nm.n_points:
        files["backbone_png"] = str(
            ctx.write(
                lambda d: plot_backbones(
                    [(model.name, nm)],
                    d / "backbone.png",
                    unit_scale=scale,
                    unit=unit,
                    title=f"{model.name}: nonlinear mode {nm.mode}",
                )
            )
        )
    levels, syns, hbm = [], [], []
    t_hbm = 0.0
    for level in model.levels:
        t0 = time.perf_counter()
        s = synthesize(nm, model.f1, level, 0, model.band_hz) if nm.n_points >= 2 else None
        t_syn = time.perf_counter() - t0
        row: dict[str, Any] = {"level": level, "synthesis_s": round(t_syn, 6)}
        if s is not None:
            syns.append(s)
            row.update(
                peak_frequency_hz=s.peak_freq_hz,
                peak_amplitude=s.peak_amplitude,
                valid=s.valid,
                reasons=s.reasons,
            )
        if args.compare:
            b = frequency_response(
                model.system,
                model.f1,
                level,
                model.band_hz,
                model.outputs,
                harmonics=model.harmonics,
                nt=model.nt or None,
                options=model.options.replace(stability=False),
                output_names=model.output_names,
                label=f"{model.name} level {level:g}",
            )
            hbm.append(b)
            t_hbm += b.timings.get("total", 0.0)
            i = b.peak(0)
            row.update(
                hbm_peak_frequency_hz=float(b.freq_hz[i]) if i >= 0 else None,
                hbm_peak_amplitude=float(b.out_amp[i, 0]) if i >= 0 else None,
                hbm_s=round(b.timings.get("total", 0.0), 4),
            )
            if s is not None and i >= 0:
                row["error_pct"] = 100 * (s.peak_amplitude / float(b.out_amp[i, 0]) - 1)
                row["freq_error_pct"] = 100 * (s.peak_freq_hz / float(b.freq_hz[i]) - 1)
        levels.append(row)
    if syns:
        files["synthesis_png"] = str(
            ctx.write(
                lambda d: plot_synthesis(
                    nm,
                    syns,
                    d / "synthesis.png",
                    hbm=hbm or None,
                    unit_scale=scale,
                    unit=unit,
                    band_hz=model.band_hz,
                    title=f"{model.name}: forced responses from the mode",
                )
            )
        )
    t_nm = float(nm.timings.get("total", 0.0))
    summary = {
        "model": str(model.path),
        "name": model.name,
        "n_dofs": model.system.n,
        "n_elements": model.system.n_el,
        "length_unit": model.length_unit,
        "harmonics": list(model.harmonics),
        "nt": nm.nt,
        "band_hz": list(model.band_hz),
        "backbone": nm.summary(),
        "levels": levels,
        "files": files,
        "out": str(out),
    }
    if args.compare:
        summary["hbm_s"] = round(t_hbm, 4)
        summary["time_ratio"] = round(t_nm / t_hbm, 4) if t_hbm > 0 else None
    ctx.write(lambda d: write_json(d / "summary.json", ctx.note_rescue(summary)))
    if nm.failed:
        raise SolveError(
            f"the backbone stopped early ({nm.message}); what was computed is in {ctx.folder}"
        )
    return summary


def _run_study(args: argparse.Namespace, ctx: Context) -> dict[str, Any]:
    from ..errors import InputError
    from ..io import write_json
    from ..io.csv_rows import write_rows_csv
    from ..log import mpi_rank
    from ..studies.engine.nlmodes import cost_rows, nlmode_sections, study_backbones
    from ..studies.engine.spec import cli_values, load_study

    spec = load_study(args.file, cli_values(args))
    if spec.kind not in ("comparison", "sweep"):
        raise InputError("kind", spec.kind, "comparison or sweep (a study with damper models)")
    out = ctx.out_dir(f"results/{spec.name}")
    rel = tuple(args.range)
    steps = args.steps
    res = study_backbones(spec, out, relative_range=rel, n_steps=steps)
    if mpi_rank() != 0:
        return {}
    write_json(out / "nlmodes.json", res)
    if res["rows"]:
        write_rows_csv(out / "nlmodes.csv", res["rows"])
    sections = nlmode_sections(res, out)
    figs = [f["path"] for s in sections for f in s["figures"]]
    return {
        "study": spec.name,
        "out": str(out),
        "backbones": res["backbones"],
        "cost": cost_rows(res),
        "figures": figs,
        **({"rows": res["rows"]} if ctx.json else {}),
    }
