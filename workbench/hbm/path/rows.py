"""The points of a path as they are recorded: one list per column.

:class:`Rows` holds the columns of the problem's record (``names``, built
into arrays at the end) and any extra columns kept only in memory (the
solved unknowns a refinement interpolates between). A refinement solved
after the loop appends a row and moves it into place (:meth:`insert_last_at`).
"""

from __future__ import annotations

import numpy as np


class Rows:
    """Columns per point: ``cols[name]`` a list with one entry per recorded point."""

    def __init__(self, names: tuple[str, ...], extra: tuple[str, ...] = ()):
        self.names = tuple(names)
        self.cols: dict[str, list] = {k: [] for k in (*self.names, *extra)}

    @property
    def n(self) -> int:
        return len(self.cols[self.names[0]])

    def add(self, **kw) -> None:
        """Append one entry to each named column."""
        for k, v in kw.items():
            self.cols[k].append(v)

    def insert_last_at(self, pos: int) -> None:
        """Move the last row to position ``pos`` (every column)."""
        for col in self.cols.values():
            col.insert(pos, col.pop())

    def pop_last(self) -> None:
        """Drop the last row (every column)."""
        for col in self.cols.values():
            col.pop()

    def arrays(
        self, empty: dict[str, tuple[int, ...]], dtypes: dict[str, type]
    ) -> dict[str, np.ndarray]:
        """The record's columns as arrays: ``empty`` gives the shape of a column without
        rows (default (0,)), ``dtypes`` the type a column is cast to."""
        out = {}
        for k in self.names:
            v = self.cols[k]
            out[k] = np.array(v) if v else np.zeros(empty.get(k, (0,)))
        for k, t in dtypes.items():
            out[k] = out[k].astype(t)
        return out
