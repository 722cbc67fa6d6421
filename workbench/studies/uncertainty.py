"""The uncertainty study: which damper is robust when the inputs are not what the drawing says.

Per damper and family (inter-blade phase) at one excitation level, the
peak amplitude, resonance frequency and friction energy per cycle of the
frequency response are computed for a Saltelli design of the uncertain
inputs (``uq-inputs``; distributions named in the study file):

========== ===================================================== ==========
input      what varies                                           kind
========== ===================================================== ==========
mu         friction coefficient                                  absolute
cf         centrifugal force on the damper                       factor
kt         tangential contact stiffness (line and face values)   factor
kn         normal contact stiffness (line and face values)       factor
damping    modal damping ratio of the assembly                   absolute
seat-tilt  misalignment of one side's seat, deg                  absolute
========== ===================================================== ==========

A distribution is ``uniform LO HI``, ``normal MEAN SD [LO HI]`` or
``lognormal MEDIAN SIGMA_LN [LO HI]`` (bounds truncate). ``factor`` inputs
multiply the nominal value (study option or ``geometry/contact.toml``).

Design: SALib's Saltelli extension of a scrambled Sobol sequence
(``SALib.sample.sobol``, which draws from ``scipy.stats.qmc.Sobol``) on the
unit cube, mapped through each input's inverse CDF. Its ``N (D + 2)`` rows
feed SALib's Sobol first- and total-order indices; its ``A`` and ``B`` rows
(``2 N`` quasi-random draws of the joint distribution) give the
distributions, percentiles and exceedance probabilities. The design of
``N`` is the first ``N`` base points of the design of ``2 N``, row for row,
so a larger study reuses every case of a smaller one.

Cases: each design row is one case of the runner (``plan.make_case`` on
the study's settings with the row's absolute values), cached under its
digest plus the seat tilt and the imperfection model's source: a killed
study resumes, ``--force`` recomputes. The FE reduction and the coupling
matrix are built once per damper (``runner.prepare_model`` on the nominal
inputs); a sample only re-makes the contact parameters, the preload vector
(the seat tilt, :mod:`workbench.studies.imperfection`) and the modal
damping: nothing is re-meshed or re-reduced.

MPI: models are prepared on every rank together, then the samples are
handed out by a shared counter (an MPI one-sided ``Fetch_and_op`` on a
window of rank 0): a rank takes the next sample when it is free, so a
separating sample 10 times dearer than a stuck one does not hold up the
others (``uq-schedule = "static"`` is round-robin, for comparison). The
numbers do not depend on the rank count: each sample is solved alone from
its own inputs.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ..io import digest, write_json
from ..log import bars_enabled, progress_bar
from ..post.results import CaseResult, family_name
from .plan import Case, make_case
from .spec import StudySpec

log = logging.getLogger(__name__)

INPUTS = ("mu", "cf", "kt", "kn", "damping", "seat-tilt")
INPUT_LABELS = {"mu": "friction coefficient mu", "cf": "CF factor", "kt": "kt factor",
                "kn": "kn factor", "damping": "modal damping ratio",
                "seat-tilt": "seat tilt, deg"}
QUANTITIES = (("peak_amplitude_mm", "peak amplitude", "mm"),
              ("peak_frequency_hz", "resonance frequency", "Hz"),
              ("friction_energy_mj", "friction energy per cycle", "mJ"))
DIST_KINDS = ("uniform", "normal", "lognormal")


# ---- distributions ----------------------------------------------------------------------


@dataclass(frozen=True)
class Distribution:
    """One input's distribution: ``kind`` with parameters ``a``, ``b`` and bounds ``lo``, ``hi``.

    uniform: ``a`` = lo, ``b`` = hi; normal: mean ``a``, standard deviation
    ``b``; lognormal: median ``a``, standard deviation of ``ln x`` ``b``.
    Bounds (None: unbounded) truncate the normal and lognormal.
    """

    kind: str
    a: float
    b: float
    lo: float | None = None
    hi: float | None = None

    def _frozen(self):
        from scipy import stats

        if self.kind == "uniform":
            return stats.uniform(loc=self.a, scale=self.b - self.a)
        if self.kind == "normal":
            return stats.norm(loc=self.a, scale=self.b)
        return stats.lognorm(s=self.b, scale=self.a)

    def ppf(self, u: np.ndarray) -> np.ndarray:
        """Inverse CDF of the (truncated) distribution at ``u`` in [0, 1]."""
        d = self._frozen()
        u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
        if self.kind == "uniform" or (self.lo is None and self.hi is None):
            return d.ppf(u)
        f_lo = d.cdf(self.lo) if self.lo is not None else 0.0
        f_hi = d.cdf(self.hi) if self.hi is not None else 1.0
        x = d.ppf(f_lo + u * (f_hi - f_lo))
        return np.clip(x, self.lo if self.lo is not None else -np.inf,
                       self.hi if self.hi is not None else np.inf)

    @property
    def support(self) -> tuple[float, float]:
        if self.kind == "uniform":
            return self.a, self.b
        return tuple(float(v) for v in self.ppf(np.array([0.0, 1.0])))  # type: ignore[return-value]

    def describe(self) -> str:
        bounds = "" if self.kind == "uniform" or (self.lo is None and self.hi is None) else \
            f", truncated to [{self.lo:g}, {self.hi:g}]"
        if self.kind == "uniform":
            return f"uniform on [{self.a:g}, {self.b:g}]"
        if self.kind == "normal":
            return f"normal, mean {self.a:g}, sd {self.b:g}{bounds}"
        return f"lognormal, median {self.a:g}, sigma(ln) {self.b:g}{bounds}"


def parse_distribution(name: str, text: str) -> Distribution:
    """``"uniform LO HI"``, ``"normal MEAN SD [LO HI]"``, ``"lognormal MEDIAN SIGMA [LO HI]"``."""
    allowed = ("'uniform LO HI', 'normal MEAN SD [LO HI]' or 'lognormal MEDIAN SIGMA_LN "
               "[LO HI]' (numbers separated by spaces or commas)")
    parts = str(text).replace(",", " ").split()
    if not parts or parts[0].lower() not in DIST_KINDS:
        raise InputError(name, text, allowed)
    kind = parts[0].lower()
    try:
        nums = [float(x) for x in parts[1:]]
    except ValueError:
        raise InputError(name, text, allowed) from None
    if len(nums) not in ((2,) if kind == "uniform" else (2, 4)):
        raise InputError(name, text, allowed)
    if not all(math.isfinite(x) for x in nums):
        raise InputError(name, text, "finite numbers")
    a, b = nums[:2]
    lo, hi = (nums[2], nums[3]) if len(nums) == 4 else (None, None)
    if kind == "uniform" and not a < b:
        raise InputError(name, text, "uniform LO HI with LO < HI")
    if kind != "uniform" and b <= 0:
        raise InputError(name, text, "a positive spread (sd or sigma_ln)")
    if kind == "lognormal" and a <= 0:
        raise InputError(name, text, "a positive median")
    if lo is not None and not lo < hi:
        raise InputError(name, text, "bounds LO < HI")
    if lo is not None and kind == "lognormal" and lo <= 0:
        raise InputError(name, text, "a positive lower bound for a lognormal")
    if lo is not None and not lo <= a <= hi:
        raise InputError(name, text, "bounds around the mean or median")
    return Distribution(kind, a, b, lo, hi)


_VALID = {"mu": (0.0, 2.0), "cf": (0.0, None), "kt": (0.0, None), "kn": (0.0, None),
          "damping": (0.0, 0.5), "seat-tilt": (-5.0, 5.0)}


def study_distributions(spec: StudySpec) -> dict[str, Distribution]:
    """The distributions of the study's uncertain inputs (``uq-inputs``), checked."""
    out: dict[str, Distribution] = {}
    for name in spec.uq_inputs:
        opt = f"uq-{name}"
        d = parse_distribution(opt, getattr(spec, opt.replace("-", "_")))
        lo, hi = d.support
        vlo, vhi = _VALID[name]
        if lo < vlo or (vlo == 0.0 and name in ("cf", "kt", "kn") and lo <= 0.0) or \
                (vhi is not None and hi > vhi):
            raise InputError(opt, getattr(spec, opt.replace("-", "_")),
                             f"a distribution within [{vlo:g}, {vhi if vhi is not None else 'inf'}]"
                             " (give bounds)")
        out[name] = d
    if not out:
        raise InputError("uq-inputs", spec.uq_inputs, "at least one uncertain input")
    return out


