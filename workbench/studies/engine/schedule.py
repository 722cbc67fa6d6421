"""Spreading independent tasks over MPI ranks: one schedule for every study kind.

:func:`run_tasks` hands task indices to whichever rank is free (an MPI
one-sided ``Fetch_and_op`` on rank 0's window) or round-robin
(``static``); :func:`schedule_efficiency` and :func:`simulate_schedule`
measure and model the result. The comparison and sweep studies hand out
their cases costliest first (:func:`case_cost`, an estimate that knows
whether the damper slips at the case's force); the uncertainty study its
samples. (The fidelity and robustness studies run in one process: they
compare timings.)
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ...log import progress_bar


class WorkCounter:
    """Hands out task indices 0, 1, 2, ... to whichever rank asks first.

    Under MPI a shared counter in a one-sided window on rank 0
    (``Fetch_and_op`` under a passive-target lock: rank 0 need not take
    part while it computes). ``static=True`` deals round-robin instead
    (rank r gets r, r + P, ...), for comparison. Without MPI it counts.
    """

    def __init__(self, comm=None, *, static: bool = False):
        self.comm = comm
        self.static = static
        self.rank = 0 if comm is None else comm.rank
        self.size = 1 if comm is None else comm.size
        self._next_static = self.rank
        self._local = 0
        self.win = None
        if comm is not None and not static:
            from mpi4py import MPI

            itemsize = MPI.LONG.Get_size()
            self.win = MPI.Win.Allocate(itemsize if self.rank == 0 else 0, itemsize, comm=comm)
            if self.rank == 0:
                buf = np.frombuffer(self.win.tomemory(), dtype=np.int64)
                buf[0] = 0
            comm.Barrier()

    def next(self) -> int:
        if self.static:
            k = self._next_static
            self._next_static += self.size
            return k
        if self.win is None:
            k = self._local
            self._local += 1
            return k
        from mpi4py import MPI

        one = np.ones(1, dtype=np.int64)
        got = np.zeros(1, dtype=np.int64)
        self.win.Lock(0, MPI.LOCK_SHARED)
        self.win.Fetch_and_op(one, got, 0, 0, MPI.SUM)
        self.win.Unlock(0)
        return int(got[0])

    def free(self) -> None:
        if self.win is not None:
            self.win.Free()
            self.win = None


def run_tasks(
    n_tasks: int, work, comm=None, *, static: bool = False, desc: str = "samples"
) -> list[dict[str, Any]]:
    """Run ``work(k)`` for k in 0..n_tasks-1 spread over the ranks; the records of every rank.

    Each record: task ``k``, ``rank``, ``start`` and ``end`` (s since the
    common start, after a barrier) and what ``work`` returned (a dict).
    Collective under MPI; every rank gets every record.
    """
    counter = WorkCounter(comm, static=static)
    if comm is not None:
        comm.Barrier()
    t0 = time.perf_counter()
    mine: list[dict[str, Any]] = []
    with progress_bar(desc, total=n_tasks if counter.size == 1 else None, unit="case") as bar:
        while True:
            k = counter.next()
            if k >= n_tasks:
                break
            ts = time.perf_counter() - t0
            extra = work(k) or {}
            mine.append(
                {
                    "k": k,
                    "rank": counter.rank,
                    "start": ts,
                    "end": time.perf_counter() - t0,
                    **extra,
                }
            )
            bar.update(1)
    if comm is not None:
        comm.Barrier()
    counter.free()
    if comm is None:
        return mine
    return sorted(sum(comm.allgather(mine), []), key=lambda r: r["k"])


def schedule_efficiency(records: list[dict[str, Any]], size: int) -> dict[str, float]:
    """Busy time, wall time (last end) and efficiency ``busy / (P wall)`` of a run's records."""
    if not records:
        return {"busy_s": 0.0, "wall_s": 0.0, "efficiency": float("nan"), "ranks": size}
    busy = float(sum(r["end"] - r["start"] for r in records))
    wall = float(max(r["end"] for r in records))
    per_rank = [
        float(sum(r["end"] - r["start"] for r in records if r["rank"] == q)) for q in range(size)
    ]
    return {
        "busy_s": busy,
        "wall_s": wall,
        "efficiency": busy / (size * wall) if wall else 1.0,
        "ranks": size,
        "busy_per_rank_s": per_rank,
    }


def simulate_schedule(costs: list[float], ranks: int, *, static: bool) -> float:
    """Makespan (s) of tasks with ``costs`` in list order on ``ranks`` workers (no overhead).

    static: round-robin (task k on worker k mod P); dynamic: the next task
    goes to the first free worker.
    """
    if static:
        loads = [0.0] * ranks
        for k, c in enumerate(costs):
            loads[k % ranks] += c
        return max(loads) if loads else 0.0
    import heapq

    free = [0.0] * ranks
    heapq.heapify(free)
    end = 0.0
    for c in costs:
        t = heapq.heappop(free) + c
        end = max(end, t)
        heapq.heappush(free, t)
    return end


def case_cost(case, prepared, screen_rows: list[dict[str, Any]] | None = None) -> float:
    """A rough relative cost of a case: what its harmonic balance costs, for the schedule.

    The unknowns ``N = 3 pairs (2 harmonics - 1)`` set the cost of a point
    (``N^2``: the Jacobian's factorisation and the contact maps); a damper
    that slips at the case's force costs about 3.5 times one that stays
    stuck (measured on the paper-like rig's curves: the stuck curves take the
    linear verdict at every point and a few Newton iterations, the slipping
    ones Hill's method along the slipping stretch and many more iterations).
    Whether it slips: the case's force against the slip onset the coupling
    screen found for its model and phase (``screen_rows``); without a screen
    row, assumed to slip.
    """
    n_pairs = prepared.assembled.n_pairs if prepared is not None else 46
    n = 3 * n_pairs * (2 * len(case.settings["harmonics"]) - 1)
    base = (n / 1000.0) ** 2 + 0.2
    rows = [
        r
        for r in screen_rows or []
        if r.get("damper") == case.damper
        and (r.get("variant") or "") == (case.variant or "")
        and abs(float(r.get("phase_deg", np.nan)) - case.phase_deg) < 1e-9
    ]
    # a row's f_slip_n None means the screen found no slip at any force (JSON has no inf)
    slips = not rows or (rows[0].get("f_slip_n") is not None and case.force_n > rows[0]["f_slip_n"])
    return base * (3.5 if slips else 1.0)


def world_comm():
    """MPI.COMM_WORLD when the process runs under mpirun with several ranks, else None."""
    from ...log import mpi_size

    if mpi_size() > 1:
        from mpi4py import MPI

        return MPI.COMM_WORLD
    return None


def study_comm():
    """MPI.COMM_WORLD when there are several ranks, else None.

    :func:`world_comm` knows mpirun (OMPI_*, PMI_SIZE); under Slurm's ``srun
    --mpi=pmix`` only PMIX_RANK and SLURM_NTASKS may be set, so those count too.
    """
    import os

    c = world_comm()
    if c is None and "PMIX_RANK" in os.environ and int(os.environ.get("SLURM_NTASKS", "1")) > 1:
        from mpi4py import MPI

        if MPI.COMM_WORLD.size > 1:
            return MPI.COMM_WORLD
    return c
