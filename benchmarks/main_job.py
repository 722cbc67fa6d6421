"""The main job timed as a user runs it: both studies of ``make run``, cold, on 2 MPI ranks.

Runs ``upd study studies/paper_rig.toml`` and ``studies/paper.toml`` under
``mpirun -n 2`` into empty folders (meshes, reductions, curves, nonlinear
modes, pictures and reports all computed), records the wall time and the
load average before and after, the time of the paper-like rig's wedge curve
out of phase at 30 N, and compares every case with the reference answers of
``benchmarks/reference/<study>.json`` (each case's peaks and stability
counts, written by --reference; last from round 19's run on mirror meshes):
the largest peak change, and the cases whose set of unstable points or peak verdict changed. Writes
``main_job.json`` in ``--out``.

    .venv/bin/python benchmarks/main_job.py --out results/bench/main-job
    .venv/bin/python benchmarks/main_job.py --reference   # write the reference from --out
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STUDIES = ("paper_rig", "paper")
REFERENCE = ROOT / "benchmarks" / "reference"


def case_key(row: dict) -> str:
    return f"{row['damper']}-{float(row['phase_deg']):g}deg-{float(row['force_n']):g}N"


def answers(summary: list[dict]) -> dict[str, dict]:
    """The answers that must not move: per case, peaks and stability counts."""
    out = {}
    for r in summary:
        unstable = int(r.get("n_unstable") or 0) + int(r.get("n_unstable_carried") or 0)
        out[case_key(r)] = {
            "peak_amplitude_mm": r.get("peak_amplitude_mm"),
            "h1_amplitude_mm": r.get("h1_amplitude_mm"),
            "peak_frequency_hz": r.get("peak_frequency_hz"),
            "n_points": r.get("n_points"),
            "unstable_points": unstable,
            "peak_stability": (r.get("peak_stability") or "").replace(" (carried)", ""),
        }
    return out


def compare(new: dict[str, dict], ref: dict[str, dict]) -> dict:
    """Largest relative peak change (%) and the cases whose stability answer changed."""
    worst, changes = 0.0, []
    for k, r in ref.items():
        n = new.get(k)
        if n is None:
            changes.append(f"{k} missing")
            continue
        for q in ("peak_amplitude_mm", "h1_amplitude_mm"):
            if r.get(q) and n.get(q):
                worst = max(worst, 100 * abs(n[q] / r[q] - 1))
        if (r["unstable_points"] > 0) != (n["unstable_points"] > 0):
            changes.append(f"{k}: unstable points {r['unstable_points']} -> {n['unstable_points']}")
        if r["peak_stability"] != n["peak_stability"] and "unknown" not in (
            r["peak_stability"] + n["peak_stability"]
        ):
            changes.append(f"{k}: peak {r['peak_stability']} -> {n['peak_stability']}")
    return {"max_peak_change_pct": worst, "verdict_changes": changes}


def run(out: Path) -> dict:
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    upd = str(Path(sys.executable).with_name("upd"))
    mpirun = ["mpirun", "-n", "2", "--oversubscribe", "-x", "OMP_NUM_THREADS=1",
              "-x", "OPENBLAS_NUM_THREADS=1"]  # fmt: skip
    res = {"load_before": round(os.getloadavg()[0], 2), "studies": {}, "answers": {}}
    t0 = time.perf_counter()
    for name in STUDIES:
        folder = out / name
        shutil.rmtree(folder, ignore_errors=True)  # cold: nothing cached
        ts = time.perf_counter()
        code = subprocess.call(
            [*mpirun, upd, "study", str(ROOT / "studies" / f"{name}.toml"), "--out", str(folder)],
            cwd=ROOT,
            env=env,
        )
        res["studies"][name] = {"exit_code": code, "wall_s": round(time.perf_counter() - ts, 1)}
    res["wall_s"] = round(time.perf_counter() - t0, 1)
    res["load_after"] = round(os.getloadavg()[0], 2)
    for name in STUDIES:
        try:
            summ = json.loads((out / name / "summary.json").read_text())
        except (OSError, ValueError):
            continue
        got = answers(summ)
        (out / f"{name}_answers.json").write_text(json.dumps(got, indent=1))
        if name == "paper_rig":
            w = [r for r in summ if case_key(r) == "wedge-180deg-30N"]
            res["wedge_30n_out_of_phase_s"] = w[0].get("wall_s") if w else None
        ref = REFERENCE / f"{name}.json"
        if ref.is_file():
            res["answers"][name] = compare(got, json.loads(ref.read_text()))
    (out / "main_job.json").write_text(json.dumps(res, indent=1))
    return res


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=ROOT / "results" / "bench" / "main-job")
    ap.add_argument(
        "--reference",
        action="store_true",
        help="write benchmarks/reference/<study>.json from the summaries in --out (no run)",
    )
    a = ap.parse_args(argv)
    if a.reference:
        REFERENCE.mkdir(exist_ok=True)
        for name in STUDIES:
            summ = json.loads((a.out / name / "summary.json").read_text())
            (REFERENCE / f"{name}.json").write_text(json.dumps(answers(summ), indent=1) + "\n")
        return 0
    a.out.mkdir(parents=True, exist_ok=True)
    res = run(a.out)
    print(json.dumps({k: v for k, v in res.items() if k != "answers"}, indent=1))
    return 0 if all(s["exit_code"] == 0 for s in res["studies"].values()) else 1


if __name__ == "__main__":
    sys.exit(main())
