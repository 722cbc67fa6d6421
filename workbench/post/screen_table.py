"""The coupling screen's table: columns, cell formats, header and cells from screen rows.

Plain formatting of the rows of :mod:`workbench.studies.engine.screening` (one
per model and phase), shared by ``upd screen`` and the study report.
"""

from __future__ import annotations

from typing import Any

COLUMNS = (
    ("damper", "damper", "{}"),
    ("variant", "variant", "{}"),
    ("family", "family", "{}"),
    ("f_stuck_hz", "stuck (Hz)", "{:.1f}"),
    ("f_slide_hz", "sliding (Hz)", "{:.1f}"),
    ("k2_over_k", "k2/k", "{:.3f}"),
    ("bound_k2_over_k", "rig bound k2/k", "{:.3f}"),
    ("f_slip_n", "slip onset (N)", "{:.3g}"),
    ("f_sep_n", "separation onset (N)", "{:.3g}"),
    ("f_cap_n", "levels off up to (N)", "{:.3g}"),
    ("stuck_peak_m_per_n", "stuck peak (mm/N)", "{:.3g}"),
    ("growth", "A(Fmax)/A(0.32 Fmax)", "{:.2f}"),
    ("verdict", "verdict", "{}"),
)


def format_cell(key: str, fmt: str, value: Any) -> str:
    """A table cell: 'never' for an onset that does not exist, mm/N from m/N."""
    if value is None:
        return "never" if key in ("f_slip_n", "f_sep_n", "f_cap_n") else "-"
    if key == "stuck_peak_m_per_n":
        value = value * 1e3
    if key in ("k2_over_k", "bound_k2_over_k") and -1e-3 < value < 0.0:
        value = 0.0  # a mode-tracking round-off (f_slide a hair above f_stuck), not a value
    return fmt.format(value)


def table(rows: list[dict[str, Any]]) -> tuple[list[str], list[list[str]]]:
    """Header and cells of the screen table (variant column only when some row has one)."""
    cols = [c for c in COLUMNS if c[0] != "variant" or any(r.get("variant") for r in rows)]
    head = [c[1] for c in cols]
    body = [[format_cell(k, f, r.get(k)) for k, _, f in cols] for r in rows]
    return head, body
