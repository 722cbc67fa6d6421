"""Figures of nonlinear modes: backbones (frequency, damping, energy, contact status) and
forced responses synthesised from them against the full harmonic balance."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .common import pyplot, readable_log, save_figure, styled
from .palette import (
    STATUS_COLORS,
    STATUS_EDGE,
    STATUS_NAMES,
    damper_style,
    family_linestyle,
)

STATUS_LABELS = STATUS_NAMES


def _label_style(label: str) -> tuple[str, object, str]:
    """(colour, line style, marker) of a curve labelled "<damper>[, family][ [variant]]":
    the damper's colour and marker; the family's line style when the label names one."""
    col, ls, mk = damper_style(label.split(",")[0].split(" [")[0].strip())
    if "," in label:
        ls = family_linestyle(label.split(",", 1)[1].split(" [")[0].strip())
    return col, ls, mk


@styled
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

    ``backbones``: (label, :class:`workbench.hbm.nlmodes.record.NlModeBranch`) pairs.
    The horizontal axis is the amplitude of output ``output`` (times
    ``unit_scale``, in ``unit``), logarithmic. The status panel shows the
    share of contact elements in each status for the first backbone.
    """
    plt = pyplot()
    fig, axs = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    for label, b in backbones:
        if b.n_points == 0:
            continue
        col, ls, mk = _label_style(label)
        x = b.out_amp[:, output] * unit_scale
        kw = dict(color=col, ls=ls, lw=1.6, label=label, marker=mk, markevery=0.1, ms=4)
        axs[0, 0].semilogx(x, b.freq_hz, **kw)
        axs[0, 1].semilogx(x, 100 * b.damping_ratio, **kw)
        e = b.friction_energy.sum(axis=1) * 1e3 if b.friction_energy.size else 0 * x
        e = np.where(e > 1e-9 * max(float(np.max(e)), 1e-300), e, np.nan)  # stuck: none
        axs[1, 0].loglog(x, e, **kw)
        if b.failed:
            axs[0, 0].plot(x[-1], b.freq_hz[-1], "x", color=col, ms=7)
    first = next((b for _, b in backbones if b.n_points and b.status.size), None)
    if first is not None:
        x = first.out_amp[:, output] * unit_scale
        st = first.status.astype(int)
        shares = np.stack([(st == k).mean(axis=1) for k in range(4)])
        axs[1, 1].stackplot(
            x,
            shares,
            labels=STATUS_LABELS,
            colors=STATUS_COLORS,
            edgecolor=STATUS_EDGE,
            linewidth=0.4,
        )
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
        ax.set_xlabel(f"{name}: largest |x(t)| over the period ({unit}, log)")
    axs[0, 0].legend(loc="best")
    fig.suptitle(title or "nonlinear modes: backbones")
    fig.tight_layout()
    return save_figure(fig, path)


@styled
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

    ``syntheses``: :class:`workbench.hbm.nlmodes.synthesis.Synthesis` records;
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
    ax.set_ylabel(f"{name}: largest |x(t)| over the period ({unit})")
    ax.set_title(title or "forced responses from the nonlinear mode")
    ax.legend(loc="best")
    return save_figure(fig, path)


@styled
def plot_synthesis_errors(rows: Sequence[dict], path: str | Path, title: str = "") -> Path:
    """Peak error of the synthesis against the full HBM per force, one line per damper/family.

    ``rows``: dicts with ``label`` ("<damper>, <family>"), ``force_n``,
    ``error_pct`` (signed) and ``valid``. Colour and marker name the damper,
    line style the family. The error axis is logarithmic (errors span
    decades), with a plain-number tick at every decade and the 2 % line
    labelled; an error of exactly 0 sits on the axis floor.
    """
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 4.4), layout="constrained")
    labels = list(dict.fromkeys(r["label"] for r in rows))
    errs = [abs(r["error_pct"]) for r in rows if r.get("error_pct") is not None]
    pos = [e for e in errs if e > 0]
    floor = min(pos) / 3 if pos else 1e-3
    for lab in labels:
        rs = sorted(
            (r for r in rows if r["label"] == lab and r.get("error_pct") is not None),
            key=lambda r: r["force_n"],
        )
        if not rs:
            continue
        col, ls, mk = _label_style(lab)
        f = [r["force_n"] for r in rs]
        e = [max(abs(r["error_pct"]), floor) for r in rs]
        ax.plot(f, e, color=col, ls=ls, lw=1.3, marker=mk, ms=6, label=lab)
        for r, fi, ei in zip(rs, f, e, strict=True):
            if r["valid"]:
                ax.plot(fi, ei, marker=mk, color=col, ms=6, ls="none")
            else:
                ax.plot(fi, ei, marker="x", color=col, ms=8, mew=2, ls="none")
    ax.axhline(2.0, color="k", lw=0.9, ls=(0, (4, 2)))
    ax.text(
        0.01, 2.0, "2 %", va="bottom", ha="left", fontsize=8, transform=ax.get_yaxis_transform()
    )
    ax.set_yscale("log")
    top = max([*errs, 2.0]) * 2.0
    ax.set_ylim(floor / 1.5, top)
    readable_log(ax, "y")
    forces = sorted({r["force_n"] for r in rows})
    if len(forces) > 1 and forces[-1] / max(forces[0], 1e-300) > 5:
        ax.set_xscale("log")
        readable_log(ax, "x")
    ax.set_xlabel("excitation force F (N)")
    ax.set_ylabel("|peak error| of the synthesis, max |x(t)| (%, log)")
    ax.set_title(title or "nonlinear-mode synthesis against the full harmonic balance")
    if labels:
        ax.plot([], [], "x", color="0.3", ms=8, mew=2, ls="none", label="flagged not valid")
        fig.legend(loc="outside right upper", fontsize=8, title="damper, family")
    return save_figure(fig, path)
