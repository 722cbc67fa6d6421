"""Issue 28's speed targets beside what this run measured (printed at the end of ``make bench``).

Reads the outputs of :mod:`run_all`'s parts in ``--out``: ``main-job`` (both
studies of ``make run``, cold, 2 MPI ranks), ``hbm`` (bench_hbm.json: the
46- and 146-pair curves and the comparison with pyHarm, in solve time and
in whole-process CPU). A target whose part was not run says so. The
reference answers (``benchmarks/reference/*.json``: each case's peaks and
verdict counts, last written from round 19's run) are compared with the main
job's: the largest peak change and the cases whose counts of unstable or
unknown points changed.

    .venv/bin/python benchmarks/targets.py --out results/bench
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / "benchmarks" / "reference"


def _load(path: Path):
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


def _row(name: str, target: str, value: str, met: bool | None) -> tuple[str, str, str, str]:
    return (name, target, value, "not run" if met is None else ("met" if met else "MISSED"))


def rows(out: Path) -> list[tuple[str, str, str, str]]:
    """(target, wanted, measured, verdict) for each target of issue 28."""
    t: list[tuple[str, str, str, str]] = []
    main = _load(out / "main-job" / "main_job.json")
    if main:
        wall = main["wall_s"]
        t.append(_row("make run, both rigs, cold, 2 ranks", "< 600 s", f"{wall:.0f} s "
                      f"(load {main.get('load_before', '?')} before)", wall < 600))  # fmt: skip
        wedge = main.get("wedge_30n_out_of_phase_s")
        t.append(_row("paper-like rig: wedge out of phase at 30 N, in the study", "< 60 s",
                      f"{wedge:.1f} s" if wedge else "no such case", wedge is not None
                      and wedge < 60))  # fmt: skip
        for rig, cmp in (main.get("answers") or {}).items():
            t.append(_row(f"{rig}: every peak as before", "within 0.3 %",
                          f"largest change {cmp['max_peak_change_pct']:.3f} %",
                          cmp["max_peak_change_pct"] <= 0.3))  # fmt: skip
            t.append(_row(f"{rig}: no definite verdict changed", "no case",
                          ", ".join(cmp["verdict_changes"]) or "none",
                          not cmp["verdict_changes"]))  # fmt: skip
    else:
        t.append(_row("make run, both rigs, cold, 2 ranks", "< 600 s", "-", None))
    hbm = _load(out / "hbm" / "bench_hbm.json")
    cases = {r["case"]: r for r in (hbm or {}).get("cases", [])}
    for name, limit in (("pairs146", 30.0), ("pairs46", 3.0)):
        r = cases.get(name)
        if r is None:
            t.append(_row(f"bench_hbm {name} curve", f"< {limit:g} s", "-", None))
            continue
        t.append(_row(f"bench_hbm {name} curve, with stability", f"< {limit:g} s",
                      f"{r['wall_s']:.2f} s (load {r['load_before']})",
                      r["wall_s"] < limit))  # fmt: skip
        t.append(_row(f"bench_hbm {name}: stability share", "< 25 %",
                      f"{100 * r['stability_share']:.0f} % ({r['hill_checks']} Hill checks of "
                      f"{r['points']} points)", r["stability_share"] < 0.25))  # fmt: skip
    ph = (hbm or {}).get("pyharm")
    if ph and ph.get("pyharm"):
        t += _pyharm_rows(ph)
    else:
        t.append(_row("unit Jenkins: pyHarm/ours", ">= 10x / >= 20x", "pyHarm not run", None))
    return t


def _pyharm_rows(ph: dict) -> list[tuple[str, str, str, str]]:
    from pyharm_compare import cheapest

    out = []
    sweep = ph["pyharm"]["sweep"]
    default = next(p for p in sweep if p["ds_max"] == 0.1)
    ours = [dict(o, tool="ours") for o in ph["ours"]]
    for want, err, label in ((10, default["amp_err"], "pyHarm's default accuracy"),
                             (20, 1e-4, "1e-4 peak error")):  # fmt: skip
        o = cheapest(ours, "ours", err)
        p = default if want == 10 else cheapest([dict(x, tool="p") for x in sweep], "p", err)
        if o is None or p is None:
            out.append(_row(f"solve time at {label}", f">= {want}x", "no run reaches it", False))
            continue
        ratio = p["cpu_s"] / o["cpu_s"]
        out.append(_row(f"solve time at {label} ({err:.1e})", f">= {want}x",
                        f"{ratio:.1f}x (pyHarm {p['cpu_s']:.3f} s, ours {o['label']} "
                        f"{o['cpu_s']:.3f} s)", ratio >= want))  # fmt: skip
    whole = ph.get("whole") or {}
    if whole.get("pyharm"):
        rows_ = whole["rows"]
        for nt in sorted({r["nt"] for r in rows_}):
            pd = next(r for r in rows_ if r["nt"] == nt and r["label"] == "ds_max 0.1")
            for want, err, label in ((10, pd["amp_err"], "pyHarm's default accuracy"),
                                     (20, 1e-4, "1e-4 peak error")):  # fmt: skip
                o = cheapest(rows_, "ours", err, nt)
                p = pd if want == 10 else cheapest(rows_, "pyHarm", err, nt)
                name = f"whole process, {nt} samples, at {label}"
                if o is None or p is None:
                    out.append(_row(name, f">= {want}x", "no run reaches it", False))
                    continue
                ratio = p["cpu_s"] / o["cpu_s"]
                out.append(_row(name, f">= {want}x", f"{ratio:.1f}x (pyHarm {p['label']} "
                                f"{p['cpu_s']:.2f} s, ours {o['label']} {o['cpu_s']:.2f} s)",
                                ratio >= want))  # fmt: skip
    return out


def report(out: Path) -> int:
    """Print the table; the number of targets missed."""
    sys.path.insert(0, str(Path(__file__).parent))
    t = rows(out)
    w = [max(len(r[k]) for r in t) for k in range(4)]
    print("\nissue 28's targets (2-core machine; see the load with each figure):")
    for r in t:
        print("  " + "  ".join(c.ljust(w[k]) for k, c in enumerate(r)))
    return sum(r[3] == "MISSED" for r in t)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=ROOT / "results" / "bench")
    a = ap.parse_args(argv)
    report(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
