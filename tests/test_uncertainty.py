"""The uncertainty study: distributions, design, Sobol indices against Ishigami's closed form,
the seat-tilt preloads, the scheduler (static vs dynamic, under MPI) and, marked slow, a tiny
real study that resumes, reuses a smaller N and gives the same numbers on 2 ranks."""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

from tests.conftest import ROOT, run_upd
from workbench.errors import InputError
from workbench.post.uncertainty import (
    answer_rows,
    driver,
    driver_verdict,
    headline,
    make_design,
    parse_distribution,
    sobol_indices,
    statistics,
)
from workbench.studies.engine.schedule import run_tasks, schedule_efficiency, simulate_schedule
from workbench.studies.kinds.uncertainty import compute as U
from workbench.studies.kinds.uncertainty.imperfection import (
    seated_preloads,
    side_coordinate,
    tilted_preloads,
)
from workbench.studies.kinds.uncertainty.samples import study_distributions

# ---- distributions and design ----------------------------------------------------------


def test_distributions_parse_and_truncate():
    d = parse_distribution("uq-mu", "normal 0.5 0.1 0.3 0.7")
    x = d.ppf(np.linspace(0, 1, 1001))
    assert x.min() == pytest.approx(0.3) and x.max() == pytest.approx(0.7)
    assert np.all(np.diff(x) >= 0)
    assert d.ppf(np.array([0.5]))[0] == pytest.approx(0.5)  # symmetric truncation keeps it
    ln = parse_distribution("uq-kt", "lognormal 2 0.5")
    assert ln.ppf(np.array([0.5]))[0] == pytest.approx(2.0)  # the median
    u = parse_distribution("uq-cf", "uniform, 0.8, 1.2")
    assert u.ppf(np.array([0.25]))[0] == pytest.approx(0.9)
    for bad in (
        "gauss 1 2",
        "uniform 2 1",
        "normal 1 -1",
        "lognormal 0 1",
        "normal 1 0.1 2 3",
        "uniform 1",
        "normal 1 x",
    ):
        with pytest.raises(InputError):
            parse_distribution("uq-mu", bad)


def test_design_of_n_is_a_prefix_of_2n_and_marginals_follow_the_distribution():
    dists = {
        "mu": parse_distribution("mu", "uniform 0.2 0.8"),
        "cf": parse_distribution("cf", "normal 1 0.1 0.7 1.3"),
    }
    small = make_design(dists, 8, seed=5)
    big = make_design(dists, 16, seed=5)
    assert small.n_rows == 8 * 4 and big.n_rows == 16 * 4
    assert np.array_equal(small.values, big.values[: small.n_rows])  # bit for bit
    assert [small.role(r) for r in range(4)] == ["A", "AB1", "AB2", "B"]
    # the A and B rows are quasi-random draws of the joint distribution
    many = make_design(dists, 1024, seed=1)
    ab = many.values[many.ab_rows]
    assert ab[:, 0].mean() == pytest.approx(0.5, abs=0.005)  # uniform 0.2..0.8
    assert ab[:, 1].std() == pytest.approx(0.1, rel=0.1)  # truncated at 3 sd: ~0.097
    assert ab[:, 1].min() >= 0.7 and ab[:, 1].max() <= 1.3


def test_statistics_percentiles_and_exceedance():
    y = np.arange(1.0, 101.0)
    st = statistics(np.append(y, np.nan), threshold=90.0)
    assert st["n"] == 100 and st["n_missing"] == 1
    assert st["p50"] == pytest.approx(50.5) and st["p95"] == pytest.approx(95.05)
    assert st["p_exceed"] == pytest.approx(0.10)


# ---- Sobol indices: the Ishigami function through the study's own design and statistics --

ISHIGAMI_S1 = (0.3139, 0.4424, 0.0)  # a = 7, b = 0.1 (closed form)
ISHIGAMI_ST = (0.5576, 0.4424, 0.2437)


