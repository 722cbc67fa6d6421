"""``upd study``: run a study file (damper comparison, sweeps, fidelity, robustness)."""

from __future__ import annotations

import argparse
from pathlib import Path

HELP = "run a study file: cases, cached results, figures and the HTML report"
DESCRIPTION = """Run a study: every damper x inter-blade phase x excitation level (x swept
value) as a harmonic balance frequency response of the rig + damper model.

The study file's keys are the options below (without --); options given on
the command line override the file. Finished cases are cached under a hash
of their parameters in DIR/cache, so an interrupted study resumes where it
stopped; --force recomputes. Under `mpirun -n N` the cases are spread over
the ranks, and each rank meshes and reduces whole models alone. Without
mpirun the meshes and FE reductions of the models run at once on a pool of
worker processes, one per core (UPD_WORKERS=N sets the number, 1 turns it
off). The run ends with DIR/report.html.

examples:
  upd study studies/paper.toml --out results/paper
  upd study studies/paper.toml --dampers cone --forces 9.6,30 --out results/cone
  upd study studies/fidelity.toml --tolerance 1%    # knob ladders vs a reference, Pareto
                                                    # front, cheapest setting within 1%
  upd study studies/robustness.toml --out results/robustness   # solution methods x hard
                                                    # cases: the map of success and failure
  mpirun -n 2 --allow-run-as-root --oversubscribe upd study studies/paper.toml"""


def add_arguments(p: argparse.ArgumentParser) -> None:
    from ..studies.spec import add_arguments as add_study_options

    p.add_argument(
        "file",
        nargs="?",
        type=Path,
        metavar="FILE",
        help="study file (TOML); without it the built-in defaults are used",
    )
    p.add_argument("--force", action="store_true", help="recompute every case, ignore caches")
    add_study_options(p)


def run(args: argparse.Namespace, ctx) -> dict:
    from ..studies.runner import study_lock
    from ..studies.spec import cli_values, load_study

    spec = load_study(args.file, cli_values(args))
    out = ctx.out_dir(f"results/{spec.name}")
    with study_lock(out):  # a second run on the same folder is refused at once
        return _run(spec, out, args)


def _run(spec, out: Path, args: argparse.Namespace) -> dict:
    from ..studies.outputs import check_failures
    from ..studies.runner import run_study

    if spec.kind == "fidelity":  # knob ladders against a reference, Pareto front, --tolerance
        from ..studies.fidelity import run_fidelity

        return run_fidelity(spec, out, force=args.force)
    if spec.kind == "robustness":  # solution methods x hard cases: the failure map
        from ..studies.robustness import run_robustness

        return run_robustness(spec, out, force=args.force)
    if spec.kind == "uncertainty":  # sampled inputs: distributions, Sobol indices (MPI)
        from ..studies.uncertainty import run_uncertainty

        return run_uncertainty(spec, out, force=args.force)
    results = run_study(spec, out, force=args.force)
    summary = {
        "study": spec.name,
        "kind": spec.kind,
        "out": str(out),
        "report": str(out / "report.html"),
        "n_cases": len(results.cases),
        "n_computed": results.extras.get("n_computed"),
        "n_reused": results.extras.get("n_reused"),
        "peak_not_reached": [c.case_id for c in results.uncovered()],
        "timings_s": {k: round(v, 2) for k, v in results.timings.items()},
        # the cases' schedule: each rank's busy time and busy / (ranks x wall)
        "schedule": {
            k: (round(v, 3) if isinstance(v, float) else v)
            for k, v in (results.extras.get("schedule") or {}).items()
            if k != "records"
        },
        "cases": results.summaries(),
    }
    check_failures(results, summary)
    return summary
