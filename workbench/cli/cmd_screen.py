"""``upd screen``: the linear coupling screen of a study's dampers (seconds, not minutes)."""

from __future__ import annotations

import argparse
from pathlib import Path

HELP = "linear coupling screen: will each damper level its family's peak off? (seconds)"
DESCRIPTION = """\
For every damper (and swept value) of a study file and every inter-blade
phase, the linear limits of the assembled rig + damper model:

  stuck / sliding   family frequency with every pair stuck, and with the
                    tangential springs removed (a freely slipping damper)
  k2/k              1 - (f_sliding / f_stuck)^2: the share of modal stiffness
                    the damper adds by sticking
  rig bound k2/k    the same with a rigid damper and 1000x stiffer contact:
                    the most coupling the rig's kinematics allows
  slip / separation the excitation per blade (N) at which the first pair
  onset             slips or lifts off in the stuck linear response
  levels off up to  the single-mode friction estimate of the force up to
                    which the peak stays level: (4/pi) Q k2/k x slip onset,
                    Q = 1/(2 damping)
  verdict           for the study's largest force: stuck, levels off, or
                    rises again

The screen shares the study's FE cache (same --out): run it first to tune a
rig or a damper in seconds per try (after the first reduction), then run
`upd study` on the same file and folder, which reuses the reduced models.
A k2/k of a few per cent cannot level a peak off, whatever mu and cf.
The meshes and reductions of all the models run at once: under mpirun
whole models per rank, else on a pool of worker processes, one per core
(UPD_WORKERS=N sets the number, 1 turns it off); worker_pool in the output
gives each task's seconds.

Takes the same study file and options as `upd study` (only those that
shape the linear model matter: dampers, phases, forces, geometry,
mesh-size, modes, contact stiffness, mu, cf, damping, sweep).

examples:
  upd screen studies/paper.toml
  upd screen studies/paper_rig.toml --dampers cone --json
  upd screen studies/paper.toml --kt-line 2e10 --kn-line 2e10 --mesh-size 14"""


def add_arguments(p: argparse.ArgumentParser) -> None:
    from ..studies.engine.spec import add_arguments as add_study_options

    p.add_argument(
        "file",
        nargs="?",
        type=Path,
        metavar="FILE",
        help="study file (TOML); without it the built-in defaults are used",
    )
    add_study_options(p)


def run(args: argparse.Namespace, ctx) -> dict:
    import sys

    from ..errors import InputError
    from ..io import write_json
    from ..io.csv_rows import write_rows_csv
    from ..log import mpi_rank
    from ..post.screen_table import table
    from ..studies.engine.schedule import world_comm as _comm
    from ..studies.engine.screening import run_screen
    from ..studies.engine.spec import cli_values, load_study

    spec = load_study(args.file, cli_values(args))
    if spec.kind not in ("comparison", "sweep"):
        raise InputError("kind", spec.kind, "comparison or sweep (a study with damper models)")
    out = ctx.out_dir(f"results/{spec.name}")
    res = run_screen(spec, out, comm=_comm())
    rows = res["rows"]
    if mpi_rank() == 0:
        write_json(out / "screen.json", rows)
        write_rows_csv(out / "screen.csv", rows)
        if not ctx.json:
            head, body = table(rows)
            widths = [max(len(h), *(len(r[i]) for r in body)) for i, h in enumerate(head)]
            line = "  ".join(h.ljust(w) for h, w in zip(head, widths, strict=True))
            sys.stdout.write(line + "\n" + "-" * len(line) + "\n")
            for r in body:
                sys.stdout.write(
                    "  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)) + "\n"
                )
    return {
        "study": spec.name,
        "out": str(out),
        "files": [str(out / "screen.json"), str(out / "screen.csv")],
        "largest_force_n": res["f_max_n"],
        "seconds_per_model": {k: round(v, 2) for k, v in res["timings"].items()},
        "worker_pool": res["pool"],
        **({"rows": rows} if ctx.json else {}),
    }
