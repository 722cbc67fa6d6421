"""One visual language for every figure and 3-D picture: dampers, contact states, verdicts.

Every colour, line style and marker that carries a meaning is read from
here, so a colour means one thing in every figure of every report:

* **a damper**: its colour, line style and marker are its shape's
  ``style`` entry (``workbench/geometry/shapes/<name>.py``, one place per
  damper); :func:`damper_style` is how every figure and the pyvista
  pictures read it. The three shapes use colours of the Okabe-Ito set
  (distinct for the common colour-vision deficiencies): cone blue, solid,
  circles; cylinder reddish purple, dashed, squares; wedge bluish green,
  dash-dot, triangles. Line style and marker alone tell them apart in
  greyscale.
* **a contact state** (:data:`STATUS_COLORS`, index = the status code of
  :mod:`workbench.post.results`): stuck dark grey, stick-slip vermilion,
  partial separation orange, full separation yellow: warm colours that no
  damper uses, their lightness rising in that order, so a greyscale print
  keeps the order.
* **a stability verdict** (:data:`VERDICTS`): one row per code of a
  branch's ``stability`` array (:mod:`workbench.hbm.stability.hill`: 1 stable,
  0 unstable, -1 unknown, 2 and 3 stable and unstable carried from checked
  neighbours) with its word, its line style where colour names
  the force, its band where line style names the damper, and the fill of
  a peak marker. Drawing, legends, captions and tables all read this
  table, so a new kind of verdict is one more row.
* **a force level**: a colour of the plasma ramp, lowest dark.

Plain data and small functions; matplotlib is imported only by the
functions that draw legend handles.
"""

from __future__ import annotations

import logging
import zlib
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

log = logging.getLogger(__name__)

# ---- dampers --------------------------------------------------------------------------

# dampers that no shape registers (a sweep variant's name that is no shape, a user label)
EXTRA_STYLES: tuple[tuple[str, str, str], ...] = (
    ("#E69F00", (0, (3, 1, 1, 1, 1, 1)), "D"),
    ("#56B4E9", (0, (1, 1)), "v"),
    ("#000000", (0, (5, 2, 1, 2)), "P"),
)


def damper_style(damper: str) -> tuple[str, Any, str]:
    """(colour, line style, marker) of a damper, from its shape's ``style`` entry.

    A variant name that starts with a shape's name ("cone-12deg", "cone
    [modes=24]") takes that shape's style; any other name gets a fixed
    style of :data:`EXTRA_STYLES` chosen by a hash of the name.
    """
    from ..geometry.shapes import all_shapes

    styles = {sh.name: sh.style for sh in all_shapes()}  # the registry, as it is now
    if damper in styles:
        return styles[damper]
    for base in sorted(styles, key=len, reverse=True):
        if damper.startswith(base):
            return styles[base]
    return EXTRA_STYLES[zlib.crc32(damper.encode()) % len(EXTRA_STYLES)]


def damper_color(damper: str) -> str:
    """The damper's colour (also its colour in the 3-D pictures)."""
    return damper_style(damper)[0]


# a line style per family where colour and marker already name the damper
FAMILY_LINESTYLE = {"in-phase": "-", "out-of-phase": (0, (5, 2))}


def family_linestyle(family: str) -> Any:
    return FAMILY_LINESTYLE.get(family, (0, (1, 1.5)))


# ---- contact states -------------------------------------------------------------------

STATUS_NAMES = ("stuck", "stick-slip", "partial separation", "full separation")
STATUS_COLORS: tuple[str, str, str, str] = ("#3d3d3d", "#D55E00", "#E69F00", "#F0E442")
STATUS_EDGE = "#3d3d3d"  # outline of the light status colours on white (lines, spheres)

