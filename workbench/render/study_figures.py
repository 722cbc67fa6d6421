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
import zlib
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..post.results import STATUS_NAMES, CaseResult, family_name
from ..post.tables import (
    peak_curve,
    status_share_curves,
    sweep_curve,
    sweep_value,
)
from ..post.tables import (
    stability_runs as _runs,
)
from .common import pyplot, readable_log, save_figure, styled

log = logging.getLogger(__name__)

# colour, line style, marker of each damper (the paper: cone solid, cylinder dashed, wedge dotted)
DAMPER_STYLE: dict[str, tuple[str, str, str]] = {
    "cone": ("#1f6fb4", "-", "o"),
    "cylinder": ("#ff7f0e", "--", "s"),
    "wedge": ("#b8860b", ":", "^"),
}
_EXTRA_COLORS = ("#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#7f7f7f")
# status 0 stuck, 1 stick-slip, 2 partial separation, 3 full separation
STATUS_COLORS: tuple[str, str, str, str] = ("#3a3a3a", "#f28e2b", "#59a14f", "#4e79a7")
FAMILY_STYLE = {"in-phase": "-", "out-of-phase": "--"}
UNSTABLE_BAND = dict(color="0.55", lw=6.0, alpha=0.35, solid_capstyle="round", zorder=1)
FIGSIZE = (7.2, 4.6)  # inches; the report shows them at 110 dpi


# ---- styles -----------------------------------------------------------------------------


def damper_style(damper: str) -> tuple[str, str, str]:
    """(colour, line style, marker) of a damper; a variant ("cone-12deg") inherits its base's."""
    if damper in DAMPER_STYLE:
        return DAMPER_STYLE[damper]
    for base, style in DAMPER_STYLE.items():
        if damper.startswith(base):
            return style
    k = zlib.crc32(damper.encode()) % len(_EXTRA_COLORS)
    return (_EXTRA_COLORS[k], "-.", "D")


def force_colors(forces: Sequence[float]) -> dict[float, str]:
    """A colour per force, lowest dark purple to highest orange (plasma 0 .. 0.8)."""
    import matplotlib

    fs = sorted(set(float(f) for f in forces))
    cmap = matplotlib.colormaps["plasma"]
    n = len(fs)
    return {f: matplotlib.colors.to_hex(cmap(0.8 * (i / (n - 1) if n > 1 else 0.0)))
            for i, f in enumerate(fs)}


def status_legend_handles(counts: Sequence[int] | None = None) -> list:
    """Square legend handles of the four statuses (with pair counts if given)."""
    from matplotlib.lines import Line2D

    out = []
    for k, name in enumerate(STATUS_NAMES):
        lab = name if counts is None else f"{name} ({counts[k]})"
        out.append(Line2D([], [], ls="none", marker="s", ms=8, color=STATUS_COLORS[k], label=lab))
    return out


def _flabel(force: float) -> str:
    return f"F = {force:g} N"


def _failed_suffix(case: CaseResult) -> str:
    return " (failed)" if case.branch.failed else ""


def _draw_branch(ax, x: np.ndarray, y: np.ndarray, stable: np.ndarray, *, color: str,
                 ls_stable: str = "-", ls_unstable: str = "--", lw: float = 1.6,
                 band: bool = False, label: str | None = None,
                 unknown: np.ndarray | None = None) -> None:
    """A curve drawn solid where stable and ``ls_unstable`` (or a grey band) where not;
    points of unknown stability (``unknown``, Hill not computed or not trusted) dotted grey."""
    first = True
    if unknown is not None and np.any(unknown):
        unk = np.asarray(unknown, dtype=bool)
        for sl, u in _runs(~unk):
            if not u:
                j = slice(max(sl.start - 1, 0), min(sl.stop + 1, x.size))
                ax.plot(x[j], y[j], color="0.55", lw=lw + 0.3, ls=":", zorder=3)
        y = np.where(unk, np.nan, y)
    for sl, ok in _runs(stable):
        if not ok and band:
            ax.plot(x[sl], y[sl], **UNSTABLE_BAND)
        ax.plot(x[sl], y[sl], color=color, lw=lw,
                ls=ls_stable if (ok or band) else ls_unstable,
                label=label if first else None, zorder=2)
        first = False


