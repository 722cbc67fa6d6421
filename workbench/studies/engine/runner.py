"""Run a study: models (geometry -> FE reduction -> assembly), then cases, then post.

Folder layout of a study (``out``)::

    out/cache/geometry/<damper>-<digest>/   meshes + geometry.h5 (reused when unchanged)
    out/cache/fe/                           ReducedModel HDF5 files (reused when unchanged)
    out/cache/cases/<digest>.h5             one finished case (atomic; the resume unit)
    out/results.h5                          every case of this study, in plan order
    out/cases/<case>.csv                    each curve as CSV
    out/cases/<case>_peak.vtu               contact pairs at the peak (ParaView; io/vtk_out.py)
    out/summary.csv, summary.json           one row per case
    out/figures/, out/tables/               pictures and tables
    out/manifest.json, out/report.html      the report

A run killed at any moment leaves only whole files behind (every write is
atomic), so running it again recomputes only the unfinished cases.
``force=True`` recomputes everything.

Models first (:mod:`.prefetch`: whole models per rank under MPI, else a
pool of local workers), then the cases spread over the ranks; rank 0
gathers the case files, writes the results and the report.
The answers do not depend on the number of ranks or workers.

The files a finished study writes (results, tables, report) are written by
:mod:`.outputs`.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import Any

from ...errors import InputError
from ...io import write_json
from ...log import bars_enabled
from ...pipeline import PreparedModel, prepare_model, solve_case
from ...post.results import CaseResult, StudyResults
from .outputs import check_failures, write_outputs
from .plan import Case, plan
from .prefetch import prefetch_study
from .schedule import world_comm
from .spec import StudySpec

log = logging.getLogger(__name__)


@contextmanager
def study_lock(out: Path) -> Iterator[None]:
    """Hold the study folder's lock (rank 0 takes it; every rank sees a refusal).

    A second ``upd study`` on the same folder is refused at once with one
    line (exit 2); a lock left by a killed run is removed (pid check).
    """
    from ...io import folder_lock

    comm = world_comm()
    if comm is None:
        with folder_lock(out):
            remove_stale_parts(out)
            yield
        return
    with ExitStack() as stack:
        err = None
        if comm.rank == 0:
            try:
                stack.enter_context(folder_lock(out))
                remove_stale_parts(out)
            except InputError as e:
                err = (e.param, e.value, e.allowed, e.why)
        err = comm.bcast(err, root=0)
        if err is not None:
            raise InputError(*err)
        yield


def run_forced_responses(spec: StudySpec, out: Path, *, force: bool = False) -> dict[str, Any]:
    """A comparison or sweep study: :func:`run_study`, then its JSON summary (what
    ``upd study --json`` prints); a failed case raises after the outputs are written."""
    results = run_study(spec, out, force=force)
    summary = {
        "study": spec.name,
        "kind": spec.kind,
        "out": str(out),
        "report": str(Path(out) / "report.html"),
        "n_cases": len(results.cases),
        "n_computed": results.extras.get("n_computed"),
        "n_reused": results.extras.get("n_reused"),
        "peak_not_reached": [c.case_id for c in results.uncovered()],
        "timings_s": {k: round(v, 2) for k, v in results.timings.items()},
        # the cases' schedule: each rank's busy time and busy / (ranks x wall)
        "schedule": {
            k: (round(v, 3) if isinstance(v, float) else v)
            for k, v in (results.extras.get("schedule") or {}).items()
            if k != "records"
        },
        "cases": results.summaries(),
    }
    check_failures(results, summary)
    return summary


def remove_stale_parts(out: Path) -> int:
    """Delete the ``.*.part`` files a killed run left (called with the folder's lock held)."""
    n = 0
    for p in list(out.rglob(".*.part*")):
        try:
            p.unlink()
            n += 1
        except OSError:
            pass
    if n:
        log.info("removed %d half-written file(s) left by an interrupted run", n)
    return n


def run_study(spec: StudySpec, out: str | Path, *, force: bool = False) -> StudyResults:
    """Compute every case of ``spec`` (resuming from ``out``) and write results and report."""
    out = Path(out)
    comm = world_comm()
    rank = 0 if comm is None else comm.rank
    size = 1 if comm is None else comm.size
    cases = plan(spec)
    if not cases:
        raise InputError("study", spec.name, "at least one case")
    t_start = time.perf_counter()
    timings: dict[str, float] = {}
    case_dir = out / "cache" / "cases"
    case_dir.mkdir(parents=True, exist_ok=True)

    # 1. models: every rank takes part (dolfinx is parallel); all are cached on disk
    prepared: dict[str, PreparedModel] = {}
    # rank 0 decides what is left to do, so every rank agrees on the split
    todo_ids = None
    if rank == 0:
        todo_ids = [c.digest for c in cases if force or not case_done(case_dir, c)]
    if comm is not None:
        todo_ids = comm.bcast(todo_ids, root=0)
    todo = [c for c in cases if c.digest in set(todo_ids)]
    need_models = list(dict.fromkeys(c.model_digest for c in todo))
    missing: list[int] = []
    if spec.field_shapes:  # the peak fields need the model of every case still without one
        from .fields import missing_fields

        missing = missing_fields(cases, out, comm)
        need_models = list(dict.fromkeys(need_models + [cases[k].model_digest for k in missing]))
    refreshed = prefetch_study(cases, need_models, out, force, timings, comm)  # serial: a pool
    for md in need_models:
        c = next(x for x in cases if x.model_digest == md)
        log.info("model for %s: geometry, reduction, assembly", c.damper)
        prepared[md] = prepare_model(c, out, force=force and md not in refreshed, comm=comm)
        for k, v in prepared[md].timings.items():
            timings[k] = timings.get(k, 0.0) + v

    # the linear coupling screen of every model (cached beside the cases): its slip onsets
    # tell the schedule which cases slip, and the report shows it
    from .schedule import case_cost, run_tasks, schedule_efficiency
    from .screening import study_screens

    t_scr = time.perf_counter()
    screen_rows = study_screens(cases, prepared, out, spec.phases, max(spec.forces), comm=comm)
    timings["coupling screen"] = time.perf_counter() - t_scr

    # 2. cases: handed out costliest first to whichever rank is free (a shared counter)
    order = sorted(todo, key=lambda c: -case_cost(c, prepared.get(c.model_digest), screen_rows))
    failures: list[str] = []
    if todo:
        log.info(
            "%d of %d cases to compute (%d cached)", len(todo), len(cases), len(cases) - len(todo)
        )
    t_cases = time.perf_counter()

    def work(k: int) -> dict[str, Any]:
        c = order[k]
        res = solve_case(prepared[c.model_digest], c)
        res.save(case_dir / f"{c.digest}.h5")
        if res.branch.failed:
            failures.append(f"{c.name}: {res.branch.message}")
            log.warning(
                "case %s stopped early: %s (its %d points are kept)",
                c.name,
                res.branch.message,
                res.branch.n_points,
            )
        elif not res.peak_covered:
            log.warning("case %s: %s", c.name, res.peak_note())
        if not bars_enabled():
            log.info(
                "case %d/%d done: %s (%d points, %.1f s)",
                k + 1,
                len(order),
                c.name,
                res.branch.n_points,
                res.timings["hbm"],
            )
        return {"case": res.case_id, "points": int(res.branch.n_points)}

    records = run_tasks(len(order), work, comm, desc=f"{spec.name}: cases") if order else []
    schedule = schedule_efficiency(records, size)
    if records and size > 1:  # each rank's busy time, in the report's cost table too
        for q, busy in enumerate(schedule["busy_per_rank_s"]):
            timings[f"cases: rank {q} busy"] = busy
    timings["cases (wall)"] = time.perf_counter() - t_cases
    # one picture set per damper, of the first model of that damper in plan order (a sweep
    # prepares several models of one damper: the report shows the first, so the others need
    # no stuck-mode solve); made also when every case came from the cache, so a resumed
    # study's report has the pictures an uninterrupted one has
    cached_costs: dict[str, float] = {}
    t_pic = time.perf_counter()
    from .pictures import study_pictures

    made = study_pictures(cases, prepared, out, comm, cached_costs)
    if made:
        timings["model pictures"] = time.perf_counter() - t_pic
    if comm is not None:
        failures = sum(comm.allgather(failures), [])
        comm.Barrier()
    nl_res = _nonlinear_modes(spec, out, prepared, cases, comm, timings)

    # 3. gather, post-process and report on rank 0
    results = StudyResults(
        name=spec.name,
        kind=spec.kind,
        cases=[CaseResult.load(case_dir / f"{c.digest}.h5") for c in cases],
        inputs=spec.as_dict(),
    )
    if spec.field_shapes:  # collective: every rank takes part in the FE expansion
        from .fields import write_study_fields

        t_f = time.perf_counter()
        model_of = {c.digest: c.model_digest for c in cases}
        write_study_fields(results, out, prepared, model_of, missing, comm)
        timings["peak fields"] = time.perf_counter() - t_f
    if rank == 0:
        _add_cached_costs(out, cases, todo, prepared, results, cached_costs)
    results.timings = timings
    results.extras["cached_costs"] = cached_costs
    if rank == 0:
        t_post = time.perf_counter()
        results.extras["bands"] = {
            md: {str(ph): list(b) for ph, b in p.bands.items()} for md, p in prepared.items()
        }
        results.extras["failures"] = failures
        results.extras["screen"] = screen_rows
        results.extras["schedule"] = schedule
        if records:  # who computed what, when: the load balance of the cases
            write_json(out / "schedule.json", {**schedule, "records": records})
        if nl_res is not None:
            results.extras["nlmodes"] = nl_res
        results.extras["n_computed"] = len(todo)
        results.extras["n_reused"] = len(cases) - len(todo)
        write_outputs(results, spec, out, prepared)
        timings["post and report"] = time.perf_counter() - t_post
    timings["total"] = time.perf_counter() - t_start
    return results


COSTS_FILE = "costs.json"


def _add_cached_costs(
    out: Path,
    cases: list[Case],
    todo: list[Case],
    prepared: dict[str, PreparedModel],
    results: StudyResults,
    cached_costs: dict[str, float],
) -> None:
    """Fill ``cached_costs`` (stage -> s) with what the work reused from the cache cost.

    A model's stages (geometry, reductions, assembly) cost what the run
    that computed them measured: ``cache/costs.json`` keeps it per model
    (updated here with the models of this run); a cached case cost its
    stored ``hbm`` time. The report lists these beside this run's times.
    """
    import json

    ledger_path = out / "cache" / COSTS_FILE
    try:
        ledger = json.loads(ledger_path.read_text())
        if not isinstance(ledger, dict):
            ledger = {}
    except (OSError, ValueError):
        ledger = {}
    for md, p in prepared.items():
        entry = dict(ledger.get(md) or {})
        for k, v in p.timings.items():
            if k in p.cached:  # reused now: what it cost in the run that computed it
                entry[k] = float(entry.get(k) or p.cached[k])
            else:
                entry[k] = float(v)
        ledger[md] = entry
        for k in p.cached:
            cached_costs[k] = cached_costs.get(k, 0.0) + entry[k]
    for md in dict.fromkeys(c.model_digest for c in cases):
        if md in prepared:
            continue
        for k, v in (ledger.get(md) or {}).items():
            cached_costs[k] = cached_costs.get(k, 0.0) + float(v)
    done = {c.digest for c in todo}
    old = [r for c, r in zip(cases, results.cases, strict=True) if c.digest not in done]
    if old:
        cached_costs[f"cases ({len(old)})"] = float(sum(r.timings.get("hbm", 0.0) for r in old))
    write_json(ledger_path, ledger)


def case_done(case_dir: Path, c: Case) -> bool:
    """True when the case's cache file exists and loads (an unreadable one is recomputed)."""
    p = case_dir / f"{c.digest}.h5"
    if not p.is_file():
        return False
    try:
        CaseResult.load(p)
        return True
    except Exception:  # noqa: BLE001 - an unreadable cache file is recomputed
        log.warning("cached case %s is unreadable; recomputing", p.name)
        return False


def _nonlinear_modes(
    spec: StudySpec, out: Path, prepared: dict, cases: list[Case], comm, timings: dict[str, float]
) -> dict | None:
    """Backbones and syntheses of a comparison study with ``nonlinear-modes`` (rank 0)."""
    if spec.kind != "comparison" or not getattr(spec, "nonlinear_modes", False):
        return None
    from .nlmodes import study_backbones

    t0 = time.perf_counter()
    res = study_backbones(spec, out, prepared=prepared, cases=cases, comm=comm)
    timings["nonlinear modes"] = time.perf_counter() - t0
    return res