# ---- design -----------------------------------------------------------------------------


@dataclass(frozen=True)
class Design:
    """A Saltelli design: ``unit`` (rows x D) on [0, 1], ``values`` in physical units.

    Row ``r`` belongs to base point ``r // (D + 2)``; within it, role 0 is
    ``A``, roles 1..D are ``AB_j`` (``A`` with column ``j - 1`` from ``B``)
    and role D + 1 is ``B`` (SALib's layout without second order).
    """

    names: tuple[str, ...]
    unit: np.ndarray
    values: np.ndarray
    n_base: int
    seed: int

    @property
    def n_rows(self) -> int:
        return int(self.unit.shape[0])

    @property
    def block(self) -> int:
        return len(self.names) + 2

    def role(self, r: int) -> str:
        j = r % self.block
        return "A" if j == 0 else "B" if j == self.block - 1 else f"AB{j}"

    @property
    def ab_rows(self) -> np.ndarray:
        """Rows of ``A`` and ``B``: 2 N draws of the joint distribution."""
        r = np.arange(self.n_rows)
        j = r % self.block
        return r[(j == 0) | (j == self.block - 1)]

    def problem(self) -> dict[str, Any]:
        """SALib's problem on the unit cube (the indices do not change under the inverse CDFs)."""
        return {"num_vars": len(self.names), "names": list(self.names),
                "bounds": [[0.0, 1.0]] * len(self.names)}


def make_design(dists: dict[str, Distribution], n: int, seed: int) -> Design:
    """SALib's Saltelli design (first and total order) of ``n`` base points."""
    import warnings

    from SALib.sample import sobol

    names = tuple(dists)
    problem = {"num_vars": len(names), "names": list(names), "bounds": [[0.0, 1.0]] * len(names)}
    with warnings.catch_warnings():  # "not a power of 2": allowed, said in the docs
        warnings.simplefilter("ignore")
        unit = sobol.sample(problem, int(n), calc_second_order=False, scramble=True,
                            seed=int(seed))
    values = np.column_stack([dists[k].ppf(unit[:, j]) for j, k in enumerate(names)])
    return Design(names, unit, values, int(n), int(seed))