def _mark_failure(ax, case: CaseResult, x: np.ndarray, y: np.ndarray, color: str) -> None:
    if case.branch.failed and x.size:
        ax.plot(x[-1], y[-1], "x", color=color, ms=9, mew=2.2, zorder=4)


def _side_legends(fig, first: tuple[list, str | None],
                  second: tuple[list[tuple[str, dict]], str | None] | None = None) -> None:
    """Legends outside the axes on the right: ``first`` (handles, title) at the top and,
    below it, ``second`` (line-style entries (label, Line2D keywords), title)."""
    from matplotlib.lines import Line2D

    handles, title = first
    fig.legend(handles=handles, loc="outside right upper", title=title)
    if second and second[0]:
        entries, title2 = second
        fig.legend(handles=[Line2D([], [], label=lab, **kw) for lab, kw in entries],
                   loc="outside right lower", title=title2)


_readable_log = readable_log  # (moved to common: the FRF figures use it too)


def _wants_log(values: Sequence[float], ratio: float = 20.0) -> bool:
    v = np.asarray([x for x in values if np.isfinite(x) and x > 0])
    return v.size > 1 and v.max() / v.min() > ratio


def _one_set(cases: Sequence[CaseResult], what: str) -> list[CaseResult]:
    if not cases:
        raise InputError(what, "[]", "at least one case")
    keys = {(c.damper, round(c.phase_deg, 9)) for c in cases}
    if len(keys) != 1:
        raise InputError(what, sorted(keys), "cases of one damper and one family")
    return sorted(cases, key=lambda c: c.force_n)


def _one_family(cases: Sequence[CaseResult], what: str) -> list[CaseResult]:
    if not cases:
        raise InputError(what, "[]", "at least one case")
    fam = {round(c.phase_deg, 9) for c in cases}
    if len(fam) != 1:
        raise InputError(what, sorted(fam), "cases of one family (one phase angle)")
    return list(cases)


def _dampers(cases: Sequence[CaseResult]) -> list[str]:
    return list(dict.fromkeys(c.damper for c in cases))


# ---- receptances (paper Figs 9-10) ------------------------------------------------------


@styled
def plot_receptances(cases: Sequence[CaseResult], path: str | Path, *,
                     forces: Sequence[float] | None = None, title: str | None = None) -> Path:
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
            _draw_branch(ax, x, y, c.stable, unknown=c.branch.unknown, color=col,
                         label=_flabel(c.force_n) + _failed_suffix(c))
            _mark_failure(ax, c, x, y, col)
            peaks.append(float(np.nanmax(y)))
            any_unstable |= bool(np.any(c.branch.unstable))
        else:
            ax.plot([], [], color=col, label=_flabel(c.force_n) + " (no point)")
    if _wants_log(peaks):
        ax.set_yscale("log")
        _readable_log(ax, "y")
    ax.set(xlabel="frequency (Hz)", ylabel="receptance |x| / F (mm/N)",
           title=title or f"{cases[0].damper} damper, {cases[0].family}: receptances")
    entries = [("stable", dict(color="0.3", ls="-"))]
    if any_unstable:
        entries.append(("unstable (Hill)", dict(color="0.3", ls="--")))
    if any(c.branch.failed for c in cases):
        entries.append(("branch failed here", dict(color="0.3", ls="none", marker="x", mew=2)))
    _side_legends(fig, (ax.get_legend_handles_labels()[0], "excitation"), (entries, "branch"))
    return save_figure(fig, path)


@styled
def plot_receptance_overlay(cases: Sequence[CaseResult], path: str | Path, *,
                            title: str | None = None) -> Path:
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
            _draw_branch(ax, x, y, c.stable, unknown=c.branch.unknown, color=col, ls_stable=ls,
                         band=True, lw=1.4,
                         label=(d + (" (failed)" if failed else "")) if first else None)
            _mark_failure(ax, c, x, y, col)
            first = False
            peaks.append(float(np.nanmax(y)))
            any_unstable |= bool(np.any(c.branch.unstable))
    if _wants_log(peaks):
        ax.set_yscale("log")
        _readable_log(ax, "y")
    fam = cases[0].family
    fs = ", ".join(f"{f:g}" for f in sorted({c.force_n for c in cases}))
    ax.set(xlabel="frequency (Hz)", ylabel="receptance |x| / F (mm/N)",
           title=title or f"{fam}: receptances of every damper\nF = {fs} N")
    band = dict(UNSTABLE_BAND)
    band.pop("zorder")
    _side_legends(fig, (ax.get_legend_handles_labels()[0], "damper"),
                  ([("unstable (Hill)", band)] if any_unstable else [], None))
    return save_figure(fig, path)


