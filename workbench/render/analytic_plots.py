"""Figures of the analytic cone kinematics (matplotlib, Agg).

Each ``plot_*`` function draws one :class:`~workbench.analytic.charts.Table`
and writes a PNG; :func:`write_analytic_figures` computes every table for a
design and writes each as PNG + CSV with the same stem. Colours name the
cases (the paper's families and, in black, the design being studied); line
styles name the method (solid: paper eq 6, dashed/dotted: exact 3-D).
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from ..analytic.charts import (
    PAPER_BETAS_DEG,
    PAPER_CONE_ANGLES_DEG,
    PAPER_LENGTHS_MM,
    PAPER_R1S_MM,
    Table,
    best_cone_angle,
    comparison_table,
    contact_slip_table,
    inclination_table,
    max_slip_table,
    slip_along_table,
)
from ..analytic.cone import ConeDesign
from .common import pyplot, save_figure, styled

log = logging.getLogger(__name__)

DESIGN_COLOR = "black"
PAPER_STYLE, EXACT_STYLE, EXTRA_STYLE = "-", "--", ":"


def _colors(values: list[float], paper_values: tuple[float, ...]) -> dict[float, str]:
    """C0, C1, C2 for the paper's cases (in order); black for an extra (the design's) value."""
    out, i = {}, 0
    for v in values:
        if any(np.isclose(v, p) for p in paper_values):
            out[v] = f"C{i}"
            i += 1
        else:
            out[v] = DESIGN_COLOR
    return out


def _design_note(design: ConeDesign) -> str:
    return (
        f"design: beta = {design.beta_deg:g} deg, alpha_c = {design.cone_angle_deg:g} deg, "
        f"R1 = {design.r1_mm:g} mm, L = {design.length_mm:g} mm"
    )


def _styles(ax, styles: list[tuple[str, str]], loc: str = "upper right") -> None:
    """A second legend saying what the line styles mean (the first one names the cases)."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], color="0.3", ls=ls, label=label) for ls, label in styles]
    first = ax.get_legend()
    ax.legend(handles=handles, loc=loc, frameon=True)
    if first is not None:
        ax.add_artist(first)