# ---- statistics and sensitivity ---------------------------------------------------------


def statistics(y: np.ndarray, threshold: float | None = None) -> dict[str, float]:
    """Mean, sd, percentiles and exceedance probability of the finite values of ``y``."""
    y = np.asarray(y, dtype=float)
    ok = y[np.isfinite(y)]
    out: dict[str, float] = {"n": int(ok.size), "n_missing": int(y.size - ok.size)}
    if ok.size == 0:
        return out
    out.update({"mean": float(ok.mean()), "sd": float(ok.std(ddof=1)) if ok.size > 1 else 0.0,
                "min": float(ok.min()), "p05": float(np.quantile(ok, 0.05)),
                "p50": float(np.quantile(ok, 0.5)), "p95": float(np.quantile(ok, 0.95)),
                "max": float(ok.max())})
    if threshold is not None:
        out["p_exceed"] = float(np.mean(ok > threshold))
    return out


def sobol_indices(design: Design, y: np.ndarray, seed: int = 0) -> dict[str, Any]:
    """SALib's first- and total-order Sobol indices of ``y`` over the design's rows.

    A base point with a missing output (NaN) is dropped whole (SALib needs
    every row of a base point); ``n_used`` says how many were kept.
    """
    from SALib.analyze import sobol

    y = np.asarray(y, dtype=float)
    if y.shape != (design.n_rows,):
        raise InputError("outputs", y.shape, f"({design.n_rows},) one per design row")
    blocks = y.reshape(design.n_base, design.block)
    keep = np.all(np.isfinite(blocks), axis=1)
    out: dict[str, Any] = {"names": list(design.names), "n_used": int(keep.sum()),
                           "n_base": design.n_base}
    if keep.sum() < 2 or np.ptp(blocks[keep]) == 0.0:
        nan = [float("nan")] * len(design.names)
        out.update(S1=nan, S1_conf=nan, ST=nan, ST_conf=nan)
        return out
    import warnings

    with warnings.catch_warnings():  # pandas FutureWarning from inside SALib 1.5
        warnings.simplefilter("ignore", FutureWarning)
        res = sobol.analyze(design.problem(), blocks[keep].ravel(), calc_second_order=False,
                            num_resamples=200, seed=seed)
    for k in ("S1", "S1_conf", "ST", "ST_conf"):
        out[k] = [float(v) for v in res[k]]
    return out


def driver(ind: dict[str, Any]) -> str | None:
    """The input with the largest total-order index (None when none is finite)."""
    st = np.asarray(ind.get("ST", []), dtype=float)
    if st.size == 0 or not np.isfinite(st).any():
        return None
    return ind["names"][int(np.nanargmax(st))]


# ---- cases ------------------------------------------------------------------------------


@functools.lru_cache(maxsize=1)
def imperfection_code() -> str:
    from ..io import code_version

    return code_version(Path(__file__).resolve().parent, ("imperfection.py",))


@dataclass(frozen=True)
class Sample:
    """One design row of one damper and family: its case and its seat tilt."""

    case: Case
    row: int
    tilt_deg: float
    inputs: dict[str, float]  # the row's values by input name (physical units)


def nominal_contact(spec: StudySpec):
    """The nominal contact parameters: the study's options, else geometry/contact.toml."""
    from ..assembly.params import load_contact_params

    return load_contact_params(mu=spec.mu, cf_n=spec.cf, kt_line_n_per_m2=spec.kt_line,
                               kn_line_n_per_m2=spec.kn_line, kt_face_n_per_m3=spec.kt_face,
                               kn_face_n_per_m3=spec.kn_face)


def sample_settings(base: dict[str, Any], nominal, x: dict[str, float]) -> dict[str, Any]:
    """The study settings of one sample: absolute contact values and damping."""
    s = dict(base)
    s["mu"] = float(x.get("mu", nominal.mu))
    s["cf"] = float(nominal.cf_n * x.get("cf", 1.0))
    kt, kn = x.get("kt", 1.0), x.get("kn", 1.0)
    s["kt-line"] = float(nominal.kt_line_n_per_m2 * kt)
    s["kt-face"] = float(nominal.kt_face_n_per_m3 * kt)
    s["kn-line"] = float(nominal.kn_line_n_per_m2 * kn)
    s["kn-face"] = float(nominal.kn_face_n_per_m3 * kn)
    s["damping"] = float(x.get("damping", base["damping"]))
    return s


def sample_case(damper: str, phase: float, force: float, settings: dict[str, Any],
                tilt_deg: float, variant: str) -> Case:
    """A runner case whose digest also covers the seat tilt and the imperfection model."""
    c = make_case(damper, phase, force, settings, variant)
    d = c.digest if tilt_deg == 0.0 else digest(
        {"case": c.digest, "seat_tilt_deg": float(tilt_deg), "model": imperfection_code()})
    object.__setattr__(c, "digest", d)
    return c


