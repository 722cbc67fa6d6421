"""The receptance curve of one bladed-disk sector under engine-order excitation."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .common import pyplot, save_figure, styled


@styled
def plot_sector_frf(branch: Any, info: dict, force_n: float, damper: str, path: str | Path) -> Any:
    """Receptance (largest |y(t)| and harmonic 1 per newton, m/N) against frequency (Hz).

    ``info``: :func:`workbench.pipeline.sector.sector_forced_response`'s dict (engine
    order, ND and direction of each harmonic, stuck frequencies). Markers: contact
    status at each point (the highest over the pairs: stuck, slipping, separating).
    """
    from .palette import damper_color

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.0, 4.6))
    f = np.asarray(branch.freq_hz)
    colour = damper_color(damper)
    if f.size:
        ax.semilogy(f, branch.out_amp[:, 0] / force_n, "-", color=colour, label="max |y(t)| / F")
        ax.semilogy(
            f,
            branch.out_h1[:, 0] / force_n,
            ls=(0, (4, 2)),
            color="#6e6e6e",
            label="harmonic 1 / F",
        )
        st = branch.status.max(axis=1) if branch.status.size else np.zeros(f.size, int)
        for code, marker, label in ((1, "o", "slipping"), (2, "x", "separating")):
            on = st == code
            if on.any():
                ax.semilogy(
                    f[on], branch.out_amp[on, 0] / force_n, marker, ms=3.5, mfc="none",
                    color=colour, label=label,
                )  # fmt: skip
    f0 = info["stuck_hz"][0]
    ax.axvline(f0, color="#999999", lw=0.8, ls=":", label=f"stuck, {f0:.1f} Hz")
    nd = info["nd_of_harmonic"]["1"]
    way = info["direction_of_harmonic"]["1"]
    ax.set_title(
        f"{damper} damper, EO {info['eo']} of {info['n_blades']} blades: ND {nd} ({way}), "
        f"F = {force_n:g} N",
        fontsize=10,
    )
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("receptance (m/N)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="best")
    return save_figure(fig, path)
