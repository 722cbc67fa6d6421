"""The study-kind registry: the built-in kinds, and a kind dropped in a folder of its own.

A kind is one package ``workbench/studies/kinds/<name>/`` with ``KIND =
StudyKind(...)``; the CLI (its ``--kind`` choices, its options and ``upd
study --help``), the study specification and the runner find it by name,
with no other edit (as tests/test_shapes.py shows for damper shapes).
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from conftest import ROOT

from workbench.errors import InputError
from workbench.studies import kinds
from workbench.studies.engine.spec import BY_NAME, OPTIONS, resolve

# A whole study kind in one package: one option of its own, its check, its run.
ECHO = '''"""A test kind: writes its one option and the damper list into the study folder."""
import json
from dataclasses import dataclass
from pathlib import Path

from workbench.errors import InputError
from workbench.studies.kinds import StudyKind
from workbench.study_options import option


@dataclass(frozen=True)
class EchoOptions:
    echo_words: int = option("int", 3, "echo: words to write", "echo", lo=1, hi=9)


def _check(spec):
    if spec.echo.echo_words == 7:
        raise InputError("echo-words", 7, "any whole number 1..9 but 7")


def _run(spec, out, force=False):
    summary = {"kind": spec.kind, "words": spec.echo.echo_words, "dampers": spec.dampers}
    Path(out, "echo.json").write_text(json.dumps(summary))
    return summary


KIND = StudyKind(name="echo", description="writes its option back (a test kind)",
                 run=_run, options=EchoOptions, check=_check, order=90)
'''

BUILT_IN = (
    "comparison",
    "sweep",
    "fidelity",
    "robustness",
    "uncertainty",
    "bladed_disk",
    "mistuning",
)


def test_the_built_in_kinds_are_registered_in_order_with_their_options():
    assert kinds.names() == BUILT_IN
    assert BY_NAME["kind"].choices == BUILT_IN
    # each kind's own options are study options, after the shared ones, in kind order
    own = [o.name for k in kinds.all_kinds() for o in k.declared]
    assert {"tolerance", "levels-nt", "methods", "uq-samples", "mistuning-std"} <= set(own)
    assert [o.name for o in OPTIONS][-len(own) :] == own
    # and they are checked in every study, whatever its kind (a typo is a typo)
    with pytest.raises(InputError, match="levels-harmonics"):
        resolve({"levels-harmonics": ["0-x"]})
    with pytest.raises(InputError, match="uq-mu"):
        resolve({"kind": "comparison", "uq-mu": "normal 0.5 0.1 -1 3"})


def test_an_unknown_kind_is_refused_with_the_list():
    with pytest.raises(InputError) as e:
        kinds.get("comparisn")
    assert "comparison" in str(e.value) and "uncertainty" in str(e.value)


@pytest.fixture
def echo_dir(tmp_path, monkeypatch):
    """The package of kind 'echo', outside the repository, registered for one test."""
    pkg = tmp_path / "kinds" / "echo"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text(ECHO)
    monkeypatch.setattr(kinds, "__path__", [*kinds.__path__, str(tmp_path / "kinds")])
    kinds.rediscover()
    yield tmp_path / "kinds"
    monkeypatch.undo()
    sys.modules.pop("workbench.studies.kinds.echo", None)
    kinds.rediscover()


def _upd_with(extra: str, *args: str) -> subprocess.CompletedProcess:
    """``upd`` in a fresh process whose kind registry also searches the folder ``extra``."""
    code = (
        "import sys, workbench.studies.kinds as k; k.__path__.append(sys.argv[1]); "
        "from workbench.cli.main import main; sys.exit(main(sys.argv[2:]))"
    )
    cmd = [sys.executable, "-c", code, extra, *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=300, cwd=ROOT)


def test_a_new_kind_package_is_found_without_other_edits(echo_dir, tmp_path):
    assert kinds.names() == (*BUILT_IN, "echo")
    assert kinds.get("echo").declared[0].name == "echo-words"
    # the CLI lists it in --help, offers its option and runs it through the registry
    h = _upd_with(str(echo_dir), "study", "--help")
    assert h.returncode == 0, h.stderr
    assert "echo         writes its option back" in h.stdout and "--echo-words" in h.stdout
    out = tmp_path / "out"
    r = _upd_with(
        str(echo_dir), "study", "--kind", "echo", "--echo-words", "5", "--dampers", "wedge",
        "--out", str(out), "--json",
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    want = {"kind": "echo", "words": 5, "dampers": ["wedge"]}
    got = json.loads(r.stdout)
    got.pop("wall_s")  # the CLI adds the run's wall time to every summary
    assert got == want == json.loads((out / "echo.json").read_text())
    # its option is range-checked like any other, and its own check runs
    bad = _upd_with(
        str(echo_dir), "study", "--kind", "echo", "--echo-words", "7", "--out", str(out)
    )
    assert bad.returncode == 2 and "echo-words" in bad.stderr and "but 7" in bad.stderr
    bad = _upd_with(
        str(echo_dir), "study", "--kind", "echo", "--echo-words", "12", "--out", str(out)
    )
    assert bad.returncode == 2 and "echo-words" in bad.stderr and "9" in bad.stderr


def test_a_kinds_inputs_table_leaves_out_what_it_does_not_read():
    """The disk kinds reduce one sector with their own modes and contact points and run
    Hill's method on worst peaks only (or not at all): their Inputs tables must not state
    the rig's ``modes``, ``points-per-line``, ``rigid-damper`` or a ``stability`` they did
    not use. Each ignored name is a real option (a typo would hide nothing), and the
    comparison still lists them."""
    names = {o.name for o in OPTIONS}
    full = {r[0] for r in kinds.inputs_table("comparison")}
    for kind in ("bladed_disk", "mistuning"):
        k = kinds.get(kind)
        assert k.ignores and set(k.ignores) <= names
        rows = {r[0] for r in kinds.inputs_table(kind)}
        assert not rows & set(k.ignores)
        assert {"damping", "harmonics", "nt", "max-points"} <= rows  # these it reads
    assert {"modes", "points-per-line", "rigid-damper", "stability"} <= full
