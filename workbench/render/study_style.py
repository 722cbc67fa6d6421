"""The drawing helpers every study figure shares, in the styles of :mod:`.palette`.

A damper always has the same colour, line style and marker, a force level
the same colour, a contact status the same colour and a stability verdict
the same line style: all of them come from :mod:`.palette` (re-exported
here). The helpers: a branch drawn piece by piece by its verdicts, a
failure cross, side legends. See :mod:`.study_figures` for the figures.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import InputError
from ..geometry.shapes import all_shapes
from ..post.results import STATUS_NAMES, CaseResult
from .common import readable_log
from .palette import (
    EXTRA_STYLES,
    STATUS_COLORS,
    STATUS_EDGE,
    VERDICTS,
    verdict,
    verdict_runs,
)

# colour, line style, marker of each damper: its shape's style entry (render/palette.py)
DAMPER_STYLE: dict[str, tuple] = {s.name: s.style for s in all_shapes()}
_EXTRA_COLORS = tuple(c for c, _, _ in EXTRA_STYLES)

FAMILY_STYLE = {"in-phase": "-", "out-of-phase": "--"}

UNSTABLE_BAND = dict(VERDICTS[1].band or {})  # kept importable (the unstable verdict's band)

FIGSIZE = (7.2, 4.6)  # inches; the report shows them at 110 dpi

__all__ = [
    "DAMPER_STYLE",
    "FAMILY_STYLE",
    "FIGSIZE",
    "UNSTABLE_BAND",
    "status_legend_handles",
]


def status_legend_handles(counts: Sequence[int] | None = None) -> list:
    """Square legend handles of the four statuses (with pair counts if given)."""
    from matplotlib.lines import Line2D

    out = []
    for k, name in enumerate(STATUS_NAMES):
        lab = name if counts is None else f"{name} ({counts[k]})"
        out.append(
            Line2D(
                [],
                [],
                ls="none",
                marker="s",
                ms=8,
                color=STATUS_COLORS[k],
                mec=STATUS_EDGE,
                label=lab,
            )
        )
    return out


def _flabel(force: float) -> str:
    return f"F = {force:g} N"


def _failed_suffix(case: CaseResult) -> str:
    return " (failed)" if case.branch.failed else ""


def _draw_branch(
    ax,
    x: np.ndarray,
    y: np.ndarray,
    stability: np.ndarray,
    *,
    color: str,
    ls_stable: str | None = None,
    lw: float = 1.6,
    band: bool = False,
    label: str | None = None,
    marker: str | None = None,
    markevery: int | None = None,
) -> None:
    """A curve drawn piece by piece by its stability verdicts (:data:`palette.VERDICTS`).

    Where colour names the force, each verdict has its own line style
    (stable solid, unstable dashed, unknown dotted). Where line style names
    the damper (``band=True``, ``ls_stable`` its line style) every piece
    keeps the damper's line style and the unstable and unknown pieces lie on
    their verdict's band. ``stability`` is the branch's int8 verdict array
    (a bool array reads as stable / unstable). ``marker`` every
    ``markevery`` points tells overlapping curves apart.
    """
    codes = np.asarray(stability)
    codes = codes.astype(int) if codes.dtype != bool else np.where(codes, 1, 0)
    first = True
    for sl, code in verdict_runs(codes):
        v = verdict(code)
        if band and v.band is not None:
            ax.plot(x[sl], y[sl], **v.band)
        ax.plot(
            x[sl],
            y[sl],
            color=color,
            lw=lw,
            ls=(ls_stable or "-") if band else v.ls,
            label=label if first else None,
            zorder=2,
        )
        first = False
    if marker and x.size:
        every = markevery or max(1, x.size // 8)
        ax.plot(
            x[every // 2 :: every],
            y[every // 2 :: every],
            ls="none",
            marker=marker,
            ms=4.5,
            color=color,
            mfc="white",
            zorder=3,
        )


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
