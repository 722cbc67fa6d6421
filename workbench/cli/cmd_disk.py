"""``upd disk``: one bladed-disk sector, its cyclic modes per nodal diameter and the fan diagram."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from .main import Context, add_geometry_options
from .values import Value, add_value

HELP = "a bladed-disk sector: cyclic modes per nodal diameter and the fan diagram (PNG)"
DESCRIPTION = """\
Build one sector of a bladed disk carrying one blade of the rig's section, its
two platform halves and the damper seated between this sector's platform and
the next one's (gmsh, periodic cyclic faces), then compute the cyclic modes of
every nodal diameter 0..N/2 with the damper stuck and without damper, and draw
the fan diagram (frequency against nodal diameter, fan.png). Under mpirun the
nodal diameters are shared over the ranks.

The rig section comes from geometry/rig.toml (or --geometry, e.g.
geometry/paper_rig.toml), the disk from geometry/disk.toml (or --disk-file);
--n-blades and --bore override it. See docs/DISK.md.

Example:
  upd disk --geometry geometry/paper_rig.toml --damper cone --n-blades 24 --out results/disk
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from ..geometry.disk import MAX_BLADES
    from ..geometry.shapes import names

    parser.add_argument(
        "--damper", default="cone", metavar="{" + ",".join(names()) + "}", help="damper shape"
    )
    add_geometry_options(parser, contact_help="TOML file with a [contact] table (stuck springs)")
    parser.add_argument(
        "--disk-file", type=Path, default=None, metavar="FILE", help="TOML file with a [disk] table"
    )
    add_value(
        parser,
        "--n-blades",
        Value("int", 2, MAX_BLADES),
        "number of blades instead of [disk] n_blades",
        metavar="N",
    )
    parser.add_argument("--bore", default=None, choices=("clamped", "free"), help="bore face")
    add_value(
        parser,
        "--families",
        Value("int", 1, 50),
        "mode families in the fan diagram",
        metavar="N",
        default=4,
    )
    add_value(
        parser,
        "--cb-modes",
        Value("int", 0, 500),
        "fixed-interface modes of the Craig-Bampton model of every ND (the sector without "
        "damper, onto the platform contact nodes), written to cyclic_cb.h5; 0: none",
        metavar="N",
        default=0,
    )
    parser.add_argument(
        "--frf",
        action="store_true",
        help="also the forced response of one sector under engine order --eo at --force "
        "(harmonic balance on the sector; sector_eo<EO>.png/.h5/.csv, docs/DISK_HBM.md)",
    )
    parser.add_argument(
        "--backbone",
        action="store_true",
        help="also the nonlinear mode (EPMC backbone) of the first family at the ND of --eo, "
        "on one sector (sector_backbone_eo<EO>.h5/.csv, docs/DISK_HBM.md)",
    )
    add_value(
        parser,
        "--eo",
        Value("int", 0, None),
        "engine order of the excitation (above N/2 it maps onto ND N - EO mod N, backward)",
        metavar="EO",
        default=1,
    )
    add_value(
        parser,
        "--force",
        Value("float", 0.0, None, lo_open=True, unit="N"),
        "harmonic-1 force on each blade's excitation point",
        metavar="N",
        default=10.0,
    )
    add_value(
        parser,
        "--frf-modes",
        Value("int", 1, 500),
        "fixed-interface modes per ND of the sector harmonic balance",
        metavar="N",
        default=10,
    )
    add_value(
        parser,
        "--band-hz",
        Value("floats", 0.0, None, lo_open=True, unit="Hz", count=2, rising=True),
        "frequency band of the forced response, LO,HI (default 0.9..1.1 x the stuck frequency)",
        metavar="LO,HI",
    )