# only the study-wide settings that shape a sample's answer enter its case: the
# uncertainty options themselves do not (a sample's values are in its settings)
_UQ_OPTIONS = ("uq-inputs", "uq-mu", "uq-cf", "uq-kt", "uq-kn", "uq-damping", "uq-seat-tilt",
               "uq-samples", "uq-seed", "uq-threshold", "uq-schedule")


def base_settings(spec: StudySpec) -> dict[str, Any]:
    s = spec.as_dict()
    for k in _UQ_OPTIONS + ("name", "kind", "dampers", "phases", "forces"):
        s.pop(k, None)
    return s


def plan_samples(spec: StudySpec, design: Design) -> list[Sample]:
    """Every sample of the study: damper x family x design row, in a stable order."""
    if len(spec.forces) != 1:
        raise InputError("forces", spec.forces, "exactly one excitation level, N, for an "
                         "uncertainty study")
    nominal = nominal_contact(spec)
    base = base_settings(spec)
    force = float(spec.forces[0])
    out = []
    for damper in spec.dampers:
        for phase in spec.phases:
            for r in range(design.n_rows):
                x = {k: float(design.values[r, j]) for j, k in enumerate(design.names)}
                s = sample_settings(base, nominal, x)
                tilt = float(x.get("seat-tilt", 0.0))
                s["seat-tilt"] = tilt
                c = sample_case(damper, phase, force, s, tilt, f"s{r}")
                out.append(Sample(c, r, tilt, x))
    return out


def prepare_sample(base_prep, case: Case, tilt_deg: float):
    """The base model of the damper with this sample's contact values, preloads and damping.

    Nothing is re-meshed or re-reduced: ``W``, ``M`` and ``K`` are the base
    model's. With the nominal values and no tilt this is exactly the model
    ``runner.prepare_model`` builds for the case.
    """
    from ..assembly.model import preloads
    from ..contact.elements import ContactElements
    from ..hbm.system import System
    from .imperfection import open_share, tilted_preloads
    from .runner import PreparedModel, contact_params_for

    t0 = time.perf_counter()
    base = base_prep.assembled
    cp = contact_params_for(case)
    contact = base.contact
    kt, kn = cp.pair_stiffness(contact.kind, contact.weight)
    beta = float(base_prep.geometry.params["rig"]["platform"]["angle_deg"])
    n0 = preloads(contact, cp.cf_n, cp.mu, beta)
    n0 = tilted_preloads(contact.points, contact.side, kn, n0, tilt_deg)
    model = dataclasses.replace(
        base, mu=np.full(contact.n_pairs, cp.mu), kt=kt, kn=kn, n0=n0,
        info={**base.info, "total_preload_n": float(n0.sum()),
              "open_share_at_rest": open_share(n0, contact.side)})
    contacts = ContactElements(W=model.W, mu=model.mu, kt1=model.kt, kt2=model.kt, kn=model.kn,
                               n0=model.n0)
    system = System(M=model.M, K=model.K, zeta=case.settings["damping"], contacts=contacts)
    timings = {"assembly (sample)": time.perf_counter() - t0}
    return PreparedModel(base_prep.geometry, base_prep.geometry_dir, model, system, {},
                         timings, cp)


# ---- scheduling -------------------------------------------------------------------------


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
            self.win = MPI.Win.Allocate(itemsize if self.rank == 0 else 0, itemsize,
                                        comm=comm)
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


def run_tasks(n_tasks: int, work, comm=None, *, static: bool = False,
              desc: str = "samples") -> list[dict[str, Any]]:
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
    with progress_bar(desc, total=n_tasks if counter.size == 1 else None,
                      unit="case") as bar:
        while True:
            k = counter.next()
            if k >= n_tasks:
                break
            ts = time.perf_counter() - t0
            extra = work(k) or {}
            mine.append({"k": k, "rank": counter.rank, "start": ts,
                         "end": time.perf_counter() - t0, **extra})
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
    per_rank = [float(sum(r["end"] - r["start"] for r in records if r["rank"] == q))
                for q in range(size)]
    return {"busy_s": busy, "wall_s": wall, "efficiency": busy / (size * wall) if wall else 1.0,
            "ranks": size, "busy_per_rank_s": per_rank}


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


# ---- the study --------------------------------------------------------------------------


def _comm():
    """MPI.COMM_WORLD when there are several ranks, else None.

    ``runner._comm`` knows mpirun (OMPI_*, PMI_SIZE); under Slurm's ``srun
    --mpi=pmix`` only PMIX_RANK and SLURM_NTASKS may be set, so those count too.
    """
    import os

    from .runner import _comm as comm

    c = comm()
    if c is None and "PMIX_RANK" in os.environ and int(os.environ.get("SLURM_NTASKS", "1")) > 1:
        from mpi4py import MPI

        if MPI.COMM_WORLD.size > 1:
            return MPI.COMM_WORLD
    return c