def _ishigami_indices(a=7.0, b=0.1):
    v = a * a / 8 + b * math.pi**4 / 5 + b * b * math.pi**8 / 18 + 0.5
    v1 = 0.5 * (1 + b * math.pi**4 / 5) ** 2
    v2 = a * a / 8
    v13 = b * b * math.pi**8 * (1 / 18 - 1 / 50)
    return (v1 / v, v2 / v, 0.0), ((v1 + v13) / v, v2 / v, v13 / v)


def test_ranking_confidence_tells_a_clear_winner_from_a_tie():
    """Paired bootstrap of the smallest-p95 verdict: a damper whose peaks are 30 % lower on
    every sample wins every resample; two dampers drawn from one distribution split the
    resamples (the samples cannot tell them apart), and the 90 % intervals overlap."""
    from workbench.post.uncertainty import ranking_confidence

    rng = np.random.default_rng(3)
    base = rng.lognormal(0.0, 0.3, size=64)
    clear = ranking_confidence(np.column_stack([base, 0.7 * base]), ["a", "b"], seed=1)
    assert clear["winner"] == "b" and clear["confidence"] == 1.0
    lo_b, hi_b = clear["p95_ci90_mm"]["b"]
    assert lo_b <= np.quantile(0.7 * base, 0.95) <= hi_b
    tie = ranking_confidence(
        np.column_stack([rng.lognormal(0, 0.3, 64), rng.lognormal(0, 0.3, 64)]), ["a", "b"], seed=1
    )
    assert 0.2 < tie["confidence"] < 0.8
    (la, ha), (lb, hb) = tie["p95_ci90_mm"]["a"], tie["p95_ci90_mm"]["b"]
    assert la < hb and lb < ha
    assert sum(tie["wins"].values()) == pytest.approx(1.0)


def test_ishigami_closed_form_matches_the_quoted_values():
    s1, st = _ishigami_indices()
    assert s1 == pytest.approx(ISHIGAMI_S1, abs=1e-4)
    assert st == pytest.approx(ISHIGAMI_ST, abs=1e-4)


def test_sobol_indices_of_ishigami_come_out_right():
    pi = f"{math.pi!r}"
    dists = {k: parse_distribution(k, f"uniform -{pi} {pi}") for k in ("x1", "x2", "x3")}
    design = make_design(dists, 4096, seed=11)
    x = design.values
    y = np.sin(x[:, 0]) + 7.0 * np.sin(x[:, 1]) ** 2 + 0.1 * x[:, 2] ** 4 * np.sin(x[:, 0])
    ind = sobol_indices(design, y, seed=3)
    # estimator error at N = 4096 (Saltelli/Jansen, scrambled Sobol): ~0.01; SALib's own
    # bootstrap half-widths are ~0.02-0.04
    assert ind["S1"] == pytest.approx(ISHIGAMI_S1, abs=0.03)
    assert ind["ST"] == pytest.approx(ISHIGAMI_ST, abs=0.03)
    assert driver(ind) == "x1"
    ver = driver_verdict(ind)  # x1 0.558 against x2 0.442: told apart at this N
    assert ver["resolved"] and ver["contenders"] == [] and ver["negligible"] == []
    # at N = 8 the half-widths (0.3-1) swallow the 0.12 gap: x2 is a contender
    small = make_design(dists, 8, seed=11)
    xs = small.values
    ys = np.sin(xs[:, 0]) + 7.0 * np.sin(xs[:, 1]) ** 2 + 0.1 * xs[:, 2] ** 4 * np.sin(xs[:, 0])
    ver8 = driver_verdict(sobol_indices(small, ys, seed=3))
    assert not ver8["resolved"] and ver8["contenders"]
    # an input with no effect is ruled out even where the driver is not resolved
    fake = dict(names=["a", "b", "c"], ST=[0.5, 0.4, 0.01], ST_conf=[0.3, 0.3, 0.02])
    assert driver_verdict(fake) == dict(
        driver="a", resolved=False, contenders=["b"], negligible=["c"]
    )
    # a driver whose interval reaches 0 still wins when every other input is negligible
    lone = dict(names=["a", "b"], ST=[0.5, 0.01], ST_conf=[0.6, 0.02])
    assert driver_verdict(lone)["resolved"]
    # a missing output drops its whole base point, the rest still gives the answer
    y[5] = np.nan
    ind2 = sobol_indices(design, y, seed=3)
    assert ind2["n_used"] == 4095
    assert ind2["ST"] == pytest.approx(ISHIGAMI_ST, abs=0.03)


