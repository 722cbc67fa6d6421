"""Figures of a study in the manner of the conical-damper paper (matplotlib, Agg).

"On the efficiency of a conical under-platform damper for turbines" shows
its results as receptances with every force level (Figs 9-10), peak
amplitude against force (Fig. 11), friction energy per cycle at resonance
(Tables 1-2), the contact status of every pair against frequency (Fig. 12)
and the share of each status at resonance against force (Fig. 13). Each
``plot_*`` function here draws one of those from plain inputs (lists of
:class:`~workbench.post.results.CaseResult`), writes a PNG and returns its
path; the numbers come from :mod:`workbench.post.tables`.

One visual language for every figure of every study (:mod:`.palette`):
a damper always has the same colour, line style and marker, a force level
the same colour, a contact status the same colour (here and in the 3-D
contact maps), and a stability verdict the same line style (stable solid,
unstable dashed, unknown dotted; where line styles name the dampers, the
unstable and unknown pieces lie on a band of their own). A branch that
failed is drawn up to where it stopped, ended with a cross and labelled
"failed". Amplitudes are the harmonic-1 amplitude of the response (the
vibration, without the mean term), unless a label says max |x(t)|.

Figures have a fixed size and resolution and carry no time stamp, so the
same inputs give the same pixels (the image regression test relies on it).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..post.results import CaseResult
from ..post.tables import peak_curve, sweep_value
from .common import pyplot, save_figure, styled
from .palette import (
    damper_style,
    force_colors,
    marker_kwargs,
    peak_marker_legend,
    verdict_counts,
    verdict_legend,
)
from .study_style import (
    FIGSIZE,
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
)
from .sweep_figures import option_label

log = logging.getLogger(__name__)

# the styles, the status and the sweep figures live in study_style.py, status_figures.py and
# sweep_figures.py; every figure stays importable from here
__all__ = [
    "failure_notes",
    "plot_energy_vs_force",
    "plot_answer",
    "plot_peak_vs_force",
    "plot_receptance_overlay",
    "plot_receptances",
    "plot_sweep_receptances",
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
    """Receptance (harmonic-1 amplitude / F) vs frequency of one damper and one family.

    Colour names the force (``forces``: the study's force list, so colours
    agree across figures); the line style the stability verdict of each
    piece (stable solid, unstable dashed, unknown dotted; the legend counts
    the points of each); a failed branch ends with a cross. Log receptance
    axis when the peaks span more than a factor 20.
    """
    cases = _one_set(cases, "cases")
    colors = force_colors(forces if forces is not None else [c.force_n for c in cases])
    plt = pyplot()
    fig, ax = plt.subplots(figsize=FIGSIZE, layout="constrained")
    peaks = []
    for c in cases:
        x, y = c.freq_hz, c.h1_receptance_mm_per_n
        col = colors.get(float(c.force_n), "k")
        if x.size:
            _draw_branch(
                ax,
                x,
                y,
                c.branch.stability,
                color=col,
                label=_flabel(c.force_n) + _failed_suffix(c),
            )
            _mark_failure(ax, c, x, y, col)
            peaks.append(float(np.nanmax(y)))
        else:
            ax.plot([], [], color=col, label=_flabel(c.force_n) + " (no point)")
    if _wants_log(peaks):
        ax.set_yscale("log")
        _readable_log(ax, "y")
    ax.set(
        xlabel="frequency (Hz)",
        ylabel="receptance, harmonic 1: |X1| / F (mm/N)",
        title=title or f"{cases[0].damper} damper, {cases[0].family}: receptances",
    )
    counts = verdict_counts(np.concatenate([c.branch.stability for c in cases]))
    entries = verdict_legend(counts)
    if any(c.branch.failed for c in cases):
        entries.append(("branch failed here", dict(color="0.3", ls="none", marker="x", mew=2)))
    _side_legends(
        fig, (ax.get_legend_handles_labels()[0], "excitation"), (entries, "stability (Hill)")
    )
    return save_figure(fig, path)


@styled
def plot_receptance_overlay(
    cases: Sequence[CaseResult], path: str | Path, *, title: str | None = None
) -> Path:
    """Every damper's receptances of one family in one axes (the paper's Fig. 9 manner).

    Each damper has its own colour, line style and open markers along its
    curves (so curves that lie on one another stay apart); all its forces
    share them. Unstable and unknown pieces lie on their verdict's band; a
    failed branch ends with a cross.
    """
    cases = _one_family(cases, "cases")
    plt = pyplot()
    fig, ax = plt.subplots(figsize=FIGSIZE, layout="constrained")
    peaks = []
    dampers = _dampers(cases)
    for k, d in enumerate(dampers):
        col, ls, mk = damper_style(d)
        own = sorted((c for c in cases if c.damper == d), key=lambda c: c.force_n)
        failed = any(c.branch.failed for c in own)
        first = True
        for c in own:
            x, y = c.freq_hz, c.h1_receptance_mm_per_n
            if not x.size:
                continue
            every = max(1, x.size // 7)
            _draw_branch(
                ax,
                x,
                y,
                c.branch.stability,
                color=col,
                ls_stable=ls,
                band=True,
                lw=1.4,
                marker=mk,
                # markers of different dampers at different points along the curve
                markevery=every + k,
            )
            if first:
                ax.plot(
                    [],
                    [],
                    color=col,
                    ls=ls,
                    marker=mk,
                    mfc="white",
                    label=d + (" (failed)" if failed else ""),
                )
            _mark_failure(ax, c, x, y, col)
            first = False
            peaks.append(float(np.nanmax(y)))
    if _wants_log(peaks):
        ax.set_yscale("log")
        _readable_log(ax, "y")
    fam = cases[0].family
    fs = ", ".join(f"{f:g}" for f in sorted({c.force_n for c in cases}))
    ax.set(
        xlabel="frequency (Hz)",
        ylabel="receptance, harmonic 1: |X1| / F (mm/N)",
        title=title or f"{fam}: receptances of every damper\nF = {fs} N",
    )
    counts = verdict_counts(np.concatenate([c.branch.stability for c in cases]))
    _side_legends(
        fig,
        (ax.get_legend_handles_labels()[0], "damper"),
        (verdict_legend(counts, band=True), "stability (Hill)"),
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
        x, y = c.freq_hz, c.h1_receptance_mm_per_n
        if not x.size:
            continue
        _draw_branch(
            ax,
            x,
            y,
            c.branch.stability,
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
        ylabel="receptance, harmonic 1: |X1| / F (mm/N)",
        title=title or f"{c0.damper}, {c0.family}, F = {c0.force_n:g} N: sweep of {name}",
    )
    counts = verdict_counts(np.concatenate([c.branch.stability for c in cases]))
    _side_legends(
        fig,
        (ax.get_legend_handles_labels()[0], option),
        (verdict_legend(counts), "stability (Hill)"),
    )
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


def _peak_axes(ax, cases: Sequence[CaseResult]) -> None:
    """Harmonic-1 peak amplitude vs force of every damper of one family, in ``ax``."""
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
            label=d + (" (failed)" if pc.failed.any() else ""),
        )
        for k in np.flatnonzero(ok):
            ax.plot(pc.force_n[k], pc.amp_mm[k], **marker_kwargs(int(pc.verdict[k]), col, mk))
            if not pc.covered[k]:  # a lower bound: the peak lies above
                ax.annotate(
                    "",
                    xy=(pc.force_n[k], pc.amp_mm[k] * 1.35),
                    xytext=(pc.force_n[k], pc.amp_mm[k]),
                    arrowprops=dict(arrowstyle="->", color=col, lw=1.4),
                )
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
    ax.set(xlabel="excitation force F (N)", ylabel="vibration amplitude, harmonic 1 (mm)")
    _readable_log(ax)
    if 1 < forces.size <= 4:  # few forces: tick each of them
        from matplotlib.ticker import NullFormatter, NullLocator

        ax.set_xticks(forces, [f"{f:g}" for f in forces])
        ax.xaxis.set_minor_locator(NullLocator())
        ax.xaxis.set_minor_formatter(NullFormatter())


def _damper_handles(cases: Sequence[CaseResult]) -> list:
    """Legend handles of the dampers (line, marker) and of the linear guide line."""
    from matplotlib.lines import Line2D

    out = []
    for d in _dampers(cases):
        col, ls, mk = damper_style(d)
        failed = any(c.branch.failed for c in cases if c.damper == d)
        lab = d + (" (failed)" if failed else "")
        out.append(Line2D([], [], color=col, ls=ls, lw=1.8, marker=mk, ms=6, label=lab))
    if len({c.force_n for c in cases}) > 1:
        out.append(
            Line2D([], [], color="0.6", lw=1.0, ls=(0, (6, 3)), label="proportional to F (linear)")
        )
    return out


def _peak_legend_entries(cases: Sequence[CaseResult]) -> list[tuple[str, dict]]:
    out = peak_marker_legend()
    if any(not c.h1_peak_covered for c in cases):
        out.append(
            ("peak not reached (lower bound)", dict(color="0.25", ls="none", marker="$\\uparrow$"))
        )
    if any(c.branch.failed for c in cases):
        out.append(("branch failed", dict(color="0.25", ls="none", marker="x", mew=2)))
    return out


@styled
def plot_peak_vs_force(
    cases: Sequence[CaseResult], path: str | Path, *, title: str | None = None
) -> Path:
    """Harmonic-1 peak amplitude vs excitation force, one curve per damper (paper Fig. 11).

    Log-log, so a linear response (a rolling cylinder) is a straight line
    of slope 1, drawn in grey through the lowest force for reference. The
    marker of each peak is filled when stable, hollow when unstable, half
    filled when unknown; an arrow up: the curve stopped before its peak (a
    lower bound); a cross: the branch failed.
    """
    cases = _one_family(cases, "cases")
    plt = pyplot()
    fig, ax = plt.subplots(figsize=FIGSIZE, layout="constrained")
    _peak_axes(ax, cases)
    ax.set_title(title or f"{cases[0].family}: vibration amplitude at resonance vs excitation")
    _side_legends(fig, (_damper_handles(cases), "damper"), (_peak_legend_entries(cases), "peak"))
    return save_figure(fig, path)


@styled
def plot_answer(cases: Sequence[CaseResult], path: str | Path, *, title: str | None = None) -> Path:
    """The report's headline chart: harmonic-1 peak amplitude vs force, one panel per family
    (in-phase first), every damper in each, the same markers as :func:`plot_peak_vs_force`."""
    from ..post.results import family_name

    fams = sorted({round(c.phase_deg, 9) for c in cases}, key=_family_key)
    if not fams:
        raise InputError("cases", "[]", "at least one case")
    plt = pyplot()
    n = len(fams)
    fig, axes = plt.subplots(
        n, 1, figsize=(5.6, 0.75 + 2.3 * n), layout="constrained", squeeze=False, sharex=True
    )
    for k, p in enumerate(fams):
        ax = axes[k, 0]
        _peak_axes(ax, [c for c in cases if abs(c.phase_deg - p) < 1e-9])
        ax.set_title(family_name(p), fontsize=10, loc="left")
        ax.set_ylabel("")
        if k < n - 1:
            ax.set_xlabel("")
    fig.supylabel("vibration amplitude at resonance, harmonic 1 (mm)", fontsize=10)
    from matplotlib.lines import Line2D

    handles = _damper_handles(cases) + [
        Line2D([], [], label=lab, **kw) for lab, kw in _peak_legend_entries(cases)
    ]
    fig.legend(handles=handles, loc="outside lower center", ncol=3, fontsize=8, frameon=False)
    fig.suptitle(title or "vibration amplitude at resonance vs excitation", fontsize=11)
    return save_figure(fig, path)


def _family_key(p: float) -> tuple[int, float]:
    from ..post.results import family_name

    return ({"in-phase": 0, "out-of-phase": 1}.get(family_name(p), 2), float(p) % 360.0)


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
