"""Mesh and reduce a study's models concurrently: local workers, or whole models per rank.

Run without ``mpirun``, a study or a screen would build its models one
after the other on one core: per damper the meshes (about 5 s on the 9 mm
rig), the rig's Craig-Bampton reduction (15-30 s), the damper's (5-7 s)
and, for the screen, the rigid damper. These are independent once a
model's meshes exist, so :func:`prefetch` runs them first as tasks on a
pool of worker processes (one per core by default), longest first, each
writing its result to the study's cache as the sequential path would; the
main process then finds every model in the cache and goes on unchanged.
The results are the very files the sequential path writes (same code, same
cache keys), so they do not depend on the number of workers.

* ``UPD_WORKERS``: worker processes (default: the cores this process may
  use); 1 turns the pool off. Under ``mpirun`` there is no pool: each rank
  takes whole models instead (:func:`prefetch_ranks`).
* Memory: a reduction is only started when the estimated peaks of the
  running ones plus its own (about 24 kB per DOF, measured: 2.3 GB for the
  141k-DOF rig with its damper, 9.9 GB for 420k DOFs) fit in 80 % of the
  memory available when the pool started; a reduction too large for that
  runs alone.
* A task that fails is logged and left to the main process, which computes
  it again and reports the error as it always does; so is all that is left
  when a worker process dies (out-of-memory killer). The workers die with
  the main process (an interrupted run keeps what the finished tasks wrote).
"""

from __future__ import annotations

import logging
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ...errors import InputError

log = logging.getLogger(__name__)

BYTES_PER_DOF = 24e3  # peak memory of a reduction per DOF (measured, see above)
MEMORY_SHARE = 0.8  # of MemAvailable at the start of the pool
_POLL_S = 0.05


def worker_count() -> int:
    """Worker processes for the pool: ``UPD_WORKERS`` or the cores this process may use."""
    raw = os.environ.get("UPD_WORKERS", "").strip()
    if raw:
        try:
            n = int(raw)
        except ValueError:
            n = 0
        if n < 1:
            raise InputError("UPD_WORKERS", raw, "a whole number >= 1 (1: no worker pool)")
        return n
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def available_memory() -> float:
    """Bytes of MemAvailable (/proc/meminfo), or +inf where it cannot be read."""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    return float("inf")


@dataclass
class Task:
    """One unit of the pool: ``geometry`` of a model, or the reduction of one of its bodies."""

    kind: str  # "geometry" | "rig" | "damper" | "damper-rigid"
    case: Any  # a plan.Case (picklable)
    n_dofs: int = 0  # known once the geometry exists (the reduction's memory estimate)
    after: str = ""  # the key of the meshes this placeholder waits for ("" for none)
    label: str = field(default="", compare=False)
    key: str = ""  # what the task writes: models sharing meshes or a reduction share it

    @property
    def memory(self) -> float:
        return BYTES_PER_DOF * self.n_dofs

    @property
    def cost(self) -> float:
        """Relative duration of the task and what waits for it, for longest-first.

        The meshes come first (every reduction of the model waits for them), then
        the rig reductions (about 20-30 s on the 9 mm rig), the dampers (5-7 s).
        """
        return {"geometry": 40.0, "rig": 30.0, "damper": 7.0, "damper-rigid": 0.3}[self.kind]


def _model_label(case) -> str:
    return case.damper + (f" [{case.variant}]" if case.variant else "")


def _reductions(case, geom, out: Path, rigid_bound: bool, force: bool) -> list[Task]:
    """The reduction tasks of a model whose geometry exists (none when all are cached)."""
    from ...fe.reduce import model_digest, model_path
    from ...reduced import ReducedModel

    s = case.settings
    fe_dir = out / "cache" / "fe"
    want = [("rig", False), ("damper", bool(s["rigid-damper"]))]
    if rigid_bound and not s["rigid-damper"]:
        want.append(("damper", True))
    tasks = []
    for body, rigid in want:
        inputs, dig = model_digest(geom, body, s["modes"], rigid)
        path = model_path(fe_dir, inputs, dig)
        if not force and ReducedModel.peek_digest(path) == dig:
            continue  # cached
        n = int(geom.stats.get(f"{body}_n_nodes", 0)) * 3
        kind = "damper-rigid" if rigid else body
        label = f"{kind} of {_model_label(case)}"
        tasks.append(Task(kind, case, n_dofs=n, label=label, key=f"fe:{path.name}"))
    return tasks