# ---- the seat tilt -------------------------------------------------------------------------


def test_seated_preloads_by_hand():
    kn = np.array([1.0, 1.0, 1.0])
    # gaps 0, 1, 2: with total 3, d = 2 (pairs 0 and 1 closed): 2 + 1 + 0
    assert seated_preloads(kn, np.array([0.0, 1.0, 2.0]), 3.0) == pytest.approx([2, 1, 0])
    # total 9: every pair closed, d = (9 + 3) / 3 = 4
    assert seated_preloads(kn, np.array([0.0, 1.0, 2.0]), 9.0) == pytest.approx([4, 3, 2])
    # total 0.5: only the first, d = 0.5
    assert seated_preloads(kn, np.array([0.0, 1.0, 2.0]), 0.5) == pytest.approx([0.5, 0, 0])


def test_tilted_preloads_keep_each_side_and_open_one_end():
    s = np.linspace(0.0, 0.03, 12)  # two lines of 12 points, 30 mm long, along x
    pts = np.vstack([np.column_stack([s, 0 * s, 0 * s]), np.column_stack([s, 0 * s + 0.01, 0 * s])])
    side = np.repeat([0, 1], 12)
    kn = np.full(24, 1e8)  # N/m per pair
    n0 = np.full(24, 100.0)  # uniform: approach 1 um
    assert np.array_equal(tilted_preloads(pts, side, kn, n0, 0.0), n0)
    assert side_coordinate(pts[:12]) == pytest.approx(s - s.mean())
    small = tilted_preloads(pts, side, kn, n0, 1e-4)  # gap at the far end 0.05 um < 1 um
    assert small[:12].sum() == pytest.approx(1200.0) and np.all(small[:12] > 0)
    assert np.all(np.diff(small[:12]) < 0) and np.array_equal(small[12:], n0[12:])
    big = tilted_preloads(pts, side, kn, n0, 0.02)  # gap 10 um: the far end opens
    assert big[:12].sum() == pytest.approx(1200.0)
    assert big[0] > 0 and big[11] == 0.0
    flip = tilted_preloads(pts, side, kn, n0, -0.02)  # the other end opens
    assert flip[:12] == pytest.approx(big[:12][::-1])


# ---- scheduling ----------------------------------------------------------------------------


def test_static_round_robin_loses_to_dynamic_when_costs_vary_tenfold():
    # a Saltelli block of 8 rows where the AB rows of one input separate (10x dearer): on 2
    # ranks round-robin hands all of them to the same rank
    costs = [1.0, 1.0, 1.0, 10.0, 1.0, 1.0, 1.0, 1.0] * 16
    static = simulate_schedule(costs, 2, static=True)
    dynamic = simulate_schedule(costs, 2, static=False)
    ideal = sum(costs) / 2
    assert static == pytest.approx(16 * 13)  # rank 1: 1 + 10 + 1 + 1 per block
    assert dynamic <= ideal + max(costs)
    assert static / dynamic > 1.3


def test_serial_run_tasks_counts_every_task_once():
    seen = []
    rec = run_tasks(7, lambda k: seen.append(k) or {"v": k * k})
    assert seen == list(range(7)) and [r["v"] for r in rec] == [k * k for k in range(7)]
    eff = schedule_efficiency(rec, 1)
    assert 0.0 < eff["efficiency"] <= 1.0 + 1e-9


_DEMO = """
import json, sys, time
from mpi4py import MPI
from workbench.studies.kinds.uncertainty.compute import run_tasks, schedule_efficiency
costs = [0.02, 0.02, 0.02, 0.2] * 6
out = {}
for static in (True, False):
    rec = run_tasks(len(costs), lambda k: time.sleep(costs[k]) or {}, MPI.COMM_WORLD,
                    static=static)
    out["static" if static else "dynamic"] = schedule_efficiency(rec, MPI.COMM_WORLD.size)
    out["tasks_" + ("static" if static else "dynamic")] = sorted(r["k"] for r in rec)
if MPI.COMM_WORLD.rank == 0:
    print(json.dumps(out))
"""