def run_uncertainty(spec: StudySpec, out: str | Path, *, force: bool = False) -> dict[str, Any]:
    """Compute every sample (resuming from ``out``), then statistics, indices and report."""
    from .runner import case_done, prepare_model, solve_case

    out = Path(out)
    comm = _comm()
    rank = 0 if comm is None else comm.rank
    size = 1 if comm is None else comm.size
    t_start = time.perf_counter()
    timings: dict[str, float] = {}
    dists = study_distributions(spec)
    design = make_design(dists, spec.uq_samples, spec.uq_seed)
    samples = plan_samples(spec, design)
    case_dir = out / "cache" / "cases"
    case_dir.mkdir(parents=True, exist_ok=True)
    todo_ids = None
    if rank == 0:
        todo_ids = [s.case.digest for s in samples if force or not case_done(case_dir, s.case)]
    if comm is not None:
        todo_ids = comm.bcast(todo_ids, root=0)
    want = set(todo_ids)
    todo = [s for s in samples if s.case.digest in want]
    todo = list({s.case.digest: s for s in todo}.values())  # equal rows solve once
    log.info("%d samples (%d dampers x %d families x %d design rows): %d to compute, "
             "%d cached", len(samples), len(spec.dampers), len(spec.phases), design.n_rows,
             len(todo), len(samples) - len(todo))

    # 1. one base model per damper (nominal inputs): geometry, reduction, assembly
    t0 = time.perf_counter()
    bases: dict[str, Any] = {}
    nominal = sample_settings(base_settings(spec), nominal_contact(spec), {})
    for damper in dict.fromkeys(s.case.damper for s in todo):
        c = make_case(damper, spec.phases[0], spec.forces[0], nominal)
        bases[damper] = prepare_model(c, out, force=force, comm=comm)
    timings["models (geometry, reduction, assembly)"] = time.perf_counter() - t0

    # 2. samples: interleave dampers and families so that a rank count's share mixes them
    order = sorted(todo, key=lambda s: (s.row, s.case.damper, s.case.phase_deg))

    def work(k: int) -> dict[str, Any]:
        s = order[k]
        c0 = time.process_time()
        prep = prepare_sample(bases[s.case.damper], s.case, s.tilt_deg)
        res = solve_case(prep, s.case)
        res.timings["hbm_cpu"] = time.process_time() - c0  # this rank's CPU: the projection's
        res.save(case_dir / f"{s.case.digest}.h5")
        if res.branch.failed:
            log.warning("sample %s stopped early: %s", s.case.name, res.branch.message)
        if not bars_enabled():
            log.info("sample %d/%d on rank %d: %s (%.1f s)", k + 1, len(order), rank,
                     s.case.name, res.timings.get("hbm", 0.0))
        return {"digest": s.case.digest, "hbm_s": float(res.timings.get("hbm", 0.0)),
                "cpu_s": float(res.timings["hbm_cpu"]),
                "failed": bool(res.branch.failed)}

    t0 = time.perf_counter()
    records = run_tasks(len(order), work, comm, static=spec.uq_schedule == "static",
                        desc=f"{spec.name}: samples") if order else []
    timings["samples (wall)"] = time.perf_counter() - t0
    sched = schedule_efficiency(records, size)
    sched["schedule"] = spec.uq_schedule
    sched["n_computed"] = len(records)

    summary: dict[str, Any] = {"study": spec.name, "kind": "uncertainty", "out": str(out),
                               "report": str(out / "report.html"), "ranks": size,
                               "n_samples": len(samples), "n_computed": len(order),
                               "n_reused": len(samples) - len(order), "schedule": sched}
    t0 = time.perf_counter()
    results = collect(samples, design, case_dir, comm)  # collective: a share per rank
    if rank == 0:
        if records:
            write_json(out / "tables" / "schedule_records.json", records)
        else:  # nothing computed: the report keeps the last computing run's schedule
            sched = _previous_schedule(out) or sched
        analysis = analyse(spec, design, dists, results)
        summary.update(analysis_summary(analysis))
        timings["post and report"] = time.perf_counter() - t0  # before the report is written
        timings["total"] = time.perf_counter() - t_start
        summary["timings_s"] = {k: round(v, 2) for k, v in timings.items()}
        write_uncertainty_outputs(spec, out, design, dists, results, analysis, sched, timings)
    if comm is not None:
        summary = comm.bcast(summary, root=0)
    return summary


# ---- post-processing --------------------------------------------------------------------


def _previous_schedule(out: Path) -> dict[str, Any] | None:
    import json

    try:
        prev = json.loads((out / "uncertainty.json").read_text()).get("schedule")
    except (OSError, ValueError):
        return None
    return prev if prev and prev.get("n_computed") else None


def sample_output(case_dir: Path, s: Sample) -> dict[str, Any]:
    """The scalar outputs of one finished sample (read from its case file)."""
    res = CaseResult.load(case_dir / f"{s.case.digest}.h5")
    summ = res.summary()
    out = {q: (np.nan if summ.get(q) is None else float(summ[q])) for q, _, _ in QUANTITIES}
    out.update(hbm_s=float(res.timings.get("hbm", np.nan)),
               cpu_s=float(res.timings.get("hbm_cpu", np.nan)), failed=bool(res.branch.failed))
    return out


