"""Plain CSV tables of dict rows, written atomically: one writer for every row table.

The report tables with their markdown twins are :class:`workbench.post.tables.Table`;
this module writes rows of records (study summaries, screens, backbones).
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from . import write_text


def csv_cell(v: Any, digits: int = 9) -> str:
    """One CSV cell: '' for None, floats to ``digits`` significant digits (nan kept)."""
    if v is None:
        return ""
    if isinstance(v, float):
        return "nan" if math.isnan(v) else f"{v:.{digits}g}"
    return str(v)


def write_rows_csv(
    path: str | Path,
    rows: Sequence[dict[str, Any]],
    cols: Sequence[str] | None = None,
    digits: int = 9,
) -> Path:
    """Write dict rows as CSV (columns ``cols``, default the first row's keys), atomically."""
    cols = list(cols if cols is not None else (rows[0] if rows else []))
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(cols)
    w.writerows([csv_cell(r.get(k), digits) for k in cols] for r in rows)
    return write_text(path, buf.getvalue())
