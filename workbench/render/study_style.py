"""The visual language shared by every study figure: damper, force and status styles.

A damper always has the same colour, line style and marker
(:data:`DAMPER_STYLE`), a force level the same colour, a contact status the
same colour (:data:`STATUS_COLORS`); plus the small drawing helpers the
figure modules share (a branch with its unstable pieces, a failure cross,
side legends). See :mod:`.study_figures` for the figures themselves.
"""

from __future__ import annotations

import zlib
from collections.abc import Sequence

import numpy as np

from ..errors import InputError
from ..geometry.shapes import all_shapes
from ..post.results import STATUS_NAMES, CaseResult
from ..post.tables import stability_runs as _runs
from .common import readable_log

# colour, line style, marker of each damper (the paper: cone solid, cylinder dashed, wedge dotted)

# (each shape names its own: workbench/geometry/shapes/<name>.py)
DAMPER_STYLE: dict[str, tuple[str, str, str]] = {s.name: s.style for s in all_shapes()}


_EXTRA_COLORS = ("#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#7f7f7f")
# status 0 stuck, 1 stick-slip, 2 partial separation, 3 full separation


STATUS_COLORS: tuple[str, str, str, str] = ("#3a3a3a", "#f28e2b", "#59a14f", "#4e79a7")


FAMILY_STYLE = {"in-phase": "-", "out-of-phase": "--"}


UNSTABLE_BAND = dict(color="0.55", lw=6.0, alpha=0.35, solid_capstyle="round", zorder=1)


FIGSIZE = (7.2, 4.6)  # inches; the report shows them at 110 dpi


def damper_style(damper: str) -> tuple[str, str, str]:
    """(colour, line style, marker) of a damper; a variant ("cone-12deg") inherits its base's."""
    styles = {sh.name: sh.style for sh in all_shapes()}  # the registry, as it is now
    if damper in styles:
        return styles[damper]
    for base, style in styles.items():
        if damper.startswith(base):
            return style
    k = zlib.crc32(damper.encode()) % len(_EXTRA_COLORS)
    return (_EXTRA_COLORS[k], "-.", "D")


def force_colors(forces: Sequence[float]) -> dict[float, str]:
    """A colour per force, lowest dark purple to highest orange (plasma 0 .. 0.8)."""
    import matplotlib

    fs = sorted(set(float(f) for f in forces))
    cmap = matplotlib.colormaps["plasma"]
    n = len(fs)
    return {
        f: matplotlib.colors.to_hex(cmap(0.8 * (i / (n - 1) if n > 1 else 0.0)))
        for i, f in enumerate(fs)
    }


def status_legend_handles(counts: Sequence[int] | None = None) -> list:
    """Square legend handles of the four statuses (with pair counts if given)."""
    from matplotlib.lines import Line2D

    out = []
    for k, name in enumerate(STATUS_NAMES):
        lab = name if counts is None else f"{name} ({counts[k]})"
        out.append(Line2D([], [], ls="none", marker="s", ms=8, color=STATUS_COLORS[k], label=lab))
    return out


def _flabel(force: float) -> str:
    return f"F = {force:g} N"


def _failed_suffix(case: CaseResult) -> str:
    return " (failed)" if case.branch.failed else ""


def _draw_branch(
    ax,
    x: np.ndarray,
    y: np.ndarray,
    stable: np.ndarray,
    *,
    color: str,
    ls_stable: str = "-",
    ls_unstable: str = "--",
    lw: float = 1.6,
    band: bool = False,
    label: str | None = None,
    unknown: np.ndarray | None = None,
) -> None:
    """A curve drawn solid where stable and ``ls_unstable`` (or a grey band) where not;
    points of unknown stability (``unknown``, Hill not computed or not trusted) dotted grey."""
    first = True
    if unknown is not None and np.any(unknown):
        unk = np.asarray(unknown, dtype=bool)
        for sl, u in _runs(~unk):
            if not u:
                j = slice(max(sl.start - 1, 0), min(sl.stop + 1, x.size))
                ax.plot(x[j], y[j], color="0.55", lw=lw + 0.3, ls=":", zorder=3)
        y = np.where(unk, np.nan, y)
    for sl, ok in _runs(stable):
        if not ok and band:
            ax.plot(x[sl], y[sl], **UNSTABLE_BAND)
        ax.plot(
            x[sl],
            y[sl],
            color=color,
            lw=lw,
            ls=ls_stable if (ok or band) else ls_unstable,
            label=label if first else None,
            zorder=2,
        )
        first = False


def _mark_failure(ax, case: CaseResult, x: np.ndarray, y: np.ndarray, color: str) -> None:
    if case.branch.failed and x.size:
        ax.plot(x[-1], y[-1], "x", color=color, ms=9, mew=2.2, zorder=4)


def _side_legends(
    fig,
    first: tuple[list, str | None],
    second: tuple[list[tuple[str, dict]], str | None] | None = None,
) -> None:
    """Legends outside the axes on the right: ``first`` (handles, title) at the top and,
    below it, ``second`` (line-style entries (label, Line2D keywords), title)."""
    from matplotlib.lines import Line2D

    handles, title = first
    fig.legend(handles=handles, loc="outside right upper", title=title)
    if second and second[0]:
        entries, title2 = second
        fig.legend(
            handles=[Line2D([], [], label=lab, **kw) for lab, kw in entries],
            loc="outside right lower",
            title=title2,
        )


_readable_log = readable_log  # (moved to common: the FRF figures use it too)


def _wants_log(values: Sequence[float], ratio: float = 20.0) -> bool:
    v = np.asarray([x for x in values if np.isfinite(x) and x > 0])
    return v.size > 1 and v.max() / v.min() > ratio


def _one_set(cases: Sequence[CaseResult], what: str) -> list[CaseResult]:
    if not cases:
        raise InputError(what, "[]", "at least one case")
    keys = {(c.damper, round(c.phase_deg, 9)) for c in cases}
    if len(keys) != 1:
        raise InputError(what, sorted(keys), "cases of one damper and one family")
    return sorted(cases, key=lambda c: c.force_n)


def _one_family(cases: Sequence[CaseResult], what: str) -> list[CaseResult]:
    if not cases:
        raise InputError(what, "[]", "at least one case")
    fam = {round(c.phase_deg, 9) for c in cases}
    if len(fam) != 1:
        raise InputError(what, sorted(fam), "cases of one family (one phase angle)")
    return list(cases)


def _dampers(cases: Sequence[CaseResult]) -> list[str]:
    return list(dict.fromkeys(c.damper for c in cases))
