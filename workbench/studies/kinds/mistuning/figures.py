"""The mistuning study's charts: the amplification factor's distribution per configuration,
the comparison of no damper / damper stuck / damper in friction with Whitehead's bound, and
the worst pattern's forced response of every blade. Plain inputs (arrays, dicts keyed by
``(damper, eo, config)``): no study module.

A *configuration* is ``"none"`` (no damper, linear), ``"stuck"`` (the damper stuck,
linear) or a friction force (``"friction"`` at a force, harmonic balance); ``configs`` is the
list of ``(key, label)`` in drawing order.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ....render.common import pyplot, readable_log, save_figure, styled
from ....render.palette import damper_color

LINEAR_COLORS = {"none": "#7f7f7f", "stuck": "#1f77b4"}


def config_colors(configs: list[tuple[str, str]]) -> dict[str, str]:
    """A colour per configuration: grey (no damper), blue (stuck), and the friction forces
    from dark red to orange."""
    import matplotlib

    fric = [k for k, _ in configs if k not in LINEAR_COLORS]
    cmap = matplotlib.colormaps["autumn"]
    out = dict(LINEAR_COLORS)
    for i, k in enumerate(fric):
        out[k] = matplotlib.colors.to_hex(cmap(0.65 * i / max(1, len(fric) - 1)))
    return out


def _grid(plt, rows: int, cols: int, w: float, h: float, **kw):
    fig, axes = plt.subplots(rows, cols, figsize=(w * cols + 0.6, h * rows + 0.4), **kw)
    return fig, np.asarray(axes).reshape(rows, cols)


@styled
def plot_af_histograms(
    dampers: list[str],
    eos: list[int],
    configs: list[tuple[str, str]],
    af: dict[tuple, np.ndarray],
    bound: float,
    n_blades: int,
    path: str | Path | None,
) -> Any:
    """Per damper (columns) and EO (rows) the histogram of the amplification factor over the
    patterns, one outline per configuration, its 95th percentile a vertical line; Whitehead's
    bound a dashed black line."""
    from matplotlib.ticker import MaxNLocator

    plt = pyplot()
    colors = config_colors(configs)
    fig, axes = _grid(plt, len(eos), len(dampers), 4.4, 3.4, squeeze=False, sharex=True)
    every = np.concatenate([np.asarray(a, float) for a in af.values()] + [np.array([1.0, bound])])
    every = every[np.isfinite(every)]
    bins = np.linspace(min(0.9, every.min()), max(bound, every.max()) * 1.02, 31)
    for r, e in enumerate(eos):
        for c, d in enumerate(dampers):
            ax = axes[r, c]
            for i, (k, label) in enumerate(configs):
                a = np.asarray(af.get((d, e, k), []), float)
                a = a[np.isfinite(a)]
                if not len(a):
                    continue
                p95 = float(np.percentile(a, 95))
                # thinner in drawing order: a configuration equal to an earlier one (a damper
                # that stays stuck) shows on top of it without hiding it
                lw = max(3.0 - 0.7 * i, 1.0)
                ax.hist(a, bins=bins, histtype="step", lw=lw, color=colors[k], label=label)
                ax.axvline(p95, color=colors[k], lw=1.0, ls=":")
            ax.axvline(bound, color="k", ls="--", lw=1.2, label=f"Whitehead bound {bound:.2f}")
            ax.axvline(1.0, color="k", lw=0.6, alpha=0.5)
            ax.set_title(f"{d}, EO {e}")
            ax.yaxis.set_major_locator(MaxNLocator(integer=True))
            ax.grid(True, alpha=0.3)
            if r == len(eos) - 1:
                ax.set_xlabel("amplification factor (worst blade / tuned peak)")
            if c == 0:
                ax.set_ylabel("patterns")
    axes[0, -1].legend(fontsize=7, loc="upper right", title="dotted: 95th percentile")
    fig.suptitle(f"Amplification factor over the mistuning patterns, {n_blades} blades")
    fig.tight_layout()
    return save_figure(fig, path)


@styled
def plot_af_comparison(
    dampers: list[str],
    eos: list[int],
    configs: list[tuple[str, str]],
    af: dict[tuple, np.ndarray],
    worst_peak_m: dict[tuple, np.ndarray],
    lower: dict[tuple, np.ndarray],
    bound: float,
    n_blades: int,
    path: str | Path | None,
) -> Any:
    """Top row: per damper (and EO) every pattern's amplification factor per configuration
    (dots), its 95th percentile (bar) and maximum (triangle), Whitehead's bound dashed.
    Bottom row: the worst blade's peak per newton of force (µm/N, log scale), 95th percentile
    and maximum. Patterns whose curve stopped early or peaks on the band edge (their peak a
    lower bound) are ringed."""
    plt = pyplot()
    colors = config_colors(configs)
    cols = [(d, e) for d in dampers for e in eos]
    fig, axes = _grid(plt, 2, len(cols), 4.2, 3.6, squeeze=False, sharey="row")
    rng = np.random.default_rng(0)  # jitter of the dots only
    ringed = False
    for c, (d, e) in enumerate(cols):
        for row, (data, scale) in enumerate(((af, 1.0), (worst_peak_m, 1e6))):
            ax = axes[row, c]
            for i, (k, _) in enumerate(configs):
                v = np.asarray(data.get((d, e, k), []), float) * scale
                ok = np.isfinite(v)
                if not ok.any():
                    continue
                x = i + rng.uniform(-0.18, 0.18, len(v))
                ax.plot(x[ok], v[ok], ".", color=colors[k], alpha=0.45, ms=4)
                lo = np.asarray(lower.get((d, e, k), np.zeros(len(v), bool)), bool) & ok
                if lo.any():
                    ringed = True
                    ax.plot(x[lo], v[lo], "o", mfc="none", mec="k", ms=7)
                p95, top = np.percentile(v[ok], 95), v[ok].max()
                ax.plot([i - 0.3, i + 0.3], [p95, p95], "-", color=colors[k], lw=2.5)
                ax.plot(i, top, "v", color=colors[k], mec="k", ms=7)
            ax.set_xticks(range(len(configs)))
            ax.set_xticklabels([lab for _, lab in configs], rotation=20, fontsize=8)
            ax.grid(True, alpha=0.3)
            if row == 0:
                ax.axhline(bound, color="k", ls="--", lw=1.2)
                ax.axhline(1.0, color="k", lw=0.6, alpha=0.5)
                ax.set_title(f"{d}, EO {e}")
            else:
                ax.set_yscale("log")
                readable_log(ax, "y")
        if c == 0:
            axes[0, 0].set_ylabel("amplification factor")
            axes[1, 0].set_ylabel("worst blade's peak per force (µm/N)")
    handles = [
        axes[0, 0].plot([], [], "-", color="k", lw=2.5, label="95th percentile")[0],
        axes[0, 0].plot([], [], "v", color="w", mec="k", label="maximum")[0],
        axes[0, 0].plot([], [], "--", color="k", label=f"Whitehead bound {bound:.2f}")[0],
    ]
    if ringed:
        handles.append(
            axes[0, 0].plot(
                [],
                [],
                "o",
                mfc="none",
                mec="k",
                label="stopped early or at the band edge: a lower bound",
            )[0]
        )
    fig.legend(handles=handles, loc="upper center", ncol=len(handles), fontsize=8,
               bbox_to_anchor=(0.5, 1.0))  # fmt: skip
    fig.suptitle(
        f"Mistuned disk of {n_blades} blades: no damper, damper stuck, damper in friction",
        y=1.05,
    )
    fig.tight_layout()
    return save_figure(fig, path)


@styled
def plot_worst_response(
    panels: list[dict[str, Any]],
    configs: list[tuple[str, str]],
    rows: list[tuple[str, int]],
    n_blades: int,
    path: str | Path | None,
) -> Any:
    """Per damper and EO (rows) and configuration (columns) the forced response of every blade of
    that configuration's worst pattern (largest amplification factor): thin grey lines, the
    worst blade thick in the damper's colour, the tuned blade dashed black. ``panels``: dicts
    with ``damper``, ``config``, ``eo``, ``pattern``, ``af``, ``worst_blade``, ``freq_hz``
    (n), ``amp_m`` (blades, n) the response per newton of force (m/N; a friction curve's
    divided by its force), ``tuned_freq_hz``, ``tuned_amp_m`` (n) and ``lower``."""
    plt = pyplot()
    keys = [k for k, _ in configs]
    labels = dict(configs)
    fig, axes = _grid(plt, len(rows), len(keys), 4.0, 3.2, squeeze=False)
    for p in panels:
        ax = axes[rows.index((p["damper"], p["eo"])), keys.index(p["config"])]
        f = np.asarray(p["freq_hz"], float)
        amp = np.asarray(p["amp_m"], float) * 1e6
        for j in range(amp.shape[0]):
            if j != p["worst_blade"]:
                ax.plot(f, amp[j], "-", color="0.6", lw=0.8)
        ax.plot(f, amp[p["worst_blade"]], "-", color=damper_color(p["damper"]), lw=2.0,
                label=f"blade {p['worst_blade'] + 1} (worst)")  # fmt: skip
        ax.plot(p["tuned_freq_hz"], np.asarray(p["tuned_amp_m"], float) * 1e6, "--",
                color="k", lw=1.0, label="tuned disk")  # fmt: skip
        ax.plot([], [], "-", color="0.6", lw=0.8, label="other blades")
        note = " (lower bound)" if p.get("lower") else ""
        ax.set_title(
            f"{p['damper']}, {labels[p['config']]}, EO {p['eo']}\npattern {p['pattern'] + 1}: "
            f"AF {p['af']:.3f}{note}",
            fontsize=9,
        )
        ax.set_xlabel("frequency (Hz)")
        ax.set_ylabel("response per force |y| / F (µm/N)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(f"Worst pattern's forced response of every blade, {n_blades} blades")
    fig.tight_layout()
    return save_figure(fig, path)
