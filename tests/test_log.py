"""Progress bars: only on a terminal unless switched, whole-number counts with their unit."""

from __future__ import annotations

import io
import sys

import pytest

from workbench import log
from workbench.errors import InputError


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def _run(monkeypatch, stream, mode: str | None) -> str:
    monkeypatch.delenv("UPD_NO_PROGRESS", raising=False)
    if mode is None:
        monkeypatch.delenv("UPD_PROGRESS", raising=False)
    else:
        monkeypatch.setenv("UPD_PROGRESS", mode)
    monkeypatch.setattr(sys, "stderr", stream)
    monkeypatch.setattr(log, "_QUIET", False)
    assert list(log.progress(range(3), "figs", unit="fig")) == [0, 1, 2]
    with log.progress_bar("frf", total=70.123456, unit="Hz") as bar:
        bar.n = 35.5
        bar.update(0)
    return stream.getvalue()


def test_no_bar_and_no_escape_codes_in_a_log_file(monkeypatch):
    assert _run(monkeypatch, io.StringIO(), None) == ""
    assert _run(monkeypatch, _Tty(), "never") == ""


def test_bars_on_a_terminal_count_whole_units(monkeypatch):
    out = _run(monkeypatch, _Tty(), None)
    assert "0/3 fig" in out  # (redrawn at most every 0.5 s: the first draw is what we see)
    assert "0/70 Hz" in out and "70.1" not in out  # a float total shown as a whole number
    forced = _run(monkeypatch, io.StringIO(), "always")
    assert "0/3 fig" in forced


def test_bad_switch_is_an_input_error(monkeypatch):
    monkeypatch.setenv("UPD_PROGRESS", "sometimes")
    monkeypatch.delenv("UPD_NO_PROGRESS", raising=False)
    monkeypatch.setattr(log, "_QUIET", False)
    with pytest.raises(InputError, match="UPD_PROGRESS"):
        log.bars_enabled()


def test_numba_does_not_colour_through_colorama():
    """colorama (a pyNastran dependency) must not be used by numba: its exit hook writes an
    escape code to stdout and breaks --json (seen under mpirun)."""
    import subprocess

    code = (
        "import workbench, numba.core.errors as e; "
        "assert not hasattr(e, 'ColorShell'), 'numba uses colorama'"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert r.stdout == ""
