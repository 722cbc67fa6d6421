"""The report sections of a sweep study: peaks against the swept value, the receptances.

Peak amplitude and resonance frequency against the swept option with
their table, the design-rule screen against the harmonic balance, for a
cone-angle sweep the friction energy next to the analytic kinematic slip,
and the receptances of each damper, family and force with one curve per
swept value. Called by :func:`workbench.render.sections.build_sections`.
"""

from __future__ import annotations

from pathlib import Path

from ..post.results import StudyResults, family_name
from ..post.tables import Table, families, slug, sweep_curves, sweep_table
from . import study_figures as sf
from .palette import verdict_caption, verdict_counts
from .section_builder import _Builder, _failures, _fam_slug, _forces_text
from .sweep_figures import option_label, plot_cone_angle_energy, plot_sweep


def _cone_design(results: StudyResults, geometry_dirs: dict[str, Path]) -> tuple[float, ...]:
    """(beta deg, R1 mm, L mm) of the cone: its geometry folder, else the geometry files."""
    gdir = geometry_dirs.get("cone")
    if gdir is not None and (Path(gdir) / "geometry.h5").is_file():
        from ..geometry.records import BuiltGeometry

        prm = BuiltGeometry.load(Path(gdir) / "geometry.h5").params
        return (
            float(prm["rig"]["platform"]["angle_deg"]),
            float(prm["cone"]["r1_mm"]),
            float(prm["cone"]["length_mm"]),
        )
    from ..geometry.params import load_geometry_params

    gp = load_geometry_params("cone", results.inputs.get("geometry") or None)
    return gp.rig.platform.angle_deg, gp.shape.r1_mm, gp.shape.length_mm


def _sweep(b: _Builder, option: str, geometry_dirs: dict[str, Path]) -> None:
    r = b.results
    name, unit = option_label(option)
    curves = sweep_curves(r, option)
    values = sorted({v for sc in curves for v in sc.value.tolist()})
    sec = b.section(
        f"sweep-{slug(option)}",
        f"Sweep of {name}",
        [
            f"Resonance of each damper and family as {name} ({option}) takes the "
            f"values {', '.join(f'{v:g}' for v in values)} {unit}".rstrip()
            + f"; forces {_forces_text(r.forces)}."
        ],
    )
    osl = slug(option)
    b.figure(
        sec,
        f"sweep_{osl}",
        f"Vibration amplitude at resonance, harmonic 1 (mm, top) and resonance frequency "
        f"(Hz, bottom) vs {name} ({unit}); one column per family, one curve per damper; "
        "hollow marker: unstable peak, half filled: unknown." + _failures(r.cases),
        lambda path: plot_sweep(r.cases, option, path),
    )
    b.table(
        sec,
        f"sweep_{osl}",
        sweep_table(curves),
        f"Sweep of {option}: resonance of every damper, family and force",
    )
    if option.replace("_", "-") == "cone-angle" and any(
        c.damper.startswith("cone") for c in r.cases
    ):
        beta, r1, length = _cone_design(r, geometry_dirs)
        cones = [c for c in r.cases if c.damper.startswith("cone")]
        b.figure(
            sec,
            f"sweep_{osl}_energy_slip",
            "Cone: friction energy per cycle at resonance (mJ) vs cone semi-angle (deg), "
            "above the largest kinematic slip per unit in-phase radial platform motion "
            f"from the paper's eq. 6 and the exact 3-D rigid-body kinematics (beta = "
            f"{beta:g} deg, R1 = {r1:g} mm, L = {length:g} mm)." + _failures(cones),
            lambda path: plot_cone_angle_energy(
                cones, path, beta_deg=beta, r1_mm=r1, length_mm=length, option=option
            ),
        )
    screen_rows = r.extras.get("screen") or []
    if screen_rows and len(r.forces) >= 2:
        from .screen_figures import design_rule_points, plot_design_rule

        pts = design_rule_points(r.cases, screen_rows)
        if pts:
            b.figure(
                sec,
                f"sweep_{osl}_design_rule",
                f"The design rule across the {name} sweep: nonlinear peak growth "
                f"A({pts[0]['f_top_n']:g} N)/A({pts[0]['f_ref_n']:g} N), A = max |x(t)|, "
                "(filled) and "
                "the coupling screen's prediction (open) against k2/k (left); friction "
                "energy per cycle at the largest force against k2/k (middle); the "
                "nonlinear growth against the screen's saturation force over the "
                "largest force (right, log). A case whose curve stopped before its peak "
                "is left out (no marker)." + _failures(r.cases),
                lambda path: plot_design_rule(pts, path),
            )
            b.table(
                sec,
                f"sweep_{osl}_design_rule",
                Table(
                    (
                        "damper",
                        "family",
                        option,
                        "k2/k",
                        "rig bound k2/k",
                        "levels off up to (N)",
                        "screen growth",
                        "nonlinear growth",
                        f"energy at {pts[0]['f_top_n']:g} N (mJ)",
                    ),
                    tuple(
                        (
                            p["damper"],
                            p["family"],
                            p["variant"].split("=", 1)[-1],
                            f"{p['k2_over_k']:.3f}",
                            "-" if p["bound_k2_over_k"] is None else f"{p['bound_k2_over_k']:.3f}",
                            "never" if p["f_cap_n"] is None else f"{p['f_cap_n']:.3g}",
                            "-" if p["growth"] is None else f"{p['growth']:.2f}",
                            "not reached" if p["growth_nl"] is None else f"{p['growth_nl']:.2f}",
                            "not reached" if p["energy_mj"] is None else f"{p['energy_mj']:.3g}",
                        )
                        for p in pts
                    ),
                ),
                f"The design rule across the {option} sweep: screen against harmonic balance",
            )
    rec = b.section(f"sweep-{slug(option)}-receptances", f"Receptances across the {name} sweep")
    for p in families(r):
        for d in r.dampers:
            for f in r.forces:
                own = r.select(damper=d, phase_deg=p, force_n=f)
                if not own:
                    continue
                b.figure(
                    rec,
                    f"sweep_{osl}_receptance_{_fam_slug(p)}_{slug(d)}_{f:g}N",
                    f"{d} damper, {family_name(p)}, F = {f:g} N: receptance, harmonic-1 "
                    f"amplitude / F (mm/N), for every value of {option}; "
                    f"{verdict_caption(_counts(own))}." + _failures(own),
                    lambda path, cs=own: sf.plot_sweep_receptances(cs, option, path),
                )


def _counts(cases) -> dict[int, int]:
    import numpy as np

    return verdict_counts(np.concatenate([c.branch.stability for c in cases]))