# a pair with no dissipation in an energy map (stuck, rolling or open): not an energy colour
ZERO_ENERGY_COLOR = "#a3a3a3"
ENERGY_CMAP = "viridis"
NOT_COMPUTED_COLOR, NOT_COMPUTED_EDGE = "#f2f2f2", "#b0b0b0"
RESONANCE_COLOR = "#000000"  # the marked resonance peak in status maps
RIG_COLOR = "#c9d3e0"  # the rig in the 3-D pictures (the damper takes its own colour)
SIDE_COLORS = ("#000000", "#6e6e6e")  # contact points on platform 1 / 2 in the rig picture
ARROW_COLORS = ("#000000", "#6b6b6b")  # excitation / response arrows in the rig picture

# ---- stability verdicts ---------------------------------------------------------------


@dataclass(frozen=True)
class Verdict:
    """How one stability verdict is named and drawn.

    ``code`` is the value in ``Branch.stability``; ``label`` the word in
    legends, captions and tables; ``ls`` the line style of a curve where
    colour names the force; ``band`` the keywords of a wide translucent
    line under the curve where line style names the damper (None: no
    band); ``fill`` the fill style of a peak marker (matplotlib
    ``fillstyle``: "full", "none", "bottom", ...); ``always``: listed in
    legends and tables even when no point has it (the three computed
    verdicts are, so a reader sees that none was unknown).
    """

    code: int
    label: str
    ls: Any
    band: dict | None = None
    fill: str = "full"
    always: bool = True
    words: str = field(default="")  # how its line looks where colour names the force
    band_words: str = field(default="")  # how it looks where line style names the damper

    def caption(self, band: bool = False) -> str:
        """'unstable dashed' (or, with ``band``, 'unstable on a grey band')."""
        return f"{self.label} {self.band_words if band else self.words}".strip()


_BAND = dict(lw=6.0, solid_capstyle="round", zorder=1)

VERDICTS: tuple[Verdict, ...] = (
    Verdict(1, "stable", "-", None, "full", words="solid", band_words="without a band"),
    Verdict(
        0,
        "unstable",
        (0, (5, 2.5)),
        dict(color="0.55", alpha=0.35, **_BAND),
        "none",
        words="dashed",
        band_words="on a grey band",
    ),
    Verdict(
        -1,
        "unknown",
        (0, (1, 1.6)),
        dict(color="0.3", alpha=0.45, ls=(0, (0.5, 0.8)), **_BAND),
        "bottom",
        words="dotted",
        band_words="on a beaded grey band",
    ),
    # carried from checked neighbours (workbench.hbm.stability.along_path): not established at
    # the point, drawn as their verdict with a break in the line
    Verdict(
        2,
        "stable (carried)",
        (0, (7, 1.5)),
        dict(color="0.7", alpha=0.2, **_BAND),
        "left",
        always=False,
        words="long dashes",
        band_words="on a faint band",
    ),
    Verdict(
        3,
        "unstable (carried)",
        (0, (5, 2, 1, 2)),
        dict(color="0.55", alpha=0.2, **_BAND),
        "right",
        always=False,
        words="dash-dot",
        band_words="on a faint grey band",
    ),
)
# how much a verdict weighs where a piece of line joins two points of different verdicts: the
# piece is drawn with the heavier one (an unstable point shows even between stable ones)
SEVERITY = {1: 0, 2: 1, -1: 2, 3: 3, 0: 4}


def verdict(code: int) -> Verdict:
    """The :class:`Verdict` of a stability code (a code not in the table is drawn as
    unknown, named by its code, and logged)."""
    by_code = {v.code: v for v in VERDICTS}
    v = by_code.get(int(code))
    if v is None:
        log.warning("stability code %s is not in render/palette.VERDICTS: drawn as unknown", code)
        base = by_code[-1]
        v = Verdict(int(code), f"verdict {int(code)}", base.ls, base.band, base.fill, False)
    return v


def verdict_label(code: int | None) -> str:
    """The word of a verdict code ("" for None)."""
    return "" if code is None else verdict(code).label