def _unique(tasks: list[Task], seen: set[str]) -> list[Task]:
    """``tasks`` without those whose key is in ``seen`` (which gets the new keys)."""
    out = []
    for t in tasks:
        if t.key and t.key in seen:
            continue
        seen.add(t.key)
        out.append(t)
    return out


def plan_tasks(
    cases, out: Path, *, rigid_bound: bool, force: bool, seen: set[str] | None = None
) -> list[Task]:
    """The tasks still to do for the models of ``cases`` (cheap: no meshing, no FE).

    Models that share their meshes (a sweep of mu or CF) or a reduced body
    share the task; ``seen`` collects the keys planned.
    """
    from ...pipeline import geometry_dir

    seen = set() if seen is None else seen
    models: dict[str, Any] = {}
    for c in cases:
        models.setdefault(c.model_digest, c)
    tasks: list[Task] = []
    for c in models.values():
        geom = cached_geometry_of(c, out)
        if geom is None:
            gkey = f"geometry:{geometry_dir(c, out)}"
            tasks += _unique([Task("geometry", c, label=f"meshes of {_model_label(c)}",
                                   key=gkey)], seen)  # fmt: skip
            tasks.append(Task("reductions", c, after=gkey))  # expanded once the meshes exist
        else:
            tasks += _unique(_reductions(c, geom, out, rigid_bound, force), seen)
    return tasks


def run_task(kind: str, case, out: str, force: bool, comm=None) -> float:
    """Worker side: do one task (writes the cache); returns its seconds.

    ``comm``: the ranks doing it (``MPI.COMM_SELF`` for a rank alone under mpirun).
    """
    from ...fe.reduce import reduce_body
    from ...pipeline import load_geometry

    t0 = time.perf_counter()
    geom = load_geometry(case, Path(out), comm)
    if kind != "geometry":
        s = case.settings
        body = "rig" if kind == "rig" else "damper"
        reduce_body(
            geom,
            body,
            n_modes=s["modes"],
            rigid=kind == "damper-rigid" or (body == "damper" and bool(s["rigid-damper"])),
            cache_dir=Path(out) / "cache" / "fe",
            comm=comm,
            force=force,
        )
    return time.perf_counter() - t0


def _stop(pool) -> None:
    """Stop an executor now: cancel what has not started, kill the workers."""
    procs = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for p in procs:
        if p.exitcode is None:
            p.kill()


def _in_worker(kind: str, case, out: str, force: bool) -> float:
    """:func:`run_task` in a pool worker; its errors come back as RuntimeError.

    The pool pickles a task's exception to send it back, and our errors
    (InputError: parameter, value, allowed range) cannot be rebuilt from a
    pickle: the task would come back as a broken pool, not as its error.
    """
    try:
        return run_task(kind, case, out, force)
    except Exception as e:  # noqa: BLE001 - reported by the main process
        raise RuntimeError(f"{type(e).__name__}: {e}") from None


def _init_worker(level: int) -> None:
    """Worker start-up: die with the parent, one thread, no progress bars, parent's log level."""
    import ctypes
    import signal

    try:
        ctypes.CDLL("libc.so.6").prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except OSError:  # pragma: no cover - not glibc
        pass
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    logging.basicConfig(format="  [worker] %(levelname).1s %(name)s: %(message)s")
    logging.getLogger("workbench").setLevel(max(level, logging.WARNING))
    # the imports (about 2.5 s) while the main process meshes the first model
    import dolfinx.fem.petsc  # noqa: F401
    import gmsh  # noqa: F401

    from ... import pipeline  # noqa: F401
    from ...fe import craig_bampton, reduce  # noqa: F401


