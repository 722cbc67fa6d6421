"""Figures of nonlinear modes: backbones (frequency, damping, energy, contact status) and
forced responses synthesised from them against the full harmonic balance."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .common import pyplot, save_figure

STATUS_LABELS = ("stuck", "stick-slip", "partial sep.", "full sep.")
STATUS_COLORS = ("#3b75af", "#ef8636", "#c53a32", "#7f7f7f")


def plot_backbones(
    backbones: Sequence[tuple[str, object]],
    path: str | Path,
    *,
    output: int = 0,
    unit_scale: float = 1.0,
    unit: str = "m",
    title: str = "",
) -> Path:
    """Frequency, damping ratio, friction energy and contact status against the amplitude.

    ``backbones``: (label, :class:`workbench.hbm.nlmodes.NlModeBranch`) pairs.
    The horizontal axis is the amplitude of output ``output`` (times
    ``unit_scale``, in ``unit``), logarithmic. The status panel shows the
    share of contact elements in each status for the first backbone.
    """
    plt = pyplot()
    fig, axs = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    colors = plt.cm.tab10(np.arange(max(len(backbones), 1)) % 10)
    for (label, b), col in zip(backbones, colors, strict=False):
        if b.n_points == 0:
            continue
        x = b.out_amp[:, output] * unit_scale
        axs[0, 0].semilogx(x, b.freq_hz, "-", color=col, lw=1.5, label=label)
        axs[0, 1].semilogx(x, 100 * b.damping_ratio, "-", color=col, lw=1.5, label=label)
        e = b.friction_energy.sum(axis=1) * 1e3 if b.friction_energy.size else 0 * x
        e = np.where(e > 1e-9 * max(float(np.max(e)), 1e-300), e, np.nan)  # stuck: none
        axs[1, 0].loglog(x, e, "-", color=col, lw=1.5, label=label)
        if b.failed:
            axs[0, 0].plot(x[-1], b.freq_hz[-1], "x", color=col, ms=7)
    first = next((b for _, b in backbones if b.n_points and b.status.size), None)
    if first is not None:
        x = first.out_amp[:, output] * unit_scale
        st = first.status.astype(int)
        shares = np.stack([(st == k).mean(axis=1) for k in range(4)])
        axs[1, 1].stackplot(x, shares, labels=STATUS_LABELS, colors=STATUS_COLORS, alpha=0.85)
        axs[1, 1].set_xscale("log")
        axs[1, 1].set_ylim(0, 1)
        axs[1, 1].legend(loc="center left", fontsize=7)
        axs[1, 1].set_title(f"contact status ({backbones[0][0]})", fontsize=9)
    name = "output"
    for _, b in backbones:
        if b.output_names:
            name = b.output_names[output]
            break
    axs[0, 0].set_ylabel("frequency (Hz)")
    axs[0, 1].set_ylabel("modal damping ratio (%)")
    axs[1, 0].set_ylabel("friction energy per cycle (mJ)")
    axs[1, 1].set_ylabel("share of contact elements")
    for ax in axs[1]:
        ax.set_xlabel(f"{name} amplitude ({unit})")
    axs[0, 0].legend(loc="best")
    fig.suptitle(title or "nonlinear modes: backbones")
    fig.tight_layout()
    return save_figure(fig, path)


def plot_synthesis(
    backbone,
    syntheses: Sequence,
    path: str | Path,
    *,
    hbm: Sequence | None = None,
    output: int = 0,
    unit_scale: float = 1.0,
    unit: str = "m",
    title: str = "",
    band_hz: tuple[float, float] | None = None,
    level_unit: str = "",
) -> Path:
    """Synthesised forced responses (solid), the full HBM curves (dashed) and the backbone.

    ``level_unit``: the excitation level's unit in the legend (e.g. "N").

    ``syntheses``: :class:`workbench.hbm.synthesis.Synthesis` records;
    ``hbm``: the HBM branches of the same levels (or None); an invalid
    synthesis is drawn dotted and its peak as an open circle.
    """
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    colors = plt.cm.viridis(np.linspace(0.05, 0.9, max(len(syntheses), 1)))
    for k, (s, col) in enumerate(zip(syntheses, colors, strict=False)):
        ax.plot(
            s.freq_hz,
            s.out_amp * unit_scale,
            "-" if s.valid else ":",
            color=col,
            lw=1.4,
            label=f"level {s.level:g}{' ' + level_unit if level_unit else ''}"
            + ("" if s.valid else " (not valid)"),
        )
        ax.plot(
            s.peak_freq_hz,
            s.peak_amplitude * unit_scale,
            "o",
            color=col,
            ms=4,
            mfc=col if s.valid else "white",
        )
        if hbm is not None and k < len(hbm) and hbm[k] is not None and hbm[k].n_points:
            b = hbm[k]
            ax.plot(
                b.freq_hz,
                b.out_amp[:, output] * unit_scale,
                "--",
                color="0.45",
                lw=1.0,
                label="full HBM" if k == 0 else None,
            )
    if backbone.n_points:
        ax.plot(
            backbone.freq_hz,
            backbone.out_amp[:, output] * unit_scale,
            "-",
            color="k",
            lw=0.8,
            alpha=0.7,
            label="backbone",
        )
    if band_hz is not None:
        ax.set_xlim(*band_hz)
    top = max([float(np.max(s.out_amp)) for s in syntheses if s.out_amp.size] + [0.0])
    if hbm:
        top = max(
            [top] + [float(b.out_amp[:, output].max()) for b in hbm if b is not None and b.n_points]
        )
    if top > 0:
        ax.set_ylim(0, 1.1 * top * unit_scale)
    name = backbone.output_names[output] if backbone.output_names else "output"
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel(f"{name} amplitude ({unit})")
    ax.set_title(title or "forced responses from the nonlinear mode")
    ax.legend(loc="best")
    return save_figure(fig, path)


def plot_synthesis_errors(rows: Sequence[dict], path: str | Path, title: str = "") -> Path:
    """Peak error of the synthesis against the full HBM per force, one line per damper/family.

    ``rows``: dicts with ``label``, ``force_n``, ``error_pct`` (signed) and ``valid``.
    """
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 4.2))
    labels = list(dict.fromkeys(r["label"] for r in rows))
    colors = plt.cm.tab10(np.arange(max(len(labels), 1)) % 10)
    for lab, col in zip(labels, colors, strict=False):
        rs = sorted(
            (r for r in rows if r["label"] == lab and r.get("error_pct") is not None),
            key=lambda r: r["force_n"],
        )
        if not rs:
            continue
        f = [r["force_n"] for r in rs]
        e = [abs(r["error_pct"]) for r in rs]
        ax.plot(f, e, "-", color=col, lw=1.2, label=lab)
        for r, fi, ei in zip(rs, f, e, strict=True):
            ax.plot(fi, ei, "o" if r["valid"] else "x", color=col, ms=5)
    ax.axhline(2.0, color="k", lw=0.8, ls="--")
    ax.set_yscale("symlog", linthresh=1.0)
    ax.set_xlabel("excitation force (N)")
    ax.set_ylabel("|peak amplitude error| (%)")
    ax.set_title(title or "synthesis against full HBM (o: valid, x: flagged not valid)")
    if labels:
        ax.legend(loc="best")
    return save_figure(fig, path)
