"""Figures of the robustness study: the methods x cases failure map, the branches, HBM vs time.

Plain inputs (the cell records of :mod:`workbench.studies.kinds.robustness.compute`), one
PNG per function, fixed size, no time stamp. Colours: ok green, wrong
answer orange, failed red (the map); HBM branches with their unstable
pieces dashed, as in :mod:`.study_figures`.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ....render.common import pyplot, save_figure, styled
from ....render.palette import VERDICTS
from ....render.palette import verdict as palette_verdict

STATUS_STYLE = {
    "ok": ("#59a14f", "ok"),
    "wrong": ("#f28e2b", "wrong answer"),
    "failed": ("#e15759", "failed"),
}
_METHOD_COLORS = (
    "#1f6fb4",
    "#ff7f0e",
    "#2ca02c",
    "#9467bd",
    "#8c564b",
    "#e377c2",
    "#17becf",
    "#7f7f7f",
    "#bcbd22",
    "#d62728",
)


def _cell_text(c: dict[str, Any]) -> str:
    t = f"{c['newton_its']} its\n{c['wall_s']:.1f} s"
    if c["status"] == "failed":
        fr = c.get("freq_reached_hz")
        t += f"\nstop {fr:.1f} Hz" if fr is not None else "\nno point"
    elif c.get("amp_dev_pct") is not None:
        t += f"\ndA {c['amp_dev_pct']:+.2g}%"
    elif c.get("reference"):
        t += "\nreference"
    return t


@styled
def plot_failure_map(
    cells: Sequence[dict[str, Any]], methods: Sequence[str], cases: Sequence[str], path: str | Path
) -> Path:
    """Grid of methods (rows) x cases (columns): colour = status, text = iterations and time."""
    from matplotlib.patches import Patch

    plt = pyplot()
    nm, nc = len(methods), len(cases)
    fig, ax = plt.subplots(figsize=(max(6.0, 1.55 * nc + 2.2), max(3.0, 0.62 * nm + 1.4)))
    by = {(c["method"], c["case"]): c for c in cells}
    for i, m in enumerate(methods):
        for j, k in enumerate(cases):
            c = by.get((m, k))
            if c is None:
                continue
            color = STATUS_STYLE[c["status"]][0]
            ax.add_patch(
                plt.Rectangle((j, i), 1, 1, facecolor=color, edgecolor="white", lw=2, alpha=0.9)
            )
            ax.text(
                j + 0.5,
                i + 0.5,
                _cell_text(c),
                ha="center",
                va="center",
                fontsize=6.8,
                color="black",
            )
    ax.set_xlim(0, nc)
    ax.set_ylim(nm, 0)
    ax.set_xticks(np.arange(nc) + 0.5)
    ax.set_xticklabels(cases, rotation=20, ha="right")
    ax.set_yticks(np.arange(nm) + 0.5)
    ax.set_yticklabels(methods)
    ax.grid(False)
    ax.tick_params(length=0)
    for s in ax.spines.values():
        s.set_visible(False)
    ax.set_title("robustness: solution methods x hard cases")
    handles = [Patch(color=v[0], label=v[1]) for v in STATUS_STYLE.values()]
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    return save_figure(fig, path)


def _draw(ax, f, a, stable, color, label, lw=1.2, ls="-"):
    f, a = np.asarray(f, float), np.asarray(a, float)
    st = np.asarray(stable, bool)
    ax.plot(f, a, color=color, lw=lw, ls=ls, label=label)
    if st.size and (~st).any():
        au = np.where(st, np.nan, a)
        ax.plot(f, au, color="0.55", lw=5.0, alpha=0.35, solid_capstyle="round", zorder=1)


@styled
def plot_branches(cells: Sequence[dict[str, Any]], cases: Sequence[str], path: str | Path) -> Path:
    """One panel per hard case: every method's branch (mm against Hz); failures end with x."""
    plt = pyplot()
    n = len(cases)
    ncol = min(3, n)
    nrow = int(np.ceil(n / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.3 * ncol, 3.1 * nrow), squeeze=False)
    methods = list(dict.fromkeys(c["method"] for c in cells))
    colors = {m: _METHOD_COLORS[i % len(_METHOD_COLORS)] for i, m in enumerate(methods)}
    for k, case in enumerate(cases):
        ax = axes[k // ncol][k % ncol]
        for c in cells:
            if c["case"] != case or not c.get("freq_hz"):
                continue
            a = 1e3 * np.asarray(c["amp"])
            lw = 2.4 if c.get("reference") else 1.0
            _draw(ax, c["freq_hz"], a, c["stable"], colors[c["method"]], c["method"], lw=lw)
            if c["status"] == "failed":
                ax.plot(c["freq_hz"][-1], a[-1], "x", color=colors[c["method"]], ms=8, mew=2)
        ax.set_title(case, fontsize=9)
        ax.set_xlabel("frequency, Hz")
        ax.set_ylabel("blade 1 peak, mm")
    for k in range(n, nrow * ncol):
        axes[k // ncol][k % ncol].set_visible(False)
    h, lab = axes[0][0].get_legend_handles_labels()
    fig.legend(
        h,
        lab,
        loc="lower center",
        ncol=min(5, len(lab)) or 1,
        frameon=False,
        bbox_to_anchor=(0.5, -0.02 - 0.03 * (len(lab) // 5)),
    )
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    return save_figure(fig, path)


@styled
def plot_hbm_vs_time(checks: Sequence[dict[str, Any]], path: str | Path) -> Path:
    """One panel per small model: the HBM branch and the time-integration amplitudes.

    The models' DOFs are in metres; amplitudes are drawn in mm, as in every
    other figure of the workbench.
    """
    plt = pyplot()
    n = len(checks)
    fig, axes = plt.subplots(1, n, figsize=(max(4.6 * n, 7.0), 3.8), squeeze=False)
    for ax, ch in zip(axes[0], checks, strict=True):
        f = np.asarray(ch["freq_hz"])
        a = 1e3 * np.asarray(ch["amp"])  # m -> mm
        v = np.asarray(ch["stability"], int)  # Hill's verdicts (render/palette.VERDICTS)
        # the stable verdict first: the others are drawn over it, so that one point shows
        for code in sorted({*(x.code for x in VERDICTS), *v.tolist()}, key=lambda k: k != 1):
            verdict = palette_verdict(code)
            # each piece runs to the next point, so that isolated points still show
            m = (v == code) | np.r_[False, v[:-1] == code]
            ax.plot(
                f,
                np.where(m, a, np.nan),
                label=f"HBM ({verdict.label}, Hill)",
                color="0.15",
                lw=1.4,
                ls=verdict.ls,
            )
        for r in ch["points"]:
            filled = r["ti_converged"]
            ax.plot(
                r["freq_hz"],
                1e3 * r["ti_amplitude"],
                "o",
                ms=7,
                mew=1.5,
                color="#e15759",
                mfc="#e15759" if filled else "none",
            )
            label = f"{r['diff_pct']:+.2g}%"
            near = r.get("diff_nearest_pct")
            if near is not None and abs(near - r["diff_pct"]) > 1e-9:
                label += f" (nearest {near:+.2g}%)"
            ax.annotate(
                label,
                (r["freq_hz"], 1e3 * r["ti_amplitude"]),
                textcoords="offset points",
                xytext=(5, 4),
                fontsize=7,
            )
        ax.plot([], [], "o", color="#e15759", label="time integration (periodic)")
        ax.plot([], [], "o", color="#e15759", mfc="none", label="time integration (not periodic)")
        ax.set_title(f"{ch['model']} ({ch['n_dofs']} DOFs)", fontsize=9)
        ax.set_xlabel("frequency (Hz)")
        ax.set_ylabel("peak |y| (mm)")
        ax.margins(y=0.12)
    h, lab = axes[0][0].get_legend_handles_labels()
    fig.legend(h, lab, loc="lower center", ncol=4, frameon=False, fontsize=8)
    fig.tight_layout(rect=(0, 0.1, 1, 1))
    return save_figure(fig, path)