def run(args: argparse.Namespace, ctx: Context) -> dict[str, Any]:
    from ..geometry import load_geometry_params
    from ..geometry.disk import load_disk_params, make_disk_layout

    # the inputs checked before MPI starts: a bad one is one line on stderr, with nothing
    # before it (OpenMPI's start-up may print its own warnings, e.g. where /sys is absent)
    gp = load_geometry_params(args.damper, args.geometry, None, args.size)
    make_disk_layout(gp, load_disk_params(args.disk_file, n_blades=args.n_blades, bore=args.bore))

    from mpi4py import MPI

    from ..assembly.params import load_contact_params
    from ..errors import run_on_root
    from ..fe.cyclic import assemble_sector, fan
    from ..fe.cyclic_cb import cb_models, save_reduced
    from ..geometry.disk_build import build_disk_sector
    from ..log import stage

    comm = MPI.COMM_WORLD
    out = ctx.out_dir("results/disk")
    kw = dict(
        geometry_file=args.geometry,
        disk_file=args.disk_file,
        n_blades=args.n_blades,
        bore=args.bore,
        size_mm=args.size,
    )
    with stage(ctx.timings, "geometry"):
        import dolfinx  # noqa: F401 - collective PETSc initialisation before rank 0 builds

        rec = run_on_root(comm, lambda: build_disk_sector(args.damper, out, **kw), "disk build")
        if comm.rank != 0:
            from ..geometry.disk_build import DiskSector

            rec = DiskSector.load(out / "disk.h5")
    cp = load_contact_params(args.contact_file, geometry_file=args.geometry)
    part = comm if comm.size > 1 else None
    result: dict[str, Any] = {}
    with stage(ctx.timings, "modes_free"):
        bare = assemble_sector(rec, cp, with_damper=False)
        result["free"] = fan(bare, args.families, part)
    models = {}
    if args.cb_modes > 0:
        with stage(ctx.timings, "craig_bampton"):
            models = cb_models(bare, args.cb_modes, part)
    with stage(ctx.timings, "modes_stuck"):
        result["stuck"] = fan(assemble_sector(rec, cp, with_damper=True), args.families, part)
    summary: dict[str, Any] = {
        "out": str(out),
        "damper": rec.damper,
        "n_blades": rec.n_blades,
        "bore": rec.bore,
        "sector_angle_deg": rec.stats["sector_angle_deg"],
        "r_root_m": rec.stats["r_root_m"],
        "sector_n_nodes": rec.stats["sector_n_nodes"],
        "damper_n_nodes": rec.stats["damper_n_nodes"],
        "n_contact_pairs": rec.stats["n_contact_pairs"],
        "ranks": comm.size,
        "fan_hz_stuck": result["stuck"].round(3).tolist(),
        "fan_hz_free": result["free"].round(3).tolist(),
    }
    if (args.frf or args.backbone) and comm.rank == 0:
        from .disk_frf import sector_backbone_run, sector_frf, sector_model

        model = sector_model(args, ctx, rec, cp)
        if args.frf:
            summary["sector"] = sector_frf(args, ctx, rec, model)
        if args.backbone:
            summary["sector_backbone"] = sector_backbone_run(args, ctx, model)
    if comm.rank == 0:

        def write(folder):
            import csv

            from ..render.disk_figures import plot_fan

            png = plot_fan(
                result["stuck"], result["free"], rec.n_blades, rec.damper, folder / "fan.png"
            )
            with open(folder / "fan.csv", "w", newline="") as fh:
                w = csv.writer(fh)
                fams = range(result["stuck"].shape[1])
                w.writerow(
                    ["nodal_diameter"]
                    + [f"stuck_family_{j + 1}_hz" for j in fams]
                    + [f"free_family_{j + 1}_hz" for j in fams]
                )
                for k in range(result["stuck"].shape[0]):
                    w.writerow([k, *result["stuck"][k], *result["free"][k]])
            files = {"fan_png": str(png), "fan_csv": str(folder / "fan.csv")}
            if args.cb_modes > 0:
                files["cyclic_cb_h5"] = str(save_reduced(models, bare, folder / "cyclic_cb.h5"))
            return files

        summary["files"] = ctx.write(write)
    return ctx.note_rescue(summary)