def collect(samples: list[Sample], design: Design, case_dir: Path,
            comm=None) -> dict[tuple, dict] | None:
    """(damper, phase) -> the design-ordered outputs of its samples (NaN where no peak).

    Under MPI each rank reads a share of the case files (rank r: samples r,
    r + P, ...) and rank 0 assembles them (the other ranks get None): the
    serial part of the post-processing does not grow with the sample count.
    """
    rank = 0 if comm is None else comm.rank
    size = 1 if comm is None else comm.size
    mine = [(k, sample_output(case_dir, samples[k])) for k in range(rank, len(samples), size)]
    if comm is not None:
        parts = comm.gather(mine, root=0)
        if rank != 0:
            return None
        mine = [x for part in parts for x in part]
    outputs = dict(mine)
    groups: dict[tuple, dict] = {}
    for k, s in enumerate(samples):
        g = groups.setdefault((s.case.damper, s.case.phase_deg), {
            q: np.full(design.n_rows, np.nan) for q, _, _ in QUANTITIES})
        g.setdefault("hbm_s", np.full(design.n_rows, np.nan))
        g.setdefault("cpu_s", np.full(design.n_rows, np.nan))
        g.setdefault("failed", np.zeros(design.n_rows, bool))
        g.setdefault("digests", [""] * design.n_rows)
        o = outputs[k]
        for q in (*(q for q, _, _ in QUANTITIES), "hbm_s", "cpu_s", "failed"):
            g[q][s.row] = o[q]
        g["digests"][s.row] = s.case.digest
    return groups


def analyse(spec: StudySpec, design: Design, dists: dict[str, Distribution],
            results: dict[tuple, dict]) -> dict[str, Any]:
    """Statistics of each quantity and Sobol indices per damper and family.

    A sample whose solve stopped early (``failed``) has no trustworthy peak
    (the branch may stop on its way up): its outputs count as missing, in
    the statistics (``n_missing``) and in the indices (its base point is
    dropped). The dampers of a family are compared on the SAME samples: the
    A and B rows every damper of the family solved (``p95_common``), which
    decides the robust damper; ``p95`` over each damper's own solved rows is
    reported beside. The threshold (``uq-threshold``, else 1.2 x the
    family's median peak over every damper) is per family.
    """
    ab = design.ab_rows
    clean = {}
    for key, g in results.items():
        bad = np.asarray(g["failed"], bool)
        clean[key] = {q: np.where(bad, np.nan, g[q]) for q, _, _ in QUANTITIES}
    fams = list(dict.fromkeys(ph for _, ph in results))
    thresholds: dict[str, float | None] = {}
    common: dict[float, np.ndarray] = {}
    for ph in fams:
        keys = [k for k in results if k[1] == ph]
        ok = np.all([np.isfinite(clean[k]["peak_amplitude_mm"][ab]) for k in keys], axis=0)
        common[ph] = ab[ok]
        if spec.uq_threshold is not None:
            thresholds[family_name(ph)] = float(spec.uq_threshold)
        else:
            pk = np.concatenate([clean[k]["peak_amplitude_mm"][ab] for k in keys])
            pk = pk[np.isfinite(pk)]
            thresholds[family_name(ph)] = 1.2 * float(np.median(pk)) if pk.size else None
    groups = []
    for (damper, phase), g in results.items():
        fam = family_name(phase)
        thr = thresholds[fam]
        c = clean[(damper, phase)]
        row: dict[str, Any] = {"damper": damper, "phase_deg": phase, "family": fam,
                               "threshold_mm": thr, "stats": {}, "indices": {}}
        for q, _, _ in QUANTITIES:
            row["stats"][q] = statistics(c[q][ab], thr if q == "peak_amplitude_mm" else None)
            row["indices"][q] = sobol_indices(design, c[q], seed=spec.uq_seed)
        pc = c["peak_amplitude_mm"][common[phase]]
        row["stats"]["peak_amplitude_mm"]["n_common"] = int(pc.size)
        if pc.size:
            row["stats"]["peak_amplitude_mm"]["p95_common"] = float(np.quantile(pc, 0.95))
        row["driver"] = driver(row["indices"]["peak_amplitude_mm"])
        row["n_failed"] = int(np.asarray(g["failed"]).sum())
        row["n_failed_ab"] = int(np.asarray(g["failed"])[ab].sum())
        row["case_time_s"] = statistics(g.get("cpu_s", g["hbm_s"]))
        groups.append(row)
    robust = {}
    for phase in fams:
        cand = [r for r in groups if r["phase_deg"] == phase
                and "p95_common" in r["stats"]["peak_amplitude_mm"]]
        if cand:
            best = min(cand, key=lambda r: r["stats"]["peak_amplitude_mm"]["p95_common"])
            robust[family_name(phase)] = best["damper"]
    return {"thresholds_mm": thresholds, "groups": groups, "robust": robust,
            "inputs": {k: d.describe() for k, d in dists.items()}}


def analysis_summary(a: dict[str, Any]) -> dict[str, Any]:
    return {"thresholds_mm": a["thresholds_mm"], "groups": answer_rows(a),
            "smallest_p95_peak": a["robust"]}


def _p95(r: dict[str, Any]) -> float:
    return r["stats"]["peak_amplitude_mm"].get("p95_common", np.inf)


