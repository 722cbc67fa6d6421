"""``upd mesh``: gmsh meshes of the rig and one damper with matched contact nodes."""

from __future__ import annotations

import argparse

from .main import Context, add_geometry_options

HELP = "mesh the rig and a damper (second-order gmsh) with node-to-node contact points"
DESCRIPTION = """\
Build the blade rig (base, two blades with platforms) and one damper seated in
the groove between the platforms, mesh both with second-order tetrahedra and
write them (rig.msh, damper.msh, XDMF, geometry.h5) with a PNG of the scene.
Every contact point is a mesh node of both the platform and the damper.

Parameters come from geometry/rig.toml and geometry/<damper>.toml; --geometry
FILE overrides any of their tables ([rig...], [cone], [cylinder], [wedge]).
A second run with the same inputs reuses the meshes in --out.

Example:
  upd mesh --damper cone --out results/mesh_cone
  upd mesh --damper wedge --size 4 --geometry my_rig.toml --out results/w --json
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from ..geometry.shapes import names

    parser.add_argument(
        "--damper", required=True, metavar="{" + ",".join(names()) + "}", help="damper shape"
    )
    add_geometry_options(parser)
    parser.add_argument(
        "--no-png", action="store_true", help="skip the picture (faster; the meshes are the same)"
    )


def run(args: argparse.Namespace, ctx: Context) -> dict:
    from ..geometry import build_geometry
    from ..log import mpi_rank, stage

    out = ctx.out_dir(f"results/mesh_{args.damper}")
    h5 = out / "geometry.h5"
    before = h5.stat().st_mtime_ns if h5.is_file() else None
    with stage(ctx.timings, "geometry"):
        geo = build_geometry(args.damper, out, geometry_file=args.geometry, size_mm=args.size)
    reused = before is not None and h5.stat().st_mtime_ns == before
    png = None
    if not args.no_png and mpi_rank() == 0:
        png = out / "scene.png"
        fresh = reused and png.is_file() and png.stat().st_mtime_ns >= h5.stat().st_mtime_ns
        if not fresh:
            from ..render.scene import render_scene

            with stage(ctx.timings, "png"):
                render_scene(geo, png)
    s = geo.stats
    keys = (
        "n_nodes",
        "n_cells",
        "rig_n_nodes",
        "rig_n_cells",
        "damper_n_nodes",
        "damper_n_cells",
        "n_contact_pairs",
        "max_pair_gap_m",
        "max_point_offset_m",
    )
    summary = {"out": str(out), "damper": geo.damper, **{k: s[k] for k in keys}}
    summary.update(
        damper_volume_m3=geo.damper_volume_m3,
        damper_volume_exact_m3=s["damper_volume_exact_m3"],
        damper_mass_kg=geo.damper_mass_kg,
        contact_kind=geo.contact.kind,
        size_mm=s["size_mm"],
        contact_size_mm=s["contact_size_mm"],
        damper_size_mm=s["damper_size_mm"],
        digest=geo.digest,
        reused=reused,
        files={
            "rig_msh": str(geo.rig_msh),
            "damper_msh": str(geo.damper_msh),
            "rig_xdmf": str(out / "rig.xdmf"),
            "damper_xdmf": str(out / "damper.xdmf"),
            "record": str(h5),
            "png": str(png) if png else None,
        },
        timings_s={k: round(v, 3) for k, v in ctx.timings.items()},
    )
    if "gamma_deg" in s:
        summary["cone_tilt_gamma_deg"] = s["gamma_deg"]
    return summary