@styled
def plot_sweep_receptances(cases: Sequence[CaseResult], option: str, path: str | Path, *,
                           title: str | None = None) -> Path:
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
        _draw_branch(ax, x, y, c.stable, unknown=c.branch.unknown, color=colors[v],
                     label=f"{option} = {v:g} {unit}".rstrip() + _failed_suffix(c))
        _mark_failure(ax, c, x, y, colors[v])
        peaks.append(float(np.nanmax(y)))
    if _wants_log(peaks):
        ax.set_yscale("log")
        _readable_log(ax, "y")
    c0 = cases[0]
    ax.set(xlabel="frequency (Hz)", ylabel="receptance |x| / F (mm/N)",
           title=title or f"{c0.damper}, {c0.family}, F = {c0.force_n:g} N: sweep of {name}")
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
    ax.plot(fx, v0 * fx / f0, color="0.6", lw=1.0, ls=(0, (6, 3)), zorder=0,
            label="proportional to F (linear)")


@styled
def plot_peak_vs_force(cases: Sequence[CaseResult], path: str | Path, *,
                       title: str | None = None) -> Path:
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
        ax.plot(pc.force_n[ok], pc.amp_mm[ok], color=col, ls=ls, lw=1.8, marker=mk, ms=6,
                label=d + (" (failed)" if pc.failed.any() else ""))
        bad = ok & ~pc.stable
        ax.plot(pc.force_n[bad], pc.amp_mm[bad], ls="none", marker=mk, ms=6, mfc="white",
                mec=col)
        ax.plot(pc.force_n[ok & pc.failed], pc.amp_mm[ok & pc.failed], "x", color=col, ms=10,
                mew=2)
        if ok.any():
            lowest.append((pc.force_n[ok][0], pc.amp_mm[ok][0]))
    forces = np.array(sorted({c.force_n for c in cases}))
    if lowest and forces.size > 1:
        f0, a0 = min(lowest)
        _proportional_guide(ax, forces, a0 * forces / f0)
    if forces.size > 1:  # log-log: the linear guide is a line of slope 1 at any force span
        ax.set_xscale("log")
        ax.set_yscale("log")
    ax.set(xlabel="excitation force F (N)", ylabel="peak response amplitude (mm)",
           title=title or f"{cases[0].family}: peak amplitude vs excitation")
    ax.legend(loc="upper left", title="damper")
    _readable_log(ax)
    return save_figure(fig, path)


@styled
def plot_energy_vs_force(cases: Sequence[CaseResult], path: str | Path, *,
                         title: str | None = None) -> Path:
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
    stuck_any = any((np.isfinite(pc.energy_mj) & (pc.energy_mj <= floor)).any()
                    for _, pc in curves)
    if stuck_any:
        fig, (ax, az) = plt.subplots(2, 1, figsize=(FIGSIZE[0], FIGSIZE[1] + 0.5), sharex=True,
                                     layout="constrained",
                                     gridspec_kw={"height_ratios": [6, 1 + 0.25 * len(curves)]})
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
            az.plot(pc.force_n[low], np.full(int(low.sum()), k), color=col, ls="none",
                    marker=mk, ms=6, mfc="white", mec=col)
    forces = np.array(sorted({c.force_n for c in cases}))
    ax.set_yscale("log")
    if forces.size > 1 and forces.max() / forces.min() > 5:
        ax.set_xscale("log")
    ax.set(ylabel="friction energy per cycle at resonance (mJ)",
           title=title or f"{cases[0].family}: energy dissipated by friction at resonance")
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
        az.set_title(f"at or below {ENERGY_FLOOR_REL:g} x the largest energy "
                     f"({floor:.1g} mJ): no slip, round-off only", fontsize=8, loc="left",
                     color="0.3", pad=3)
    return save_figure(fig, path)