@styled
def plot_inclination(table: Table, design: ConeDesign, path: str | Path) -> Path:
    """Damper inclination gamma vs cone angle, one curve per platform angle (paper Fig. 3)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.6), layout="constrained")
    betas = sorted(set(table["beta_deg"].tolist()))
    colors = _colors(betas, PAPER_BETAS_DEG)
    for b in betas:
        t = table.where(beta_deg=b)
        label = f"beta = {b:g} deg" + (" (design)" if colors[b] == DESIGN_COLOR else "")
        ax.plot(t["cone_angle_deg"], t["gamma_deg"], color=colors[b], lw=1.8, label=label)
        ax.axvline(b, color=colors[b], lw=0.6, ls=":", alpha=0.7)
    g = float(
        np.degrees(
            np.arcsin(
                np.sin(np.radians(design.cone_angle_deg)) / np.sin(np.radians(design.beta_deg))
            )
        )
    )
    ax.plot(
        [design.cone_angle_deg],
        [g],
        "o",
        ms=7,
        mfc="white",
        mec=DESIGN_COLOR,
        mew=1.5,
        label=f"design: gamma = {g:.2f} deg",
    )
    ax.set(
        xlabel="cone semi-angle alpha_c (deg)",
        ylabel="damper inclination gamma (deg)",
        xlim=(0, max(betas) * 1.02),
        ylim=(0, 92),
        title="Damper axis inclination vs cone angle\n"
        "sin(gamma) = sin(alpha_c)/sin(beta); dotted: alpha_c = beta (vertical)",
    )
    ax.set_yticks(np.arange(0, 91, 15))
    ax.legend(loc="upper left")
    return save_figure(fig, path)


@styled
def plot_slip_along(table: Table, design: ConeDesign, path: str | Path) -> Path:
    """Slip along the damper for several cone angles (paper Fig. 5) and its exact 3-D value."""
    plt = pyplot()
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11.5, 4.6), sharey=True, layout="constrained")
    angles = sorted(set(table["cone_angle_deg"].tolist()))
    colors = _colors(angles, PAPER_CONE_ANGLES_DEG)
    for ac in angles:
        t = table.where(cone_angle_deg=ac, side=0)
        c = colors[ac]
        lab = f"alpha_c = {ac:g} deg" + (" (design)" if c == DESIGN_COLOR else "")
        a1.plot(t["position_mm"], np.abs(t["slip_ratio_paper"]), color=c, lw=1.8, label=lab)
        a2.plot(
            t["position_mm"],
            np.abs(t["transverse_slip_ratio_3d"]),
            color=c,
            lw=1.8,
            ls=PAPER_STYLE,
            label=lab,
        )
        a2.plot(t["position_mm"], t["slip_ratio_3d"], color=c, lw=1.4, ls=EXACT_STYLE)
    a1.set(
        title="(a) paper eq. 6: |s|/v", ylabel="kinematic slip / relative radial motion |s|/v (-)"
    )
    a2.set(title="(b) exact 3-D rigid body (either contact line)")
    top = 1.4 * max(np.abs(table["slip_ratio_paper"]).max(), table["slip_ratio_3d"].max())
    for ax in (a1, a2):
        ax.set(
            xlabel="position along the axis from the small end (mm)",
            xlim=(0, design.length_mm),
            ylim=(0, top),
        )
        ax.legend(loc="upper left")
    _styles(
        a2,
        [("-", "transverse |s_t2|/v"), ("--", "total |s|/v (with longitudinal)")],
        loc="upper right",
    )
    fig.suptitle(f"Kinematic slip along the damper\n{_design_note(design)}", fontsize=10)
    return save_figure(fig, path)


@styled
def plot_max_slip(table: Table, design: ConeDesign, path: str | Path) -> Path:
    """Largest slip vs cone angle varying beta, R1 and L (paper Fig. 6 a-c), paper and 3-D."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(15.5, 4.8), layout="constrained")
    specs = (
        ("beta", "beta_deg", "beta = {:g} deg", PAPER_BETAS_DEG, "(a) platform angle"),
        ("r1", "r1_mm", "R1 = {:g} mm", PAPER_R1S_MM, "(b) small radius"),
        ("length", "length_mm", "L = {:g} mm", PAPER_LENGTHS_MM, "(c) length"),
    )
    for ax, (family, key, fmt, paper_values, title) in zip(axes, specs, strict=True):
        fam = table.where(family=family)
        values = sorted(set(fam[key].tolist()))
        colors = _colors(values, paper_values)
        for v in values:
            t = fam.where(**{key: v})
            c = colors[v]
            lab = fmt.format(v) + (" (design)" if c == DESIGN_COLOR else "")
            ax.plot(t["cone_angle_deg"], t["max_slip_ratio_paper"], color=c, lw=1.8, label=lab)
            ax.plot(
                t["cone_angle_deg"],
                t["max_transverse_slip_ratio_3d"],
                color=c,
                lw=1.2,
                ls=EXACT_STYLE,
            )
            i = int(np.argmax(t["max_slip_ratio_paper"]))
            ax.plot(t["cone_angle_deg"][i], t["max_slip_ratio_paper"][i], "^", color=c, ms=5)
        others = {
            "beta": f"R1 = {design.r1_mm:g} mm, L = {design.length_mm:g} mm",
            "r1": f"beta = {design.beta_deg:g} deg, L = {design.length_mm:g} mm",
            "length": f"beta = {design.beta_deg:g} deg, R1 = {design.r1_mm:g} mm",
        }[family]
        ax.set(
            title=f"{title}; {others}",
            xlabel="cone semi-angle alpha_c (deg)",
            ylabel="largest slip / relative radial motion s_max/v (-)",
        )
        ax.set_xlim(0, max(fam["beta_deg"]) * 1.02)
        ax.set_ylim(bottom=0)
        ax.legend(loc="upper left")
        _styles(ax, [(PAPER_STYLE, "paper eq. 6"), (EXACT_STYLE, "exact 3-D, transverse")])
    fig.suptitle(
        "Largest kinematic slip vs cone angle (triangles: maximum of eq. 6); "
        "the 3-D total with longitudinal slip is in paper_vs_3d.png",
        fontsize=10,
    )
    return save_figure(fig, path)


