"""The mistuning study's results from its task records: amplification factors, their
statistics, the answer (which damper keeps the worst blade lowest), the tables (CSV), the
results file (HDF5 with units), the figures, the summary JSON and the report (rank 0).

A task record is :func:`workbench.studies.kinds.mistuning.compute.solve_task`'s plus its
``damper`` and ``pattern`` (-1: the tuned disk); peaks are per newton of force (m/N).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from ....io import write_json
from ....io.csv_rows import write_rows_csv
from ...engine.outputs import write_manifest_and_report

TUNED = -1  # the pattern index of the tuned disk


def config_key(config: str | float) -> str:
    """The name of a configuration: "none", "stuck" or "friction_<force>N"."""
    return config if isinstance(config, str) else f"friction_{float(config):g}N"


def configs_of(forces: list[float]) -> list[tuple[str, str]]:
    """Every configuration of a study, ``(key, label)`` in order."""
    return [("none", "no damper"), ("stuck", "damper stuck")] + [
        (config_key(f), f"friction, {f:g} N") for f in forces
    ]


def _groups(tasks: list[dict]) -> dict[tuple, dict[int, dict]]:
    g: dict[tuple, dict[int, dict]] = {}
    for t in tasks:
        g.setdefault((t["damper"], t["eo"], t["config"]), {})[int(t["pattern"])] = t
    return g


def amplification(tasks: list[dict]) -> dict[tuple, dict[str, Any]]:
    """Per (damper, EO, configuration): ``af`` (patterns,) the worst blade's peak over the
    tuned disk's worst blade's peak, ``worst_peak`` (m/N) and ``worst_blade`` of each
    pattern, ``lower`` (a blade's peak of the pattern is a lower bound, so its AF may be
    too), the tuned peak (m/N), its frequency and whether it is a lower bound, ``tasks``
    (pattern -> record)."""
    out = {}
    for key, by_p in _groups(tasks).items():
        tuned = by_p[TUNED]
        tp = np.asarray(tuned["peak_m_per_n"], float)
        n = max(by_p) + 1
        peaks = np.full((n, len(tp)), np.nan)
        lower = np.zeros(n, dtype=bool)
        for p, t in by_p.items():
            if p != TUNED:
                peaks[p] = np.asarray(t["peak_m_per_n"], float)
                lower[p] = any(t["lower"])
        worst = np.nanmax(peaks, axis=1)
        j_t = int(np.nanargmax(tp))
        out[key] = {
            "af": worst / tp[j_t],
            "worst_peak": worst,
            "worst_blade": np.nanargmax(peaks, axis=1),
            "lower": lower,
            "peaks": peaks,
            "tuned_peak": float(tp[j_t]),
            "tuned_hz": float(tuned["peak_hz"][j_t]),
            "tuned_lower": bool(any(tuned["lower"])),
            "tasks": by_p,
        }
    return out


def stats_rows(af: dict, configs: list[tuple[str, str]], bound: float) -> list[dict]:
    """Per (damper, EO, configuration) the distribution of the amplification factor."""
    rows = []
    for (d, e, c), a in af.items():
        v = a["af"][np.isfinite(a["af"])]
        force = a["tasks"][TUNED].get("force_n")
        p = int(np.nanargmax(a["af"]))
        rows.append(
            {
                "damper": d,
                "eo": e,
                "config": c,
                "label": dict(configs)[c],
                "force_n": force,
                "tuned_peak_m_per_n": a["tuned_peak"],
                "tuned_peak_hz": a["tuned_hz"],
                "af_mean": float(v.mean()),
                "af_p50": float(np.percentile(v, 50)),
                "af_p95": float(np.percentile(v, 95)),
                "af_max": float(v.max()),
                "worst_pattern": p + 1,
                "worst_blade": int(a["worst_blade"][p]) + 1,
                "worst_peak_m_per_n_p95": float(
                    np.percentile(a["worst_peak"][a["af"] == a["af"]], 95)
                ),
                "worst_peak_m_per_n_max": float(np.nanmax(a["worst_peak"])),
                "whitehead_bound": bound,
                "n_above_whitehead": int((v > bound).sum()),
                "n_lower_bound": int(a["lower"].sum()),
                "tuned_lower_bound": a["tuned_lower"],
            }
        )
    order = {k: i for i, (k, _) in enumerate(configs)}
    return sorted(rows, key=lambda r: (r["eo"], order[r["config"]], r["damper"]))


def answer_rows(stats: list[dict], dampers: list[str], forces: list[float]) -> list[dict]:
    """Per EO and friction force the damper whose worst blade is lowest (the 95th
    percentile of the worst blade's peak over the patterns, in friction at that force), its
    amplification factors in friction and, for the same disk, without the damper and with it
    stuck; every damper's worst-blade peak (m) at that force."""
    by = {(r["damper"], r["eo"], r["config"]): r for r in stats}
    rows = []
    for e in sorted({r["eo"] for r in stats}):
        for f in forces:
            c = config_key(f)
            got = [by[(d, e, c)] for d in dampers if (d, e, c) in by]
            if not got:
                continue
            best = min(got, key=lambda r: r["worst_peak_m_per_n_p95"])
            d = best["damper"]
            none, stuck = by[(d, e, "none")], by[(d, e, "stuck")]
            rows.append(
                {
                    "eo": e,
                    "force_n": f,
                    "best_damper": d,
                    "worst_peak_m_p95": best["worst_peak_m_per_n_p95"] * f,
                    "af_p95": best["af_p95"],
                    "af_max": best["af_max"],
                    "af_p95_without_damper": none["af_p95"],
                    "af_max_without_damper": none["af_max"],
                    "worst_peak_m_p95_without_damper": none["worst_peak_m_per_n_p95"] * f,
                    "af_p95_stuck": stuck["af_p95"],
                    "af_max_stuck": stuck["af_max"],
                    "lower_bounds": best["n_lower_bound"] + int(best["tuned_lower_bound"]),
                    **{
                        f"{r['damper']}_worst_peak_m_p95": r["worst_peak_m_per_n_p95"] * f
                        for r in got
                    },  # fmt: skip
                }
            )
    return rows


def _tables(tables: Path, af: dict, pats, stats, answer) -> dict[str, Path]:
    peaks, afs = [], []
    for (d, e, c), a in af.items():
        for p, t in sorted(a["tasks"].items()):
            f = t.get("force_n")
            df = np.zeros(pats.n_blades) if p == TUNED else pats.df[p]
            for j, v in enumerate(t["peak_m_per_n"]):
                peaks.append(
                    {
                        "damper": d,
                        "eo": e,
                        "config": c,
                        "force_n": f,
                        "pattern": "tuned" if p == TUNED else p + 1,
                        "blade": j + 1,
                        "freq_deviation": float(df[j]),
                        "stiffness_factor": float((1 + df[j]) ** 2),
                        "peak_m_per_n": v,
                        "peak_m": None if f is None else v * f,
                        "peak_hz": t["peak_hz"][j],
                        "lower_bound": bool(t["lower"][j]),
                    }
                )
            if p != TUNED:
                afs.append(
                    {
                        "damper": d,
                        "eo": e,
                        "config": c,
                        "force_n": f,
                        "pattern": p + 1,
                        "af": float(a["af"][p]),
                        "worst_blade": int(a["worst_blade"][p]) + 1,
                        "worst_peak_m_per_n": float(a["worst_peak"][p]),
                        "lower_bound": bool(a["lower"][p]),
                        "stopped_early": not t["completed"],
                    }
                )
    pat_rows = [
        {"pattern": p + 1, **{f"blade_{j + 1}_df": float(v) for j, v in enumerate(pats.df[p])}}
        for p in range(pats.n_patterns)
    ]
    files = {
        "peaks_csv": tables / "mistuning_peaks.csv",
        "af_csv": tables / "mistuning_af.csv",
        "stats_csv": tables / "mistuning_stats.csv",
        "answer_csv": tables / "mistuning_answer.csv",
        "patterns_csv": tables / "mistuning_patterns.csv",
    }
    for name, rows in (
        ("peaks_csv", peaks),
        ("af_csv", afs),
        ("stats_csv", stats),
        ("answer_csv", answer),
        ("patterns_csv", pat_rows),
    ):
        write_rows_csv(files[name], rows)
    return files


def _h5(path: Path, af, pats, dampers, eos, configs, forces, bound) -> None:
    import h5py

    keys = [k for k, _ in configs]
    shape = (len(dampers), len(eos), len(keys), pats.n_patterns, pats.n_blades)
    peak, hz = np.full(shape, np.nan), np.full(shape, np.nan)
    low = np.zeros(shape, dtype=bool)
    tpeak, thz = np.full(shape[:3] + shape[4:], np.nan), np.full(shape[:3] + shape[4:], np.nan)
    amp = np.full(shape[:4], np.nan)
    for (d, e, c), a in af.items():
        i, k, m = dampers.index(d), eos.index(e), keys.index(c)
        amp[i, k, m] = a["af"]
        for p, t in a["tasks"].items():
            if p == TUNED:
                tpeak[i, k, m], thz[i, k, m] = t["peak_m_per_n"], t["peak_hz"]
            else:
                peak[i, k, m, p], hz[i, k, m, p] = t["peak_m_per_n"], t["peak_hz"]
                low[i, k, m, p] = t["lower"]
    axes = "[damper, eo, config, pattern, blade]"
    shape_t = "[damper, eo, config, blade]"
    data = {
        "peak_m_per_n": (peak, "m/N", f"each blade's peak response per newton of force {axes}"),
        "peak_hz": (hz, "Hz", f"frequency of each blade's peak {axes}"),
        "lower_bound": (low, "1", f"the peak is a lower bound (stopped early, band edge) {axes}"),
        "tuned_peak_m_per_n": (tpeak, "m/N", f"the tuned disk's blade peaks {shape_t}"),
        "tuned_peak_hz": (thz, "Hz", f"the tuned disk's peak frequencies {shape_t}"),
        "af": (
            amp,
            "1",
            "amplification factor: worst blade / tuned peak [damper, eo, config, pattern]",
        ),
        "freq_deviation": (pats.df, "1", "blade frequency deviation df [pattern, blade]"),
        "stiffness_deviation": (
            pats.delta,
            "1",
            "blade stiffness deviation (1 + df)^2 - 1 [pattern, blade]",
        ),
        "forces_n": (np.array(forces, float), "N", "forces of the friction configurations"),
        "eos": (np.array(eos), "1", "engine orders"),
    }
    with h5py.File(path, "w") as h:
        for name, (v, unit, text) in data.items():
            h[name] = v
            h[name].attrs["unit"] = unit
            h[name].attrs["description"] = text
        h.attrs["dampers"] = json.dumps(dampers)
        h.attrs["configs"] = json.dumps(keys)
        h.attrs["n_blades"] = pats.n_blades
        h.attrs["whitehead_bound"] = bound
        h.attrs["std_percent"] = pats.std_percent
        h.attrs["sampling"] = pats.sampling
        h.attrs["seed"] = pats.seed


def _panels(af: dict, curves: dict, configs) -> list[dict]:
    """The worst pattern's curves per (damper, EO, configuration) for the figure (m/N)."""
    panels = []
    for (d, e, c), a in af.items():
        if not np.isfinite(a["af"]).any():
            continue
        p = int(np.nanargmax(a["af"]))
        if (d, e, c, "worst") in curves:
            w, t = curves[(d, e, c, "worst")], curves[(d, e, c, "tuned")]
            f, amp = w["freq_hz"], np.asarray(w["amp_m_per_n"], float)
            tf, tamp = t["freq_hz"], np.asarray(t["amp_m_per_n"], float).max(axis=0)
        else:
            tw, tt = a["tasks"][p], a["tasks"][TUNED]
            if not tw.get("freq_hz") or not tt.get("freq_hz"):
                continue
            force = tw["force_n"]
            f, amp = tw["freq_hz"], np.asarray(tw["amp_m"], float) / force
            tf, tamp = tt["freq_hz"], np.asarray(tt["amp_m"], float).max(axis=0) / force
        panels.append(
            {
                "damper": d,
                "eo": e,
                "config": c,
                "pattern": p,
                "af": float(a["af"][p]),
                "worst_blade": int(a["worst_blade"][p]),
                "freq_hz": f,
                "amp_m": amp,
                "tuned_freq_hz": tf,
                "tuned_amp_m": tamp,
                "lower": bool(a["lower"][p]),
            }
        )
    return panels


def write_outputs(spec, out: Path, tasks, pats, curves, summary: dict, timings: dict) -> None:
    """Tables (CSV), results (HDF5 with units), figures, summary JSON and report (rank 0)."""
    from ....pipeline.mistuning import whitehead_bound
    from .figures import plot_af_comparison, plot_af_histograms, plot_worst_response
    from .report import mistuning_sections

    dampers = list(spec.dampers)
    forces = [float(f) for f in spec.forces]
    eos = list(summary["eos"])
    n_b = int(summary["n_blades"])
    bound = whitehead_bound(n_b)
    configs = configs_of(forces)
    tables, figs = out / "tables", out / "figures"
    tables.mkdir(parents=True, exist_ok=True)
    figs.mkdir(parents=True, exist_ok=True)
    af = amplification(tasks)
    stats = stats_rows(af, configs, bound)
    answer = answer_rows(stats, dampers, forces)
    files = _tables(tables, af, pats, stats, answer)
    _h5(out / "mistuning.h5", af, pats, dampers, eos, configs, forces, bound)
    a_of = {k: v["af"] for k, v in af.items()}
    paths = {
        "af_hist_png": plot_af_histograms(
            dampers, eos, configs, a_of, bound, n_b, figs / "mistuning_af_hist.png"
        ),
        "af_compare_png": plot_af_comparison(
            dampers,
            eos,
            configs,
            a_of,
            {k: v["worst_peak"] for k, v in af.items()},
            {k: v["lower"] for k, v in af.items()},
            bound,
            n_b,
            figs / "mistuning_af_compare.png",
        ),
        "worst_response_png": plot_worst_response(
            _panels(af, curves, configs),
            configs,
            [(d, e) for d in dampers for e in eos],
            n_b,
            figs / "mistuning_worst_response.png",
        ),
    }
    summary["whitehead_bound"] = bound
    summary["stats"] = stats
    summary["answer"] = answer
    summary["failed"] = [  # patterns numbered from 1, as in the tables
        {
            "damper": t["damper"],
            "eo": t["eo"],
            "pattern": "tuned" if t["pattern"] == TUNED else t["pattern"] + 1,
            "config": t["config"],
            "message": t["message"],
        }
        for t in tasks
        if not t["completed"]
    ]
    summary["files"] = {
        "h5": str(out / "mistuning.h5"),
        **{k: str(v) for k, v in files.items()},
        **{k: str(v) for k, v in paths.items()},
    }
    head = [
        f"EO {r['eo']} at {r['force_n']:g} N: {r['best_damper']} keeps the worst blade lowest "
        f"({r['worst_peak_m_p95'] * 1e6:.3g} µm, 95th percentile); amplification factor "
        f"{r['af_p95']:.3f} (95th percentile; max {r['af_max']:.3f}) with it in friction, "
        f"{r['af_p95_without_damper']:.3f} (max {r['af_max_without_damper']:.3f}) without it"
        + (
            f" ({r['lower_bounds']} of its peaks are lower bounds: sweeps stopped early)"
            if r["lower_bounds"]
            else ""
        )
        for r in answer
    ]
    summary["headline"] = head
    sections = mistuning_sections(summary, stats, answer, configs)
    write_manifest_and_report(
        out,
        spec,
        f"mistuned disk of {n_b} blades: {pats.n_patterns} patterns of {pats.std_percent:g} % "
        "frequency scatter,",
        head,
        timings,
        sections,
    )
    write_json(out / "mistuning.json", summary)