# ---- contact status (paper Figs 12-13) --------------------------------------------------


NOT_COMPUTED_COLOR = "#f2f2f2"
NOT_COMPUTED_EDGE = "#b0b0b0"
ZOOM_MAX_SHARE = 0.6  # no zoom row when the slipping part covers more of the band than this


def _band(case: CaseResult, lo: float, hi: float) -> tuple[float, float]:
    """The case's frequency band (Hz), or the computed span if it has none."""
    b = getattr(case.branch, "band_hz", None)
    if b is not None and len(b) == 2 and np.all(np.isfinite(b)) and b[1] > b[0]:
        return min(float(b[0]), lo), max(float(b[1]), hi)
    return lo, hi


def _uncovered(x0: np.ndarray, x1: np.ndarray, lo: float, hi: float) -> list[tuple[float, float]]:
    """Parts of [lo, hi] covered by no cell [x0, x1] (frequencies with no computed point)."""
    order = np.argsort(x0)
    gaps, reach = [], lo
    for a, b in zip(x0[order], x1[order], strict=True):
        if a > reach:
            gaps.append((reach, float(a)))
        reach = max(reach, float(b))
    if reach < hi:
        gaps.append((reach, hi))
    span = hi - lo
    return [(a, b) for a, b in gaps if b - a > 1e-9 * span]


def status_zoom(case: CaseResult) -> tuple[float, float] | None:
    """A frequency window (Hz) around the part of the branch where some pair slips or opens.

    Widened by a quarter of its width on each side (at least 0.5 % of the
    peak frequency); None when the branch has no point.
    """
    st = np.asarray(case.branch.status)
    f = case.freq_hz
    if st.ndim != 2 or st.shape[0] == 0:
        return None
    active = (st != 0).any(axis=1)
    i = case.peak_index
    if active.any():
        a, b = float(f[active].min()), float(f[active].max())
    else:
        a = b = float(f[i])
    pad = max(0.25 * (b - a), 0.005 * float(f[i]))
    return a - pad, b + pad


def _status_panel(ax, case: CaseResult, side_labels: bool = True) -> None:
    """Colour every (frequency, pair) cell by status; sides split by a dashed line."""
    from matplotlib.collections import PolyCollection

    f = case.freq_hz
    st = case.branch.status
    n_pts, n_pairs = st.shape if st.ndim == 2 else (0, 0)
    if n_pts == 0 or n_pairs == 0:
        ax.text(0.5, 0.5, "no point computed", transform=ax.transAxes, ha="center")
        return
    span = float(np.ptp(f)) or 1.0
    cap = 0.08 * span  # cells reach halfway to the neighbours, at most 4 % of the band wide
    d = np.abs(np.diff(f))
    left = np.minimum(np.concatenate([[cap], d]) / 2, cap / 2)
    right = np.minimum(np.concatenate([d, [cap]]) / 2, cap / 2)
    x0, x1 = f - left, f + right
    j = np.arange(n_pairs)
    X0 = np.repeat(x0, n_pairs)
    X1 = np.repeat(x1, n_pairs)
    Y = np.tile(j, n_pts).astype(float) + 1.0  # pairs numbered from 1, as in the paper
    verts = np.stack([np.stack([X0, Y - 0.5], 1), np.stack([X1, Y - 0.5], 1),
                      np.stack([X1, Y + 0.5], 1), np.stack([X0, Y + 0.5], 1)], axis=1)
    colors = np.asarray(STATUS_COLORS)[np.clip(st.reshape(-1).astype(int), 0, 3)]
    ax.add_collection(PolyCollection(verts, facecolors=colors, edgecolors="none",
                                     antialiased=False, rasterized=True))
    lo, hi = _band(case, float(x0.min()), float(x1.max()))
    for g0, g1 in _uncovered(x0, x1, lo, hi):  # no computed point there: say so
        ax.axvspan(g0, g1, facecolor=NOT_COMPUTED_COLOR, edgecolor=NOT_COMPUTED_EDGE,
                   hatch="////", lw=0.0, zorder=0.5)
    ax.set_xlim(lo, hi)
    ax.set_ylim(0.5, n_pairs + 0.5)
    side = np.asarray(case.side)
    n0 = int(np.sum(side == 0))
    if 0 < n0 < n_pairs:
        ax.axhline(n0 + 0.5, color="k", ls="--", lw=1.3)
    if 0 < n0 < n_pairs and side_labels:
        ax.text(1.01, (n0 / 2 + 0.5) / n_pairs, "platform 1", transform=ax.transAxes,
                rotation=90, va="center", fontsize=8)
        ax.text(1.01, (n0 + (n_pairs - n0) / 2 + 0.5) / n_pairs, "platform 2",
                transform=ax.transAxes, rotation=90, va="center", fontsize=8)
    i = case.peak_index
    if i >= 0:
        ax.axvline(f[i], color="#c0392b", lw=1.4, ls=":")
    ax.grid(False)