@styled
def plot_comparison(table: Table, design: ConeDesign, path: str | Path) -> Path:
    """Paper eq 6 against the exact 3-D slip over all cone angles: values, ratio, difference."""
    plt = pyplot()
    fig, (a1, a2, a3) = plt.subplots(1, 3, figsize=(15.5, 4.8), layout="constrained")
    ac = table["cone_angle_deg"]
    a1.plot(ac, table["max_slip_ratio_paper"], "C0", lw=2.0, label="paper eq. 6 (transverse)")
    a1.plot(
        ac,
        table["max_transverse_slip_ratio_3d"],
        "C1",
        lw=1.8,
        ls=EXACT_STYLE,
        label="exact 3-D: transverse",
    )
    a1.plot(
        ac,
        table["max_longitudinal_slip_ratio_3d"],
        "C2",
        lw=1.6,
        ls=EXTRA_STYLE,
        label="exact 3-D: longitudinal",
    )
    a1.plot(ac, table["max_slip_ratio_3d"], "C3", lw=1.8, ls="-.", label="exact 3-D: total")
    for col, c in (("max_slip_ratio_paper", "C0"), ("max_transverse_slip_ratio_3d", "C1")):
        x, y = best_cone_angle(table, col)
        a1.plot([x], [y], "^", color=c, ms=7)
        a1.annotate(
            f"{y:.3f} at {x:.1f} deg",
            (x, y),
            textcoords="offset points",
            xytext=(4, 6),
            fontsize=8,
            color=c,
        )
    a1.axvline(design.cone_angle_deg, color="0.4", lw=0.8, ls=":")
    a1.set(
        title="(a) largest slip along the damper",
        xlabel="cone semi-angle alpha_c (deg)",
        ylabel="slip / relative radial motion (-)",
    )
    a1.set_ylim(bottom=0)
    a1.legend(loc="upper left")

    a2.plot(
        ac,
        table["transverse_3d_over_paper"],
        "C1",
        lw=1.8,
        label="exact 3-D transverse / paper eq. 6",
    )
    a2.axhline(0.5, color="0.5", lw=0.8, ls=":", label="1/2 (cylinder limit)")
    a2.axvline(design.cone_angle_deg, color="0.4", lw=0.8, ls=":")
    a2.set(
        title="(b) ratio of the like-for-like (transverse) slips",
        xlabel="cone semi-angle alpha_c (deg)",
        ylabel="ratio (-)",
    )
    a2.set_ylim(bottom=0)
    a2.legend(loc="upper left")

    a3.plot(
        ac, table["difference_3d_minus_paper"], "C3", lw=1.8, label="exact 3-D total - paper eq. 6"
    )
    a3.plot(
        ac,
        table["max_transverse_slip_ratio_3d"] - table["max_slip_ratio_paper"],
        "C1",
        lw=1.5,
        ls=EXACT_STYLE,
        label="exact 3-D transverse - paper eq. 6",
    )
    a3.axhline(0.0, color="0.5", lw=0.8)
    a3.axvline(design.cone_angle_deg, color="0.4", lw=0.8, ls=":")
    a3.set(
        title="(c) difference",
        xlabel="cone semi-angle alpha_c (deg)",
        ylabel="difference in s_max/v (-)",
    )
    a3.legend(loc="lower left")
    for ax in (a1, a2, a3):
        ax.set_xlim(0, design.beta_deg)
    fig.suptitle(
        "Paper estimate vs exact 3-D rigid-body kinematics (relative radial motion v; "
        f"middle section rolling)\n{_design_note(design)}",
        fontsize=10,
    )
    return save_figure(fig, path)


