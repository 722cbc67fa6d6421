"""The label of the cone's status maps: why its line centres slip (issue 31, item 4).

"On the efficiency of a conical under-platform damper for turbines" shows
the cone's contact lines stuck in the middle and slipping at the ends; the
cone of this workbench slips along the whole line at 30 N. The reason was
measured on the paper-like rig at the main job's setting
(docs/notes/energy_convergence.md, "Item 4: why the cone's line centres
slip"; docs/FINDINGS.md): the relative motion along each line is a
near-uniform slide plus a normal rocking that unloads the line ends once per
cycle, and once the slide at the centre passes the slip limit
``mu N0 / kt`` every pair slips.

:func:`cone_status_label` gives, for the cases of one cone status map:

- a note per panel computed from that case's own record (the slide at the
  middle of the lines against ``mu N0 / kt``, and the swing of the normal
  load at the centre and the ends: :func:`workbench.post.line_slide.centre_slide`),
  on any rig;
- on the paper-like rig the explanation under the map and in the caption,
  with the force interval where this study's own cases cross the limit and
  pointers to the note and FINDINGS.

Only the cone's in-phase maps get a label: the mechanism was measured there.
Out of phase the normal load at the line centre swings by 47-97 % of the
preload in the main job, so the slide-to-limit ratio alone does not say
whether the centre slips (cone at 9.6 N: ratio 1.27, 9 of the 10 central
pairs stuck).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from ..post.line_slide import (
    CENTRAL_PAIRS,
    END_PAIRS,
    CentreSlide,
    centre_slide,
    limit_crossing,
)
from ..post.results import CaseResult

NOTE = "docs/notes/energy_convergence.md"
NOTE_SECTION = "Item 4: why the cone's line centres slip"
FINDINGS = "docs/FINDINGS.md"
PAPER_RIG_FILE = "paper_rig.toml"  # geometry/paper_rig.toml: the rig the reason was measured on
# the section's sentence when a cone map carries the explanation
EXPLAINED = (
    "The cone's in-phase map carries the reason its line centres slip at the higher forces "
    "while the paper's stay stuck with slipping ends, measured on this paper-like rig at the "
    "main job's setting (studies/paper_rig.toml) and not claimed for other rigs or dampers. "
    "Each panel's numbers (the slide at the line centres against the slip limit mu N0/kt, "
    "the swing of the normal load) are computed from that case's own solution. "
    f"Details: {NOTE} ('{NOTE_SECTION}') and {FINDINGS}."
)


@dataclass(frozen=True)
class StatusLabel:
    """What a cone status map carries: a note per panel ("" where the case's record does
    not hold the contact displacements), the explanation under the map (None off the
    paper-like rig or out of phase) and the sentences added to the figure's caption."""

    panel_notes: list[str]
    footnote: str | None
    caption: str


def on_paper_rig(case: CaseResult) -> bool:
    """True when the case was solved on the paper-like rig (geometry/paper_rig.toml)."""
    g = case.params.get("geometry") if isinstance(case.params, dict) else None
    return bool(g) and Path(str(g)).name == PAPER_RIG_FILE


def _panel_note(s: CentreSlide | None) -> str:
    if s is None:
        return ""
    note = f"centre slide {s.slide_um:.2f} um = {s.ratio:.2f} x mu N0/kt ({s.limit_um:.2f} um)"
    if s.swing_centre is not None and s.swing_ends is not None:
        note += (
            f"\nnormal load swing: centre {100 * s.swing_centre:.0f} %, "
            f"ends {100 * s.swing_ends:.0f} %"
        )
    return note


def _crossing_words(family: Sequence[CaseResult]) -> str:
    slides = [s for s in (centre_slide(c) for c in family) if s is not None]
    cross = limit_crossing(slides)
    if cross is not None:
        return f"here it passes between {cross[0]:g} and {cross[1]:g} N"
    if slides and all(s.ratio >= 1.0 for s in slides):
        return "here it is past at every force"
    if slides and all(s.ratio < 1.0 for s in slides):
        return "here it stays below at every force"
    return "this study's records do not say at which force it passes"


def cone_status_label(
    cases: Sequence[CaseResult], family: Sequence[CaseResult] = ()
) -> StatusLabel | None:
    """The label of one cone status map (``cases``: its panels; ``family``: every force of
    the same damper and family, for the force at which the slide passes the limit).
    None for any other damper or family, and where there is nothing to say."""
    cases = list(cases)
    if not cases or any(c.damper != "cone" or abs(c.phase_deg) > 1e-9 for c in cases):
        return None
    slides = [centre_slide(c) for c in cases]
    notes = [_panel_note(s) for s in slides]
    caption = ""
    if any(notes):
        caption = (
            " Under each panel title, from the case's own solution at the resonance: the "
            "slide at the middle of the contact lines (harmonic-1 amplitude of the tangential "
            f"relative displacement, mean over the {CENTRAL_PAIRS} central pairs of each line) "
            "against mu N0/kt, the slide at which a pair held stuck reaches the slip limit at "
            "its preload (above 1 it slips unless its normal load rises enough); and the swing "
            "of the normal load over the preload, kn u_n/N0 (u_n the harmonic-1 normal "
            f"amplitude), at the centre and at the {END_PAIRS} pairs at each end of each line."
        )
    footnote = None
    if all(on_paper_rig(c) for c in cases):
        when = _crossing_words(family or cases)
        footnote = (
            "Why the line centres slip here but stay stuck in the paper (measured on this "
            "paper-like rig at the main job's setting): each line slides almost uniformly and "
            "rocks, which unloads its ends once per cycle. Once the centre's slide passes "
            f"mu N0/kt the centres slip as well; {when}. The paper's stuck centres need a smaller "
            "in-phase peak, hence slide, than this rig gives. "
            f"See {NOTE} ('{NOTE_SECTION}') and {FINDINGS}."
        )
        caption += (
            f" {footnote} Inside the lines stuck and slipping pairs alternate node by node: "
            "the compliance of the mesh at each contact node varies along the line "
            "(workbench/assembly/flexibility.py)."
        )
    if not any(notes) and footnote is None:
        return None
    return StatusLabel(panel_notes=notes, footnote=footnote, caption=caption)
