"""Figures of a study in the manner of the conical-damper paper (matplotlib, Agg).

"On the efficiency of a conical under-platform damper for turbines" shows
its results as receptances with every force level (Figs 9-10), peak
amplitude against force (Fig. 11), friction energy per cycle at resonance
(Tables 1-2), the contact status of every pair against frequency (Fig. 12)
and the share of each status at resonance against force (Fig. 13). Each
``plot_*`` function here draws one of those from plain inputs (lists of
:class:`~workbench.post.results.CaseResult`), writes a PNG and returns its
path; the numbers come from :mod:`workbench.post.tables`.

One visual language for every figure of every study:

* a damper always has the same colour, line style and marker
  (:data:`DAMPER_STYLE`: cone blue solid, cylinder orange dashed, wedge
  gold dotted, as the paper's figures);
* a force level always has the same colour in the per-damper figures
  (dark purple for the lowest through orange for the highest);
* a contact status always has the same colour (:data:`STATUS_COLORS`:
  stuck dark grey, stick-slip orange, partial separation green, full
  separation blue), here and in the 3-D contact maps;
* a branch's unstable points (Hill) are dashed in the per-damper figures
  and highlighted with a grey band where damper line styles are in use;
  a branch that failed is drawn up to where it stopped, ended with a cross
  and labelled "failed".

Figures have a fixed size and resolution and carry no time stamp, so the
same inputs give the same pixels (the image regression test relies on it).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..post.results import CaseResult
from ..post.tables import peak_curve, sweep_value
from .common import pyplot, save_figure, styled
from .status_figures import plot_status_map, plot_status_shares, status_zoom
from .study_style import (
    _EXTRA_COLORS,
    DAMPER_STYLE,
    FAMILY_STYLE,
    FIGSIZE,
    STATUS_COLORS,
    UNSTABLE_BAND,
    _dampers,
    _draw_branch,
    _failed_suffix,
    _flabel,
    _mark_failure,
    _one_family,
    _one_set,
    _readable_log,
    _side_legends,
    _wants_log,
    damper_style,
    force_colors,
    status_legend_handles,
)
from .sweep_figures import option_label, plot_cone_angle_energy, plot_sweep

log = logging.getLogger(__name__)

# the styles, the status and the sweep figures live in study_style.py, status_figures.py and
# sweep_figures.py; every figure stays importable from here
__all__ = [
    "DAMPER_STYLE",
    "FAMILY_STYLE",
    "FIGSIZE",
    "STATUS_COLORS",
    "UNSTABLE_BAND",
    "_EXTRA_COLORS",
    "damper_style",
    "failure_notes",
    "force_colors",
    "option_label",
    "plot_cone_angle_energy",
    "plot_energy_vs_force",
    "plot_peak_vs_force",
    "plot_receptance_overlay",
    "plot_receptances",
    "plot_status_map",
    "plot_status_shares",
    "plot_sweep",
    "plot_sweep_receptances",
    "status_legend_handles",
    "status_zoom",
]


# ---- receptances (paper Figs 9-10) ------------------------------------------------------


@styled
def plot_receptances(
    cases: Sequence[CaseResult],
    path: str | Path,
    *,
    forces: Sequence[float] | None = None,
    title: str | None = None,
) -> Path:
    """Receptance vs frequency of one damper and one family, every force in one axes.

    Colour names the force (``forces``: the study's force list, so colours
    agree across figures); stable parts solid, unstable dashed; a failed
    branch ends with a cross. Log receptance axis when the peaks span more
    than a factor 20.
    """
    cases = _one_set(cases, "cases")
    colors = force_colors(forces if forces is not None else [c.force_n for c in cases])
    plt = pyplot()
    fig, ax = plt.subplots(figsize=FIGSIZE, layout="constrained")
    peaks, any_unstable = [], False
    for c in cases:
        x, y = c.freq_hz, c.receptance_mm_per_n
        col = colors.get(float(c.force_n), "k")
        if x.size:
            _draw_branch(
                ax,
                x,
                y,
                c.stable,
                unknown=c.branch.unknown,
                color=col,
                label=_flabel(c.force_n) + _failed_suffix(c),
            )
            _mark_failure(ax, c, x, y, col)
            peaks.append(float(np.nanmax(y)))
            any_unstable |= bool(np.any(c.branch.unstable))
        else:
            ax.plot([], [], color=col, label=_flabel(c.force_n) + " (no point)")
    if _wants_log(peaks):
        ax.set_yscale("log")
        _readable_log(ax, "y")
    ax.set(
        xlabel="frequency (Hz)",
        ylabel="receptance |x| / F (mm/N)",
        title=title or f"{cases[0].damper} damper, {cases[0].family}: receptances",
    )
    entries = [("stable", dict(color="0.3", ls="-"))]
    if any_unstable:
        entries.append(("unstable (Hill)", dict(color="0.3", ls="--")))
    if any(c.branch.failed for c in cases):
        entries.append(("branch failed here", dict(color="0.3", ls="none", marker="x", mew=2)))
    _side_legends(fig, (ax.get_legend_handles_labels()[0], "excitation"), (entries, "branch"))
    return save_figure(fig, path)


@styled
def plot_receptance_overlay(
    cases: Sequence[CaseResult], path: str | Path, *, title: str | None = None
) -> Path:
    """Every damper's receptances of one family in one axes (the paper's Fig. 9 manner).

    Each damper has its own colour and line style (cone solid, cylinder
    dashed, wedge dotted); all its forces share them. Unstable parts lie on
    a grey band; a failed branch ends with a cross.
    """
    cases = _one_family(cases, "cases")
    plt = pyplot()
    fig, ax = plt.subplots(figsize=FIGSIZE, layout="constrained")
    peaks, any_unstable = [], False
    for d in _dampers(cases):
        col, ls, _ = damper_style(d)
        own = sorted((c for c in cases if c.damper == d), key=lambda c: c.force_n)
        failed = any(c.branch.failed for c in own)
        first = True
        for c in own:
            x, y = c.freq_hz, c.receptance_mm_per_n
            if not x.size:
                continue
            _draw_branch(
                ax,
                x,
                y,
                c.stable,
                unknown=c.branch.unknown,
                color=col,
                ls_stable=ls,
                band=True,
                lw=1.4,
                label=(d + (" (failed)" if failed else "")) if first else None,
            )
            _mark_failure(ax, c, x, y, col)
            first = False
            peaks.append(float(np.nanmax(y)))
            any_unstable |= bool(np.any(c.branch.unstable))
    if _wants_log(peaks):
        ax.set_yscale("log")
        _readable_log(ax, "y")
    fam = cases[0].family
    fs = ", ".join(f"{f:g}" for f in sorted({c.force_n for c in cases}))
    ax.set(
        xlabel="frequency (Hz)",
        ylabel="receptance |x| / F (mm/N)",
        title=title or f"{fam}: receptances of every damper\nF = {fs} N",
    )
    band = dict(UNSTABLE_BAND)
    band.pop("zorder")
    _side_legends(
        fig,
        (ax.get_legend_handles_labels()[0], "damper"),
        ([("unstable (Hill)", band)] if any_unstable else [], None),
    )
    return save_figure(fig, path)


@styled
def plot_sweep_receptances(
    cases: Sequence[CaseResult], option: str, path: str | Path, *, title: str | None = None
) -> Path:
    """Receptances of one damper, family and force, one curve per value of the swept option."""
    cases = _one_set(cases, "cases")
    cases = sorted(cases, key=lambda c: sweep_value(c, option))
    name, unit = option_label(option)
    values = [sweep_value(c, option) for c in cases]
    colors = force_colors(values)  # the same ramp: lowest value dark, highest light
    plt = pyplot()
    fig, ax = plt.subplots(figsize=FIGSIZE, layout="constrained")
    peaks = []
    for c, v in zip(cases, values, strict=True):
        x, y = c.freq_hz, c.receptance_mm_per_n
        if not x.size:
            continue
        _draw_branch(
            ax,
            x,
            y,
            c.stable,
            unknown=c.branch.unknown,
            color=colors[v],
            label=f"{option} = {v:g} {unit}".rstrip() + _failed_suffix(c),
        )
        _mark_failure(ax, c, x, y, colors[v])
        peaks.append(float(np.nanmax(y)))
    if _wants_log(peaks):
        ax.set_yscale("log")
        _readable_log(ax, "y")
    c0 = cases[0]
    ax.set(
        xlabel="frequency (Hz)",
        ylabel="receptance |x| / F (mm/N)",
        title=title or f"{c0.damper}, {c0.family}, F = {c0.force_n:g} N: sweep of {name}",
    )
    _side_legends(fig, (ax.get_legend_handles_labels()[0], option))
    return save_figure(fig, path)


# ---- resonance values vs force (paper Fig. 11, Tables 1-2) -------------------------------


def _by_damper(cases: Sequence[CaseResult]):
    for d in _dampers(cases):
        yield d, peak_curve([c for c in cases if c.damper == d])


def _proportional_guide(ax, forces: np.ndarray, values: np.ndarray) -> None:
    """A thin grey line of slope 1 (response proportional to force) through the lowest point."""
    ok = np.isfinite(values) & (values > 0)
    if ok.sum() < 1 or forces.size < 2:
        return
    f0, v0 = forces[ok][0], values[ok][0]
    fx = np.array([forces.min(), forces.max()])
    ax.plot(
        fx,
        v0 * fx / f0,
        color="0.6",
        lw=1.0,
        ls=(0, (6, 3)),
        zorder=0,
        label="proportional to F (linear)",
    )


@styled
def plot_peak_vs_force(
    cases: Sequence[CaseResult], path: str | Path, *, title: str | None = None
) -> Path:
    """Largest response amplitude vs excitation force, one curve per damper (paper Fig. 11).

    Log-log, so a linear response (a rolling cylinder) is a straight line
    of slope 1, drawn in grey through the lowest force for reference.
    Hollow markers: the peak point is unstable; a cross: the branch failed.
    """
    cases = _one_family(cases, "cases")
    plt = pyplot()
    fig, ax = plt.subplots(figsize=FIGSIZE, layout="constrained")
    lowest = []
    for d, pc in _by_damper(cases):
        col, ls, mk = damper_style(d)
        ok = np.isfinite(pc.amp_mm) & (pc.amp_mm > 0)
        ax.plot(
            pc.force_n[ok],
            pc.amp_mm[ok],
            color=col,
            ls=ls,
            lw=1.8,
            marker=mk,
            ms=6,
            label=d + (" (failed)" if pc.failed.any() else ""),
        )
        bad = ok & ~pc.stable
        ax.plot(pc.force_n[bad], pc.amp_mm[bad], ls="none", marker=mk, ms=6, mfc="white", mec=col)
        ax.plot(pc.force_n[ok & pc.failed], pc.amp_mm[ok & pc.failed], "x", color=col, ms=10, mew=2)
        if ok.any():
            lowest.append((pc.force_n[ok][0], pc.amp_mm[ok][0]))
    forces = np.array(sorted({c.force_n for c in cases}))
    if lowest and forces.size > 1:
        f0, a0 = min(lowest)
        _proportional_guide(ax, forces, a0 * forces / f0)
    if forces.size > 1:  # log-log: the linear guide is a line of slope 1 at any force span
        ax.set_xscale("log")
        ax.set_yscale("log")
    ax.set(
        xlabel="excitation force F (N)",
        ylabel="peak response amplitude (mm)",
        title=title or f"{cases[0].family}: peak amplitude vs excitation",
    )
    ax.legend(loc="upper left", title="damper")
    _readable_log(ax)
    return save_figure(fig, path)


@styled
def plot_energy_vs_force(
    cases: Sequence[CaseResult], path: str | Path, *, title: str | None = None
) -> Path:
    """Friction energy per cycle at resonance vs force, one curve per damper (log y).

    The values of the paper's Tables 1-2 as a figure. Energies at or below
    the floor (:data:`workbench.post.tables.ENERGY_FLOOR_REL` times the
    largest in the figure: round-off of contacts that stick or roll) are not
    numbers: they sit in a "stuck / 0" strip under the log axis, one row per
    damper, and the floor is written on it. Missing values (a failed
    branch) are said so in the legend.
    """
    from ..post.tables import ENERGY_FLOOR_REL, STUCK_TEXT, energy_floor

    cases = _one_family(cases, "cases")
    plt = pyplot()
    curves = list(_by_damper(cases))
    floor = energy_floor(np.concatenate([pc.energy_mj for _, pc in curves]))
    stuck_any = any((np.isfinite(pc.energy_mj) & (pc.energy_mj <= floor)).any() for _, pc in curves)
    if stuck_any:
        fig, (ax, az) = plt.subplots(
            2,
            1,
            figsize=(FIGSIZE[0], FIGSIZE[1] + 0.5),
            sharex=True,
            layout="constrained",
            gridspec_kw={"height_ratios": [6, 1 + 0.25 * len(curves)]},
        )
    else:
        fig, ax = plt.subplots(figsize=FIGSIZE, layout="constrained")
        az = None
    for k, (d, pc) in enumerate(curves):
        col, ls, mk = damper_style(d)
        e = pc.energy_mj
        fin = np.isfinite(e)
        up = fin & (e > floor)
        low = fin & ~up
        lab = d + (" (failed)" if pc.failed.any() else "")
        if (~fin).any():
            lab += f" ({int((~fin).sum())} missing)"
        if low.any():
            lab += f" ({int(low.sum())} stuck)"
        ax.plot(pc.force_n[up], e[up], color=col, ls=ls, lw=1.8, marker=mk, ms=6, label=lab)
        ax.plot(pc.force_n[up & pc.failed], e[up & pc.failed], "x", color=col, ms=10, mew=2)
        if az is not None and low.any():
            az.plot(
                pc.force_n[low],
                np.full(int(low.sum()), k),
                color=col,
                ls="none",
                marker=mk,
                ms=6,
                mfc="white",
                mec=col,
            )
    forces = np.array(sorted({c.force_n for c in cases}))
    ax.set_yscale("log")
    if forces.size > 1 and forces.max() / forces.min() > 5:
        ax.set_xscale("log")
    ax.set(
        ylabel="friction energy per cycle at resonance (mJ)",
        title=title or f"{cases[0].family}: energy dissipated by friction at resonance",
    )
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="upper left", title="damper")
    _readable_log(ax)
    bottom = az if az is not None else ax
    bottom.set_xlabel("excitation force F (N)")
    if az is not None:
        az.set_ylim(-0.8, len(curves) - 0.2)
        az.set_yticks([])
        az.set_ylabel(STUCK_TEXT, rotation=0, ha="right", va="center")
        az.grid(False, axis="y")
        az.set_title(
            f"at or below {ENERGY_FLOOR_REL:g} x the largest energy "
            f"({floor:.1g} mJ): no slip, round-off only",
            fontsize=8,
            loc="left",
            color="0.3",
            pad=3,
        )
    return save_figure(fig, path)


# ---- contact status (paper Figs 12-13) --------------------------------------------------


# ---- sweeps ---------------------------------------------------------------------------


def failure_notes(cases: Sequence[CaseResult]) -> list[str]:
    """One sentence per failed or incomplete branch, for captions."""
    out = []
    for c in cases:
        b = c.branch
        if b.failed or not b.completed:
            last = f"{b.freq_hz[-1]:.1f} Hz" if b.n_points else "its first point"
            why = b.message or "no reason recorded"
            state = "failed" if b.failed else "stopped early"
            out.append(
                f"{c.damper}, {c.family}, F = {c.force_n:g} N {state} after "
                f"{b.n_points} points (last at {last}): {why}."
            )
    return out