@styled
def plot_status_map(cases: Sequence[CaseResult], path: str | Path, *,
                    title: str | None = None) -> Path:
    """Contact status of every pair vs frequency for one damper and family (paper Fig. 12).

    One panel per case (e.g. 9.6 N and 30 N), pairs on y (side 0 first,
    then side 1 above the dashed line), frequency on x, colour the status;
    the dotted red line marks the resonance peak.
    """
    cases = _one_set(cases, "cases")
    plt = pyplot()
    n = len(cases)
    windows = [status_zoom(c) for c in cases]
    spans = [float(np.ptp(c.freq_hz)) if c.branch.n_points else 0.0 for c in cases]
    zoom = all(w is not None and s > 0 and (w[1] - w[0]) < ZOOM_MAX_SHARE * s
               for w, s in zip(windows, spans, strict=True))
    rows = 2 if zoom else 1
    fig, axes = plt.subplots(rows, n, figsize=(3.9 * n + 0.6, 4.6 if rows == 1 else 7.6),
                             sharey=True, layout="constrained", squeeze=False,
                             height_ratios=[1, 1.25] if zoom else None)
    for k, c in enumerate(cases):
        for row in range(rows):
            ax = axes[row, k]
            _status_panel(ax, c, side_labels=k == n - 1)
            ax.set_xlabel("frequency (Hz)")
        i = c.peak_index
        head = f"F = {c.force_n:g} N" + (f", peak at {c.freq_hz[i]:.1f} Hz" if i >= 0 else "")
        if c.branch.failed:
            head += f"\nbranch failed at {c.freq_hz[-1]:.1f} Hz" if c.branch.n_points else \
                "\nbranch failed"
        axes[0, k].set_title(head, fontsize=10)
        if zoom:
            w0, w1 = windows[k]
            axes[1, k].set_xlim(w0, w1)
            axes[1, k].set_title(f"zoom: {w0:.1f}-{w1:.1f} Hz, where pairs slip or open",
                                 fontsize=9)
            axes[0, k].axvspan(w0, w1, facecolor="none", edgecolor="#c0392b", lw=1.0,
                               ls="--", zorder=3)
    for row in range(rows):
        axes[row, 0].set_ylabel("contact pair number")
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    extra = [Patch(facecolor=NOT_COMPUTED_COLOR, edgecolor=NOT_COMPUTED_EDGE, hatch="////",
                   label="not computed (no point)"),
             Line2D([], [], color="#c0392b", ls=":", lw=1.4, label="resonance peak")]
    fig.legend(handles=status_legend_handles() + extra, loc="outside lower center", ncol=6,
               frameon=False)
    c0 = cases[0]
    fig.suptitle(title or f"{c0.damper} damper, {c0.family}: contact status of every pair")
    return save_figure(fig, path)


