"""Frequency response curves of the harmonic balance (matplotlib, Agg).

:func:`plot_frf` draws one curve per excitation level (stable parts solid,
unstable parts dashed, parts of unknown stability dotted grey, the peak
marked); :func:`plot_status_map` draws the contact status of every element
along a branch (frequency on x, element on y), in the manner of the
contact-status charts of "On the efficiency of a conical under-platform
damper for turbines". Both take branches
(:class:`workbench.hbm.Branch`) and write a PNG.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .common import pyplot, save_figure

STATUS_COLORS = ("#2b6cb0", "#d9822b", "#7cb342", "#9e9e9e")
STATUS_LABELS = ("stuck", "stick-slip", "partial separation", "full separation")


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) index ranges of equal values in an array (stop exclusive)."""
    if mask.size == 0:
        return []
    edges = np.flatnonzero(np.diff(mask.astype(int))) + 1
    starts = np.concatenate([[0], edges])
    stops = np.concatenate([edges, [mask.size]])
    return list(zip(starts, stops, strict=True))


def plot_frf(
    branches: Sequence,
    path: str | Path,
    *,
    output: int = 0,
    unit_scale: float = 1.0,
    unit: str = "m",
    title: str = "",
    per_level: bool = False,
) -> Path:
    """Output amplitude against frequency for each branch; unstable parts dashed.

    ``unit_scale`` multiplies the amplitudes (1e3 for mm from m);
    ``per_level`` divides them by the excitation level (a receptance).
    """
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    colors = plt.cm.viridis(np.linspace(0.05, 0.9, max(len(branches), 1)))
    for b, col in zip(branches, colors, strict=False):
        if b.n_points == 0:
            continue
        f = b.freq_hz
        a = b.out_amp[:, output] * unit_scale / (b.level if per_level and b.level else 1.0)
        label = f"level {b.level:g}" + (" (failed)" if b.failed else "")
        first = True
        verdict = np.asarray(b.stability)
        for s, e in _runs(verdict):
            seg = slice(max(s - 1, 0), e)  # join the segments
            v = int(verdict[s])
            ax.plot(
                f[seg],
                a[seg],
                {1: "-", 0: "--"}.get(v, ":"),
                color=col if v >= 0 else "0.55",
                lw=1.4 if v >= 0 else 1.8,
                label=label if first else None,
            )
            first = False
        i = b.peak(output)
        ax.plot(f[i], a[i], "o", color=col, ms=4, mfc=col if b.stable[i] else "white")
        if b.failed:
            ax.plot(f[-1], a[-1], "x", color=col, ms=7)
    name = branches[0].output_names[output] if branches and branches[0].output_names else "output"
    ylab = f"{name} amplitude / level ({unit}/N)" if per_level else f"{name} amplitude ({unit})"
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel(ylab)
    ax.set_title(
        title or "frequency response (solid: stable, dashed: unstable, dotted grey: unknown)"
    )
    if any(b.n_points for b in branches):
        ax.legend(loc="best")
    return save_figure(fig, path)


def plot_status_map(branch, path: str | Path, title: str = "") -> Path:
    """Contact status of every element (y) at every point (x: frequency) of a branch.

    One square marker per element and point, coloured by status; points on
    a folded branch share frequencies and are drawn in continuation order.
    """
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    st = np.asarray(branch.status, dtype=int)
    if st.size:
        n_pts, n_el = st.shape
        f = np.repeat(branch.freq_hz, n_el)
        e = np.tile(np.arange(1, n_el + 1), n_pts)
        colors = np.asarray(STATUS_COLORS)[st.ravel()]
        size = float(np.clip(2.5e4 / max(n_pts * n_el, 1), 4, 60))
        ax.scatter(f, e, c=colors, marker="s", s=size, linewidths=0)
        ax.set_ylim(0.5, n_el + 0.5)
        from matplotlib.ticker import MaxNLocator

        ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    handles = [plt.Rectangle((0, 0), 1, 1, color=c) for c in STATUS_COLORS]
    ax.legend(handles, STATUS_LABELS, loc="upper right", fontsize=7)
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("contact element")
    ax.set_title(title or f"contact status, level {branch.level:g}")
    return save_figure(fig, path)
