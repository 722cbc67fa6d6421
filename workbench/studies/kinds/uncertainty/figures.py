"""Figures of the uncertainty study: distributions, exceedance, Sobol tornado, scatter, schedule.

Plain inputs: the design (:class:`workbench.post.uncertainty.Design`),
the per (damper, phase) outputs and the analysis dict of
:func:`workbench.studies.kinds.uncertainty.compute.analyse`. One PNG per function, fixed
size, no time stamp. Dampers keep one colour throughout.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from ....post.results import family_name
from ....render.common import pyplot, save_figure
from ....render.palette import damper_color

QUANTITIES = (
    ("peak_amplitude_mm", "peak amplitude, mm"),
    ("peak_frequency_hz", "resonance frequency, Hz"),
    ("friction_energy_mj", "friction energy per cycle, mJ"),
)


def _color(d: str, k: int = 0) -> str:
    """The damper's colour of every figure (render/palette.py); ``k`` is unused."""
    return damper_color(d)


def _families(results: dict[tuple, dict]) -> list[float]:
    return list(dict.fromkeys(ph for _, ph in results))


def _dampers(results: dict[tuple, dict]) -> list[str]:
    return list(dict.fromkeys(d for d, _ in results))


def plot_violins(design, results: dict[tuple, dict], path: str | Path) -> Path:
    """Violins of each quantity (rows) per family (columns), the dampers side by side.

    The A and B rows of the design (2 N draws); a bar marks the 95th percentile.
    """
    plt = pyplot()
    fams, dampers = _families(results), _dampers(results)
    ab = design.ab_rows
    fig, axes = plt.subplots(
        len(QUANTITIES), len(fams), figsize=(4.2 * len(fams) + 1, 9.0), squeeze=False
    )
    for j, ph in enumerate(fams):
        for i, (q, label) in enumerate(QUANTITIES):
            ax = axes[i, j]
            data, pos, cols = [], [], []
            for k, d in enumerate(dampers):
                g = results.get((d, ph))
                if g is None:
                    continue
                y = np.where(np.asarray(g["failed"])[ab], np.nan, g[q][ab])
                y = y[np.isfinite(y)]
                if y.size == 0:
                    continue
                data.append(y)
                pos.append(k)
                cols.append(_color(d, k))
            if data:
                if all(np.ptp(y) > 0 for y in data):
                    parts = ax.violinplot(
                        data, positions=pos, widths=0.8, showmedians=True, showextrema=True
                    )
                    for body, c in zip(parts["bodies"], cols, strict=True):
                        body.set_facecolor(c)
                        body.set_alpha(0.45)
                    for key in ("cmedians", "cmins", "cmaxes", "cbars"):
                        parts[key].set_color("#333333")
                        parts[key].set_linewidth(0.8)
                else:
                    ax.boxplot(data, positions=pos, widths=0.5)
                for p, y, c in zip(pos, data, cols, strict=True):
                    ax.plot([p - 0.3, p + 0.3], [np.quantile(y, 0.95)] * 2, color=c, lw=2.2)
                    ax.scatter(
                        np.full(y.size, p) + (np.random.default_rng(p).random(y.size) - 0.5) * 0.18,
                        y,
                        s=5,
                        color="k",
                        alpha=0.35,
                        lw=0,
                    )
            ax.set_xticks(range(len(dampers)))
            ax.set_xticklabels(dampers)
            ax.set_xlim(-0.6, len(dampers) - 0.4)
            if j == 0:
                ax.set_ylabel(label)
            if i == 0:
                ax.set_title(family_name(ph))
    fig.suptitle(
        f"Response over {len(ab)} samples (violin, median; thick bar: 95th percentile)", fontsize=11
    )
    fig.tight_layout()
    return save_figure(fig, path)