def prefetch(cases, out: str | Path, *, rigid_bound: bool = False, force: bool = False) -> dict:
    """Mesh and reduce the models of ``cases`` on a pool of local workers (see the module).

    ``rigid_bound``: also the rigid damper of each model (the screen's rig
    bound). Returns ``{"workers", "tasks", "failed", "seconds", "task_seconds"}``
    (``workers`` 0 when the pool was not used: mpirun, ``UPD_WORKERS=1``, or
    fewer than two tasks).
    """
    from ...log import mpi_size, progress_bar

    out = Path(out)
    t_start = time.perf_counter()
    res: dict[str, Any] = dict(workers=0, tasks=0, failed=[], seconds=0.0, task_seconds={})
    if mpi_size() > 1:
        return res
    n_workers = worker_count()
    tasks = plan_tasks(cases, out, rigid_bound=rigid_bound, force=force)
    n_work = sum(1 for t in tasks if t.kind != "reductions")
    if n_workers < 2 or n_work + 2 * sum(t.kind == "reductions" for t in tasks) < 2:
        return res
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    n_workers = min(n_workers, max(2, n_work))
    env = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "UPD_NO_PROGRESS": "1"}
    saved = {k: os.environ.get(k) for k in env}
    os.environ.update(env)  # spawned workers copy the environment when they start
    try:
        # concurrent.futures, not multiprocessing.Pool: a worker that dies (out-of-memory
        # killer) breaks the executor and every future says so; a Pool loses the task and,
        # if the worker died waiting for work, holding its queue's lock, hangs on terminate
        pool = ProcessPoolExecutor(
            n_workers,
            mp_context=mp.get_context("spawn"),
            initializer=_init_worker,
            initargs=(logging.getLogger("workbench").getEffectiveLevel(),),
        )
        for _ in range(n_workers):  # start every worker now, with this environment
            pool.submit(int)
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    n_models = len({t.case.model_digest for t in tasks})
    log.info("models: meshes and reductions of %d model(s) on %d worker processes",
             n_models, n_workers)  # fmt: skip
    sch = _Scheduler(pool, tasks, n_workers, MEMORY_SHARE * available_memory(), out, res)
    sch.rigid_bound, sch.force = rigid_bound, force
    try:
        with progress_bar("models: meshes and reductions", total=n_work, unit="task") as bar:
            sch.bar = bar
            # the workers take a few seconds to start (imports): the main process meshes
            # the first model meanwhile, the others are queued for the workers
            first = next((t for t in sch.pending if t.kind == "geometry"), None)
            if first is not None:
                sch.pending.remove(first)
            sch.start()
            if first is not None:
                sch.run_here(first)
            while (sch.pending or sch.running) and not sch.abandoned:
                sch.collect()
                sch.start()
                time.sleep(_POLL_S)
    except BaseException:
        _stop(pool)  # Ctrl-C or an error in the parent: stop the workers at once
        raise
    if sch.abandoned:
        _stop(pool)
    else:
        pool.shutdown(wait=True)
    res.update(workers=n_workers, tasks=sch.done, seconds=time.perf_counter() - t_start)
    return res


