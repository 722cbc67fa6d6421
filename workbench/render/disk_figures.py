"""The fan (SAFE) diagram of a bladed disk: frequency against nodal diameter.

One line per mode family (the n-th frequency of every nodal diameter),
solid with the damper stuck, dashed with no damper; markers at the integer
nodal diameters only (a nodal diameter is a whole number: the lines only
guide the eye). Optional engine-order lines ``f = EO x speed`` are not
drawn here (no speed is known at this stage).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .common import pyplot, save_figure, styled


@styled
def plot_fan(
    stuck_hz: np.ndarray | None,
    free_hz: np.ndarray | None,
    n_blades: int,
    damper: str,
    path: str | Path | None,
) -> Any:
    """Fan diagram; ``stuck_hz``/``free_hz``: (N//2 + 1, n_families) Hz, row = nodal diameter."""
    from .palette import damper_color

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.0, 4.6))
    colour = damper_color(damper)
    for hz, style, marker, label, col in (
        (free_hz, (0, (4, 2)), "o", "no damper", "#6e6e6e"),
        (stuck_hz, "-", "s", f"{damper} damper stuck", colour),
    ):
        if hz is None:
            continue
        nd = np.arange(hz.shape[0])
        for j in range(hz.shape[1]):
            ax.plot(
                nd,
                hz[:, j],
                linestyle=style,
                marker=marker,
                ms=4,
                color=col,
                mfc="white" if style != "-" else col,
                label=label if j == 0 else None,
            )
    ax.set_xlabel("nodal diameter k")
    ax.set_ylabel("frequency (Hz)")
    ax.set_title(f"Fan diagram, {n_blades} blades (first families)")
    ax.set_xlim(-0.3, n_blades // 2 + 0.3)
    ax.set_ylim(bottom=0.0)
    step = max(1, (n_blades // 2) // 12)
    ax.set_xticks(np.arange(0, n_blades // 2 + 1, step))
    ax.grid(True, alpha=0.3)
    ax.legend(loc="lower right")
    fig.tight_layout()
    return save_figure(fig, path)
