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


def code_version(
    package_dir: str | Path, names: tuple[str, ...] | None = None, tag: str = ""
) -> str:
    """Package version plus a hash of the sources that produce a cached result.

    ``names``: the files of ``package_dir`` that count, relative to it
    (default: every ``*.py`` in it and in its sub-packages, e.g. the contact
    laws of ``contact/laws/``). A change to any of them changes the version,
    so every cache keyed on it is rebuilt.
    """
    from .. import __version__

    here = Path(package_dir)
    files = sorted(here.rglob("*.py")) if names is None else [here / n for n in names]
    parts = [file_digest(f, 8) for f in files if f.is_file()]
    return f"{__version__}+{tag}{digest(parts, 8)}"


def unwritable(folder: str | Path) -> str | None:
    """None if a file can be created, written and removed in ``folder``, else the reason.

    A real write, not ``os.access``: root passes every permission check, yet
    cannot write in /sys or /proc or on a read-only or full file system.
    """
    try:
        fd, tmp = tempfile.mkstemp(prefix=".upd-probe-", dir=folder)
    except OSError as e:
        return e.strerror or type(e).__name__
    try:
        os.write(fd, b"upd\n")
    except OSError as e:
        return e.strerror or type(e).__name__
    finally:
        os.close(fd)
        try:
            os.unlink(tmp)
        except OSError:
            pass
    return None


def rescue_folder(name: str) -> Path:
    """A new folder for results that could not be written where asked: under the system's
    temporary folder, else the home folder (``upd-<name>-XXXX``)."""
    import pathlib

    for base in (tempfile.gettempdir(), str(pathlib.Path.home())):
        try:
            d = Path(tempfile.mkdtemp(prefix=f"upd-{name}-", dir=base))
        except OSError:
            continue
        if unwritable(d) is None:
            return d
    raise OSError(f"no writable folder for the results of {name}")


def utf8_name(text: str) -> str | None:
    """None if ``text`` (a file name) is valid UTF-8, else its bytes shown with escapes.

    Python keeps the bytes of a name that is not UTF-8 as surrogates; HDF5,
    gmsh, JSON and HTML cannot write them.
    """
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        return os.fsencode(text).decode("utf-8", "backslashreplace")
    return None


LOCK_NAME = ".upd.lock"


def _process_start(pid: int) -> str:
    """The start time of a process (clock ticks since boot, from /proc), "" if unknown."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
        return stat.rsplit(")", 1)[1].split()[19]
    except (OSError, IndexError):
        return ""


def _lock_owner_alive(info: dict[str, Any]) -> bool:
    """True when the process that wrote a lock file still runs (on this host)."""
    import socket

    pid = info.get("pid")
    if not isinstance(pid, int) or pid <= 0:
        return False
    if info.get("host") not in (None, socket.gethostname()):
        return True  # another machine's process: it cannot be checked, so it is respected
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass  # it exists, owned by another user
    start = info.get("start")
    return not (start and _process_start(pid) and _process_start(pid) != start)  # pid reused


@contextmanager
def folder_lock(folder: str | Path, option: str = "--out") -> Iterator[Path]:
    """Hold ``folder/.upd.lock`` while a run writes into ``folder``.

    A second run on the same folder is refused at once with an
    :class:`~workbench.errors.InputError` naming ``option``, the folder and
    the process holding it. A lock left by a run that was killed (its
    process no longer exists, or its pid now belongs to another process) is
    stale: it is removed with a warning and the run goes on.
    """
    import logging
    import socket
    import time

    from ..errors import InputError

    folder = Path(folder)
    lock = folder / LOCK_NAME
    me = {
        "pid": os.getpid(),
        "host": socket.gethostname(),
        "start": _process_start(os.getpid()),
        "since": time.strftime("%Y-%m-%d %H:%M:%S"),
    }
    for _ in range(20):
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            try:
                text = lock.read_text()
                info = json.loads(text)
            except FileNotFoundError:
                continue  # released meanwhile: try again
            except (OSError, ValueError):
                # being written by its owner this instant, or a stale half-written lock
                try:
                    young = time.time() - lock.stat().st_mtime < 5.0
                except FileNotFoundError:
                    continue
                if young:
                    time.sleep(0.2)
                    continue
                info = {}
            if isinstance(info, dict) and _lock_owner_alive(info):
                raise InputError(
                    option,
                    str(folder),
                    "a folder no other upd run is writing to",
                    f"in use by process {info.get('pid')} since {info.get('since', '?')}; "
                    "wait for it to end or choose another folder",
                ) from None
            logging.getLogger(__name__).warning(
                "removing the stale lock of %s (process %s no longer runs)",
                folder,
                info.get("pid", "?") if isinstance(info, dict) else "?",
            )
            try:
                lock.unlink()
            except FileNotFoundError:
                pass
            continue
        with os.fdopen(fd, "w") as fh:
            fh.write(json.dumps(me) + "\n")
        break
    else:
        raise InputError(
            option, str(folder), "a folder whose lock can be taken", f"could not take {lock}"
        )
    try:
        yield lock
    finally:
        try:
            if json.loads(lock.read_text()).get("pid") == me["pid"]:
                lock.unlink()
        except (OSError, ValueError):
            pass