def plot_exceedance(
    design, results: dict[tuple, dict], thresholds: dict[str, float | None], path: str | Path
) -> Path:
    """P(peak > x) against x per damper, one panel per family; the family's threshold dashed.

    Samples whose solve stopped early (``failed``) are left out.
    """
    plt = pyplot()
    fams, dampers = _families(results), _dampers(results)
    ab = design.ab_rows
    fig, axes = plt.subplots(1, len(fams), figsize=(5.2 * len(fams), 3.9), squeeze=False)
    for j, ph in enumerate(fams):
        ax = axes[0, j]
        for k, d in enumerate(dampers):
            g = results.get((d, ph))
            if g is None:
                continue
            y = np.where(np.asarray(g["failed"])[ab], np.nan, g["peak_amplitude_mm"][ab])
            y = np.sort(y[np.isfinite(y)])
            if y.size == 0:
                continue
            p = 1.0 - np.arange(1, y.size + 1) / y.size
            ax.step(np.r_[y[0], y], np.r_[1.0, p], where="post", color=_color(d, k), label=d)
            ax.plot([np.quantile(y, 0.95)] * 2, [0, 0.05], color=_color(d, k), lw=2.5)
        threshold = thresholds.get(family_name(ph))
        if threshold is not None:
            ax.axvline(threshold, color="k", ls="--", lw=1, label=f"threshold {threshold:.3g} mm")
        ax.axhline(0.05, color="0.5", ls=":", lw=1)
        ax.set_xlabel("peak amplitude x, mm")
        ax.set_ylabel("P(peak > x)")
        ax.set_ylim(-0.02, 1.02)
        ax.set_title(family_name(ph))
        ax.legend(loc="upper right")
    fig.suptitle(
        "Exceedance probability of the peak (ticks at the bottom: 95th percentiles)", fontsize=11
    )
    fig.tight_layout()
    return save_figure(fig, path)


def plot_tornado(
    analysis: dict[str, Any], path: str | Path, quantity: str = "peak_amplitude_mm"
) -> Path:
    """Sobol total (bar) and first-order (dark bar) indices of ``quantity`` per damper and family.

    Inputs sorted by total-order index; whiskers: SALib's 95% bootstrap half-widths.
    """
    plt = pyplot()
    groups = analysis["groups"]
    fams = list(dict.fromkeys(r["family"] for r in groups))
    dampers = list(dict.fromkeys(r["damper"] for r in groups))
    fig, axes = plt.subplots(
        len(dampers),
        len(fams),
        figsize=(4.8 * len(fams) + 0.6, 2.3 * len(dampers) + 0.8),
        squeeze=False,
    )
    for r in groups:
        ax = axes[dampers.index(r["damper"]), fams.index(r["family"])]
        ind = r["indices"][quantity]
        st = np.nan_to_num(np.asarray(ind["ST"], float))
        s1 = np.nan_to_num(np.asarray(ind["S1"], float))
        stc = np.nan_to_num(np.asarray(ind["ST_conf"], float))
        order = np.argsort(st)
        y = np.arange(len(order))
        c = _color(r["damper"], dampers.index(r["damper"]))
        ax.barh(
            y,
            st[order],
            color=c,
            alpha=0.4,
            label="total ST",
            xerr=stc[order],
            error_kw={"lw": 0.8, "capsize": 2},
        )
        ax.barh(y, np.clip(s1[order], 0, None), height=0.45, color=c, label="first order S1")
        ax.set_yticks(y)
        ax.set_yticklabels([ind["names"][i] for i in order])
        ax.set_xlim(0, max(1.0, float(np.max(st + stc)) if st.size else 1.0))
        ax.set_title(f"{r['damper']}, {r['family']} (N = {ind['n_used']})", fontsize=10)
        ax.axvline(0, color="k", lw=0.6)
    axes[0, 0].legend(loc="lower right")
    for ax in axes[-1]:
        ax.set_xlabel("Sobol index of the peak amplitude")
    fig.suptitle("Which input drives the spread of the peak", fontsize=11)
    fig.tight_layout()
    return save_figure(fig, path)