class _Scheduler:
    """The pool's bookkeeping: pending and running tasks, results, the progress bar."""

    def __init__(self, pool, tasks, n_workers: int, budget: float, out: Path, res: dict):
        self.pool, self.pending, self.n_workers, self.budget = pool, list(tasks), n_workers, budget
        self.out, self.res = out, res
        self.running: dict[Any, Task] = {}
        self.seen: set[str] = {t.key for t in tasks if t.key}
        self.abandoned = False
        self.done = 0
        self.bar = None
        self.rigid_bound = self.force = False

    def finish(self, t: Task, secs: float | None, err: BaseException | None = None) -> None:
        """Record a finished task; a model's meshes release its reduction tasks."""
        self.done += 1
        self.bar.update(1)
        waiting_for_it = [p for p in self.pending if t.key and p.after == t.key]
        self.pending = [p for p in self.pending if p not in waiting_for_it]
        if err is not None:
            log.warning("%s failed (%s); the main process retries it", t.label, err)
            self.res["failed"].append(t.label)
            return
        self.res["task_seconds"][t.label] = round(secs, 2)
        log.info("%s: %.1f s", t.label, secs)
        if t.kind == "geometry":  # the reductions of every model on these meshes
            for p in waiting_for_it:
                self.pending += _unique(
                    _expand(p.case, self.out, self.rigid_bound, self.force), self.seen
                )
            waiting = sum(p.kind != "reductions" for p in self.pending)
            self.bar.total = self.done + len(self.running) + waiting

    def abandon(self, why: str) -> None:
        """A worker died: list what is unfinished as failed (the main process does it)."""
        left = [t.label for t in self.running.values()]
        left += [t.label for t in self.pending if t.kind != "reductions"]
        log.warning(
            "a worker process died (%s); the main process does the %d unfinished task(s) "
            "and the reductions still waiting for meshes",
            why,
            len(left),
        )
        self.res["failed"] += left
        self.running.clear()
        self.pending.clear()
        self.abandoned = True

    def collect(self) -> None:
        from concurrent.futures.process import BrokenProcessPool

        for fut, t in list(self.running.items()):
            if fut.done():
                del self.running[fut]
                try:
                    secs = fut.result()
                except BrokenProcessPool as e:
                    self.running[fut] = t  # unfinished: listed by abandon()
                    self.abandon(str(e) or "the process pool broke")
                    return
                except Exception as e:  # noqa: BLE001 - left to the main process
                    self.finish(t, None, e)
                else:
                    self.finish(t, secs)

    def run_here(self, t: Task) -> None:
        """Run a task in the main process (while the workers start)."""
        try:
            secs = run_task(t.kind, t.case, str(self.out), self.force)
        except Exception as e:  # noqa: BLE001 - the sequential path reports it again
            self.finish(t, None, e)
        else:
            self.finish(t, secs)

    def start(self) -> None:
        """Start the longest pending tasks that may run (free worker, memory, dependencies).

        A worker that died while idle breaks the pool without a future to say so: the
        submission raises, and the work is left to the main process as in :meth:`collect`.
        """
        from concurrent.futures.process import BrokenProcessPool

        ready = sorted((t for t in self.pending if t.kind != "reductions"), key=lambda t: -t.cost)
        for t in ready:
            if len(self.running) >= self.n_workers:
                return
            in_use = sum(r.memory for r in self.running.values())
            if self.running and in_use + t.memory > self.budget:
                continue  # waits for memory; a task too large for the budget runs alone
            try:
                fut = self.pool.submit(_in_worker, t.kind, t.case, str(self.out), self.force)
            except BrokenProcessPool as e:  # t stays pending: listed by abandon()
                self.abandon(str(e) or "the process pool broke")
                return
            self.pending.remove(t)
            self.running[fut] = t


def _expand(case, out: Path, rigid_bound: bool, force: bool) -> list[Task]:
    """The reduction tasks of a model whose meshes were just written (none if they were not)."""
    geom = cached_geometry_of(case, out)  # read only: no collective build under mpirun
    return [] if geom is None else _reductions(case, geom, out, rigid_bound, force)


def prefetch_models(cases, out, comm, *, rigid_bound: bool, force: bool = False) -> dict:
    """:func:`prefetch_ranks` under MPI (``comm`` not None), else :func:`prefetch`."""
    if comm is not None:
        return prefetch_ranks(cases, out, comm, rigid_bound=rigid_bound, force=force)
    return prefetch(cases, out, rigid_bound=rigid_bound, force=force)


def prefetch_study(
    cases, need_models: list[str], out: Path, force: bool, timings: dict, comm
) -> set:
    """:func:`prefetch_models` for the models ``need_models`` (digests) of a study's
    ``cases``.

    Adds the pool's wall time to ``timings``; returns the models it recomputed
    under ``force`` (the main process must not recompute them again).
    """
    if not need_models:
        return set()
    firsts = [next(x for x in cases if x.model_digest == md) for md in need_models]
    pool = prefetch_models(firsts, out, comm, rigid_bound=True, force=force)
    if not pool["workers"]:
        return set()
    timings["models (concurrent)"] = pool["seconds"]
    return set(need_models) if force and not pool["failed"] else set()


