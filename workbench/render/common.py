"""Settings shared by every figure: off-screen pyvista, a fixed matplotlib style."""

from __future__ import annotations

import os
from pathlib import Path


def offscreen_pyvista():
    """Import pyvista set up for off-screen rendering (EGL, no display) with a fixed theme."""
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
    import pyvista as pv

    pv.OFF_SCREEN = True
    pv.set_plot_theme("document")
    pv.global_theme.font.size = 12
    pv.global_theme.window_size = [1200, 900]
    return pv


def pyplot():
    """Import matplotlib.pyplot with the Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    plt.rcParams.update({
        "figure.dpi": 110, "savefig.dpi": 110, "axes.grid": True, "grid.alpha": 0.3,
        "font.size": 10, "legend.fontsize": 8, "figure.autolayout": False,
    })
    return plt


def save_figure(fig, path: str | Path) -> Path:
    """Save a matplotlib figure as PNG atomically and close it."""
    from ..io import atomic_path

    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", bbox_inches="tight")
    import matplotlib.pyplot as plt

    plt.close(fig)
    return path
