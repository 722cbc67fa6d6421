"""Figures of a sweep study: resonance peaks against the swept option, the cone angle.

:func:`plot_sweep` draws peak amplitude and resonance frequency against
any swept study option (its label from the option's help text,
:func:`option_label`); :func:`plot_cone_angle_energy` the cone's friction
energy against its angle next to the kinematic slip of the rigid cone.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..post.results import CaseResult, family_name
from ..post.tables import sweep_curve, sweep_value
from .common import pyplot, save_figure, styled
from .palette import damper_style, force_colors, marker_kwargs
from .study_style import DAMPER_STYLE, FAMILY_STYLE, _dampers, _readable_log, _wants_log


def option_label(option: str) -> tuple[str, str]:
    """(description, unit) of a study option (a shared one or a registered kind's own) from
    its help text and unit, e.g. ("centrifugal force on the damper", "N"); ("option", "-")
    for an unknown one."""
    from ..study_options import find

    o = find(option)
    if o is None:
        return option, "-"
    text = o.help
    while "(" in text and ")" in text[text.index("(") :]:
        a = text.index("(")
        b = text.index(")", a)
        text = (text[:a] + text[b + 1 :]).replace("  ", " ")
    text = text.strip().rstrip(",")
    if ", " in text:
        name, unit = text.rsplit(", ", 1)
        if len(unit) <= 12:
            return name.strip(), unit.strip()
    return text, o.unit or "-"


def _axis_label(option: str) -> str:
    name, unit = option_label(option)
    return f"{name}, {option} ({unit})"


@styled
def plot_sweep(
    cases: Sequence[CaseResult], option: str, path: str | Path, *, title: str | None = None
) -> Path:
    """Peak amplitude (top) and resonance frequency (bottom) vs the swept option.

    One column per family; one curve per damper (its colour, style and
    marker), and per force when the sweep has several (labelled).
    Hollow markers: unstable peak; crosses: failed branches.
    """
    if not cases:
        raise InputError("cases", "[]", "the cases of a sweep")
    fams = sorted(
        {round(c.phase_deg, 9) for c in cases},
        key=lambda p: ({"in-phase": 0, "out-of-phase": 1}.get(family_name(p), 2), p),
    )
    forces = sorted({c.force_n for c in cases})
    plt = pyplot()
    fig, axes = plt.subplots(
        2,
        len(fams),
        figsize=(4.6 * len(fams) + 1.6, 6.4),
        sharex=True,
        layout="constrained",
        squeeze=False,
    )
    fstyles = ["-", "--", ":", "-."]
    for col, p in enumerate(fams):
        for d in _dampers(cases):
            color, ls, mk = damper_style(d)
            for kf, f in enumerate(forces):
                sel = [
                    c
                    for c in cases
                    if c.damper == d and abs(c.phase_deg - p) < 1e-9 and abs(c.force_n - f) < 1e-12
                ]
                if not sel:
                    continue
                sc = sweep_curve(sel, option)
                style = ls if len(forces) == 1 else fstyles[kf % len(fstyles)]
                lab = d if len(forces) == 1 else f"{d}, F = {f:g} N"
                if sc.failed.any():
                    lab += " (failed)"
                for row, y in ((0, sc.amp_mm), (1, sc.freq_hz)):
                    ax = axes[row, col]
                    ax.plot(
                        sc.value,
                        y,
                        color=color,
                        ls=style,
                        marker=mk,
                        ms=6,
                        lw=1.7,
                        label=lab if (row == 0 and col == 0) else None,
                    )
                    codes = sc.verdict if sc.verdict is not None else sc.stable.astype(int)
                    for k in np.flatnonzero(codes != 1):  # hollow: unstable, half: unknown
                        ax.plot(sc.value[k], y[k], **marker_kwargs(int(codes[k]), color, mk))
                    ax.plot(sc.value[sc.failed], y[sc.failed], "x", color=color, ms=10, mew=2)
        axes[0, col].set_title(
            family_name(p) + (f", F = {forces[0]:g} N" if len(forces) == 1 else "")
        )
        axes[1, col].set_xlabel(_axis_label(option))
    axes[0, 0].set_ylabel("vibration amplitude at\nresonance, harmonic 1 (mm)")
    axes[1, 0].set_ylabel("resonance frequency (Hz)")
    for col, p in enumerate(fams):
        amps = [
            c.h1_mm[c.h1_peak_index]
            for c in cases
            if c.h1_peak_index >= 0 and abs(c.phase_deg - p) < 1e-9
        ]
        if _wants_log(amps, 30.0):
            axes[0, col].set_yscale("log")
            _readable_log(axes[0, col], "y")
    values = [sweep_value(c, option) for c in cases]
    if _wants_log(values, 20.0):  # e.g. a load sweep over decades: log x spreads the low end
        axes[1, 0].set_xscale("log")  # shared x: every panel follows
        _readable_log(axes[1, 0], "x")
    fig.legend(loc="outside right center", title="damper")
    name, _ = option_label(option)
    fig.suptitle(title or f"Sweep of {name}: resonance peaks")
    return save_figure(fig, path)


@styled
def plot_cone_angle_energy(
    cases: Sequence[CaseResult],
    path: str | Path,
    *,
    beta_deg: float,
    r1_mm: float,
    length_mm: float,
    option: str = "cone-angle",
    title: str | None = None,
) -> Path:
    """Friction energy at resonance vs cone angle (top) next to the kinematic slip (bottom).

    Top: the cone's friction energy per cycle at resonance (mJ, log), one
    curve per family (line style) and force (colour). Bottom: the largest
    kinematic slip per unit relative radial platform motion for in-phase
    motion: the paper's eq. 6 (:func:`workbench.analytic.max_slip_ratio`)
    and the exact 3-D rigid-body values (:func:`workbench.analytic.sweep_cone_angle`),
    for the platform angle ``beta_deg``, small radius ``r1_mm`` and length
    ``length_mm`` of the cone.
    """
    from ..analytic import max_slip_ratio, sweep_cone_angle

    cones = [c for c in cases if c.damper.startswith("cone")]
    if not cones:
        raise InputError("cases", [c.damper for c in cases], "cone cases of a cone-angle sweep")
    values = np.array([sweep_value(c, option) for c in cones])
    hi = min(0.995 * beta_deg, max(float(values.max()) * 1.15, float(values.max()) + 2.0))
    grid = np.linspace(0.0, hi, 161)
    plt = pyplot()
    fig, (a1, a2) = plt.subplots(
        2, 1, figsize=(7.2, 6.6), sharex=True, layout="constrained", height_ratios=(1.3, 1.0)
    )
    forces = sorted({c.force_n for c in cones})
    colors = force_colors(forces)
    fams = sorted(
        {round(c.phase_deg, 9) for c in cones},
        key=lambda p: ({"in-phase": 0, "out-of-phase": 1}.get(family_name(p), 2), p),
    )
    for p in fams:
        fam = family_name(p)
        for f in forces:
            sel = [c for c in cones if abs(c.phase_deg - p) < 1e-9 and abs(c.force_n - f) < 1e-12]
            if not sel:
                continue
            sc = sweep_curve(sel, option)
            ok = np.isfinite(sc.energy_mj) & (sc.energy_mj > 0)
            a1.plot(
                sc.value[ok],
                sc.energy_mj[ok],
                color=colors[f],
                ls=FAMILY_STYLE.get(fam, ":"),
                marker="o",
                ms=5,
                lw=1.7,
                label=f"{fam}, F = {f:g} N" + (" (failed)" if sc.failed.any() else ""),
            )
            a1.plot(
                sc.value[ok & sc.failed],
                sc.energy_mj[ok & sc.failed],
                "x",
                color=colors[f],
                ms=10,
                mew=2,
            )
    energies = [c.energy_mj[c.h1_peak_index].sum() for c in cones if c.h1_peak_index >= 0]
    if _wants_log(energies, 30.0):
        a1.set_yscale("log")
        _readable_log(a1, "y")
    a1.set(
        ylabel="friction energy per cycle\nat resonance (mJ)",
        title=title or "Cone: friction energy at resonance and kinematic slip vs cone angle",
    )
    a1.legend(loc="best", fontsize=8)
    eq6 = max_slip_ratio(grid, beta_deg, r1_mm, length_mm)
    exact = sweep_cone_angle(grid, beta_deg, r1_mm, length_mm)
    a2.plot(grid, eq6, color="k", lw=1.8, label="paper eq. 6 (middle section rolls)")
    a2.plot(
        grid,
        exact["max_transverse_slip_ratio"],
        color="0.35",
        lw=1.5,
        ls="--",
        label="exact 3-D rigid body, transverse",
    )
    a2.plot(
        grid,
        exact["max_slip_ratio"],
        color="0.35",
        lw=1.5,
        ls=":",
        label="exact 3-D rigid body, total",
    )
    for v in np.unique(values):
        a2.axvline(v, color=DAMPER_STYLE["cone"][0], lw=0.8, alpha=0.35)
    a2.set(
        xlabel="cone semi-angle alpha_c (deg)",
        ylabel="largest kinematic slip\nper radial motion s/v (-)",
        ylim=(0, None),
    )
    a2.text(
        0.99,
        0.04,
        f"in-phase motion; beta = {beta_deg:g} deg, R1 = {r1_mm:g} mm, "
        f"L = {length_mm:g} mm; blue lines: swept angles",
        transform=a2.transAxes,
        ha="right",
        va="bottom",
        fontsize=7.5,
        color="0.3",
    )
    a2.legend(loc="upper right", fontsize=8)
    return save_figure(fig, path)
