"""The worker pool that meshes and reduces a study's models at once
(workbench.studies.engine.prefetch).

* the pool writes the very models one process writes (bitwise) and the
  screen built on them is the same;
* its scheduler starts the meshes first, never exceeds the memory budget
  (a task larger than the budget runs alone), and leaves a failed task to
  the main process (with the reductions that waited for it);
* a bad ``UPD_WORKERS`` is refused with its name.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np
import pytest

from workbench.errors import InputError
from workbench.studies.engine.prefetch import Task, _Scheduler, worker_count

ROOT = Path(__file__).resolve().parents[1]
TINY = ROOT / "tests" / "studies" / "tiny.toml"


@pytest.fixture(scope="module")
def one_process(tmp_path_factory):
    """The tiny screen computed the usual way, in one process (UPD_WORKERS=1, conftest)."""
    from conftest import run_upd

    out = tmp_path_factory.mktemp("one_process")
    r = run_upd("screen", TINY, "--out", out, "--json")
    assert r.code == 0, r
    assert r.json["worker_pool"]["workers"] == 0
    return out


def assert_same_models(a: Path, b: Path) -> None:
    """Both folders hold the same three reduced models, bit for bit, and the same screen."""
    files = sorted(p.name for p in (a / "cache" / "fe").glob("*.h5"))
    assert len(files) == 3  # rig, damper, rigid damper (the screen's rig bound)
    assert files == sorted(p.name for p in (b / "cache" / "fe").glob("*.h5"))
    for name in files:
        with h5py.File(a / "cache" / "fe" / name) as x, h5py.File(b / "cache" / "fe" / name) as y:
            for key in ("K", "M"):
                assert np.array_equal(x[key][()], y[key][()]), (name, key)

    def rows(out):
        return [{k: v for k, v in r.items() if k != "seconds"} for r in json.loads(
            (out / "screen.json").read_text())]  # fmt: skip

    assert rows(a) == rows(b)


@pytest.mark.xdist_group("prefetch")
def test_the_pool_writes_the_models_one_process_writes(one_process, tmp_path, monkeypatch):
    from conftest import run_upd

    monkeypatch.setenv("UPD_WORKERS", "2")
    r = run_upd("screen", TINY, "--out", tmp_path / "pool", "--json")
    assert r.code == 0, r
    pool = r.json["worker_pool"]
    # meshes, rig, damper and the rigid damper of the screen's rig bound
    assert pool["workers"] == 2 and pool["tasks"] == 4 and pool["failed"] == []
    assert_same_models(one_process, tmp_path / "pool")


@pytest.mark.mpi
@pytest.mark.xdist_group("prefetch")
def test_ranks_write_the_models_one_process_writes(one_process, tmp_path):
    """Under mpirun each rank reduces whole models alone: the same files, bit for bit."""
    import os
    import shutil
    import subprocess
    import sys

    par = tmp_path / "mpi"
    cmd = [shutil.which("mpirun"), "-n", "2", "--allow-run-as-root", "--oversubscribe",
           sys.executable, "-m", "workbench.cli.main", "screen", str(TINY), "--out", str(par),
           "--json"]  # fmt: skip
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=600, env=dict(os.environ))
    assert p.returncode == 0, p.stderr[-3000:]
    pool = json.loads(p.stdout)["worker_pool"]
    assert pool["workers"] == 2 and pool["tasks"] == 4 and pool["failed"] == []
    assert_same_models(one_process, par)


def test_a_bad_worker_count_is_refused_with_its_name(tmp_path, monkeypatch):
    from conftest import run_upd

    for bad in ("0", "two"):
        monkeypatch.setenv("UPD_WORKERS", bad)
        with pytest.raises(InputError, match="UPD_WORKERS"):
            worker_count()
        r = run_upd("screen", TINY, "--out", tmp_path / "x")
        assert r.code == 2 and "UPD_WORKERS" in r.err and bad in r.err, r


# --- the scheduler, with a pool that runs nothing --------------------------------------


@dataclass
class FakeCase:
    model_digest: str
    damper: str = "cone"
    variant: str = ""


class FakeFuture:
    def __init__(self, value=None, error=None):
        self.value, self.error, self.finished = value, error, False

    def done(self):
        return self.finished

    def result(self):
        if self.error is not None:
            raise self.error
        return self.value


class FakePool:
    def __init__(self):
        self.started: list[tuple] = []

    def submit(self, fn, *args):
        f = FakeFuture(value=1.0)
        self.started.append((args[0], args[1].model_digest, f))
        return f


class FakeBar:
    total = 0

    def update(self, n):
        pass


def scheduler(tasks, budget, n_workers=2):
    sch = _Scheduler(FakePool(), tasks, n_workers, budget, Path("."), dict(failed=[],
                     task_seconds={}))  # fmt: skip
    sch.bar = FakeBar()
    return sch


def test_meshes_start_first_and_memory_is_never_overcommitted():
    a, b = FakeCase("a"), FakeCase("b")
    tasks = [
        Task("rig", a, n_dofs=3000, label="rig a"),  # 72 MB each at 24 kB a DOF
        Task("rig", b, n_dofs=3000, label="rig b"),
        Task("geometry", FakeCase("c"), label="meshes c"),
        Task("reductions", FakeCase("c"), after="c"),
    ]
    sch = scheduler(tasks, budget=100e6)
    sch.start()
    kinds = [s[0] for s in sch.pool.started]
    assert kinds == ["geometry", "rig"]  # meshes first; the two rigs do not fit together
    assert sum(t.memory for t in sch.running.values()) <= 100e6
    # the placeholder of model c's reductions is never sent to a worker
    assert all(s[0] != "reductions" for s in sch.pool.started)


def test_a_task_larger_than_the_budget_runs_alone():
    big, small = FakeCase("big"), FakeCase("small")
    tasks = [Task("rig", big, n_dofs=10**6, label="big"), Task("damper", small, n_dofs=10,
             label="small")]  # fmt: skip
    sch = scheduler(tasks, budget=1e6)
    sch.start()
    assert [s[1] for s in sch.pool.started] == ["big"]  # alone, though over the budget
    sch.pool.started[0][2].finished = True
    sch.collect()
    sch.start()
    assert [s[1] for s in sch.pool.started] == ["big", "small"]


def test_a_failed_mesh_leaves_its_models_to_the_main_process():
    c, d = FakeCase("c"), FakeCase("d")  # two models on the same meshes (a sweep of mu)
    tasks = [
        Task("geometry", c, label="meshes c", key="geometry:g"),
        Task("reductions", c, after="geometry:g"),
        Task("reductions", d, after="geometry:g"),
    ]
    sch = scheduler(tasks, budget=1e9)
    sch.start()
    assert len(sch.pool.started) == 1  # the placeholders are never sent to a worker
    r = sch.pool.started[0][2]
    r.error, r.finished = RuntimeError("gmsh said no"), True
    sch.collect()
    assert sch.res["failed"] == ["meshes c"]
    assert sch.pending == [] and sch.running == {}  # neither model's reductions attempted


def test_a_pool_broken_by_an_idle_worker_leaves_the_work_to_the_main_process():
    """A worker killed while it waits for work breaks the pool with no future to tell:
    the next submission raises. The scheduler stops there and lists the unstarted work
    as failed (the main process does it), never an internal error."""
    from concurrent.futures.process import BrokenProcessPool

    class BrokenPool(FakePool):
        def submit(self, fn, *args):
            raise BrokenProcessPool("A child process terminated abruptly")

    tasks = [Task("rig", FakeCase("a"), n_dofs=10, label="rig a"),
             Task("damper", FakeCase("a"), n_dofs=10, label="damper a")]  # fmt: skip
    sch = scheduler(tasks, budget=1e9)
    sch.pool = BrokenPool()
    sch.start()
    assert sch.abandoned
    assert sorted(sch.res["failed"]) == ["damper a", "rig a"]
    assert sch.pending == [] and sch.running == {}


def test_a_task_error_survives_the_trip_back_from_a_worker(monkeypatch):
    """The pool pickles a task's exception; ours cannot be rebuilt from a pickle (it
    would come back as a broken pool), so the worker sends a RuntimeError that carries
    the message."""
    import pickle

    import workbench.studies.engine.prefetch as pf

    def boom(*args):
        raise InputError("points-per-line", 1, "a whole number >= 2")

    monkeypatch.setattr(pf, "run_task", boom)
    with pytest.raises(RuntimeError) as info:
        pf._in_worker("rig", None, ".", False)
    back = pickle.loads(pickle.dumps(info.value))
    assert "InputError" in str(back) and "points-per-line = 1" in str(back)
    with pytest.raises(TypeError):  # why: the original does not survive the trip
        pickle.loads(pickle.dumps(InputError("points-per-line", 1, "a whole number >= 2")))


def test_an_error_while_planning_on_rank_0_is_raised_on_every_rank():
    """Under mpirun rank 0 plans alone; its error must reach the other ranks, which would
    otherwise wait in the next collective forever."""
    from workbench.studies.engine.prefetch import _on_root

    class Comm:  # what rank 1 sees: rank 0's broadcast of its failure
        rank = 1

        def bcast(self, obj, root=0):
            return ("input", "cone-angle", 80.0, "0 < cone-angle < 45", "")

    with pytest.raises(InputError, match="cone-angle = 80.0"):
        _on_root(Comm(), lambda: None)


def _children(pid: int) -> set[int]:
    """Live processes whose parent is ``pid`` (from /proc)."""
    kids = set()
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid and fields[0] != "Z":
            kids.add(int(stat.parent.name))
    return kids


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


@pytest.mark.slow  # 20 s; the worker-death test below covers the pool's failure path
def test_killed_main_process_takes_its_workers_and_keeps_finished_models(tmp_path, monkeypatch):
    """SIGKILL of ``upd screen`` once a worker has written a reduced model: no worker
    outlives it, and the rerun reuses the finished model instead of recomputing it."""
    import os
    import signal
    import subprocess
    import sys
    import time

    from conftest import run_upd

    out = tmp_path / "killed"
    env = dict(os.environ, UPD_WORKERS="2")
    cmd = [sys.executable, "-m", "workbench.cli.main", "screen", str(TINY), "--out", str(out)]
    p = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    fe = out / "cache" / "fe"
    workers: set[int] = set()
    t0 = time.time()
    while time.time() - t0 < 300 and p.poll() is None:
        workers |= _children(p.pid)
        if any(fe.glob("*.h5")):
            break
        time.sleep(0.05)
    assert p.poll() is None, "the screen finished before a reduced model appeared"
    finished = {f.name for f in fe.glob("*.h5")}
    assert finished and len(workers) >= 2  # the two workers (and multiprocessing's tracker)
    p.send_signal(signal.SIGKILL)
    p.wait()
    p.stderr.close()
    t_kill = time.time()
    # they go at once (PR_SET_PDEATHSIG: 0.15 s measured); without it they were still
    # running their task 20 s later
    while time.time() - t_kill < 10 and any(_alive(w) for w in workers):
        time.sleep(0.05)
    assert not [w for w in workers if _alive(w)], "workers outlived the killed main process"
    monkeypatch.setenv("UPD_WORKERS", "2")
    r = run_upd("screen", TINY, "--out", out, "--json", "-v")
    assert r.code == 0, r
    for name in finished:  # written by a worker of the killed run, reused as it is
        assert f"reusing {fe / name}" in r.err, name
    assert r.json["worker_pool"]["failed"] == []


def test_a_worker_killed_mid_run_leaves_its_work_to_the_main_process(tmp_path):
    """The out-of-memory killer's case: a worker dies, busy or waiting for work (then
    holding the task queue's lock: multiprocessing.Pool hung there). The pool notices,
    stops, and the main process finishes (exit 0, the three models)."""
    import os
    import signal
    import subprocess
    import sys
    import time

    out = tmp_path / "hit"
    env = dict(os.environ, UPD_WORKERS="2")
    cmd = [sys.executable, "-m", "workbench.cli.main", "screen", str(TINY), "--out", str(out),
           "--json"]  # fmt: skip
    p = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    victim = None
    t0 = time.time()
    while victim is None and time.time() - t0 < 300 and p.poll() is None:
        if any((out / "cache" / "geometry").glob("*/geometry.h5")):  # reductions under way
            for pid in _children(p.pid):
                try:
                    cmdline = Path(f"/proc/{pid}/cmdline").read_bytes()
                except OSError:
                    continue
                if b"spawn_main" in cmdline:
                    victim = pid
                    break
        time.sleep(0.05)
    assert victim is not None, "no worker found while the reductions ran"
    os.kill(victim, signal.SIGKILL)
    stdout, stderr = p.communicate(timeout=600)
    assert p.returncode == 0, stderr[-3000:]
    assert "a worker process died" in stderr
    res = json.loads(stdout)
    assert res["worker_pool"]["failed"], res["worker_pool"]
    assert len(list((out / "cache" / "fe").glob("*.h5"))) == 3
    assert len(json.loads((out / "screen.json").read_text())) == 1  # one model, one phase