@styled
def plot_status_shares(cases: Sequence[CaseResult], path: str | Path, *,
                       title: str | None = None) -> Path:
    """Share of the pairs in each status at resonance vs force (paper Fig. 13).

    Colour names the status, line style and marker the damper. Statuses
    that no damper reaches at any force are left out of the axes but kept
    in the legend (marked "none").
    """
    cases = _one_family(cases, "cases")
    plt = pyplot()
    fig, ax = plt.subplots(figsize=FIGSIZE, layout="constrained")
    seen = np.zeros(4, bool)
    forces_all = []
    for d in _dampers(cases):
        _, ls, mk = damper_style(d)
        forces, shares = status_share_curves([c for c in cases if c.damper == d])
        forces_all += list(forces)
        for k, key in enumerate(shares):
            v = 100.0 * shares[key]
            if np.nanmax(v, initial=0.0) <= 0.0:
                continue
            seen[k] = True
            ax.plot(forces, v, color=STATUS_COLORS[k], ls=ls, marker=mk, ms=5, lw=1.6)
    from matplotlib.lines import Line2D

    fs = np.array(forces_all)
    if fs.size > 1 and fs.max() / fs.min() > 5:
        ax.set_xscale("log")
    ax.set(xlabel="excitation force F (N)", ylabel="share of contact pairs at resonance (%)",
           ylim=(-3, 103), title=title or f"{cases[0].family}: contact status at resonance")
    _readable_log(ax, "x")
    handles = [Line2D([], [], color=STATUS_COLORS[k], lw=2.5,
                      label=STATUS_NAMES[k] + ("" if seen[k] else " (none)"))
               for k in range(4)]
    _side_legends(fig, (handles, "status"),
                  ([(d, dict(color="0.3", ls=damper_style(d)[1], marker=damper_style(d)[2]))
                    for d in _dampers(cases)], "damper"))
    return save_figure(fig, path)


# ---- sweeps ---------------------------------------------------------------------------


def option_label(option: str) -> tuple[str, str]:
    """(description, unit) of a study option from its help text, e.g. ("centrifugal force
    on the damper", "N"); ("option", "-") for an unknown one."""
    from ..studies.spec import BY_NAME

    o = BY_NAME.get(option) or BY_NAME.get(option.replace("_", "-"))
    if o is None:
        return option, "-"
    text = o.help
    while "(" in text and ")" in text[text.index("("):]:
        a = text.index("(")
        b = text.index(")", a)
        text = (text[:a] + text[b + 1:]).replace("  ", " ")
    text = text.strip().rstrip(",")
    if ", " in text:
        name, unit = text.rsplit(", ", 1)
        if len(unit) <= 12:
            return name.strip(), unit.strip()
    return text, "-"


def _axis_label(option: str) -> str:
    name, unit = option_label(option)
    return f"{name}, {option} ({unit})"


