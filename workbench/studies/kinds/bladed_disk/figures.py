"""The bladed-disk study's charts: peak and friction energy against engine order, the fan
diagram with the engine-order line. Plain inputs (arrays, lists of dicts): no study module."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ....render.common import pyplot, save_figure, styled
from ....render.palette import damper_color

MARKERS = ("o", "s", "^", "D", "v", "P")


def _per_damper(dampers, forces, eos, values, scale, ylabel, title, path, lower=None, what=""):
    """One panel per damper, one line per force; ``lower`` [damper, force, eo] marks the
    cases whose curve stopped early or peaks on its band edge (ringed, labelled ``what``)."""
    plt = pyplot()
    n = len(dampers)
    fig, axes = plt.subplots(1, n, figsize=(4.2 * n + 0.6, 3.8), squeeze=False, sharey=True)
    for i, (d, ax) in enumerate(zip(dampers, axes[0], strict=True)):
        for j, f in enumerate(forces):
            ax.plot(
                eos,
                values[i, j] * scale,
                marker=MARKERS[j % len(MARKERS)],
                color=damper_color(d),
                alpha=0.45 + 0.55 * (j + 1) / len(forces),
                label=f"{f:g} N",
            )
            if lower is not None and lower[i, j].any():
                m = lower[i, j]
                ax.plot(
                    np.asarray(eos)[m],
                    values[i, j][m] * scale,
                    "o",
                    ms=13,
                    mfc="none",
                    mec="black",
                    label=f"stopped early or at the band edge: {what}",
                )
        ax.set_title(f"{d}")
        ax.set_xlabel("engine order EO")
        ax.set_xticks(eos)
        ax.grid(True, alpha=0.3)
        ax.legend(title="force per blade", fontsize=8)
        if i == 0:
            ax.set_ylabel(ylabel)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


@styled
def plot_peaks_vs_eo(
    dampers, forces, eos, peak_m, n_blades, path: str | Path | None, lower=None
) -> Any:
    """Per damper the peak amplitude (µm) against EO, one line per force;
    ``peak_m``: [damper, force, eo] in metres; ``lower``: which are lower bounds."""
    fig = _per_damper(
        dampers,
        forces,
        eos,
        peak_m,
        1e6,
        "peak |y| at the response point (µm)",
        f"Peak response against engine order, {n_blades} blades",
        path,
        lower,
        "a lower bound",
    )
    return save_figure(fig, path)


@styled
def plot_energy_vs_eo(dampers, forces, eos, energy_j, path: str | Path | None, lower=None) -> Any:
    """Per damper the friction energy per sector and cycle at the peak (mJ) against EO;
    ``energy_j``: [damper, force, eo] in joules; ``lower``: curves without their peak."""
    fig = _per_damper(
        dampers,
        forces,
        eos,
        energy_j,
        1e3,
        "friction energy at the peak (mJ / sector / cycle)",
        "Friction energy dissipated by the damper against engine order",
        path,
        lower,
        "not at the peak",
    )
    return save_figure(fig, path)


def folded_nd(eo: np.ndarray, n_blades: int) -> np.ndarray:
    """The ND an engine order (any real value) excites: the zigzag of the fan diagram."""
    k = np.mod(eo, n_blades)
    return np.minimum(k, n_blades - k)


@styled
def plot_fan_eo(fans, n_blades, worst, cases, path: str | Path | None) -> Any:
    """Fan diagram (damper stuck; ``fans``: damper -> [ND, family] Hz), each case's peak
    frequency at its ND (markers), and for each damper's worst EO the engine-order line
    ``f = EO x speed`` through that crossing (the speed at which it is resonant)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(9.6, 4.8))
    top = 0.0
    for d, hz in fans.items():
        nd = np.arange(hz.shape[0])
        for j in range(hz.shape[1]):
            ax.plot(
                nd,
                hz[:, j],
                "-",
                marker="s",
                ms=3,
                color=damper_color(d),
                label=f"{d} stuck" if j == 0 else None,
            )
        top = max(top, float(np.nanmax(hz[:, 0])))
    for c in cases:
        top = max(top, float(c["peak_hz"]))
        ax.plot(c["nd"], c["peak_hz"], "x", color=damper_color(c["damper"]), ms=7)
    ax.plot([], [], "x", color="k", label="peak of a case (at its EO's ND)")
    done = set()
    for w in worst:
        if w["worst_eo"] == 0 or (w["damper"], w["worst_eo"]) in done:
            continue
        done.add((w["damper"], w["worst_eo"]))
        rev_s = w["peak_hz"] / w["worst_eo"]
        e = np.linspace(0.0, max(w["worst_eo"], n_blades / 2), 400)
        ax.plot(
            folded_nd(e, n_blades),
            e * rev_s,
            ":",
            color=damper_color(w["damper"]),
            lw=1.3,
            label=f"EO line at {60 * rev_s:.0f} rpm ({w['damper']}: worst EO {w['worst_eo']})",
        )
    ax.set_xlabel("nodal diameter k")
    ax.set_ylabel("frequency (Hz)")
    ax.set_title(f"Fan diagram and engine-order excitation, {n_blades} blades")
    ax.set_xlim(-0.3, n_blades // 2 + 0.3)
    ax.set_ylim(0.0, 1.3 * top)  # the first family and the peaks; higher families clipped
    ax.set_xticks(np.arange(0, n_blades // 2 + 1, max(1, (n_blades // 2) // 12)))
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7)
    fig.tight_layout()
    return save_figure(fig, path)
