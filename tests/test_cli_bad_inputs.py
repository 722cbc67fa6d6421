"""Every bad input of tests/data/bad_inputs.toml is one clear line and exit code 2.

The table is data: one row per case (see the comment at its top), so adding
a case is one line. Each row runs ``upd`` in this process through
:func:`workbench.cli.main.main` (a subprocess per row would cost a second
of imports each), in a fresh folder holding the row's files, and checks:

- the exit code (2 unless the row says otherwise);
- stderr holds exactly one error line, ``upd ...: error: ...``, containing
  the row's ``needle`` (the parameter, option or file that is wrong), and no
  traceback and no "internal error";
- a rejected run leaves no output folder behind (``--out`` naming a folder
  that did not exist before);
- no work starts before the error: meshing (``gmsh.initialize``) and the
  harmonic balance (``Fourier``) are booby-trapped, so a row whose input is
  refused only after them fails (a bad input costs no work, and never a
  minute of meshing).
"""

from __future__ import annotations

import contextlib
import io
import json
import logging
import re
import shlex
import shutil
import tomllib
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import ROOT

TABLE = ROOT / "tests" / "data" / "bad_inputs.toml"
ROWS = tomllib.loads(TABLE.read_text())["row"]
ERROR_LINE = re.compile(r"^upd( \w+)?: error: ")


def _fill(text: str, d: Path) -> str:
    """``{d}`` the row's folder, ``{root}`` the repository, ``{ff}`` the byte 0xff (a file
    name that is not UTF-8, as Python keeps it: a surrogate)."""
    return text.replace("{d}", str(d)).replace("{root}", str(ROOT)).replace("{ff}", "\udcff")


def make_file(d: Path, name: str, spec: str) -> None:
    """Write one file of a row. ``spec`` is its text, or a directive:

    ``@hex HEX``              these bytes;
    ``@npz JSON``             a .npz of the arrays ``{"M": [[...]], ...}``;
    ``@h5 JSON``              an HDF5 file of those arrays;
    ``@h5cut JSON``           the same HDF5 file cut to half its length (truncated);
    ``@npzpy EXPR``           a .npz of the arrays of a Python expression (``np`` is numpy):
                              any dtype, CSR parts, complex values;
    ``@example NAME | OLD | NEW``
                              studies/examples/NAME with OLD replaced by NEW (its matrix
                              file is copied beside it).
    """
    p = d / _fill(name, d)
    p.parent.mkdir(parents=True, exist_ok=True)
    if spec.startswith("@npzpy "):
        arrays = eval(spec[7:], {"np": np})  # noqa: S307 - the test table's own data
        with p.open("wb") as fh:
            np.savez(fh, **arrays)
    elif spec.startswith("@hex "):
        p.write_bytes(bytes.fromhex(spec[5:].replace(" ", "")))
    elif spec.startswith(("@npz ", "@h5 ", "@h5cut ")):
        kind, _, data = spec.partition(" ")
        arrays = {k: np.asarray(v, dtype=float) for k, v in json.loads(data).items()}
        if kind == "@npz":
            with p.open("wb") as fh:
                np.savez(fh, **arrays)
        else:
            import h5py

            with h5py.File(p, "w") as h:
                for k, v in arrays.items():
                    h[k] = v
            if kind == "@h5cut":
                raw = p.read_bytes()
                p.write_bytes(raw[: len(raw) // 2])
    elif spec.startswith("@example "):
        src, old, new = (_nl(s.strip()) for s in spec[9:].split("|"))
        text = (ROOT / "studies" / "examples" / src).read_text()
        assert old in text, f"{old!r} not in {src}"
        p.write_text(text.replace(old, new))
        for npz in (ROOT / "studies" / "examples").glob(Path(src).stem + ".npz"):
            if not (d / npz.name).exists():
                shutil.copy(npz, d / npz.name)
    else:
        p.write_text(_nl(_fill(spec, d)))


def _nl(text: str) -> str:
    """``\\n`` written in a TOML literal string is a new line too."""
    return text.replace("\\n", "\n")


@contextlib.contextmanager
def _own_logging():
    """Let main() set up logging for this call only (its handler writes to the captured
    stderr) and restore the workbench logger afterwards for the other tests."""
    lg = logging.getLogger("workbench")
    saved = (lg.handlers[:], lg.level, lg.propagate)
    lg.handlers = []
    try:
        yield
    finally:
        lg.handlers, lg.level, lg.propagate = saved


def run_inprocess(argv: list[str], cwd: Path) -> tuple[int, str, str]:
    from workbench.cli.main import main

    out, err = io.StringIO(), io.StringIO()
    with (
        contextlib.chdir(cwd),
        contextlib.redirect_stdout(out),
        contextlib.redirect_stderr(err),
        _own_logging(),
    ):
        try:
            code = main(argv)
        except SystemExit as e:  # argparse
            code = e.code if isinstance(e.code, int) else 1
    return code, out.getvalue(), err.getvalue()


def test_the_table_is_large_and_every_row_is_distinct():
    assert len(ROWS) >= 140
    keys = [(r["argv"], json.dumps(r.get("files", {}), sort_keys=True)) for r in ROWS]
    dup = {k for k in keys if keys.count(k) > 1}
    assert not dup, dup


def _no_work(monkeypatch) -> None:
    """Meshing and the harmonic balance raise if they start: a refused input costs none."""
    import gmsh

    from workbench.hbm.core import fourier

    def boom(*_a, **_k):
        raise AssertionError("work started before the input was refused")

    monkeypatch.setattr(gmsh, "initialize", boom)
    monkeypatch.setattr(fourier.Fourier, "__post_init__", boom)


@pytest.mark.parametrize("row", ROWS, ids=[f"{i}:{r['argv'][:60]}" for i, r in enumerate(ROWS)])
def test_bad_input_is_one_line_naming_the_parameter(row, tmp_path, monkeypatch):
    _no_work(monkeypatch)
    d = tmp_path
    for name, spec in row.get("files", {}).items():
        make_file(d, name, spec)
    argv = [_fill(a, d) for a in shlex.split(row["argv"])]
    outs = [Path(argv[i + 1]) for i, a in enumerate(argv[:-1]) if a == "--out"]
    fresh = [p if p.is_absolute() else d / p for p in outs]
    fresh = [p for p in fresh if not p.exists()]
    code, _, err = run_inprocess(argv, d)
    want = row.get("exit", 2)
    errors = [ln for ln in err.splitlines() if ERROR_LINE.match(ln)]
    assert code == want, f"exit {code}, stderr:\n{err[-1500:]}"
    assert "Traceback" not in err and "internal error" not in err, err[-1500:]
    assert len(errors) == 1, err[-1500:]
    assert row["needle"] in errors[0], errors[0]
    for p in fresh:
        assert not p.exists(), f"a rejected run left {p}"