def plot_scatter(
    design, results: dict[tuple, dict], analysis: dict[str, Any], path: str | Path
) -> Path:
    """Peak amplitude against each group's most influential input (every design row)."""
    plt = pyplot()
    groups = analysis["groups"]
    n = len(groups)
    cols = min(3, n)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.3 * cols, 3.4 * rows), squeeze=False)
    dampers = list(dict.fromkeys(r["damper"] for r in groups))
    for k, r in enumerate(groups):
        ax = axes[k // cols, k % cols]
        g = results[(r["damper"], r["phase_deg"])]
        name = r["driver"] or design.names[0]
        j = list(design.names).index(name)
        x = design.values[:, j]
        y = g["peak_amplitude_mm"]
        failed = np.asarray(g["failed"], bool) & np.isfinite(y)
        ok = np.isfinite(y) & ~failed
        c = _color(r["damper"], dampers.index(r["damper"]))
        ax.scatter(x[ok], y[ok], s=10, color=c, alpha=0.7, lw=0)
        if failed.any():
            ax.scatter(
                x[failed],
                y[failed],
                s=16,
                marker="x",
                color="k",
                label="solve stopped early\n(highest point reached)",
            )
            ax.legend(loc="best")
        ax.set_xlabel(_input_label(name))
        ax.set_ylabel("peak amplitude, mm")
        ax.set_title(f"{r['damper']}, {r['family']}", fontsize=10)
    for k in range(n, rows * cols):
        axes[k // cols, k % cols].axis("off")
    fig.suptitle("Peak amplitude against the most influential input (largest ST)", fontsize=11)
    fig.tight_layout()
    return save_figure(fig, path)


def _input_label(name: str) -> str:
    from ....post.uncertainty import INPUT_LABELS

    return INPUT_LABELS.get(name, name)


def plot_schedule(records: list[dict[str, Any]], path: str | Path, title: str = "") -> Path:
    """Gantt chart of the samples on each rank (one bar per sample, its wall time)."""
    plt = pyplot()
    ranks = sorted({r["rank"] for r in records})
    fig, ax = plt.subplots(figsize=(9.0, 0.7 * len(ranks) + 1.6))
    for r in records:
        c = (
            "#e15759"
            if r.get("hbm_s", 0) > 3 * np.median([x.get("hbm_s", 0) for x in records])
            else "#4e79a7"
        )
        ax.barh(
            r["rank"],
            r["end"] - r["start"],
            left=r["start"],
            height=0.6,
            color=c,
            edgecolor="white",
            lw=0.4,
        )
    ax.set_yticks(ranks)
    ax.set_yticklabels([f"rank {q}" for q in ranks])
    ax.set_xlabel("wall time since the samples started, s")
    ax.set_title(title or "Samples on each rank (red: more than 3x the median cost)", fontsize=10)
    fig.tight_layout()
    return save_figure(fig, path)


def uncertainty_figures(
    figdir: str | Path, design, results: dict[tuple, dict], analysis: dict[str, Any]
) -> list[dict[str, str]]:
    """Every figure of the study; ``[{"id", "path" (relative to the study), "caption"}]``."""
    figdir = Path(figdir)
    made = []
    plot_violins(design, results, figdir / "uq_distributions.png")
    made.append(
        {
            "id": "violins",
            "path": "figures/uq_distributions.png",
            "caption": "Peak amplitude, resonance frequency and friction energy over the samples, "
            "the three dampers side by side in each family; thick bar: 95th percentile.",
        }
    )
    plot_exceedance(design, results, analysis["thresholds_mm"], figdir / "uq_exceedance.png")
    made.append(
        {
            "id": "exceedance",
            "path": "figures/uq_exceedance.png",
            "caption": "Probability that the peak amplitude exceeds x; dashed: the threshold.",
        }
    )
    plot_tornado(analysis, figdir / "uq_sobol_peak.png")
    made.append(
        {
            "id": "tornado",
            "path": "figures/uq_sobol_peak.png",
            "caption": "Sobol indices of the peak amplitude (SALib): total order (light, with 95% "
            "bootstrap whiskers) and first order (dark).",
        }
    )
    plot_scatter(design, results, analysis, figdir / "uq_scatter.png")
    made.append(
        {
            "id": "scatter",
            "path": "figures/uq_scatter.png",
            "caption": "Peak amplitude of every sample against its group's most influential input.",
        }
    )
    rec = figdir.parent / "tables" / "schedule_records.json"
    if rec.is_file():
        records = json.loads(rec.read_text())
        if records:
            plot_schedule(records, figdir / "uq_schedule.png")
            made.append(
                {
                    "id": "schedule",
                    "path": "figures/uq_schedule.png",
                    "caption": "The last run's samples on each rank (dynamic: a "
                    "rank takes the next "
                    "sample when it is free).",
                }
            )
    return made
