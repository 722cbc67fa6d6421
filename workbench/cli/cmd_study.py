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
    from ..studies.engine.spec import add_arguments as add_study_options
    from ..studies.kinds import all_kinds

    # the kinds come from the registry (workbench/studies/kinds/): one line each
    p.description = (
        (p.description or "")
        + "\n\nstudy kinds (kind = ...):\n"
        + "\n".join(f"  {k.name:<12} {k.description}" for k in all_kinds())
    )

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
    from ..studies.engine.runner import study_lock
    from ..studies.engine.spec import cli_values, load_study
    from ..studies.kinds import get as get_kind

    spec = load_study(args.file, cli_values(args))
    out = ctx.out_dir(f"results/{spec.name}")
    with study_lock(out):  # a second run on the same folder is refused at once
        return get_kind(spec.kind).run(spec, out, args.force)
