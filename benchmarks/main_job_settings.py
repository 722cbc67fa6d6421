"""Which harmonic set puts the main job within 2 % of the converged answer, and at what cost?
(issue 31, item 2: the friction energy at the default setting within 2 % of the extrapolated
limit, or the cheapest setting that is, made the default if it costs less than twice today's.)

Runs the whole main job (`upd study studies/paper_rig.toml` under `mpirun -n 2`: 42 curves,
their stability and the six nonlinear modes) once per harmonic set, each cold in a fresh
folder (meshes and reductions included, as `make run` does), and times it with the load
average before. Then reads each run's twelve fidelity cases (the six families at 9.6 and
30 N) as the fidelity studies read them (`CaseResult.refined_peak`: the peak between the
computed points) and sets them against the all-knob limits of the pad study
(`results/fid_paper_rig_pads/tables/fidelity_base_vs_limit.json`, `upd study
studies/fidelity_paper_rig_pads.toml`): the signed error of every number +- the limit's
uncertainty, "n.t." where the limit is not trusted. The other knobs stay at the main job's
setting, so a set's error is the main job's error with that set.

    python benchmarks/main_job_settings.py                      # 0-3, 0-4, 0-5 (about 16 min)
    python benchmarks/main_job_settings.py --harmonics 0-3,0-5  # a choice
    python benchmarks/main_job_settings.py --harmonics 0-5@64   # 0-5 at nt 64 (default 128)
    python benchmarks/main_job_settings.py --report             # the table from the runs

Runs go to results/main_job_settings/h<set>/ (kept: --report reads them; a run whose
folder exists is not repeated unless --force). Prints, per set: wall time, its ratio to
0-3, the load before, then per case the energy, peak and frequency errors, and the worst
energy error; writes results/main_job_settings/summary.json.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

for _k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ.setdefault(_k, "1")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

OUT = ROOT / "results" / "main_job_settings"
STUDY = ROOT / "studies" / "paper_rig.toml"
LIMITS = ROOT / "results" / "fid_paper_rig_pads" / "tables" / "fidelity_base_vs_limit.json"
QS = (
    ("friction_energy_mj", "energy"),
    ("peak_amplitude_mm", "peak max|x|"),
    ("peak_frequency_hz", "frequency"),
)


def harmonic_list(label: str) -> list[int]:
    """The set "0-4" is [0, 1, 2, 3, 4] ("0-5@64": the harmonics of "0-5")."""
    m = re.fullmatch(r"(\d+)-(\d+)(@\d+)?", label)
    if m is None or int(m[1]) > int(m[2]):
        raise SystemExit(
            f"--harmonics: {label!r} is not a set; allowed: LO-HI with LO <= HI, "
            "optionally @NT (e.g. 0-5 or 0-5@64)"
        )
    return list(range(int(m[1]), int(m[2]) + 1))


def nt_option(label: str) -> list[str]:
    """The set "0-5@64" runs at ``--nt 64``: samples per period other than the default."""
    return ["--nt", label.split("@")[1]] if "@" in label else []


def run(runs: Path, label: str, force: bool) -> dict:
    """The main job with harmonics ``label``, cold, on 2 ranks, into ``runs``: wall time and
    load before."""
    out = runs / f"h{label}"
    rec = out / "timing.json"
    if rec.is_file() and not force:
        return json.loads(rec.read_text())
    if out.exists():
        shutil.rmtree(out)
    out.mkdir(parents=True)
    load = os.getloadavg()
    cmd = ["mpirun", "-n", "2", "--allow-run-as-root", "--oversubscribe",
           str(ROOT / ".venv" / "bin" / "upd"), "study", str(STUDY),
           "--harmonics", ",".join(map(str, harmonic_list(label))), *nt_option(label),
           "--out", str(out)]  # fmt: skip
    print(f"harmonics {label}: {' '.join(cmd[5:])}", flush=True)
    t0 = time.perf_counter()
    with open(out / "run.log", "w") as log:
        code = subprocess.call(cmd, stdout=log, stderr=subprocess.STDOUT, cwd=ROOT)
    wall = time.perf_counter() - t0
    r = {"harmonics": label, "wall_s": wall, "load_before": load, "exit": code}
    rec.write_text(json.dumps(r, indent=1))
    print(f"  {wall:.0f} s wall, exit {code}, load before {load[0]:.2f}", flush=True)
    return r


def values(runs: Path, label: str) -> dict[str, dict[str, float | None]]:
    """Per fidelity condition ("cone 0 deg 30 N"), the refined peak quantities."""
    from workbench.post.fidelity import condition_name, zeroed
    from workbench.post.results import StudyResults

    res = StudyResults.load(runs / f"h{label}" / "results.h5")
    out = {}
    for c in res.cases:
        key = condition_name(c.phase_deg, c.force_n, c.damper)
        pk = c.refined_peak()
        out[key] = {q: None if pk.get(q) is None else zeroed(q, float(pk[q])) for q, _ in QS}
    return out


def _worst_energy(rows: list[dict], cone_wedge: bool = False) -> tuple | None:
    """(case, error %, uncertainty %) of the largest trusted energy error (of the cone and
    the wedge only, with ``cone_wedge``), None if there is none."""
    rs = [r for r in rows if r["quantity"] == "friction_energy_mj"]
    if cone_wedge:
        rs = [r for r in rs if not r["case"].startswith("cylinder")]
    w = max(rs, key=lambda r: abs(r["error_pct"]), default=None)
    return None if w is None else (w["case"], w["error_pct"], w["uncertainty_pct"])


def report(runs_dir: Path, labels: list[str]) -> dict:
    if not LIMITS.is_file():
        raise SystemExit(f"{LIMITS} is missing: run the pad study first (see the docstring)")
    lim = json.loads(LIMITS.read_text())["cases"]
    missing = [x for x in labels if not (runs_dir / f"h{x}" / "timing.json").is_file()]
    if missing:
        raise SystemExit(
            f"no run of harmonics {', '.join(missing)} in {runs_dir}: run without --report"
        )
    runs = {x: json.loads((runs_dir / f"h{x}" / "timing.json").read_text()) for x in labels}
    base = runs.get("0-3", {}).get("wall_s")
    summary: dict = {"limits": str(LIMITS.relative_to(ROOT)), "sets": {}}
    for x in labels:
        r = runs[x]
        ratio = f", {r['wall_s'] / base:.2f} x 0-3" if base else ""
        print(f"\nharmonics {x}: {r['wall_s']:.0f} s wall{ratio} (load before "
              f"{r['load_before'][0]:.2f}, exit {r['exit']})")  # fmt: skip
        vals = values(runs_dir, x)
        rows = []
        for cond, qs in lim.items():
            cells = []
            for q, name in QS:
                e = qs[q]
                v = vals.get(cond, {}).get(q)
                if v == 0.0 and q == "friction_energy_mj":
                    cells.append(f"{name} 0 (stuck)")
                    continue
                if v is None or e.get("limit") is None or not e.get("trusted"):
                    cells.append(f"{name} {v if v is None else f'{v:.4g}'}: n.t.")
                    continue
                err = 100.0 * (v / e["limit"] - 1.0)
                u = e["uncertainty_pct"]
                rows.append({"case": cond, "quantity": q, "value": v, "error_pct": err,
                             "uncertainty_pct": u})  # fmt: skip
                cells.append(f"{name} {v:.4g}: {err:+.2f} +- {u:.2g} %")
            print(f"  {cond:22s} " + " | ".join(cells))
        worst, cw = _worst_energy(rows), _worst_energy(rows, cone_wedge=True)
        if worst:
            print(f"  worst trusted energy error: {worst[0]}, {worst[1]:+.2f} +- {worst[2]:.2g} %")
        if cw:
            print(f"  on the cone and the wedge: {cw[0]}, {cw[1]:+.2f} +- {cw[2]:.2g} %")
        summary["sets"][x] = {
            "timing": r,
            "rows": rows,
            "worst_energy": worst,
            "worst_energy_cone_wedge": cw,
        }
    (runs_dir / "summary.json").write_text(json.dumps(summary, indent=1))
    return summary


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument(
        "--harmonics",
        default="0-3,0-4,0-5",
        help="sets, e.g. 0-3,0-4,0-5; 0-5@64 runs 0-5 at 64 samples a period (the default: "
        "16 per highest harmonic, a power of two)",
    )
    ap.add_argument("--report", action="store_true", help="only the table from the runs")
    ap.add_argument("--force", action="store_true", help="run again where a run exists")
    ap.add_argument("--out", default=str(OUT), help="folder of the runs (a second timing: another)")
    a = ap.parse_args()
    runs = Path(a.out).resolve()
    labels = a.harmonics.split(",")
    for x in labels:
        harmonic_list(x)  # a malformed set is refused before any run
    if not a.report:
        for x in labels:
            run(runs, x, a.force)
    report(runs, labels)


if __name__ == "__main__":
    main()
