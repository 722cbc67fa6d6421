"""Pareto front and tolerance pick over (time, error) records.

Plain selection on numbers, no solving: :func:`pareto_front` finds the
settings that no other beats in both compute time and error, and
:func:`pick_cheapest` the cheapest row whose worst error meets a tolerance.
Used by the fidelity study (``workbench.studies.kinds.fidelity.compute``) and its charts
(``workbench.studies.kinds.fidelity.figures``).
"""

from __future__ import annotations

import math
from typing import Any


def pareto_front(points: list[tuple[float, float | None]]) -> list[int]:
    """Indices of the non-dominated (time, error) points, cheapest first.

    A point is dominated when another is no slower and no less accurate and
    strictly better in one of the two. Points without an error (None, NaN)
    are never on the front.
    """
    ok = [i for i, (t, e) in enumerate(points) if e is not None and math.isfinite(e)]
    ok.sort(key=lambda i: (points[i][0], points[i][1]))
    front: list[int] = []
    best = math.inf
    for i in ok:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def pick_cheapest(rows: list[dict[str, Any]], tolerance_pct: float) -> dict[str, Any]:
    """The cheapest row whose ``max_error_pct`` is within the tolerance.

    ``rows``: dicts with ``label``, ``time_s`` and ``max_error_pct`` (None
    for a setting that could not be compared). Returns ``{"met": bool,
    "picked": row or None, "closest": row or None, "reason": str}``; when
    nothing meets the tolerance, ``closest`` is the most accurate row.
    """
    valid = [
        r for r in rows if r.get("max_error_pct") is not None and math.isfinite(r["max_error_pct"])
    ]
    meeting = [r for r in valid if r["max_error_pct"] <= tolerance_pct]
    if meeting:
        best = min(meeting, key=lambda r: (r["time_s"], r["max_error_pct"]))
        return {
            "met": True,
            "picked": best,
            "closest": best,
            "reason": (
                f"'{best['label']}' is the cheapest of the {len(meeting)} of {len(rows)} measured "
                f"settings whose worst error ({best['max_error_pct']:.3g} %) is within "
                f"{tolerance_pct:g} %: {best['time_s']:.1f} s"
            ),
        }
    if not valid:
        return {
            "met": False,
            "picked": None,
            "closest": None,
            "reason": (
                f"no setting meets {tolerance_pct:g} %: none of the {len(rows)} settings could be "
                "compared with the reference (failed solves)"
            ),
        }
    close = min(valid, key=lambda r: (r["max_error_pct"], r["time_s"]))
    return {
        "met": False,
        "picked": None,
        "closest": close,
        "reason": (
            f"NO setting meets {tolerance_pct:g} %: the closest is '{close['label']}' with a worst "
            f"error of {close['max_error_pct']:.3g} % ({close['time_s']:.1f} s); refine the "
            "levels or loosen the tolerance"
        ),
    }
