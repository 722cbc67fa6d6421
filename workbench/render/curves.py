"""Frequency response curves of the harmonic balance (matplotlib, no pyplot state).

:func:`plot_frf` draws one curve per excitation level (stable parts solid,
unstable parts dashed, parts of unknown stability dotted, as
:data:`workbench.render.palette.VERDICTS` draws them; the peak marked);
:func:`plot_status_map` draws the contact status of every element along a
branch (frequency on x, element on y), in the manner of the
contact-status charts of "On the efficiency of a conical under-platform
damper for turbines". Both take branches
(:class:`workbench.hbm.Branch`) and write a PNG.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .common import pyplot, readable_log, save_figure, styled
from .palette import (
    STATUS_COLORS,
    STATUS_NAMES,
    marker_kwargs,
    verdict,
    verdict_counts,
    verdict_legend,
    verdict_runs,
)

STATUS_LABELS = STATUS_NAMES


@styled
def plot_frf(
    branches: Sequence,
    path: str | Path | None,
    *,
    output: int = 0,
    unit_scale: float = 1.0,
    unit: str = "m",
    title: str = "",
    per_level: bool = True,
    force_per_level_n: float = 1.0,
    log: bool = True,
) -> Path:
    """Receptance (amplitude per newton) against frequency, one curve per force level.

    Each branch's force amplitude is ``level * force_per_level_n`` (N: the
    largest harmonic force of the model per unit level). ``per_level``
    divides the amplitude by it, so curves of different forces lie on one
    another while the contact sticks and part where it slips; the log axis
    (``log``) shows both ends of that story. Every computed point is a dot
    on its curve; unstable parts are dashed, the peak is circled (hollow:
    unstable), a cross marks where a branch failed.
    ``unit_scale`` multiplies the amplitudes (1e3 for mm from m).
    """
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    colors = plt.cm.viridis(np.linspace(0.05, 0.9, max(len(branches), 1)))
    for b, col in zip(branches, colors, strict=False):
        if b.n_points == 0:
            continue
        f = b.freq_hz
        force = b.level * force_per_level_n
        a = b.out_amp[:, output] * unit_scale / (force if per_level and force else 1.0)
        label = f"F = {force:.3g} N" + (" (failed)" if b.failed else "")
        first = True
        for seg, code in verdict_runs(np.asarray(b.stability)):
            ax.plot(
                f[seg],
                a[seg],
                color=col,
                ls=verdict(code).ls,
                lw=1.4,
                label=label if first else None,
            )
            first = False
        ax.plot(f, a, ".", color=col, ms=2.5)  # the computed points
        i = b.peak(output)
        ax.plot(f[i], a[i], **marker_kwargs(int(b.stability[i]), col, "o"))
        if b.failed:
            ax.plot(f[-1], a[-1], "x", color=col, ms=7)
    name = branches[0].output_names[output] if branches and branches[0].output_names else "output"
    ylab = (
        f"receptance: {name} max |y(t)| / F ({unit}/N)"
        if per_level
        else f"{name}: largest |y(t)| over the period ({unit})"
    )
    if log and any(b.n_points for b in branches):
        ax.set_yscale("log")
        readable_log(ax, "y")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel(ylab)
    ax.set_title(title or "frequency response")
    if any(b.n_points for b in branches):
        from matplotlib.lines import Line2D

        handles, labels = ax.get_legend_handles_labels()
        counts = verdict_counts(np.concatenate([np.asarray(b.stability) for b in branches]))
        handles += [Line2D([], [], label=lab, **kw) for lab, kw in verdict_legend(counts)]
        handles.append(Line2D([], [], color="0.3", ls="none", marker="o", label="peak"))
        ax.legend(handles=handles, loc="best", title="force; stability (Hill)")
    return save_figure(fig, path)


@styled
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
    handles = [plt.Rectangle((0, 0), 1, 1, facecolor=c, edgecolor="0.25") for c in STATUS_COLORS]
    ax.legend(handles, STATUS_LABELS, loc="upper right", fontsize=7)
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("contact element")
    ax.set_title(title or f"contact status, level {branch.level:g}")
    return save_figure(fig, path)
