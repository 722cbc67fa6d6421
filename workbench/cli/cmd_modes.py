"""``upd modes``: modes of the rig with a damper, stuck or free, first bending pair named."""

from __future__ import annotations

import argparse

from .main import Context, add_geometry_options
from .values import Value, add_value

HELP = "modes of the rig with the damper stuck or free (dolfinx + SLEPc), first bending named"
DESCRIPTION = """\
Mesh the rig and a damper (cached), assemble linear elasticity with quadratic
tetrahedra (base clamped, damper free) and compute the lowest modes with
SLEPc (shift-and-invert, MUMPS).

--contact stuck ties every contact pair by springs kt, kt, kn in its frame
(geometry/contact.toml, or --contact-file): the linear limit of a damper
that never slips. --contact free leaves the damper off the platforms (the
blades alone; the damper's own free-free frequencies are listed beside).

The first bending in-phase and out-of-phase modes are named from the
computed shapes (x-displacement of the two response points). Shapes go to
modes_rig.pvd / modes_damper.pvd (one VTU per mode with its frequency; read
by ParaView, meshio and pyvista), to modes_rig.xdmf / modes_damper.xdmf
(dolfinx layout) and to mode_NN.png and first_bending.png. Everywhere
modes are numbered from 1 ("time" = mode number in ParaView).

Examples:
  upd modes --damper cone --out results/modes_cone --json
  mpirun -n 2 --allow-run-as-root --oversubscribe -x OMP_NUM_THREADS=1 \\
      .venv/bin/upd modes --damper wedge --contact free --n 6
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--damper", required=True, metavar="{cone,cylinder,wedge}", help="damper shape"
    )
    parser.add_argument(
        "--contact",
        default="stuck",
        metavar="{stuck,free}",
        help="contact pairs tied by springs (stuck, default) or absent (free)",
    )
    add_value(parser, "--n", Value("int", 1, 200), "number of modes", metavar="N", default=10)
    add_geometry_options(parser, "contact parameters TOML (default geometry/contact.toml)")
    parser.add_argument("--no-png", action="store_true", help="skip the mode-shape pictures")


def run(args: argparse.Namespace, ctx: Context) -> dict:
    from ..assembly.params import load_contact_params
    from ..errors import check_choice, check_int
    from ..geometry import build_geometry
    from ..io import write_json
    from ..log import mpi_rank, stage

    contact = check_choice("contact", args.contact, ("stuck", "free"))
    n = check_int("n", args.n, 1, 200)
    params = load_contact_params(args.contact_file, geometry_file=args.geometry)
    out = ctx.out_dir(f"results/modes_{args.damper}")
    with stage(ctx.timings, "geometry"):
        geom = build_geometry(
            args.damper, out / "geometry", geometry_file=args.geometry, size_mm=args.size
        )
    from ..fe.modes import compute_modes

    res = compute_modes(
        geom,
        contact=contact,
        n=n,
        contact_params=params,
        out_dir=out,
        shapes=not args.no_png,
        timings=ctx.timings,
    )
    summary = {"out": str(out), **res.summary()}
    if not args.no_png and mpi_rank() == 0:
        from ..render.modes import render_modes

        with stage(ctx.timings, "png"):
            pngs = render_modes(res, out)
        summary["files"]["png"] = [str(p) for p in pngs]
    summary["timings_s"] = {k: round(v, 3) for k, v in ctx.timings.items()}
    summary["geometry_digest"] = geom.digest
    if mpi_rank() == 0:
        write_json(out / "modes.json", summary)
    return summary
