"""Ours against pyHarm on the unit Jenkins oscillator: work against precision, side by side.

The single-DOF Jenkins oscillator (m = 1, k = 1, c = 0.02, kt = 20,
mu N = 1; dimensionless) forced by ``level cos(w t)`` over w = 0.5..3 rad/s
at five levels, harmonics 0-7 and 128 samples per period in both tools.

Both tools solve the same discretised problem, so their errors are measured
against one reference of that problem: ours with the same harmonics and
samples, small steps and a peak bracket of 1e-8. The error of a run is the
worst relative error of the peak amplitude (largest |x(t)| inside the band)
over the resonance peaks, levels 0.8, 0.9 and 1. At levels 0.6 and 0.7 the
largest amplitude inside the band is at its end (the stuck resonance,
sqrt(21) rad/s, lies beyond it): ours puts a point on the band end, pyHarm
steps past it and its largest amplitude inside the band is taken; the
error over all five levels is reported too, with its own ratio.

Each tool is run at several settings (pyHarm: its largest step ``ds_max``,
its one step knob; ours: the default, which computes Hill's stability at
every point where pyHarm computes none, and coarser or finer settings), which
gives a curve of error against process CPU time for each. The ratio "at
equal accuracy" of one of our runs is the CPU of pyHarm's cheapest run that
is at least as accurate, divided by ours; when no pyHarm run of the sweep
is, the ratio is given as a lower bound (">": the CPU of pyHarm's most
accurate run over ours). Every curve is run three times in each tool and
its least CPU kept (the machines we run on vary by +-30 % from one run to
the next). The discretisation error of
128 samples itself (against 1024) is printed as the scale below which a
peak's accuracy no longer matters to a user.

Run by ``bench_hbm.py --cases pyharm`` (pyHarm in its own environment, see
benchmarks/pyharm_jenkins.py); writes pyharm_compare.png in the output folder.
"""

from __future__ import annotations

import json
import os
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from workbench.hbm.io.examples import unit_jenkins

TWO_PI = 2 * np.pi
EXAMPLE = unit_jenkins()
LEVELS = EXAMPLE.levels  # pyHarm's continuation stops at once above mu N
BAND_RAD_S = tuple(round(TWO_PI * f, 12) for f in EXAMPLE.band_hz)  # (0.5, 3.0)
HARMONICS = tuple(range(8))
NT = 128
PYHARM_DS = (0.1, 0.03, 0.01, 0.003, 0.001)  # pyHarm's default ds_max is 0.1
OURS = {  # label: SolverOptions keywords
    "default": {},
    "peak bracket 1e-2": dict(peak_ftol=1e-2),
    "no peak refinement": dict(refine_peak=False),
    "stability off": dict(stability=False),  # pyHarm computes no stability
    "ds_max 0.05": dict(ds_max=0.05),
}
REPEAT = 3  # runs of every curve in both tools; the least CPU is kept


def _ours(nt: int = NT, repeat: int = 1, **kw) -> dict:
    """Our five curves with options ``kw``: CPU, points, peak amplitude and frequency each."""
    from workbench.hbm import SolverOptions, frequency_response

    s, f1, band = EXAMPLE.system, EXAMPLE.f1, EXAMPLE.band_hz
    rows = []
    for lv in LEVELS:
        cpu = np.inf
        for _ in range(repeat):  # the least CPU of repeats: the machine's noise is +-30 %
            t0 = time.process_time()
            b = frequency_response(
                s, f1, lv, band, [0], harmonics=HARMONICS, nt=nt, options=SolverOptions(**kw)
            )
            cpu = min(cpu, time.process_time() - t0)
        sm = b.summary()
        rows.append(dict(level=lv, cpu_s=cpu, points=b.n_points,
                         peak_amplitude=sm["peak_amplitude"],
                         peak_omega=TWO_PI * sm["peak_frequency_hz"]))  # fmt: skip
    return dict(cpu_s=sum(r["cpu_s"] for r in rows), levels=rows)