@pytest.mark.mpi
def test_mpi_shared_counter_balances_and_beats_round_robin():
    env = dict(
        os.environ,
        OMPI_ALLOW_RUN_AS_ROOT="1",
        OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
        PYTHONPATH=str(ROOT),
    )
    p = subprocess.run(
        [
            "mpirun",
            "-n",
            "2",
            "--oversubscribe",
            "-x",
            "OMP_NUM_THREADS=1",
            "-x",
            "PYTHONPATH",
            sys.executable,
            "-c",
            _DEMO,
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
    )
    assert p.returncode == 0, p.stderr[-3000:]
    r = json.loads(p.stdout.strip().splitlines()[-1])
    assert r["tasks_static"] == list(range(24)) and r["tasks_dynamic"] == list(range(24))
    # sleeps: static puts every 0.2 s task on rank 1 (1.32 s vs 0.24 s); dynamic ~0.8 s
    assert r["static"]["wall_s"] > 1.25 * r["dynamic"]["wall_s"]
    assert r["dynamic"]["efficiency"] > 0.75


# ---- a tiny real study (slow) --------------------------------------------------------------

TINY = ROOT / "tests" / "studies" / "uncertainty_tiny.toml"
Q = ("peak_amplitude_mm", "peak_frequency_hz", "friction_energy_mj")


def _h5(path):
    import h5py

    with h5py.File(path, "r") as h:
        g = h["samples/cone/in-phase"]
        return {q: g[q][()] for q in Q}, json.loads(g.attrs["digests"])


@pytest.mark.slow
@pytest.mark.mpi
def test_tiny_study_caches_resumes_grows_and_matches_on_two_ranks(tmp_path):
    out = tmp_path / "uq"
    r = run_upd("study", TINY, "--out", out, "--json", "-q")
    assert r.code == 0, r.stderr[-3000:]
    j = r.json
    n = j["n_samples"]
    assert n == 8 * (6 + 2) and j["n_computed"] == n
    first, digests = _h5(out / "uncertainty.h5")
    assert np.isfinite(first["peak_amplitude_mm"]).all()
    for f in ("report.html", "tables/uncertainty_stats.csv", "tables/uncertainty_indices.csv"):
        assert (out / f).is_file(), f
    # cached: nothing to compute, same numbers
    r2 = run_upd("study", TINY, "--out", out, "--json", "-q")
    assert r2.code == 0 and r2.json["n_computed"] == 0 and r2.json["n_reused"] == n
    # killed run: some case files lost -> only those are recomputed, same numbers
    for d in digests[:5]:
        (out / "cache" / "cases" / f"{d}.h5").unlink()
    r3 = run_upd("study", TINY, "--out", out, "--json", "-q")
    assert r3.code == 0 and r3.json["n_computed"] == 5
    again, _ = _h5(out / "uncertainty.h5")
    for q in Q:
        assert np.array_equal(again[q], first[q]), q
    # twice the samples: the first 8 base points are reused
    r4 = run_upd("study", TINY, "--out", out, "--json", "-q", "--uq-samples", "16")
    assert r4.code == 0 and r4.json["n_reused"] == n and r4.json["n_computed"] == n
    # two ranks, same reduced models (copied cache): the same digests and numbers
    mpi = tmp_path / "mpi"
    shutil.copytree(out / "cache" / "geometry", mpi / "cache" / "geometry")
    shutil.copytree(out / "cache" / "fe", mpi / "cache" / "fe")
    env = dict(
        os.environ,
        OMPI_ALLOW_RUN_AS_ROOT="1",
        OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
        PYTHONPATH=str(ROOT),
        UPD_NO_PROGRESS="1",
    )
    p = subprocess.run(
        [
            "mpirun",
            "-n",
            "2",
            "--oversubscribe",
            "-x",
            "OMP_NUM_THREADS=1",
            "-x",
            "PYTHONPATH",
            "-x",
            "UPD_NO_PROGRESS",
            sys.executable,
            "-m",
            "workbench.cli.main",
            "study",
            str(TINY),
            "--out",
            str(mpi),
            "--json",
            "-q",
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=1800,
        env=env,
    )
    assert p.returncode == 0, p.stderr[-3000:]
    # a rank's stdout is a pty under OpenMPI: colorama (imported by numba) writes its
    # reset code ESC[0m there at exit once numba has formatted a message; keep the JSON
    jm = json.loads(p.stdout[p.stdout.index("{") : p.stdout.rindex("}") + 1])
    assert jm["ranks"] == 2 and jm["n_computed"] == n
    par, dpar = _h5(mpi / "uncertainty.h5")
    assert dpar == digests
    for q in Q:
        assert np.array_equal(par[q], first[q]), q


# ---- figures (synthetic outputs through the study's analysis) -------------------------------


def test_figures_and_analysis_on_synthetic_outputs(tmp_path):
    from types import SimpleNamespace

    from tests.conftest import assert_nonblank
    from workbench.studies.kinds.uncertainty.figures import uncertainty_figures

    dists = {
        "mu": parse_distribution("mu", "normal 0.5 0.1 0.25 0.75"),
        "seat-tilt": parse_distribution("t", "normal 0 0.01 -0.03 0.03"),
    }
    design = make_design(dists, 32, 1)
    x = design.values
    res = {}
    for k, d in enumerate(("cone", "wedge")):
        for ph in (0.0, 180.0):
            pk = 0.3 + 0.1 * k + 0.2 * (x[:, 0] - 0.5) ** 2 + 5.0 * k * np.abs(x[:, 1])
            res[(d, ph)] = {
                "peak_amplitude_mm": pk,
                "peak_frequency_hz": 312 + x[:, 0],
                "friction_energy_mj": x[:, 0] ** 2,
                "hbm_s": np.ones(len(pk)),
                "failed": np.zeros(len(pk), bool),
                "digests": [""] * len(pk),
            }
    spec = SimpleNamespace(uncertainty=SimpleNamespace(uq_threshold=0.4, uq_seed=1))
    a = U.analyse(spec, design, dists, res)
    assert a["robust"] == {"in-phase": "cone", "out-of-phase": "cone"}
    drivers = {(r["damper"], r["family"]): r["driver"] for r in a["groups"]}
    assert drivers[("cone", "in-phase")] == "mu" and drivers[("wedge", "in-phase")] == "seat-tilt"
    ans = answer_rows(a)
    assert [(r["family"], r["rank"], r["damper"]) for r in ans][:2] == [
        ("in-phase", 1, "cone"),
        ("in-phase", 2, "wedge"),
    ]
    assert any("the cone has the smallest 95th-percentile peak" in x for x in headline(a))
    figs = uncertainty_figures(tmp_path / "figures", design, res, a)
    assert {f["id"] for f in figs} >= {"violins", "exceedance", "tornado", "scatter"}
    for f in figs:
        assert_nonblank(tmp_path / f["path"])
    U.write_h5(tmp_path / "u.h5", design, dists, res, a)
    import h5py

    with h5py.File(tmp_path / "u.h5", "r") as h:
        assert h["samples/wedge/out-of-phase/peak_amplitude_mm"].shape == (design.n_rows,)
        assert h["analysis/wedge/in-phase"].attrs["driver"] == "seat-tilt"


def test_bad_uncertainty_inputs_exit_2_before_any_work(tmp_path):
    from workbench.studies.engine.spec import resolve

    for values, needle in (
        ({"uq-mu": "gauss 0.5 0.1"}, "uq-mu"),
        ({"uq-damping": "normal 0.002 0.01"}, "uq-damping"),
        ({"uq-kt": "normal 1 1"}, "uq-kt"),
    ):
        with pytest.raises(InputError, match=needle):
            study_distributions(resolve({"kind": "uncertainty", **values}))
    r = run_upd(
        "study",
        "--kind",
        "uncertainty",
        "--dampers",
        "cone",
        "--forces",
        "15,30",
        "--out",
        tmp_path / "o",
    )
    assert r.code == 2 and "forces" in r.err and r.err.count("\n") == 1, r.err
    assert not (tmp_path / "o" / "cache" / "fe").exists()