@styled
def plot_sweep(cases: Sequence[CaseResult], option: str, path: str | Path, *,
               title: str | None = None) -> Path:
    """Peak amplitude (top) and resonance frequency (bottom) vs the swept option.

    One column per family; one curve per damper (its colour, style and
    marker), and per force when the sweep has several (labelled).
    Hollow markers: unstable peak; crosses: failed branches.
    """
    if not cases:
        raise InputError("cases", "[]", "the cases of a sweep")
    fams = sorted({round(c.phase_deg, 9) for c in cases},
                  key=lambda p: ({"in-phase": 0, "out-of-phase": 1}.get(family_name(p), 2), p))
    forces = sorted({c.force_n for c in cases})
    plt = pyplot()
    fig, axes = plt.subplots(2, len(fams), figsize=(4.6 * len(fams) + 1.6, 6.4), sharex=True,
                             layout="constrained", squeeze=False)
    fstyles = ["-", "--", ":", "-."]
    for col, p in enumerate(fams):
        for d in _dampers(cases):
            color, ls, mk = damper_style(d)
            for kf, f in enumerate(forces):
                sel = [c for c in cases if c.damper == d and abs(c.phase_deg - p) < 1e-9
                       and abs(c.force_n - f) < 1e-12]
                if not sel:
                    continue
                sc = sweep_curve(sel, option)
                style = ls if len(forces) == 1 else fstyles[kf % len(fstyles)]
                lab = d if len(forces) == 1 else f"{d}, F = {f:g} N"
                if sc.failed.any():
                    lab += " (failed)"
                for row, y in ((0, sc.amp_mm), (1, sc.freq_hz)):
                    ax = axes[row, col]
                    ax.plot(sc.value, y, color=color, ls=style, marker=mk, ms=6, lw=1.7,
                            label=lab if (row == 0 and col == 0) else None)
                    bad = ~sc.stable
                    ax.plot(sc.value[bad], y[bad], ls="none", marker=mk, ms=6, mfc="white",
                            mec=color)
                    ax.plot(sc.value[sc.failed], y[sc.failed], "x", color=color, ms=10, mew=2)
        axes[0, col].set_title(family_name(p) + (f", F = {forces[0]:g} N"
                                                 if len(forces) == 1 else ""))
        axes[1, col].set_xlabel(_axis_label(option))
    axes[0, 0].set_ylabel("peak response amplitude (mm)")
    axes[1, 0].set_ylabel("resonance frequency (Hz)")
    for col, p in enumerate(fams):
        amps = [c.amp_mm[c.peak_index] for c in cases
                if c.peak_index >= 0 and abs(c.phase_deg - p) < 1e-9]
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
def plot_cone_angle_energy(cases: Sequence[CaseResult], path: str | Path, *, beta_deg: float,
                           r1_mm: float, length_mm: float, option: str = "cone-angle",
                           title: str | None = None) -> Path:
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
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7.2, 6.6), sharex=True, layout="constrained",
                                 height_ratios=(1.3, 1.0))
    forces = sorted({c.force_n for c in cones})
    colors = force_colors(forces)
    fams = sorted({round(c.phase_deg, 9) for c in cones},
                  key=lambda p: ({"in-phase": 0, "out-of-phase": 1}.get(family_name(p), 2), p))
    for p in fams:
        fam = family_name(p)
        for f in forces:
            sel = [c for c in cones if abs(c.phase_deg - p) < 1e-9 and abs(c.force_n - f) < 1e-12]
            if not sel:
                continue
            sc = sweep_curve(sel, option)
            ok = np.isfinite(sc.energy_mj) & (sc.energy_mj > 0)
            a1.plot(sc.value[ok], sc.energy_mj[ok], color=colors[f],
                    ls=FAMILY_STYLE.get(fam, ":"), marker="o", ms=5, lw=1.7,
                    label=f"{fam}, F = {f:g} N" + (" (failed)" if sc.failed.any() else ""))
            a1.plot(sc.value[ok & sc.failed], sc.energy_mj[ok & sc.failed], "x",
                    color=colors[f], ms=10, mew=2)
    energies = [c.energy_mj[c.peak_index].sum() for c in cones if c.peak_index >= 0]
    if _wants_log(energies, 30.0):
        a1.set_yscale("log")
        _readable_log(a1, "y")
    a1.set(ylabel="friction energy per cycle\nat resonance (mJ)",
           title=title or "Cone: friction energy at resonance and kinematic slip vs cone angle")
    a1.legend(loc="best", fontsize=8)
    eq6 = max_slip_ratio(grid, beta_deg, r1_mm, length_mm)
    exact = sweep_cone_angle(grid, beta_deg, r1_mm, length_mm)
    a2.plot(grid, eq6, color="k", lw=1.8, label="paper eq. 6 (middle section rolls)")
    a2.plot(grid, exact["max_transverse_slip_ratio"], color="0.35", lw=1.5, ls="--",
            label="exact 3-D rigid body, transverse")
    a2.plot(grid, exact["max_slip_ratio"], color="0.35", lw=1.5, ls=":",
            label="exact 3-D rigid body, total")
    for v in np.unique(values):
        a2.axvline(v, color=DAMPER_STYLE["cone"][0], lw=0.8, alpha=0.35)
    a2.set(xlabel="cone semi-angle alpha_c (deg)",
           ylabel="largest kinematic slip\nper radial motion s/v (-)", ylim=(0, None))
    a2.text(0.99, 0.04, f"in-phase motion; beta = {beta_deg:g} deg, R1 = {r1_mm:g} mm, "
            f"L = {length_mm:g} mm; blue lines: swept angles", transform=a2.transAxes,
            ha="right", va="bottom", fontsize=7.5, color="0.3")
    a2.legend(loc="upper right", fontsize=8)
    return save_figure(fig, path)


def failure_notes(cases: Sequence[CaseResult]) -> list[str]:
    """One sentence per failed or incomplete branch, for captions."""
    out = []
    for c in cases:
        b = c.branch
        if b.failed or not b.completed:
            last = f"{b.freq_hz[-1]:.1f} Hz" if b.n_points else "its first point"
            why = b.message or "no reason recorded"
            state = "failed" if b.failed else "stopped early"
            out.append(f"{c.damper}, {c.family}, F = {c.force_n:g} N {state} after "
                       f"{b.n_points} points (last at {last}): {why}.")
    return out

