"""Contact-status figures of a study (paper Figs 12-13): status against frequency and force.

:func:`plot_status_map` draws the status of every contact pair against
frequency (one panel per case, with a zoom on the slipping part);
:func:`plot_status_shares` the share of each status at resonance against
force.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..post.results import STATUS_NAMES, CaseResult
from ..post.tables import status_share_curves
from .common import pyplot, save_figure, styled
from .palette import (
    NOT_COMPUTED_COLOR,
    NOT_COMPUTED_EDGE,
    RESONANCE_COLOR,
    STATUS_COLORS,
    STATUS_EDGE,
    damper_style,
)
from .study_style import (
    FIGSIZE,
    _dampers,
    _one_family,
    _one_set,
    _readable_log,
    _side_legends,
    status_legend_handles,
)

# the resonance line stays visible on every status colour: black with a white rim
_RESONANCE = dict(color=RESONANCE_COLOR, lw=1.6, ls=(0, (2, 1.5)))


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
    i = case.h1_peak_index
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
    verts = np.stack(
        [
            np.stack([X0, Y - 0.5], 1),
            np.stack([X1, Y - 0.5], 1),
            np.stack([X1, Y + 0.5], 1),
            np.stack([X0, Y + 0.5], 1),
        ],
        axis=1,
    )
    colors = np.asarray(STATUS_COLORS)[np.clip(st.reshape(-1).astype(int), 0, 3)]
    ax.add_collection(
        PolyCollection(
            verts, facecolors=colors, edgecolors="none", antialiased=False, rasterized=True
        )
    )
    lo, hi = _band(case, float(x0.min()), float(x1.max()))
    for g0, g1 in _uncovered(x0, x1, lo, hi):  # no computed point there: say so
        ax.axvspan(
            g0,
            g1,
            facecolor=NOT_COMPUTED_COLOR,
            edgecolor=NOT_COMPUTED_EDGE,
            hatch="////",
            lw=0.0,
            zorder=0.5,
        )
    ax.set_xlim(lo, hi)
    ax.set_ylim(0.5, n_pairs + 0.5)
    side = np.asarray(case.side)
    n0 = int(np.sum(side == 0))
    if 0 < n0 < n_pairs:
        ax.axhline(n0 + 0.5, color="k", ls="--", lw=1.3)
    if 0 < n0 < n_pairs and side_labels:
        ax.text(
            1.01,
            (n0 / 2 + 0.5) / n_pairs,
            "platform 1",
            transform=ax.transAxes,
            rotation=90,
            va="center",
            fontsize=8,
        )
        ax.text(
            1.01,
            (n0 + (n_pairs - n0) / 2 + 0.5) / n_pairs,
            "platform 2",
            transform=ax.transAxes,
            rotation=90,
            va="center",
            fontsize=8,
        )
    i = case.h1_peak_index
    if i >= 0:
        from matplotlib import patheffects

        ax.axvline(
            f[i], **_RESONANCE, path_effects=[patheffects.withStroke(linewidth=3.2, foreground="w")]
        )
    ax.grid(False)


def draw_status_panel(
    ax, freq_hz, status, side, peak_index: int, band_hz=None, side_labels: bool = True
) -> None:
    """The status-map panel of :func:`plot_status_map` from plain arrays (a curve that is
    not a :class:`CaseResult`, e.g. a bladed-disk case): ``status`` (points, pairs),
    ``peak_index`` the resonance point (-1: none), ``band_hz`` the band asked for."""
    from types import SimpleNamespace

    branch = SimpleNamespace(status=np.asarray(status), band_hz=band_hz)
    case = SimpleNamespace(
        freq_hz=np.asarray(freq_hz, dtype=float),
        branch=branch,
        side=np.asarray(side),
        h1_peak_index=int(peak_index),
    )
    _status_panel(ax, case, side_labels)


@styled
def plot_status_map(
    cases: Sequence[CaseResult],
    path: str | Path,
    *,
    title: str | None = None,
    panel_notes: Sequence[str] | None = None,
    footnote: str | None = None,
) -> Path:
    """Contact status of every pair vs frequency for one damper and family (paper Fig. 12).

    One panel per case (e.g. 9.6 N and 30 N), pairs on y (side 0 first,
    then side 1 above the dashed line), frequency on x, colour the status;
    the dashed black line marks the resonance (the harmonic-1 peak).
    ``panel_notes``: one line per case added under its panel title ("" for
    none); ``footnote``: a paragraph under the legend (wrapped to the width).
    """
    cases = _one_set(cases, "cases")
    if panel_notes is not None and len(panel_notes) != len(cases):
        raise InputError("panel_notes", len(panel_notes), f"one per case ({len(cases)})")
    plt = pyplot()
    n = len(cases)
    windows = [status_zoom(c) for c in cases]
    spans = [float(np.ptp(c.freq_hz)) if c.branch.n_points else 0.0 for c in cases]
    zoom = all(
        w is not None and s > 0 and (w[1] - w[0]) < ZOOM_MAX_SHARE * s
        for w, s in zip(windows, spans, strict=True)
    )
    rows = 2 if zoom else 1
    width, note = 3.9 * n + 0.6, None
    if footnote:  # as the legend's title: the layout keeps it clear of the panels and the key
        import textwrap

        # about 0.5 em per character at 8.5 pt, across 95 % of the figure's width
        note = textwrap.fill(footnote, int(0.95 * width * 72 / (0.5 * 8.5)))
    extra_h = 0.0 if note is None else (note.count("\n") + 1) * 8.5 * 1.25 / 72
    fig, axes = plt.subplots(
        rows,
        n,
        figsize=(width, (4.6 if rows == 1 else 7.6) + extra_h),
        sharey=True,
        layout="constrained",
        squeeze=False,
        height_ratios=[1, 1.25] if zoom else None,
    )
    for k, c in enumerate(cases):
        for row in range(rows):
            ax = axes[row, k]
            _status_panel(ax, c, side_labels=k == n - 1)
            ax.set_xlabel("frequency (Hz)")
        i = c.h1_peak_index
        head = f"F = {c.force_n:g} N" + (f", peak at {c.freq_hz[i]:.1f} Hz" if i >= 0 else "")
        if c.branch.failed:
            head += (
                f"\nbranch failed at {c.freq_hz[-1]:.1f} Hz"
                if c.branch.n_points
                else "\nbranch failed"
            )
        if panel_notes is not None and panel_notes[k]:
            head += "\n" + panel_notes[k]
        axes[0, k].set_title(head, fontsize=10)
        if zoom:
            w0, w1 = windows[k]
            axes[1, k].set_xlim(w0, w1)
            axes[1, k].set_title(
                f"zoom: {w0:.1f}-{w1:.1f} Hz, where pairs slip or open", fontsize=9
            )
            axes[0, k].axvspan(w0, w1, facecolor="none", edgecolor="0.2", lw=1.0, ls="--", zorder=3)
    for row in range(rows):
        axes[row, 0].set_ylabel("contact pair number")
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    extra = [
        Patch(
            facecolor=NOT_COMPUTED_COLOR,
            edgecolor=NOT_COMPUTED_EDGE,
            hatch="////",
            label="not computed (no point)",
        ),
        Line2D([], [], **_RESONANCE, label="resonance (harmonic-1 peak)"),
    ]
    fig.legend(
        handles=status_legend_handles() + extra,
        loc="outside lower center",
        ncol=6,
        frameon=False,
        title=note,
        title_fontsize=8.5,
    )
    c0 = cases[0]
    fig.suptitle(title or f"{c0.damper} damper, {c0.family}: contact status of every pair")
    return save_figure(fig, path)


@styled
def plot_status_shares(
    cases: Sequence[CaseResult], path: str | Path, *, title: str | None = None
) -> Path:
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
            ax.plot(
                forces, v, color=STATUS_COLORS[k], ls=ls, marker=mk, ms=5, lw=1.8, mec=STATUS_EDGE
            )
    from matplotlib.lines import Line2D

    fs = np.array(forces_all)
    if fs.size > 1 and fs.max() / fs.min() > 5:
        ax.set_xscale("log")
    ax.set(
        xlabel="excitation force F (N)",
        ylabel="share of contact pairs at resonance (%)",
        ylim=(-3, 103),
        title=title or f"{cases[0].family}: contact status at resonance",
    )
    _readable_log(ax, "x")
    handles = [
        Line2D(
            [],
            [],
            color=STATUS_COLORS[k],
            lw=2.5,
            label=STATUS_NAMES[k] + ("" if seen[k] else " (none)"),
        )
        for k in range(4)
    ]
    _side_legends(
        fig,
        (handles, "status"),
        (
            [
                (d, dict(color="0.3", ls=damper_style(d)[1], marker=damper_style(d)[2]))
                for d in _dampers(cases)
            ],
            "damper",
        ),
    )
    return save_figure(fig, path)
