"""Settings shared by every figure: off-screen pyvista, a fixed matplotlib style."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any


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


STYLE = {
    "figure.dpi": 110,
    "savefig.dpi": 110,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "font.size": 10,
    "legend.fontsize": 8,
    "figure.autolayout": False,
}

_SUBPLOTS_ARGS = (
    "nrows",
    "ncols",
    "sharex",
    "sharey",
    "squeeze",
    "width_ratios",
    "height_ratios",
    "subplot_kw",
    "gridspec_kw",
)


class _Figures:
    """The part of ``matplotlib.pyplot`` the figure code uses, without pyplot's state.

    Figures are plain :class:`matplotlib.figure.Figure` objects: they need no
    backend, are never registered with pyplot (nothing to close, nothing
    shown twice in a notebook) and leave the process's backend alone, so
    ``%matplotlib inline`` keeps working after ``import workbench``. The
    workbench style (:data:`STYLE`) applies while a figure is built and
    saved (:func:`save_figure`).
    """

    def __init__(self) -> None:
        import matplotlib.cm
        import matplotlib.patches

        self.cm = matplotlib.cm
        self.Rectangle = matplotlib.patches.Rectangle

    @staticmethod
    def figure(**fig_kw):
        import matplotlib
        from matplotlib.figure import Figure

        with matplotlib.rc_context(STYLE):
            return Figure(**fig_kw)

    def subplots(self, *args, **kw):
        import matplotlib

        sub = {k: kw.pop(k) for k in list(kw) if k in _SUBPLOTS_ARGS}
        with matplotlib.rc_context(STYLE):
            fig = self.figure(**kw)
            return fig, fig.subplots(*args, **sub)


def styled(fn):
    """Run a figure function in the workbench style (:data:`STYLE`), leaving rcParams as found."""
    import functools

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        import matplotlib

        with matplotlib.rc_context(STYLE):
            return fn(*args, **kwargs)

    return wrapper


def pyplot() -> _Figures:
    """Figure factory with pyplot's ``subplots``/``figure`` API and no global backend."""
    return _Figures()


def save_figure(fig, path: str | Path | None) -> Any:
    """Save a matplotlib figure as PNG atomically (in the workbench style); return the path.

    With ``path=None`` nothing is written and the Figure itself is returned:
    every ``plot_*`` function of :mod:`workbench.render` passes its ``path``
    here, so ``plot_x(..., path=None)`` gives a Figure to show or adjust.
    """
    import matplotlib

    from ..io import atomic_path

    if path is None:
        return fig
    path = Path(path)
    with matplotlib.rc_context(STYLE), atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", bbox_inches="tight")
    if _is_pyplot_figure(fig):
        import matplotlib.pyplot as plt

        plt.close(fig)
    return path


def _is_pyplot_figure(fig) -> bool:
    """True for a figure that pyplot manages (made by a caller with plt); ours are not."""
    return getattr(fig.canvas, "manager", None) is not None


def readable_log(ax, which: str = "both") -> None:
    """Plain-number tick labels (0.1, 0.2, 0.5, 1, 2, ...) on log axes spanning <= 3 decades.

    Wider axes keep matplotlib's powers of ten.
    """
    from matplotlib import ticker

    names = ("x", "y") if which == "both" else (which,)
    for name in names:
        axis = getattr(ax, f"{name}axis")
        if axis.get_scale() != "log":
            continue
        lo, hi = sorted(ax.get_xlim() if name == "x" else ax.get_ylim())
        if lo <= 0 or hi / lo > 1e3:
            continue
        fmt = ticker.FuncFormatter(lambda v, _: f"{v:g}")
        axis.set_major_formatter(fmt)
        axis.set_minor_locator(ticker.LogLocator(subs=(2.0, 5.0)))
        axis.set_minor_formatter(fmt)
