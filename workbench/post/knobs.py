"""The modelling knobs a fidelity study can move, in their canonical order.

A module of its own, with no imports, so that the study options (read at every
``upd`` start) and the fidelity post-processing share one list without the
options loading numpy and the case records.
"""

from __future__ import annotations

KNOBS = (
    "mesh-size",
    "contact-mesh-size",
    "modes",
    "harmonics",
    "nt",
    "points-per-line",
    "rigid-damper",
)

__all__ = ["KNOBS"]
