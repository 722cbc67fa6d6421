"""A study never lies about its state (issue 13).

- a curve that stops before its resonance: the peak is only a lower bound,
  the case is named in the summary and the report, and the run exits 3;
- one run at a time on a study folder (a lock with a pid check);
- Ctrl-C during the curves of a second run: the one-line message, exit 130;
- a resumed report equals an uninterrupted one, apart from honest cost
  lines (reused work shown as reused, with its original cost).

The end-to-end tests work on copies of the tiny study that conftest's
``tiny_resumed`` runs once (tests/studies/tiny.toml, coarse mesh), so each
reuses its meshes and reduced models. The resumed report is checked in
tests/test_study_resume_mpi.py.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.conftest import ROOT, TINY, run_upd
from tests.synthetic import synthetic_case, synthetic_study
from workbench.errors import InputError, SolveError
from workbench.io import LOCK_NAME, folder_lock
from workbench.post.answer import cases_table
from workbench.studies.engine.outputs import check_failures, headline

pytestmark = pytest.mark.xdist_group("resume")  # shares the tiny study of conftest
CMD = [sys.executable, "-m", "workbench.cli.main", "study", str(TINY)]


# ---- incomplete curves: the peak is a lower bound (no FE) ---------------------------------


def _cut(case, n: int, message: str = "stopped after max_points = 5 points"):
    """The case as a continuation stopped after ``n`` points without failing."""
    import dataclasses

    b = case.branch
    sl = slice(0, n)
    short = dataclasses.replace(
        b,
        freq_hz=b.freq_hz[sl],
        stable=b.stable[sl],
        newton_its=b.newton_its[sl],
        energy_residual=b.energy_residual[sl],
        out_amp=b.out_amp[sl],
        out_h1=b.out_h1[sl],
        out_harm=b.out_harm[sl],
        status=b.status[sl],
        friction_energy=b.friction_energy[sl],
        x=b.x[sl],
        work_ext=b.work_ext[sl],
        work_visc=b.work_visc[sl],
        work_friction=b.work_friction[sl],
        work_normal=b.work_normal[sl],
        max_floquet_real=b.max_floquet_real[sl],
        completed=False,
        failed=False,
        message=message,
    )
    return dataclasses.replace(case, branch=short)


def test_a_curve_stopped_before_its_resonance_reports_a_lower_bound_only():
    full = synthetic_case("cone", 180.0, 30.0)
    assert full.peak_covered and full.summary()["peak_lower_bound_mm"] is None
    cut = _cut(full, 5)  # like --max-points 5: the curve ends far below the resonance
    s = cut.summary()
    assert not cut.peak_covered and s["peak_covered"] is False
    assert s["peak_amplitude_mm"] is None and s["peak_frequency_hz"] is None
    assert s["friction_energy_mj"] is None
    # the lower bound is honest: below the true peak, and said to be a lower bound
    assert 0 < s["peak_lower_bound_mm"] < full.summary()["peak_amplitude_mm"]
    assert "lower bound" in s["peak_note"] and "max_points" in s["peak_note"]


def test_a_peak_at_the_band_edge_is_not_a_peak():
    import dataclasses

    full = synthetic_case("cone", 180.0, 30.0)
    i = full.peak_index
    b = full.branch
    rising = dataclasses.replace(
        full,
        branch=dataclasses.replace(
            b,
            freq_hz=b.freq_hz[: i + 1],
            out_amp=b.out_amp[: i + 1],
            stable=b.stable[: i + 1],
            friction_energy=b.friction_energy[: i + 1],
            status=b.status[: i + 1],
            energy_residual=b.energy_residual[: i + 1],
        ),
    )
    assert rising.branch.completed and not rising.peak_covered
    assert "band edge" in rising.peak_note()


def test_study_with_a_short_curve_exits_3_and_names_it_everywhere():
    r = synthetic_study(dampers=("cone",), phases=(180.0,), forces=(9.6, 30.0))
    r.cases[1] = _cut(r.cases[1], 5)
    assert [c.case_id for c in r.uncovered()] == ["cone-180deg-30N"]
    with pytest.raises(SolveError) as e:
        check_failures(r, {"n_cases": 2})
    assert e.value.exit_code == 3 and e.value.summary == {"n_cases": 2}
    msg = str(e.value)
    assert "\n" not in msg and "cone-180deg-30N" in msg and "lower bound" in msg
    head = " ".join(headline(r))
    assert "NOT reached" in head and "at least" in head
    t = cases_table(r)
    rows = {row[2]: row for row in t.rows}  # one damper and family: by force
    amp, curve = t.header.index("vibration amplitude, harmonic 1 (mm)"), t.header.index("curve")
    assert rows["30"][amp].startswith(">= ") and rows["30"][amp].endswith("(peak not reached)")
    assert rows["30"][curve].startswith("stopped early after 5 points")
    assert rows["9.6"][curve].startswith("complete")
    check_failures(synthetic_study(dampers=("cone",), phases=(180.0,)))  # all fine: no error


# ---- the folder lock (no FE) --------------------------------------------------------------


def test_lock_refuses_a_live_owner_and_removes_a_stale_one(tmp_path, caplog, monkeypatch):
    import logging

    monkeypatch.setattr(logging.getLogger("workbench"), "propagate", True)
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        (tmp_path / LOCK_NAME).write_text(
            json.dumps({"pid": sleeper.pid, "host": os.uname().nodename})
        )
        with pytest.raises(InputError) as e, folder_lock(tmp_path):
            pass
        assert "--out" in str(e.value) and f"process {sleeper.pid}" in str(e.value)
    finally:
        sleeper.kill()
        sleeper.wait()
    # the owner is gone (killed): its lock is stale and must not block
    with folder_lock(tmp_path) as lock:
        assert json.loads(lock.read_text())["pid"] == os.getpid()
    assert not (tmp_path / LOCK_NAME).exists()
    assert "stale lock" in caplog.text
    # a pid that now belongs to another process (started at another time) is stale too
    (tmp_path / LOCK_NAME).write_text(json.dumps({"pid": os.getpid(), "start": "1"}))
    with folder_lock(tmp_path):
        pass


# ---- end to end, on copies of one finished tiny study -------------------------------------


@pytest.fixture(scope="module")
def warm(tiny_resumed) -> Path:
    return tiny_resumed[0]


def _copy(warm: Path, dest: Path, drop_cases: bool = False) -> Path:
    shutil.copytree(warm, dest)
    if drop_cases:
        for p in (dest / "cache" / "cases").glob("*.h5"):
            p.unlink()
    return dest


def _wait_for(path: Path, text: str, p: subprocess.Popen, timeout: float = 120.0) -> None:
    t0 = time.time()
    while text not in (path.read_text() if path.exists() else ""):
        assert p.poll() is None, f"ended early: {path.read_text()[-2000:]}"
        assert time.time() - t0 < timeout, f"no {text!r}"
        time.sleep(0.05)


def test_curves_stopped_by_max_points_exit_3_with_lower_bounds(warm, tmp_path):
    out = _copy(warm, tmp_path / "s")
    # half-written files of a killed run (atomic writes leave them only on SIGKILL)
    stale = [
        out / "cache" / "cases" / ".0123.h5.abcd.part",
        out / "figures" / ".x.png.k.part",
        out / "cache" / "geometry" / ".rig.1234.part.msh",
    ]
    for p in stale:
        p.write_bytes(b"half")
    r = run_upd("study", TINY, "--out", out, "--json", "--max-points", "5")
    assert not any(p.exists() for p in stale)  # cleaned at the next run
    assert r.code == 3, r
    err = r.err.strip().splitlines()[-1]
    assert err.startswith("upd study: error: 2 case(s) did not reach their resonance peak")
    assert "lower bound" in err
    j = json.loads(r.out)  # the summary is still printed
    assert sorted(j["peak_not_reached"]) == ["cone-180deg-15N", "cone-180deg-30N"]
    full = {c["case"]: c for c in json.loads((warm / "summary.json").read_text())}
    for c in json.loads((out / "summary.json").read_text()):
        assert c["peak_amplitude_mm"] is None and not c["peak_covered"]
        assert 0 < c["peak_lower_bound_mm"] < full[c["case"]]["peak_amplitude_mm"]
    html = (out / "report.html").read_text()
    assert "Peak NOT reached" in html and "peak not reached" in html


def test_a_second_run_on_the_same_folder_is_refused_at_once(warm, tmp_path):
    out = _copy(warm, tmp_path / "s", drop_cases=True)
    log = tmp_path / "first.err"
    with log.open("w") as fh:  # with its progress bars, as a user sees it
        first = subprocess.Popen(
            [*CMD, "--out", str(out)],
            cwd=ROOT,
            stdout=subprocess.DEVNULL,
            stderr=fh,
            env=dict(os.environ, UPD_NO_PROGRESS="0", UPD_PROGRESS="always"),
        )
    try:
        _wait_for(log, "model for cone", first)
        t0 = time.time()
        second = run_upd("study", TINY, "--out", out, "--json")
        assert first.poll() is None, "the first run ended before the second was refused"
        assert second.code == 2, second
        (line,) = second.err.strip().splitlines()
        assert "--out" in line and f"in use by process {first.pid}" in line
        assert time.time() - t0 < 30  # at once: before any work
        assert first.wait(timeout=300) == 0, log.read_text()[-2000:]
    finally:
        if first.poll() is None:
            first.kill()
    assert not (out / LOCK_NAME).exists()
    assert "cases:" in log.read_text()  # the bar was drawn ...
    assert "TqdmWarning" not in log.read_text()  # ... without tqdm clamping its fraction


def test_ctrl_c_during_the_curves_of_a_second_run(warm, tmp_path):
    """A warm cache: gmshio is imported before any gmsh session (the reported bug)."""
    out = _copy(warm, tmp_path / "s", drop_cases=True)
    log = tmp_path / "run.err"
    with log.open("w") as fh:
        # a run started in the background of a script inherits SIGINT ignored (and then
        # rightly ignores Ctrl-C); the test is about our handler, so the child starts with
        # the default disposition whatever the test runner's
        p = subprocess.Popen(
            [*CMD, "--out", str(out)],
            cwd=ROOT,
            stdout=subprocess.DEVNULL,
            stderr=fh,
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        )
    try:
        _wait_for(log, "cases to compute", p)
        p.send_signal(signal.SIGINT)
        assert p.wait(timeout=120) == 130, log.read_text()[-2000:]
    finally:
        if p.poll() is None:
            p.kill()
    assert "upd study: interrupted; finished work is kept" in log.read_text()
    assert not (out / LOCK_NAME).exists()
    assert not list(out.rglob("*.part"))


def test_a_corrupt_cache_file_is_rebuilt_with_a_warning(tmp_path, caplog, monkeypatch):
    import logging

    from workbench.fe.reduce import _load_if_current
    from workbench.geometry.build import _reusable

    monkeypatch.setattr(logging.getLogger("workbench"), "propagate", True)
    bad = tmp_path / "rig_cb12_0123.h5"
    bad.write_bytes(b"\x89HDF\r\n\x1a\n" + b"\0" * 64)  # a truncated HDF5 file
    assert _load_if_current(bad, "0123") is None
    assert "unreadable; rebuilding" in caplog.text
    caplog.clear()
    geo = tmp_path / "geometry.h5"
    geo.write_bytes(b"not hdf5")
    assert _reusable(geo, "0123") is None
    assert "unreadable" in caplog.text and "rebuilding" in caplog.text
