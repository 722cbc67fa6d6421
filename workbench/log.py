"""Logging and progress bars.

Library code logs through ``logging.getLogger(__name__)`` and shows progress
with :func:`progress`; it never prints. The CLI calls :func:`setup` once:
messages and bars go to stderr so that ``--json`` output on stdout stays
machine-readable. Under MPI only rank 0 draws bars.

Bars are drawn only when stderr is a terminal, so a log file or a CI log
gets plain log lines and no escape codes. The switch is the environment
variable ``UPD_PROGRESS``: ``auto`` (default: bars on a terminal only),
``always`` or ``never`` (``UPD_NO_PROGRESS=1`` is the same as ``never``);
``-q`` turns them off too. Counts are whole numbers with the unit they
count (case, fig, rhs, Hz of the band swept).
"""

from __future__ import annotations

import logging
import os
import sys
import time
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from typing import TypeVar

T = TypeVar("T")

_QUIET = False


def setup(verbosity: int = 0) -> None:
    """Configure the ``workbench`` logger: -1 quiet, 0 info, 1+ debug."""
    global _QUIET
    _QUIET = verbosity < 0
    level = logging.WARNING if verbosity < 0 else logging.INFO if verbosity == 0 else logging.DEBUG
    root = logging.getLogger("workbench")
    root.setLevel(level)
    if not root.handlers:
        h = logging.StreamHandler(sys.stderr)
        rank = mpi_rank()
        prefix = f"[{rank}] " if mpi_size() > 1 else ""
        h.setFormatter(logging.Formatter(prefix + "%(levelname).1s %(name)s: %(message)s"))
        root.addHandler(h)
    root.propagate = False


def mpi_rank() -> int:
    """This process's MPI rank, without importing mpi4py when not under MPI."""
    for var in ("OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"):
        if var in os.environ:
            return int(os.environ[var])
    return 0


def mpi_size() -> int:
    """The number of MPI ranks, without importing mpi4py when not under MPI."""
    for var in ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE"):
        if var in os.environ:
            return int(os.environ[var])
    return 1


PROGRESS_CHOICES = ("auto", "always", "never")


def bars_enabled() -> bool:
    """True when progress bars are drawn (see the module docstring for the switch)."""
    if _QUIET or mpi_rank() != 0 or os.environ.get("UPD_NO_PROGRESS", "") == "1":
        return False
    mode = os.environ.get("UPD_PROGRESS", "auto").strip().lower() or "auto"
    if mode not in PROGRESS_CHOICES:
        from .errors import check_choice

        check_choice("UPD_PROGRESS", mode, PROGRESS_CHOICES)
    if mode == "auto":
        return sys.stderr.isatty()
    return mode == "always"


# whole numbers even when a bar counts a float quantity (the Hz of a band)
_FORMAT = (
    "{desc}: {percentage:3.0f}%|{bar}| {n:.0f}/{total:.0f} {unit} [{elapsed}<{remaining}{postfix}]"
)


def progress(
    iterable: Iterable[T], desc: str, total: int | None = None, unit: str = "item"
) -> Iterator[T]:
    """Iterate with a progress bar on stderr (name, count, rate, ETA)."""
    from tqdm import tqdm

    if total is None and hasattr(iterable, "__len__"):
        total = len(iterable)  # type: ignore[arg-type]
    yield from tqdm(
        iterable,
        desc=desc,
        total=total,
        unit=unit,
        file=sys.stderr,
        disable=not bars_enabled(),
        mininterval=0.5,
        dynamic_ncols=True,
        leave=False,
        bar_format=_FORMAT if total is not None else None,
    )


@contextmanager
def progress_bar(desc: str, total: float, unit: str = "item"):
    """A manually advanced bar: ``with progress_bar(..) as bar: bar.update(n)``.

    ``bar.set_postfix_str(s)`` shows extra state (for example the current
    frequency of a continuation).
    """
    from tqdm import tqdm

    bar = tqdm(
        desc=desc,
        total=total,
        unit=unit,
        file=sys.stderr,
        disable=not bars_enabled(),
        mininterval=0.5,
        dynamic_ncols=True,
        leave=False,
        bar_format=_FORMAT,
    )
    try:
        yield bar
    finally:
        bar.close()


@contextmanager
def stage(timings: dict[str, float] | None, name: str):
    """Time a block; add the wall time in seconds to ``timings[name]``."""
    t0 = time.perf_counter()
    try:
        yield
    finally:
        if timings is not None:
            timings[name] = timings.get(name, 0.0) + time.perf_counter() - t0