def _pyharm(python: str) -> dict:
    cmd = [python, str(Path(__file__).with_name("pyharm_jenkins.py")),
           "--levels", ",".join(f"{v:g}" for v in LEVELS), "--nh", str(max(HARMONICS)),
           "--nti", str(NT), "--band", ",".join(f"{v:g}" for v in BAND_RAD_S),
           "--ds-max", ",".join(f"{v:g}" for v in PYHARM_DS), "--repeat", str(REPEAT)]  # fmt: skip
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    with tempfile.TemporaryDirectory() as tmp:  # pyHarm writes a .pyHarm/ folder in its cwd
        out = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=3600, cwd=tmp)
    if out.returncode != 0:
        raise RuntimeError(f"pyHarm failed: {out.stderr.strip().splitlines()[-1:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def errors(run: dict, ref: list[tuple[float, float]]) -> dict:
    """Worst relative peak errors of a run: over the resonance peaks, and over all levels.

    ``amp_err`` / ``omega_err``: over the levels whose reference peak lies inside
    the band (resonance peaks); ``amp_err_all``: over all levels (band ends too).
    """
    w_end = BAND_RAD_S[1] * (1 - 1e-9)
    ea = [abs(r["peak_amplitude"] / a - 1) for r, (a, _) in zip(run["levels"], ref, strict=True)]
    ew = [abs(r["peak_omega"] / w - 1) for r, (_, w) in zip(run["levels"], ref, strict=True)]
    inner = [k for k, (_, w) in enumerate(ref) if w < w_end] or list(range(len(ref)))
    return dict(amp_err=max(ea[k] for k in inner), omega_err=max(ew[k] for k in inner),
                amp_err_all=max(ea), amp_err_levels=ea)  # fmt: skip


def ratio_at_equal_accuracy(
    ours: dict, sweep: list[dict], key: str = "amp_err"
) -> tuple[float, bool]:
    """(pyHarm CPU / ours, exact): pyHarm's cheapest run at least as accurate as ``ours``.

    ``key``: the error compared ("amp_err": resonance peaks; "amp_err_all": all
    levels). ``exact`` is False when no pyHarm run of the sweep is as accurate:
    the ratio is then a lower bound (its most accurate run's CPU over ours).
    """
    ok = [p["cpu_s"] for p in sweep if p[key] <= ours[key]]
    if ok:
        return min(ok) / ours["cpu_s"], True
    best = min(sweep, key=lambda p: p[key])
    return best["cpu_s"] / ours["cpu_s"], False


def run(pyharm_python: str | None) -> dict:
    """Both tools at every setting, the references, and the ratios; the chart is plot()."""
    _ours(**OURS["default"])  # numba kernels and caches warm
    ref = [(r["peak_amplitude"], r["peak_omega"]) for r in _ours(
        stability=False, ds_max=0.02, peak_ftol=1e-8, peak_iterations=80)["levels"]]  # fmt: skip
    fine = _ours(nt=1024, stability=False, ds_max=0.02, peak_ftol=1e-8, peak_iterations=80)
    disc = errors(fine, ref)
    ours = []
    for label, kw in OURS.items():
        r = _ours(repeat=REPEAT, **kw)
        ours.append(dict(label=label, options=kw, **r, **errors(r, ref)))
    row = dict(case="pyharm", levels=list(LEVELS), nt=NT, reference=ref,
               discretisation_err=disc["amp_err"], discretisation_err_all=disc["amp_err_all"],
               ours=ours, pyharm=None)  # fmt: skip
    py = (
        pyharm_python
        or os.environ.get("PYHARM_PYTHON")
        or str(Path(__file__).resolve().parents[1] / ".venv-bench" / "bin" / "python")
    )
    if not Path(py).is_file():
        row["note"] = f"pyHarm not run: no interpreter at {py} (see benchmarks/pyharm_jenkins.py)"
        return row
    try:
        ph = _pyharm(py)
    except RuntimeError as e:
        row["note"] = str(e)
        return row
    sweep = []
    for s in ph["sweep"]:
        cpu = sum(r["cpu_s"] for r in s["levels"])
        sweep.append(dict(label=f"ds_max {s['ds_max']:g}", ds_max=s["ds_max"], cpu_s=cpu,
                          levels=s["levels"], **errors(dict(levels=s["levels"]), ref)))  # fmt: skip
    for o in ours:
        o["ratio"], o["ratio_exact"] = ratio_at_equal_accuracy(o, sweep)
        o["ratio_all"], o["ratio_all_exact"] = ratio_at_equal_accuracy(o, sweep, "amp_err_all")
    row["pyharm"] = dict(version=ph["version"], warm_up_cpu_s=ph["warm_up_cpu_s"], sweep=sweep)
    return row


def _ratio(o: dict, key: str) -> str:
    return f"{'' if o[key + '_exact'] else '> '}{o[key]:.1f}"


def report(row: dict) -> None:
    """The side-by-side table."""
    print(f"\nunit Jenkins oscillator, levels {', '.join(f'{v:g}' for v in LEVELS)}, harmonics "
          f"0-{max(HARMONICS)}, {NT} samples: process CPU of the five solves (compilation "
          "excluded), worst relative error of the peak amplitude against the same "
          "discretisation solved to convergence, over the resonance peaks (levels 0.8-1) and "
          "over all levels (0.6, 0.7: the band end)")  # fmt: skip
    print(f"discretisation error of {NT} samples (against 1024), worst peak amplitude: "
          f"{row['discretisation_err']:.1e} (resonance peaks), "
          f"{row['discretisation_err_all']:.1e} (all levels)")  # fmt: skip
    ph = row["pyharm"]
    print(f"{'tool':7s} {'setting':19s} {'cpu_s':>7s} {'points':>6s} {'err_peaks':>9s} "
          f"{'w_err':>8s} {'err_all':>8s} | pyHarm/ours at equal accuracy: peaks, all")  # fmt: skip
    for o in row["ours"]:
        pts = sum(r["points"] for r in o["levels"])
        rat = f"{_ratio(o, 'ratio')}, {_ratio(o, 'ratio_all')}" if ph else ""
        print(f"{'ours':7s} {o['label']:19s} {o['cpu_s']:7.3f} {pts:6d} {o['amp_err']:9.1e} "
              f"{o['omega_err']:8.1e} {o['amp_err_all']:8.1e} | {rat}")  # fmt: skip
    if not ph:
        print(row["note"])
        return
    for p in ph["sweep"]:
        pts = sum(r["points"] for r in p["levels"])
        print(f"{'pyHarm':7s} {p['label']:19s} {p['cpu_s']:7.3f} {pts:6d} {p['amp_err']:9.1e} "
              f"{p['omega_err']:8.1e} {p['amp_err_all']:8.1e} |")  # fmt: skip
    for w in (row.get("whole") or {}).get("rows", []):
        print(f"whole process, {w['nt']} samples: {w['tool']:6s} {w['label']:34s} "
              f"cpu {w['cpu_s']:7.3f} s  worst peak error {w['amp_err']:.1e}")  # fmt: skip
    d0, p0 = row["ours"][0], ph["sweep"][0]
    print(f"defaults against defaults: ours {d0['cpu_s']:.3f} s, pyHarm {p0['cpu_s']:.3f} s: "
          f"pyHarm/ours {p0['cpu_s'] / d0['cpu_s']:.2f} (peak errors {d0['amp_err']:.1e} and "
          f"{p0['amp_err']:.1e}); at ours' default accuracy pyHarm/ours "
          f"{_ratio(d0, 'ratio')} (resonance peaks), {_ratio(d0, 'ratio_all')} (all levels); "
          f"pyHarm {ph['version']}, its compilation {ph['warm_up_cpu_s']:.1f} s (cached on "
          "disk)")  # fmt: skip


def plot(row: dict, path: Path) -> None:
    """Error against CPU time, log-log, one curve per tool; resonance peaks and all levels."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 5), sharex=True, sharey=True)
    floor = 1e-12  # an error of round-off size is drawn on this line
    titles = {"amp_err": "resonance peaks (levels 0.8, 0.9, 1)",
              "amp_err_all": "all five levels (0.6, 0.7: largest at the band end)"}  # fmt: skip
    for ax, (key, title) in zip(axes, titles.items(), strict=True):
        sweep = (row["pyharm"] or {}).get("sweep", [])
        for name, runs, mk in (("ours", row["ours"], "o"), ("pyHarm", sweep, "s")):
            if not runs:
                continue
            x = [r["cpu_s"] for r in runs]
            y = [max(r[key], floor) for r in runs]
            if name == "pyHarm":
                ax.plot(x, y, mk + "-", color="C1",
                        label="pyHarm pseudo-arc-length, by largest step")  # fmt: skip
            else:
                ax.plot(x, y, mk, ms=8, color="C0", label="ours, by setting")
            for j, (r, xi, yi) in enumerate(zip(runs, x, y, strict=True)):
                dy = 4 if name == "pyHarm" or j % 2 == 0 else -10  # ours: labels alternate
                ax.annotate(r["label"], (xi, yi), textcoords="offset points", xytext=(6, dy),
                            fontsize=7)  # fmt: skip
        disc = row["discretisation_err" + ("_all" if key == "amp_err_all" else "")]
        ax.axhline(disc, color="0.5", ls="--", lw=1,
                   label=f"error of {NT} samples itself (against 1024)")  # fmt: skip
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("process CPU time of the five curves (s)")
        ax.set_title(title, fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("worst relative error of the peak amplitude")
    axes[0].legend(fontsize=8, loc="upper right")
    missing = "" if row["pyharm"] else f"\n{row.get('note', 'pyHarm not run')}: ours only"
    fig.suptitle(f"Unit Jenkins oscillator, harmonics 0-{max(HARMONICS)}, {NT} samples: error "
                 f"against the same discretisation solved to convergence{missing}",
                 fontsize=11)  # fmt: skip
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


# ---- whole process: `upd frf` against a pyHarm script, each started from the shell ----------
WHOLE_NT = (128, 1024)
OURS_WHOLE = {  # label: [solver] keys of the model file (upd frf --no-figures)
    "default": {},
    "peak bracket 1e-2": {"peak_ftol": 0.01},
    "peak bracket 1e-2, stability off": {"peak_ftol": 0.01, "stability": False},
}
PYHARM_WHOLE_DS = (0.1, 0.003)  # its default, and the step that reaches 1e-4


def _toml(v) -> str:
    """A TOML value (booleans lower case)."""
    return str(v).lower() if isinstance(v, bool) else repr(v)


def _model_file(folder: Path, nt: int, solver: dict) -> Path:
    """The unit Jenkins oscillator as an ``upd frf`` model file (the five levels)."""
    np.savez(folder / "unit_jenkins.npz", M=np.eye(1), K=np.eye(1), C=0.02 * np.eye(1))
    lines = [
        "[model]", 'matrices = "unit_jenkins.npz"', 'mass = "M"', 'stiffness = "K"',
        'damping = "C"', 'length_unit = "1"', "", "[excitation]", "dofs = [0]",
        "amplitudes_n = [1.0]", "phases_deg = [0.0]",
        f"levels = [{', '.join(f'{v:g}' for v in LEVELS)}]", "", "[band]",
        f"start_hz = {EXAMPLE.band_hz[0]!r}", f"end_hz = {EXAMPLE.band_hz[1]!r}", "", "[hbm]",
        f"harmonics = [{', '.join(str(h) for h in HARMONICS)}]", f"nt = {nt}", "", "[output]",
        "dofs = [0]", 'names = ["x"]', "", "[[contact]]", "dofs = [0]", "mu = 1.0",
        "kt_n_per_m = 20.0", "n0_n = 1.0", "", "[solver]",
        *(f"{k} = {_toml(v)}" for k, v in solver.items()),
    ]  # fmt: skip
    path = folder / f"unit_jenkins_{nt}.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


def _child_cpu(cmd: list[str], cwd: Path, env: dict) -> tuple[float, str]:
    """(user + system CPU of the child process, its stdout)."""
    import resource

    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    out = subprocess.run(cmd, capture_output=True, text=True, cwd=cwd, env=env, timeout=3600)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if out.returncode != 0:
        raise RuntimeError(f"{cmd[0]} failed: {out.stderr.strip().splitlines()[-1:]}")
    return (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime), out.stdout


def whole_process(pyharm_python: str | None, rounds: int = 3) -> dict:
    """Whole-process CPU (start to exit, imports and output included; compiled kernels cached)
    of ``upd frf --no-figures`` and of a pyHarm script doing the same five curves, each
    setting run ``rounds`` times alternating between the tools, the least kept; the worst
    peak error of each run against the same discretisation solved to convergence."""
    import sys

    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", UPD_NO_PROGRESS="1")
    env.pop("PYTHONPATH", None)
    upd = str(Path(sys.executable).with_name("upd"))
    py = (
        pyharm_python
        or env.get("PYHARM_PYTHON")
        or str(Path(__file__).resolve().parents[1] / ".venv-bench" / "bin" / "python")
    )
    have_pyharm = Path(py).is_file()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for nt in WHOLE_NT:
            ref = [(r["peak_amplitude"], r["peak_omega"]) for r in _ours(
                nt=nt, stability=False, ds_max=0.02, peak_ftol=1e-8, peak_iterations=80
            )["levels"]]  # fmt: skip
            runs: dict[tuple[str, str], list[float]] = {}
            errs: dict[tuple[str, str], float] = {}
            for _ in range(rounds):
                for label, solver in OURS_WHOLE.items():
                    folder = tmp / f"ours_{nt}_{len(runs)}"
                    folder.mkdir(exist_ok=True)
                    model = _model_file(folder, nt, solver)
                    cpu, _ = _child_cpu(
                        [upd, "frf", str(model), "--no-figures", "-q", "--json",
                         "--out", str(folder / "out")], folder, env)  # fmt: skip
                    summ = json.loads((folder / "out" / "summary.json").read_text())
                    got = [dict(peak_amplitude=c["peak_amplitude"],
                                peak_omega=TWO_PI * c["peak_frequency_hz"])
                           for c in summ["curves"]]  # fmt: skip
                    runs.setdefault(("ours", label), []).append(cpu)
                    errs[("ours", label)] = errors(dict(levels=got), ref)["amp_err"]
                if have_pyharm:
                    for ds in PYHARM_WHOLE_DS:
                        cmd = [py, str(Path(__file__).with_name("pyharm_jenkins.py")), "--whole",
                               "--levels", ",".join(f"{v:g}" for v in LEVELS),
                               "--nh", str(max(HARMONICS)), "--nti", str(nt),
                               "--band", ",".join(f"{v:g}" for v in BAND_RAD_S),
                               "--ds-max", f"{ds:g}"]  # fmt: skip
                        cpu, text = _child_cpu(cmd, tmp, env)
                        got = json.loads(text.strip().splitlines()[-1])["levels"]
                        key = ("pyHarm", f"ds_max {ds:g}")
                        runs.setdefault(key, []).append(cpu)
                        errs[key] = errors(dict(levels=got), ref)["amp_err"]
            for (tool, label), cpus in runs.items():
                rows.append(dict(nt=nt, tool=tool, label=label, cpu_s=min(cpus),
                                 amp_err=errs[(tool, label)]))  # fmt: skip
    return dict(rows=rows, pyharm=have_pyharm, note="" if have_pyharm else f"no pyHarm at {py}")


def cheapest(rows: list[dict], tool: str, max_err: float, nt: int | None = None) -> dict | None:
    """The cheapest run of ``tool`` with a worst peak error <= ``max_err`` (None if none)."""
    ok = [r for r in rows if r.get("tool", tool) == tool and r["amp_err"] <= max_err
          and (nt is None or r.get("nt") == nt)]  # fmt: skip
    return min(ok, key=lambda r: r["cpu_s"]) if ok else None