@styled
def plot_contact_slip(table: Table, design: ConeDesign, path: str | Path) -> Path:
    """The cone in the groove with slip-coloured contact points and arrows; slip components."""
    from ..analytic.rigid import groove_geometry

    plt = pyplot()
    geo = groove_geometry(design)
    fig = plt.figure(figsize=(12.5, 5.4), layout="constrained")
    gs = fig.add_gridspec(1, 2, width_ratios=(1.15, 1.0))
    ax = fig.add_subplot(gs[0], projection="3d")
    # cone surface
    xi = np.linspace(0.0, design.length_mm, 24)
    th = np.linspace(0.0, 2 * np.pi, 48)
    e1 = np.array([1.0, 0.0, 0.0])
    e2 = np.cross(geo.axis, e1)
    c = geo.section_center(xi)
    r = geo.radius(xi)
    surf = c[:, None, :] + r[:, None, None] * (
        np.cos(th)[None, :, None] * e1 + np.sin(th)[None, :, None] * e2
    )
    ax.plot_surface(
        surf[..., 0],
        surf[..., 1],
        surf[..., 2],
        color="tab:blue",
        alpha=0.22,
        linewidth=0,
        shade=True,
    )
    ends = geo.section_center(np.array([-0.15, 1.15]) * design.length_mm)
    ax.plot(ends[:, 0], ends[:, 1], ends[:, 2], "k-.", lw=0.8)
    # platform planes: from the ridge (y axis) down a little past the contact lines
    y0, y1 = surf[..., 1].min() - 3, surf[..., 1].max() + 3
    s_max = 1.35 * float(np.max(-table["z_mm"])) / np.cos(np.radians(design.beta_deg))
    b = np.radians(design.beta_deg)
    for sgn in (-1.0, 1.0):
        s = np.array([0.0, s_max])
        X = np.outer(sgn * s * np.sin(b), [1, 1])
        Y = np.outer(np.ones(2), [y0, y1])
        Z = np.outer(-s * np.cos(b), [1, 1])
        ax.plot_surface(X, Y, Z, color="0.5", alpha=0.18, linewidth=0)
    ax.plot([0, 0], [y0, y1], [0, 0], color="0.3", lw=1.0)
    slip = table["slip_ratio"]
    sc = ax.scatter(
        table["x_mm"],
        table["y_mm"],
        table["z_mm"],
        c=slip,
        cmap="viridis",
        s=22,
        depthshade=False,
        vmin=0.0,
    )
    scale = 0.25 * design.length_mm / max(float(slip.max()), 1e-12)
    every = slice(None, None, 3)
    ax.quiver(
        table["x_mm"][every],
        table["y_mm"][every],
        table["z_mm"][every],
        scale * table["slip_x_ratio"][every],
        scale * table["slip_y_ratio"][every],
        scale * table["slip_z_ratio"][every],
        color="C3",
        lw=1.0,
        arrow_length_ratio=0.25,
    )
    ax.set(
        xlabel="x (mm)",
        ylabel="y (mm)",
        zlabel="z (mm)",
        title="damper in the groove: contact points coloured by |s|/v,\n"
        "red arrows: slip of the damper relative to the platform",
    )
    pts = np.concatenate([surf.reshape(-1, 3), table["x_mm"][:, None] * [1, 0, 0]])
    ax.set_box_aspect(np.ptp(pts, axis=0) + 6)
    ax.view_init(elev=20, azim=-28)
    fig.colorbar(sc, ax=ax, shrink=0.55, pad=0.02, location="left", label="|s|/v (-)")

    ax2 = fig.add_subplot(gs[1])
    for k, color, marker in ((0, "C0", "o"), (1, "C3", "")):
        t = table.where(side=k)
        ax2.plot(
            t["position_mm"],
            t["transverse_slip_ratio"],
            color=color,
            lw=1.8,
            marker=marker,
            ms=4,
            mfc="none",
            label=f"side {k}: transverse (t2)",
        )
        ax2.plot(
            t["position_mm"],
            t["longitudinal_slip_ratio"],
            color=color,
            lw=1.4,
            ls=EXACT_STYLE,
            marker=marker,
            ms=4,
            mfc="none",
            label=f"side {k}: longitudinal (t1)",
        )
    t = table.where(side=0)
    ax2.plot(
        t["position_mm"],
        t["slip_ratio_paper"],
        "k",
        lw=1.0,
        ls=EXTRA_STYLE,
        label="paper eq. 6 (signed)",
    )
    ax2.axhline(0.0, color="0.5", lw=0.8)
    ax2.set(
        xlabel="position along the axis from the small end (mm)",
        ylabel="slip / relative radial motion s/v (-)",
        title="exact 3-D slip in each pair frame (t1: large -> small end)",
        xlim=(0, design.length_mm),
    )
    ax2.legend(loc="best")
    fig.suptitle(
        f"Exact 3-D kinematics at the contact points ({design.length_mm:g} mm long, "
        f"{table.where(side=0)['position_mm'].size} points per line)\n"
        f"{_design_note(design)}",
        fontsize=10,
    )
    return save_figure(fig, path)


def write_analytic_figures(
    design: ConeDesign, out_dir: str | Path, step_deg: float = 0.25, n_points: int = 23
) -> list[Path]:
    """Compute every analytic chart of ``design`` and write each as PNG and CSV in ``out_dir``.

    ``step_deg`` is the cone-angle step of the sweeps; ``n_points`` the
    number of contact points per line in the 3-D picture. Returns the
    written paths.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    jobs = (
        (inclination_table(design, step_deg), plot_inclination),
        (slip_along_table(design), plot_slip_along),
        (max_slip_table(design, step_deg), plot_max_slip),
        (comparison_table(design, step_deg), plot_comparison),
        (contact_slip_table(design, n_points), plot_contact_slip),
    )
    written: list[Path] = []
    for table, plot in jobs:
        written.append(plot(table, design, out / f"{table.name}.png"))
        written.append(table.write_csv(out / f"{table.name}.csv"))
        log.info("wrote %s.png and .csv (%s)", table.name, table.title)
    return written
