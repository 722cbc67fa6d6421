"""One HDF5 writer and reader for the records of a followed path.

A forced response (:class:`workbench.hbm.forced.branch.Branch`) and a backbone
(:class:`workbench.hbm.nlmodes.record.NlModeBranch`) are dataclasses of
per-point arrays, a few other arrays and scalar attributes. Each class
declares its file layout once (:class:`Layout`): the datasets, in the order
they are written, and the attributes with the kind of value each holds.
:func:`write_record` writes an object by its layout atomically (a reader
never sees half a file), :func:`read_record` returns the keyword arguments
that rebuild it. :class:`PathRecord` gives both classes ``save`` and
``load`` through their ``LAYOUT``.

Attribute kinds: ``"float"``, ``"int"``, ``"bool"``, ``"str"`` (scalars),
``"floats"`` / ``"ints"`` (a tuple, stored as an array), ``"names"`` (a
tuple of strings, stored as a JSON list) and ``"json"`` (a dict, stored as
JSON; numbers numpy holds are written as floats).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

KINDS = ("float", "int", "bool", "str", "floats", "ints", "names", "json")


@dataclass(frozen=True)
class Layout:
    """The HDF5 layout of one record class.

    ``datasets``: the array fields written as datasets, in order;
    ``required``: those a file must have (reading a file without them
    raises ``KeyError``); the others are read where present (older files)
    and otherwise left to the class's default. ``attrs``: (field name, kind)
    of each attribute of the root group, in the order written.
    """

    datasets: tuple[str, ...]
    attrs: tuple[tuple[str, str], ...]
    required: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        bad = [k for _, k in self.attrs if k not in KINDS]
        if bad:
            raise ValueError(f"attribute kinds {bad} not in {KINDS}")
        extra = set(self.required) - set(self.datasets)
        if extra:
            raise ValueError(f"required datasets {sorted(extra)} not in the layout")


def _encode(value: Any, kind: str) -> Any:
    if kind == "floats":
        return np.asarray(value, dtype=float)
    if kind == "ints":
        return np.asarray(value, dtype=int)
    if kind == "names":
        return json.dumps(list(value))
    if kind == "json":
        return json.dumps(value, default=float)
    return value


def _decode(value: Any, kind: str) -> Any:
    if kind == "floats":
        return tuple(float(v) for v in value)
    if kind == "ints":
        return tuple(int(v) for v in value)
    if kind in ("names", "json"):
        out = json.loads(value)
        return tuple(out) if kind == "names" else out
    return {"float": float, "int": int, "bool": bool, "str": str}[kind](value)


def write_record(path: str | Path, obj: Any, layout: Layout) -> Path:
    """Write ``obj``'s datasets and attributes by ``layout`` to ``path`` atomically."""
    import h5py

    from . import atomic_path

    path = Path(path)
    with atomic_path(path) as tmp, h5py.File(tmp, "w") as h:
        for name in layout.datasets:
            h.create_dataset(name, data=getattr(obj, name))
        for name, kind in layout.attrs:
            h.attrs[name] = _encode(getattr(obj, name), kind)
    return path


def read_record(path: str | Path, layout: Layout) -> dict[str, Any]:
    """The keyword arguments of the record stored at ``path`` by ``layout``."""
    import h5py

    with h5py.File(path, "r") as h:
        kw = {name: h[name][()] for name in layout.datasets if name in layout.required or name in h}
        for name, kind in layout.attrs:
            kw[name] = _decode(h.attrs[name], kind)
    return kw


R = TypeVar("R", bound="PathRecord")


class PathRecord:
    """What a record of a followed path shares: its file layout (``LAYOUT``), ``save``
    and ``load``. Subclasses are dataclasses whose fields the layout names."""

    LAYOUT: Layout

    def save(self, path: str | Path) -> Path:
        """Write to HDF5 atomically."""
        return write_record(path, self, self.LAYOUT)

    @classmethod
    def load(cls: type[R], path: str | Path) -> R:
        return cls(**cls.from_file(read_record(path, cls.LAYOUT)))

    @classmethod
    def from_file(cls, kw: dict[str, Any]) -> dict[str, Any]:
        """The keyword arguments as read, adjusted to the class (default: unchanged)."""
        return kw
