"""Files: atomic writes, canonical hashing, small HDF5 helpers.

Everything that is cached or resumed is written atomically (to a temporary
file in the same folder, then renamed), so a run killed at any moment
never leaves a half-written file that a later run would read.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np


@contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it over ``path`` on success."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent)
    os.close(fd)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; results are for everyone to read
    try:
        yield Path(tmp)
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def write_text(path: str | Path, text: str) -> Path:
    """Write a text file atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return Path(path)


def write_json(path: str | Path, obj: Any) -> Path:
    """Write JSON atomically (numpy scalars and arrays converted)."""
    return write_text(path, json.dumps(obj, indent=2, default=to_jsonable) + "\n")


def to_jsonable(o: Any) -> Any:
    """``json.dumps`` default: numpy types, paths, dataclass-like records."""
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    if hasattr(o, "__dataclass_fields__"):
        import dataclasses

        return dataclasses.asdict(o)
    raise TypeError(f"cannot write {type(o).__name__} as JSON")


def canonical_json(obj: Any) -> str:
    """A stable JSON text of ``obj`` (sorted keys, floats by repr)."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), default=to_jsonable)


def digest(obj: Any, n: int = 16) -> str:
    """Hex digest of the canonical JSON of ``obj``: the cache key of a unit of work."""
    return hashlib.sha256(canonical_json(obj).encode()).hexdigest()[:n]


def file_digest(path: str | Path, n: int = 16) -> str:
    """Hex digest of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()[:n]


def code_version(package_dir: str | Path, names: tuple[str, ...] | None = None,
                 tag: str = "") -> str:
    """Package version plus a hash of the sources that produce a cached result.

    ``names``: the files of ``package_dir`` that count (default: every
    ``*.py`` in it). A change to any of them changes the version, so every
    cache keyed on it is rebuilt.
    """
    from . import __version__

    here = Path(package_dir)
    files = sorted(here.glob("*.py")) if names is None else [here / n for n in names]
    parts = [file_digest(f, 8) for f in files if f.is_file()]
    return f"{__version__}+{tag}{digest(parts, 8)}"