def prefetch_ranks(cases, out, comm, *, rigid_bound: bool = False, force: bool = False) -> dict:
    """Under mpirun: each rank meshes and reduces whole models alone (``COMM_SELF``).

    MUMPS shares one factorisation badly between ranks (its distributed
    solves were no faster on two ranks than on one), while independent
    models keep every rank busy; the files are those one process writes.
    Two collective phases: the meshes (round robin), then the reductions
    (longest first to the least loaded rank). Skipped with fewer than two
    tasks, or when the largest reductions would not fit in memory side by
    side (the ranks then reduce each model together, as before). Failures
    are left to the collective path. Collective; returns what
    :func:`prefetch` does.
    """
    import dolfinx  # noqa: F401 - PETSc's collective start-up before any rank works alone
    from mpi4py import MPI

    out = Path(out)
    t_start = time.perf_counter()
    res: dict[str, Any] = dict(workers=0, tasks=0, failed=[], seconds=0.0, task_seconds={})
    seen: set[str] = set()
    tasks = _on_root(comm, lambda: plan_tasks(cases, out, rigid_bound=rigid_bound, force=force,
                                              seen=seen))  # fmt: skip
    geo = [t for t in tasks if t.kind == "geometry"]
    if comm.size < 2 or len(tasks) + len(geo) < 2:
        return res
    done: list[tuple[str, float | None, str]] = []

    def run(ts):
        for t in ts:
            try:
                secs = run_task(t.kind, t.case, str(out), force, MPI.COMM_SELF)
                done.append((t.label, secs, ""))
            except Exception as e:  # noqa: BLE001 - the collective path reports it again
                done.append((t.label, None, f"{type(e).__name__}: {e}"))

    mine = geo[comm.rank :: comm.size]
    run(mine)
    ok = {t.key for t, (_, secs, _) in zip(mine, done, strict=True) if secs is not None}
    meshed = set().union(*comm.allgather(ok))

    def reductions():
        red = [t for t in tasks if t.kind not in ("geometry", "reductions")]
        for p in tasks:  # the models on meshes made just now, by any rank
            if p.kind == "reductions" and p.after in meshed:
                red += _unique(_expand(p.case, out, rigid_bound, force), seen)
        plan = _assign(red, comm.size, MEMORY_SHARE * available_memory())
        if plan is None:
            log.info("models: the largest reductions do not fit in memory side by side; "
                     "the ranks reduce each model together")  # fmt: skip
        return plan

    plan = _on_root(comm, reductions)
    if plan is not None:
        run(plan[comm.rank])
    everything = comm.gather(done, root=0)
    if comm.rank == 0:
        for lbl, secs, err in (x for part in everything for x in part):
            if secs is None:
                log.warning("%s failed on its rank (%s); all ranks retry it together", lbl, err)
                res["failed"].append(lbl)
            else:
                res["task_seconds"][lbl] = round(secs, 2)
    res = comm.bcast(res, root=0)
    # no reductions done here (memory): nothing was refreshed, the collective path does it all
    res.update(workers=comm.size if plan is not None else 0)
    res.update(tasks=len(geo) + sum(len(p) for p in (plan or [])))
    res["seconds"] = time.perf_counter() - t_start
    return res


def _on_root(comm, fn):
    """``fn()`` on rank 0, its result on every rank; an error there is raised on every rank
    (:func:`workbench.errors.run_on_root`)."""
    from ...errors import run_on_root

    return comm.bcast(run_on_root(comm, fn, "planning the models"), root=0)


def cached_geometry_of(case, out: Path):
    """The finished geometry record of a case's model, or None (no meshing)."""
    from ...geometry.build import cached_geometry
    from ...pipeline import geometry_dir, geometry_request

    req = geometry_request(case)
    return cached_geometry(req.pop("damper"), geometry_dir(case, out), **req)


def _assign(tasks: list[Task], n_ranks: int, budget: float) -> list[list[Task]] | None:
    """Tasks per rank, longest first to the least loaded; None when memory forbids it."""
    biggest = sorted((t.memory for t in tasks), reverse=True)[:n_ranks]
    if len(biggest) > 1 and sum(biggest) > budget:
        return None
    load = [0.0] * n_ranks
    plan: list[list[Task]] = [[] for _ in range(n_ranks)]
    for t in sorted(tasks, key=lambda t: -t.cost * max(t.n_dofs, 1)):
        r = min(range(n_ranks), key=load.__getitem__)
        plan[r].append(t)
        load[r] += t.cost * max(t.n_dofs, 1)
    return plan
