"""``upd analytic``: closed-form cone damper kinematics with an exact 3-D cross-check."""

from __future__ import annotations

import argparse
from typing import Any

from .main import Context, num
from .values import Value, add_value

HELP = "cone damper kinematics: inclination and kinematic slip (paper eqs 1-6) + exact 3-D check"
DESCRIPTION = """\
Design-stage kinematics of a conical under-platform damper, without finite
elements. For the given platform angle, cone angle, small radius and length
it prints the inclination gamma of the damper axis, the section angle
alpha_1 and the largest kinematic slip ratio s_max/v under in-phase (radial)
relative motion v of the platforms. The slip ratio comes from the paper's
closed form (eqs 1-6 of "On the efficiency of a conical under-platform damper
for turbines") and from an exact 3-D rigid-body solution: a cone tangent to
both platform planes, with its middle section rolling. The 3-D slip is
split into a transverse part (the one eq. 6 estimates) and a longitudinal
part along the contact lines.

With --out DIR it also writes PNG + CSV charts: inclination vs cone angle
(paper Fig. 3), slip along the damper (Fig. 5), largest slip vs cone angle
for the platform angle, R1 and L families (Fig. 6), paper vs 3-D over all
cone angles, and the 3-D slip at every contact point.

Example:
  upd analytic --beta 45 --cone-angle 10 --r1 10 --length 40 --json
  upd analytic --out results/analytic
"""


def add_arguments(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("damper and groove")
    g.add_argument(
        "--beta",
        type=num,
        default=45.0,
        metavar="DEG",
        help="platform angle between each contact plane and the radial direction, "
        "deg, 0 < beta < 90 (default 45)",
    )
    g.add_argument(
        "--cone-angle",
        type=num,
        default=10.0,
        metavar="DEG",
        help="cone semi-angle alpha_c, deg, 0 <= alpha_c < beta; 0 is a cylinder (default 10)",
    )
    g.add_argument(
        "--r1",
        type=num,
        default=10.0,
        metavar="MM",
        help="small-end radius R1, mm, > 0 (default 10)",
    )
    g.add_argument(
        "--length",
        type=num,
        default=40.0,
        metavar="MM",
        help="damper length L along its axis, mm, > 0 (default 40); R2 = R1 + L tan(alpha_c)",
    )
    g = p.add_argument_group("charts (with --out)")
    add_value(
        g,
        "--points",
        Value("int", 3, 10_000, name="points"),
        "contact points per line for the 3-D slip table (23 as the paper)",
        metavar="N",
        default=23,
    )
    add_value(
        g,
        "--step",
        Value("float", 0.01, 5.0, unit="deg", name="step"),
        "cone-angle step of the sweeps",
        metavar="DEG",
        default=0.25,
    )


def run(args: argparse.Namespace, ctx: Context) -> dict[str, Any]:
    from ..analytic import ConeDesign, paper_kinematics, rigid_body_kinematics
    from ..analytic.charts import best_cone_angle, comparison_table
    from ..errors import check_int, check_range
    from ..log import stage

    design = ConeDesign(
        beta_deg=args.beta, cone_angle_deg=args.cone_angle, r1_mm=args.r1, length_mm=args.length
    )
    n_points = check_int("points", args.points, 3, 10_000)
    step = check_range("step", args.step, 0.01, 5.0, unit="deg")
    out = ctx.out_dir("results/analytic") if ctx.out is not None else None  # before any work
    with stage(ctx.timings, "kinematics"):
        pk = paper_kinematics(design)
        rk = rigid_body_kinematics(design, n_points=n_points)
        cmp = comparison_table(design, step)
    best_paper = best_cone_angle(cmp, "max_slip_ratio_paper")
    best_trans = best_cone_angle(cmp, "max_transverse_slip_ratio_3d")
    summary: dict[str, Any] = {
        "inputs": {
            "beta_deg": design.beta_deg,
            "cone_angle_deg": design.cone_angle_deg,
            "r1_mm": design.r1_mm,
            "length_mm": design.length_mm,
        },
        "gamma_deg": pk.gamma_deg,
        "alpha1_deg": pk.alpha1_deg,
        "r2_mm": pk.r2_mm,
        "rm_mm": pk.rm_mm,
        "max_slip_ratio": pk.max_slip_ratio,
        "max_slip_ratio_3d": rk.max_slip_ratio,
        "max_transverse_slip_ratio_3d": rk.max_transverse_slip_ratio,
        "max_longitudinal_slip_ratio_3d": rk.max_longitudinal_slip_ratio,
        "transverse_3d_over_paper": (
            rk.max_transverse_slip_ratio / pk.max_slip_ratio if pk.max_slip_ratio > 0 else None
        ),
        "best_cone_angle_deg": best_paper[0],
        "best_max_slip_ratio": best_paper[1],
        "best_cone_angle_3d_transverse_deg": best_trans[0],
        "best_max_transverse_slip_ratio_3d": best_trans[1],
        "notes": "slip ratios per unit relative radial platform displacement v; "
        "max_slip_ratio is paper eq. 6 (transverse); *_3d from the exact rigid-body "
        "solution with the middle section rolling; longitudinal slip shared equally by "
        "the two contact lines; best_* maximise over cone angles at this beta, R1, L",
    }
    if out is not None:
        from ..io import write_json
        from ..render.analytic_plots import write_analytic_figures

        with stage(ctx.timings, "figures"):
            files = write_analytic_figures(design, out, step_deg=step, n_points=n_points)
        files.append(write_json(out / "summary.json", summary))
        summary["files"] = [str(f) for f in files]
    summary["timings_s"] = {k: round(v, 3) for k, v in ctx.timings.items()}
    return summary