def verdict_runs(codes: Sequence[int] | np.ndarray) -> list[tuple[slice, int]]:
    """Split a branch into runs of one verdict for drawing: ``[(slice, code), ...]``.

    A run ends on the first point of the next one, so the drawn pieces join
    into one unbroken line; a piece between two points takes the heavier of
    their verdicts (:data:`SEVERITY`: stable, stable carried, unknown,
    unstable carried, unstable): a piece between a stable and an unstable
    (or unknown, or carried) point is drawn so, and one such point shows as
    a piece of line.
    """
    c = np.asarray(codes, dtype=int)
    n = c.size
    if n == 0:
        return []
    if n == 1:
        return [(slice(0, 1), int(c[0]))]
    a, b = c[:-1], c[1:]
    rank = np.vectorize(lambda k: SEVERITY.get(int(k), 2))
    seg = np.where(rank(b) > rank(a), b, a)  # the heavier verdict of the two ends
    runs, start = [], 0
    for i in range(1, seg.size + 1):
        if i == seg.size or seg[i] != seg[start]:
            runs.append((slice(start, i + 1), int(seg[start])))
            start = i
    return runs


def verdict_counts(codes: Sequence[int] | np.ndarray) -> dict[int, int]:
    """Points per verdict code: every code of :data:`VERDICTS` (0 when absent), then any
    other code found."""
    c = np.asarray(codes, dtype=int).ravel()
    out = {v.code: int(np.sum(c == v.code)) for v in VERDICTS}
    for code in sorted(set(c.tolist()) - set(out)):
        out[int(code)] = int(np.sum(c == code))
    return out


def verdicts_shown(counts: dict[int, int]) -> list[Verdict]:
    """The verdicts a legend or table lists: the ``always`` ones and any present."""
    return [verdict(k) for k, n in counts.items() if n or verdict(k).always]


def verdict_caption(counts: dict[int, int] | None = None, band: bool = False) -> str:
    """'stability (Hill's method): stable solid (120 points), unstable dashed (3 points),
    unknown dotted (0 points)' (without counts when ``counts`` is None)."""
    vs = verdicts_shown(counts) if counts is not None else list(VERDICTS)
    parts = [
        v.caption(band) + (f" ({counts.get(v.code, 0)} points)" if counts is not None else "")
        for v in vs
    ]
    return "stability (Hill's method): " + ", ".join(parts)


def verdict_legend(
    counts: dict[int, int], *, color: str = "0.25", band: bool = False, what: str = "points"
) -> list[tuple[str, dict]]:
    """Legend entries ``(label, Line2D keywords)`` of the verdicts, with their counts."""
    out = []
    for v in verdicts_shown(counts):
        lab = f"{v.label} ({counts.get(v.code, 0)} {what})"
        if band and v.band is not None:
            kw = {k: val for k, val in v.band.items() if k not in ("zorder", "solid_capstyle")}
        elif band:
            kw = dict(color=color, ls="-", lw=1.6)
        else:
            kw = dict(color=color, ls=v.ls, lw=1.6)
        out.append((lab, kw))
    return out


def peak_marker_legend(marker: str = "o") -> list[tuple[str, dict]]:
    """Legend entries of the peak markers: filled stable, hollow unstable, half unknown."""
    return [
        (
            f"peak {v.label}",
            dict(ls="none", marker=marker, ms=7, color="0.25", fillstyle=v.fill, mfc="0.25")
            if v.fill != "none"
            else dict(ls="none", marker=marker, ms=7, color="0.25", mfc="white"),
        )
        for v in VERDICTS
    ]


def marker_kwargs(code: int, color: str, marker: str, ms: float = 6.0) -> dict:
    """Marker keywords of a point whose verdict is ``code`` (filled, hollow, half)."""
    v = verdict(code)
    if v.fill == "none":
        return dict(marker=marker, ms=ms, mfc="white", mec=color, ls="none")
    return dict(
        marker=marker, ms=ms, fillstyle=v.fill, mfc=color, mec=color, mfcalt="white", ls="none"
    )


# ---- force levels ---------------------------------------------------------------------


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


# ---- checks ---------------------------------------------------------------------------


def lightness(color: str) -> float:
    """Relative luminance (0 black .. 1 white) of a colour: its grey level in print."""
    import matplotlib.colors as mc

    rgb = np.asarray(mc.to_rgb(color))
    lin = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
    return float(lin @ np.array([0.2126, 0.7152, 0.0722]))