def headline(a: dict[str, Any]) -> list[str]:
    lines = []
    for fam, best in a["robust"].items():
        grp = {r["damper"]: r for r in a["groups"] if r["family"] == fam}
        if len(grp) < 2:
            continue
        n = grp[best]["stats"]["peak_amplitude_mm"]["n_common"]
        others = ", ".join(f"{d} {_p95(r):.4g} mm" for d, r in grp.items() if d != best)
        lines.append(f"{fam}: the {best} has the smallest 95th-percentile peak, "
                     f"{_p95(grp[best]):.4g} mm ({others}; over the {n} samples every damper "
                     "solved)")
    for r in a["groups"]:
        st = r["stats"]["peak_amplitude_mm"]
        if "p95" not in st:
            lines.append(f"{r['damper']}, {r['family']}: no peak in any sample")
            continue
        pe = st.get("p_exceed")
        lines.append(
            f"{r['damper']}, {r['family']}: peak median {st['p50']:.4g} mm, 95th percentile "
            f"{st['p95']:.4g} mm, P(peak > {r['threshold_mm']:.3g} mm) = "
            f"{pe:.2f}; driven by {r['driver'] or '?'}"
            + (f" ({r['n_failed']} solves stopped early: left out)" if r["n_failed"] else ""))
    return lines


def answer_rows(a: dict[str, Any]) -> list[dict[str, Any]]:
    """Per family, the dampers ranked by 95th-percentile peak (common samples), the driver."""
    rows = []
    for fam in dict.fromkeys(r["family"] for r in a["groups"]):
        grp = [r for r in a["groups"] if r["family"] == fam]
        for k, r in enumerate(sorted(grp, key=_p95)):
            st = r["stats"]["peak_amplitude_mm"]
            ind = r["indices"]["peak_amplitude_mm"]
            j = ind["names"].index(r["driver"]) if r["driver"] else None
            rows.append({"family": fam, "rank": k + 1, "damper": r["damper"],
                         "peak_p50_mm": st.get("p50"),
                         "peak_p95_common_mm": st.get("p95_common"),
                         "n_common": st.get("n_common"), "peak_p95_mm": st.get("p95"),
                         "threshold_mm": r["threshold_mm"], "p_exceed": st.get("p_exceed"),
                         "driver": r["driver"],
                         "driver_ST": ind["ST"][j] if j is not None else None,
                         "driver_ST_conf": ind["ST_conf"][j] if j is not None else None,
                         "failed_solves": r["n_failed"]})
    return rows


def stats_rows(a: dict[str, Any]) -> list[dict[str, Any]]:
    rows = []
    for r in a["groups"]:
        for q, label, unit in QUANTITIES:
            st = r["stats"][q]
            rows.append({"damper": r["damper"], "family": r["family"],
                         "quantity": f"{label}, {unit}",
                         **{k: (round(v, 6) if isinstance(v, float) else v)
                            for k, v in st.items()}})
    return rows


def index_rows(a: dict[str, Any]) -> list[dict[str, Any]]:
    rows = []
    for r in a["groups"]:
        for q, label, _unit in QUANTITIES:
            ind = r["indices"][q]
            for j, name in enumerate(ind["names"]):
                rows.append({"damper": r["damper"], "family": r["family"], "quantity": label,
                             "input": name, "S1": round(ind["S1"][j], 4),
                             "S1_conf": round(ind["S1_conf"][j], 4),
                             "ST": round(ind["ST"][j], 4), "ST_conf": round(ind["ST_conf"][j], 4),
                             "base_points_used": ind["n_used"]})
    return rows


def write_h5(path: Path, design: Design, dists: dict[str, Distribution],
             results: dict[tuple, dict], a: dict[str, Any]) -> Path:
    """``uncertainty.h5``: the design, every sample's outputs, the statistics and indices."""
    import json

    import h5py

    from ..io import atomic_path

    with atomic_path(path) as tmp, h5py.File(tmp, "w") as h:
        d = h.create_group("design")
        d["unit"] = design.unit
        d["values"] = design.values
        d.attrs["names"] = json.dumps(list(design.names))
        d.attrs["n_base"], d.attrs["seed"] = design.n_base, design.seed
        d.attrs["distributions"] = json.dumps({k: v.describe() for k, v in dists.items()})
        d["ab_rows"] = design.ab_rows
        for (damper, phase), g in results.items():
            grp = h.create_group(f"samples/{damper}/{family_name(phase)}")
            for q, _, unit in QUANTITIES:
                grp[q] = g[q]
                grp[q].attrs["unit"] = unit
            grp["hbm_s"] = g["hbm_s"]  # wall time of the solve, s
            # CPU time of the sample (its model and solve), s
            grp["cpu_s"] = g.get("cpu_s", np.full_like(g["hbm_s"], np.nan))
            grp["failed"] = g["failed"]
            grp.attrs["digests"] = json.dumps(g["digests"])
        for r in a["groups"]:
            grp = h.create_group(f"analysis/{r['damper']}/{r['family']}")
            for q, _, _ in QUANTITIES:
                sq = grp.create_group(q)
                for k, v in r["stats"][q].items():
                    sq.attrs[k] = v
                for k in ("S1", "S1_conf", "ST", "ST_conf"):
                    sq[k] = np.asarray(r["indices"][q][k], dtype=float)
            grp.attrs["driver"] = r["driver"] or ""
            grp.attrs["threshold_mm"] = np.nan if r["threshold_mm"] is None else r["threshold_mm"]
        h.attrs["thresholds_mm"] = json.dumps(a["thresholds_mm"])
    return path


