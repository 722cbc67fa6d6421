"""Benchmark: 6 nonlinear modes + synthesis against the 42 forced responses they replace.

The paper's comparison costs 3 dampers x 2 families x 7 forces = 42 full
HBM curves. Here each damper and family gets one backbone (extended
periodic motion concept, :func:`workbench.hbm.nlmodes.backbone.nonlinear_mode`) and
the 7 forced responses are synthesised from it
(:func:`workbench.hbm.nlmodes.synthesis.synthesize`); the 42 HBM curves are
computed as the study computes them (same harmonics, Hill stability on,
:func:`workbench.hbm.frequency_response`), and the peaks compared.

Model: the synthetic two-blade rig with a free-free damper
(:func:`workbench.hbm.io.examples.line_damper_rig`, springs and lumped masses,
the size of the cone model with 23 pairs per line: 363 DOFs), not the FE
rig; three contact settings stand in for the three dampers (line stiffness
and friction coefficient), both families, the paper's seven forces.

Prints per damper and family: backbone time, HBM time of its 7 curves,
the peak error of every force and whether the synthesis flags itself
valid; then the totals: time ratio (backbones + syntheses) / (42 curves),
the worst peak error where valid, and how many syntheses are valid. Writes
bench_nlmodes.json and bench_nlmodes.csv to --out. The target (issue 17):
ratio < 0.1 at < 2 % peak error where valid.

    .venv/bin/python benchmarks/bench_nlmodes.py --out results/bench_nlmodes
    .venv/bin/python benchmarks/bench_nlmodes.py --per-line 5 --out /tmp/b   # quick
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("UPD_NO_PROGRESS", "1")

FORCES = (0.096, 3.84, 9.6, 15.0, 20.0, 25.0, 30.0)
# three contact settings standing in for the three dampers of the paper
DAMPERS = {
    "A (k 5e8, mu 0.5)": dict(k_line_n_per_m2=5.0e8, mu=0.5),
    "B (k 2e8, mu 0.5)": dict(k_line_n_per_m2=2.0e8, mu=0.5),
    "C (k 1e9, mu 0.3)": dict(k_line_n_per_m2=1.0e9, mu=0.3),
}
FAMILIES = ("in-phase", "out-of-phase")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=Path("results/bench_nlmodes"))
    ap.add_argument("--per-line", type=int, default=23, help="contact pairs per line (23)")
    ap.add_argument("--forces", default=",".join(map(str, FORCES)))
    ap.add_argument("--harmonics", default="0,1,2,3")
    ap.add_argument(
        "--no-stability",
        action="store_true",
        help="HBM curves without Hill's method (the study computes it)",
    )
    args = ap.parse_args(argv)
    from workbench.hbm import SolverOptions, frequency_response
    from workbench.hbm.io.examples import line_damper_rig
    from workbench.hbm.nlmodes.backbone import nonlinear_mode
    from workbench.hbm.nlmodes.synthesis import synthesize

    forces = [float(v) for v in args.forces.split(",")]
    H = tuple(int(v) for v in args.harmonics.split(","))
    opts = SolverOptions(stability=not args.no_stability, max_points=400)
    args.out.mkdir(parents=True, exist_ok=True)
    rows, groups = [], []
    load0 = os.getloadavg()[0]
    for dname, kw in DAMPERS.items():
        for fam in FAMILIES:
            ex = line_damper_rig(n_per_line=args.per_line, family=fam, **kw)
            t0 = time.perf_counter()
            nm = nonlinear_mode(
                ex.system,
                f1=ex.f1,
                band_hz=ex.band_hz,
                harmonics=H,
                outputs=ex.outputs,
                levels=forces,
                max_fold_points=20,
                label=f"{dname} {fam}",
            )
            t_nm = time.perf_counter() - t0
            t_syn, t_hbm = 0.0, 0.0
            for F in forces:
                t1 = time.perf_counter()
                s = synthesize(nm, ex.f1, F, 0, ex.band_hz) if nm.n_points >= 2 else None
                t_syn += time.perf_counter() - t1
                t1 = time.perf_counter()
                b = frequency_response(
                    ex.system, ex.f1, F, ex.band_hz, ex.outputs, harmonics=H, options=opts
                )
                dt = time.perf_counter() - t1
                t_hbm += dt
                i = b.peak(0)
                row = dict(
                    damper=dname,
                    family=fam,
                    force_n=F,
                    hbm_s=round(dt, 3),
                    hbm_peak_hz=float(b.freq_hz[i]) if i >= 0 else None,
                    hbm_peak_mm=float(b.out_amp[i, 0]) * 1e3 if i >= 0 else None,
                    hbm_failed=bool(b.failed),
                )
                if s is not None:
                    row.update(
                        syn_peak_hz=s.peak_freq_hz,
                        syn_peak_mm=s.peak_amplitude * 1e3,
                        valid=s.valid,
                        reasons="; ".join(s.reasons),
                    )
                    if i >= 0:
                        row["error_pct"] = 100 * (row["syn_peak_mm"] / row["hbm_peak_mm"] - 1)
                        row["freq_error_pct"] = 100 * (s.peak_freq_hz / row["hbm_peak_hz"] - 1)
                rows.append(row)
                print(
                    f"  {dname:18s} {fam:12s} F {F:6.3g} N: HBM {row['hbm_peak_mm']:.5g} mm "
                    f"at {row['hbm_peak_hz']:.2f} Hz ({dt:.1f} s) | synthesis "
                    f"{row.get('syn_peak_mm', float('nan')):.5g} mm, error "
                    f"{row.get('error_pct', float('nan')):+.2f} %, "
                    f"{'valid' if row.get('valid') else 'NOT valid: ' + row.get('reasons', '')}",
                    flush=True,
                )
            groups.append(
                dict(
                    damper=dname,
                    family=fam,
                    backbone_s=round(t_nm, 3),
                    synthesis_s=round(t_syn, 4),
                    hbm_s=round(t_hbm, 3),
                    points=nm.n_points,
                    message=nm.message,
                    damping_max=float(nm.damping_ratio.max()) if nm.n_points else None,
                )
            )
            print(
                f"{dname:18s} {fam:12s}: backbone {t_nm:.1f} s ({nm.n_points} points, "
                f"{nm.message}), {len(forces)} HBM curves {t_hbm:.1f} s",
                flush=True,
            )
    t_n = sum(g["backbone_s"] + g["synthesis_s"] for g in groups)
    t_h = sum(g["hbm_s"] for g in groups)
    valid = [r for r in rows if r.get("valid") and r.get("error_pct") is not None]
    errs = [abs(r["error_pct"]) for r in valid]
    summary = dict(
        n_backbones=len(groups),
        n_curves=len(rows),
        backbones_s=round(t_n, 2),
        hbm_s=round(t_h, 2),
        time_ratio=round(t_n / t_h, 4) if t_h else None,
        n_valid=len(valid),
        max_error_valid_pct=round(max(errs), 3) if errs else None,
        mean_error_valid_pct=round(sum(errs) / len(errs), 3) if errs else None,
        max_error_all_pct=round(
            max(abs(r["error_pct"]) for r in rows if r.get("error_pct") is not None), 3
        ),
        target="time ratio < 0.1 at < 2 % peak error where valid",
        model=f"line_damper_rig, {args.per_line} pairs per line (synthetic, not the FE rig)",
        harmonics=list(H),
        stability=not args.no_stability,
        loadavg=[load0, os.getloadavg()[0]],
    )
    (args.out / "bench_nlmodes.json").write_text(
        json.dumps(dict(summary=summary, groups=groups, rows=rows), indent=1)
    )
    with open(args.out / "bench_nlmodes.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=sorted({k for r in rows for k in r}))
        w.writeheader()
        w.writerows(rows)
    print()
    for k, v in summary.items():
        print(f"{k:22s} {v}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
