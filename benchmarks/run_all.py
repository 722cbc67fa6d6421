"""Every benchmark and slow check, one after the other: ``make bench``.

Parts (``--parts``, default all, in this order):

    main-job    benchmarks/main_job.py: both studies of ``make run``, cold, on 2 MPI ranks,
                timed, and their answers against benchmarks/reference/
    hbm         benchmarks/bench_hbm.py: harmonic balance curves (single DOF to 146 pairs)
                and the comparison with pyHarm (solve time and whole process)
    nlmodes     benchmarks/bench_nlmodes.py: 6 nonlinear modes + synthesis against 42 curves
    fe          benchmarks/bench_fe.py: meshing, assembly, eigen solve and reduction
                against the number of DOFs, serial and on 2 ranks (the longest part)
    slow-tests  the tests marked ``slow`` (pytest -m slow)
    fidelity    upd study studies/fidelity.toml: error against compute time per knob
    robustness  upd study studies/robustness.toml: the failure map of the solution methods
    runup       benchmarks/runup_ratchet.py: the cylinder out of phase at 9.6 N on the
                paper-like rig with mu 0.5 (it ratchets), harmonic balance against a
                500-period run-up from rest

Each part writes into its own folder under ``--out`` and its console output
to ``<part>.log`` there; ``summary.json`` records the exit code and wall
time of each part. A part that fails does not stop the others; the exit
code is non-zero if any failed. At the end issue 28's speed targets are
printed beside the figures of this run (benchmarks/targets.py). The
studies resume from their caches, so an interrupted ``make bench``
continues where it stopped (the main job starts cold each time).

    .venv/bin/python benchmarks/run_all.py --out results/bench
    .venv/bin/python benchmarks/run_all.py --parts hbm,fidelity --out /tmp/bench
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PY = sys.executable
UPD = str(Path(PY).with_name("upd"))
PARTS = ("main-job", "hbm", "nlmodes", "fe", "slow-tests", "fidelity", "robustness", "runup")


def command(part: str, out: Path) -> list[str]:
    """The command line of one part, writing into ``out / part``."""
    d = str(out / part)
    return {
        "main-job": [PY, str(ROOT / "benchmarks" / "main_job.py"), "--out", d],
        "hbm": [PY, str(ROOT / "benchmarks" / "bench_hbm.py"), "--out", d],
        "nlmodes": [PY, str(ROOT / "benchmarks" / "bench_nlmodes.py"), "--out", d],
        "fe": [PY, str(ROOT / "benchmarks" / "bench_fe.py"), "--out", d],
        "slow-tests": [PY, "-m", "pytest", "-q", "-m", "slow", "-p", "no:cacheprovider"],
        "fidelity": [UPD, "study", str(ROOT / "studies" / "fidelity.toml"), "--out", d],
        "robustness": [UPD, "study", str(ROOT / "studies" / "robustness.toml"), "--out", d],
        "runup": [
            PY,
            str(ROOT / "benchmarks" / "runup_ratchet.py"),
            "--periods",
            "400",
            "--out",
            d,
        ],
    }[part]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0],
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog=__doc__.split("\n\n", 1)[1],
    )
    ap.add_argument(
        "--out",
        type=Path,
        default=ROOT / "results" / "bench",
        help="folder of the results (default results/bench)",
    )
    ap.add_argument(
        "--parts", default=",".join(PARTS), help="comma list of parts among " + ", ".join(PARTS)
    )
    args = ap.parse_args(argv)
    parts = [p.strip() for p in args.parts.split(",") if p.strip()]
    for p in parts:
        if p not in PARTS:
            print(
                f"error: --parts: '{p}' is not a part; allowed: {', '.join(PARTS)}", file=sys.stderr
            )
            return 2
    args.out.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    summary: dict[str, dict] = {}
    for i, part in enumerate(parts, 1):
        (args.out / part).mkdir(exist_ok=True)
        log_path = args.out / part / f"{part}.log"
        cmd = command(part, args.out)
        print(f"[{i}/{len(parts)}] {part}: {' '.join(cmd)}  (log: {log_path})", flush=True)
        t0 = time.perf_counter()
        with open(log_path, "w") as log:
            code = subprocess.call(cmd, cwd=ROOT, env=env, stdout=log, stderr=subprocess.STDOUT)
        wall = time.perf_counter() - t0
        summary[part] = {"exit_code": code, "wall_s": round(wall, 1), "log": str(log_path)}
        print(
            f"[{i}/{len(parts)}] {part}: {'ok' if code == 0 else f'FAILED (exit {code})'} "
            f"in {wall:.0f} s",
            flush=True,
        )
        with open(args.out / "summary.json", "w") as f:
            json.dump(summary, f, indent=2)
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import targets

    targets.report(args.out)
    bad = [p for p, s in summary.items() if s["exit_code"] != 0]
    if bad:
        print("failed parts: " + ", ".join(bad) + " (see their logs)", file=sys.stderr)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