def write_uncertainty_outputs(spec: StudySpec, out: Path, design: Design,
                              dists: dict[str, Distribution], results: dict[tuple, dict],
                              a: dict[str, Any], sched: dict[str, Any],
                              timings: dict[str, float]) -> None:
    """Tables, HDF5, figures, ``uncertainty.json``, manifest and report."""
    from ..post.tables import write_rows_csv
    from .runner import write_manifest_and_report

    tables = out / "tables"
    write_rows_csv(tables / "uncertainty_answer.csv", answer_rows(a))
    write_rows_csv(tables / "uncertainty_stats.csv", stats_rows(a))
    write_rows_csv(tables / "uncertainty_indices.csv", index_rows(a))
    write_rows_csv(tables / "uncertainty_inputs.csv",
                   [{"input": k, "meaning": INPUT_LABELS[k], "distribution": d.describe()}
                    for k, d in dists.items()])
    samp = []
    for (damper, phase), g in results.items():
        for r in range(design.n_rows):
            samp.append({"damper": damper, "family": family_name(phase), "row": r,
                         "role": design.role(r),
                         **{k: float(design.values[r, j]) for j, k in enumerate(design.names)},
                         **{q: g[q][r] for q, _, _ in QUANTITIES},
                         "hbm_s": g["hbm_s"][r], "failed": bool(g["failed"][r])})
    write_rows_csv(tables / "uncertainty_samples.csv", samp)
    write_h5(out / "uncertainty.h5", design, dists, results, a)
    write_json(out / "uncertainty.json", {"analysis": a, "schedule": sched,
                                          "timings": timings})
    figures: list[dict[str, str]] = []
    try:
        from ..render.uncertainty_figures import uncertainty_figures

        figures = uncertainty_figures(out / "figures", design, results, a)
    except ImportError:  # the figure module is optional only while it is being built
        pass
    sections = _sections(spec, design, a, sched, figures)
    write_manifest_and_report(out, spec, "uncertainty study,", headline(a), timings, sections)


def _sections(spec: StudySpec, design: Design, a: dict[str, Any], sched: dict[str, Any],
              figures: list[dict[str, str]]) -> list[dict[str, Any]]:
    figs = {f["id"]: f for f in figures}

    def pick(*ids: str) -> list[dict[str, str]]:
        return [{"path": figs[i]["path"], "caption": figs[i]["caption"]} for i in ids
                if i in figs]

    n_ab = len(design.ab_rows)
    setup = [
        f"Every damper in every family at {spec.forces[0]:g} N, under a Saltelli design "
        f"of N = {design.n_base} base points of a scrambled Sobol sequence (seed "
        f"{design.seed}): {design.n_rows} cases per damper and family. The distributions "
        f"and percentiles use its {n_ab} A and B rows (quasi-random draws of the joint "
        "distribution); the Sobol indices (SALib) use every row.",
        "Uncertain inputs: " + "; ".join(f"{k}: {v}" for k, v in a["inputs"].items()) + ".",
        "The seat tilt misaligns one side's seat: the preload along that side's line or face "
        "tilts with the initial gap and vanishes at one end when the gap exceeds the static "
        "approach (workbench/studies/imperfection.py). The FE reduction is shared by all "
        "samples of a damper.",
    ]
    eff = sched.get("efficiency")
    run = [f"The last run that computed cases: {sched.get('n_computed', 0)} cases on "
           f"{sched.get('ranks', 1)} rank(s), "
           f"schedule {sched.get('schedule')}: wall {sched.get('wall_s', 0):.1f} s, busy "
           f"{sched.get('busy_s', 0):.1f} s, efficiency "
           f"{(eff if eff == eff else float('nan')):.2f}."] if sched.get("n_computed") else \
        ["Every case was found in the cache."]
    return [
        {"id": "uq-setup", "title": "Inputs and design", "text": setup,
         "tables": [{"path": "tables/uncertainty_inputs.csv", "caption": "uncertain inputs"}]},
        {"id": "uq-dist", "title": "Distributions of the response", "text": [
            "Peak amplitude, resonance frequency and friction energy per cycle at the peak "
            "over the samples, per damper and family; the 95th percentile decides which "
            "damper is robust."],
         "figures": pick("violins", "exceedance"),
         "tables": [{"path": "tables/uncertainty_answer.csv", "caption":
                     "per family, the dampers ranked by their 95th-percentile peak over the "
                     "samples every damper solved (p95_common; p95: each damper's own solved "
                     "samples), P(peak > threshold) and the input that drives the spread "
                     "(largest total Sobol index, with its bootstrap half-width)"},
                    {"path": "tables/uncertainty_stats.csv",
                     "caption": "statistics over the A and B rows (thresholds: " + ", ".join(
                         f"{f} {t:.4g} mm" for f, t in a["thresholds_mm"].items()
                         if t is not None) + "; solves stopped early are missing)"}]},
        {"id": "uq-sens", "title": "Sensitivity", "text": [
            "Sobol first-order (S1) and total-order (ST) indices of each output (SALib, "
            "with 95% bootstrap half-widths); the input with the largest ST drives the "
            "spread."],
         "figures": pick("tornado", "scatter"),
         "tables": [{"path": "tables/uncertainty_indices.csv", "caption": "Sobol indices"}]},
        {"id": "uq-run", "title": "Computation", "text": run, "figures": pick("schedule"),
         "tables": []},
    ]
