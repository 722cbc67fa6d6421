"""``upd reduce``: Craig-Bampton (or rigid) reduced models of the rig and the damper."""

from __future__ import annotations

import argparse

from .main import Context, add_geometry_options
from .values import Value, add_value

HELP = "Craig-Bampton reduced models of the rig and the damper (HDF5, cached)"
DESCRIPTION = """\
Mesh the rig and a damper (cached), then reduce each body onto its interface
nodes (every contact node; for the rig also the excitation and response
points) with --modes fixed-interface modes (Craig-Bampton, SLEPc + MUMPS).
The damper is free-free (the interface holds it during the reduction) or,
with --rigid-damper, a rigid body with 6 DOFs (mass and inertia from its
mesh).

Writes rig.h5 and damper.h5 in --out (ReducedModel: matrices, interface
nodes, contact frames, inputs and code version) and keeps digest-named
copies under --out/cache: a second run with unchanged inputs reuses them.
The summary also lists the stuck frequencies of the coupled reduced model
(contact springs from geometry/contact.toml) as a check.

Example:
  upd reduce --damper cone --modes 12 --out results/reduced_cone --json
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--damper", required=True, metavar="{cone,cylinder,wedge}", help="damper shape"
    )
    add_value(
        parser,
        "--modes",
        Value("int", 0, 500),
        "fixed-interface modes per body (12 as in the paper)",
        metavar="M",
        default=12,
    )
    parser.add_argument(
        "--rigid-damper",
        action="store_true",
        help="a rigid 6-DOF damper instead of its Craig-Bampton model",
    )
    add_geometry_options(
        parser, "contact parameters of the stuck check (default geometry/contact.toml)"
    )
    parser.add_argument("--force", action="store_true", help="rebuild even if cached")


def run(args: argparse.Namespace, ctx: Context) -> dict:
    import numpy as np
    import scipy.linalg as sl

    from ..assembly.params import load_contact_params
    from ..errors import check_int
    from ..geometry import build_geometry
    from ..io import write_json
    from ..log import mpi_rank, stage

    n_modes = check_int("modes", args.modes, 0, 500)
    params = load_contact_params(args.contact_file, geometry_file=args.geometry)
    out = ctx.out_dir(f"results/reduced_{args.damper}")
    with stage(ctx.timings, "geometry"):
        geom = build_geometry(
            args.damper, out / "geometry", geometry_file=args.geometry, size_mm=args.size
        )
    from ..fe.coupling import stuck_reduced_system
    from ..fe.modes import classify_bending
    from ..fe.reduce import cached_model, reduce_body, save_model

    bodies = {}
    summary: dict = {
        "out": str(out),
        "damper": geom.damper,
        "geometry_digest": geom.digest,
        "bodies": {},
    }
    for name, rigid in (("rig", False), ("damper", bool(args.rigid_damper))):
        cached = cached_model(geom, name, n_modes=n_modes, rigid=rigid, cache_dir=out / "cache")
        t: dict[str, float] = {}
        with stage(ctx.timings, f"reduce {name}"):
            rm = reduce_body(
                geom,
                name,
                n_modes=n_modes,
                rigid=rigid,
                cache_dir=out / "cache",
                force=args.force,
                timings=t,
            )
        path = out / f"{name}.h5"
        if mpi_rank() == 0:
            save_model(rm, path, geom.contact)
        bodies[name] = rm
        summary["bodies"][name] = {
            "kind": rm.kind,
            "n_reduced": rm.n,
            "n_full_dofs": rm.n_full_dofs,
            "n_interface_nodes": rm.n_nodes,
            "fixed_interface_modes_hz": [round(float(f), 1) for f in rm.mode_freqs_hz],
            "reused": bool(cached is not None and not args.force),
            "digest": rm.digest,
            "file": str(path),
            "timings_s": rm.timings,
        }
    with stage(ctx.timings, "stuck check"):
        rig, dmp = bodies["rig"], bodies["damper"]
        K, M = stuck_reduced_system(rig, dmp, geom.contact, params)
        k = min(10, K.shape[0])
        lam, V = sl.eigh(K, M, subset_by_index=[0, k - 1])
        resp = (rig.T[rig.node_dofs(rig.node_sets["response"])] @ V[: rig.n]).T.reshape(-1, 2, 3)
        labels, i_in, i_out = classify_bending(resp)
        freqs = np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi)
    summary["stuck_reduced"] = {
        "freqs_hz": [round(float(f), 2) for f in freqs],
        "first_bending_in_phase_hz": None if i_in is None else round(float(freqs[i_in]), 2),
        "first_bending_out_of_phase_hz": None if i_out is None else round(float(freqs[i_out]), 2),
    }
    summary["timings_s"] = {k: round(v, 3) for k, v in ctx.timings.items()}
    if mpi_rank() == 0:
        write_json(out / "reduce.json", summary)
    return summary
