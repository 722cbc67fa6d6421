"""Benchmark of the FE stage: time and peak memory against the number of DOFs.

For each rig mesh size and each number of MPI ranks (default 1 and 2) a
worker process (``mpirun -n R python bench_fe.py --worker ...``) runs the
FE pipeline from scratch and times each stage:

    mesh        build_geometry: gmsh meshing of the rig and the damper (rank 0)
    assembly    reading both meshes into dolfinx and assembling K and M (P2)
    eigen       the unreduced rig + damper with stuck contacts: 10 modes (SLEPc)
    reduction   Craig-Bampton of the rig (12 fixed-interface modes, constraint
                modes for every interface node) and of the damper

Peak memory is ``ru_maxrss`` of each rank after each stage (a running
maximum), summed over the ranks. The first bending pair (stuck) at each
size gives the mesh convergence. The default damper is the wedge: its 146
contact pairs plus the excitation and response points make the "about 150
interface nodes" of the issue's target (a rig of at least 300k DOFs reduced
in under 3 minutes on 2 ranks, under 12 GB).

Prints a table, writes bench_fe.json, bench_fe.csv and bench_fe.png in --out.
Timings are only meaningful on a quiet machine; the script records the load
average before and after each run. On the 2-core sandbox, 2 ranks are not
expected to be faster than 1 (see docs and the closing note of issue 4).

    .venv/bin/python benchmarks/bench_fe.py --out results/bench_fe
    .venv/bin/python benchmarks/bench_fe.py --sizes 9 6 --ranks 1 --out /tmp/b   # quick
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import resource
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_SIZES = (9.0, 6.0, 4.5, 3.5)  # rig element size, mm: about 25k .. 340k DOFs
STAGES = ("mesh", "assembly", "eigen", "reduction")


def _rss_gb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024**2  # KiB -> GiB


def worker(args: argparse.Namespace) -> None:
    """One part of the pipeline (under mpirun); rank 0 writes the JSON record.

    ``--part modes``: mesh, assembly, stuck eigen solve of the unreduced model.
    ``--part reduce``: (meshes reused) Craig-Bampton of the rig and the damper,
    in a process of its own so that its peak memory is its own.
    """
    from mpi4py import MPI

    from workbench.geometry import build_geometry

    comm = MPI.COMM_WORLD
    out = Path(args.work)
    t: dict[str, float] = {}
    mem: dict[str, float] = {}
    rec: dict = {}

    def mark(stage: str, t0: float) -> None:
        comm.Barrier()
        t[stage] = time.perf_counter() - t0
        mem[stage] = float(sum(comm.allgather(_rss_gb())))

    comm.Barrier()
    t0 = time.perf_counter()
    geom = build_geometry(args.damper, out / "geometry", size_mm=args.size)
    if args.part == "modes":
        mark("mesh", t0)
        rec.update(_modes_part(geom, comm, mark))
    else:
        from workbench.fe.reduce import reduce_body

        t0 = time.perf_counter()
        rt: dict[str, float] = {}
        rrig = reduce_body(geom, "rig", n_modes=12, comm=comm, timings=rt)
        mark("reduce_rig", t0)
        t0 = time.perf_counter()
        reduce_body(geom, "damper", n_modes=12, comm=comm)
        mark("reduce_damper", t0)
        rec.update(
            n_interface_nodes_rig=rrig.n_nodes,
            reduce_rig_stages_s={k: round(v, 3) for k, v in rt.items()},
        )
    if comm.rank == 0:
        rec.update(
            time_s={k: round(v, 3) for k, v in t.items()},
            peak_mem_gb={k: round(v, 3) for k, v in mem.items()},
        )
        Path(args.record).write_text(json.dumps(rec, indent=2))


def _modes_part(geom, comm, mark) -> dict:
    from workbench.assembly.params import load_contact_params
    from workbench.fe.coupling import pair_springs, stuck_fe_system
    from workbench.fe.interface import locate_nodes
    from workbench.fe.modes import FREE_SHIFT_HZ, classify_bending, load_bodies
    from workbench.fe.parallel import allsum
    from workbench.fe.solvers import eigen_solve

    t0 = time.perf_counter()
    bodies = load_bodies(geom, comm)
    mark("assembly", t0)
    rig, dmp = bodies["rig"], bodies["damper"]
    t0 = time.perf_counter()
    params = load_contact_params()
    pn = locate_nodes(rig, geom.contact.points)
    dn = locate_nodes(dmp, geom.contact.points)
    rn = locate_nodes(rig, geom.response_points)
    en = locate_nodes(rig, geom.excitation_points)
    K, M, is_r, _ = stuck_fe_system(rig, dmp, pn, dn, pair_springs(geom.contact, params))
    sol = eigen_solve(K, M, 10, sigma=-((2 * math.pi * FREE_SHIFT_HZ) ** 2), prefix="upd_modes_")
    resp, exc = [], []
    for v in sol.vectors:
        sub = v.getSubVector(is_r)
        a = sub.getArray()
        for nodes, dest in ((rn, resp), (en, exc)):
            vals = [a[3 * b : 3 * b + 3] if b >= 0 else [0.0, 0.0, 0.0] for b in nodes.local_block]
            dest.append(allsum(comm, vals))
        v.restoreSubVector(is_r, sub)
    _, i_in, i_out = classify_bending(resp, exc)
    freqs = [float(f) for f in sol.freqs_hz]
    mark("eigen", t0)
    return {
        "n_dofs_rig": rig.n_dofs,
        "n_dofs_damper": dmp.n_dofs,
        "n_dofs": rig.n_dofs + dmp.n_dofs,
        "freqs_hz": freqs,
        "first_bending_in_phase_hz": None if i_in is None else freqs[i_in],
        "first_bending_out_of_phase_hz": None if i_out is None else freqs[i_out],
    }


def run_case(size: float, ranks: int, damper: str, out: Path) -> dict:
    """Run both parts for one size and rank count (fresh meshes); merge their records."""
    work = out / "work" / f"{damper}_{size:g}mm_{ranks}r"
    if work.exists():
        shutil.rmtree(work)
    work.mkdir(parents=True)
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", UPD_NO_PROGRESS="1")
    rec: dict = {"damper": damper, "size_mm": size, "ranks": ranks, "time_s": {}, "peak_mem_gb": {}}
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    for part in ("modes", "reduce"):
        record = work / f"{part}.json"
        cmd = [
            "mpirun",
            "-n",
            str(ranks),
            "--allow-run-as-root",
            "--oversubscribe",
            sys.executable,
            str(Path(__file__).resolve()),
            "--worker",
            "--part",
            part,
            "--size",
            str(size),
            "--damper",
            damper,
            "--work",
            str(work),
            "--record",
            str(record),
        ]
        p = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, env=env)
        if p.returncode != 0:
            sys.stderr.write(p.stderr[-4000:])
            rec.update(failed=True, error=(p.stderr.strip().splitlines() or ["?"])[-1])
            return rec
        part_rec = json.loads(record.read_text())
        rec["time_s"].update(part_rec.pop("time_s"))
        rec["peak_mem_gb"].update(part_rec.pop("peak_mem_gb"))
        rec.update(part_rec)
    rec["time_s"]["reduction"] = rec["time_s"]["reduce_rig"] + rec["time_s"]["reduce_damper"]
    rec.update(
        wall_s=round(time.perf_counter() - t0, 2),
        load_before=round(load0, 2),
        load_after=round(os.getloadavg()[0], 2),
    )
    shutil.rmtree(work / "geometry", ignore_errors=True)
    return rec


def _peaks(r: dict) -> tuple[float, float]:
    """(peak GB of the modes process, peak GB of the reduction process), all ranks."""
    m = r["peak_mem_gb"]
    return m["eigen"], max(m["reduce_rig"], m["reduce_damper"])


def write_outputs(records: list[dict], out: Path) -> None:
    ok = [r for r in records if not r.get("failed")]
    meta = {
        "machine": {"cpus": os.cpu_count(), "uname": " ".join(os.uname())},
        "note": "times: wall seconds of each stage on rank 0 after a barrier; peak "
        "memory: ru_maxrss after each stage (a running maximum per process), "
        "summed over ranks; the modes part (mesh, assembly, eigen) and the "
        "reduction run in separate processes",
        "records": records,
    }
    (out / "bench_fe.json").write_text(json.dumps(meta, indent=2))
    with open(out / "bench_fe.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(
            ["damper", "size_mm", "ranks", "n_dofs_rig", "n_dofs_total"]
            + [f"{s}_s" for s in STAGES]
            + [
                "reduce_rig_s",
                "peak_mem_modes_gb",
                "peak_mem_reduction_gb",
                "in_phase_hz",
                "out_of_phase_hz",
                "load_before",
                "load_after",
            ]
        )
        for r in ok:
            w.writerow(
                [r["damper"], r["size_mm"], r["ranks"], r["n_dofs_rig"], r["n_dofs"]]
                + [r["time_s"][s] for s in STAGES]
                + [r["time_s"]["reduce_rig"]]
                + list(_peaks(r))
                + [
                    r["first_bending_in_phase_hz"],
                    r["first_bending_out_of_phase_hz"],
                    r["load_before"],
                    r["load_after"],
                ]
            )
    if ok:
        plot(ok, out / "bench_fe.png")


def plot(ok: list[dict], png: Path) -> None:
    sys.path.insert(0, str(ROOT))
    from workbench.render.common import pyplot, save_figure

    plt = pyplot()
    fig, ax = plt.subplots(1, 3, figsize=(16, 4.8))
    style = {1: "o-", 2: "s--"}
    for ranks in sorted({r["ranks"] for r in ok}):
        rs = sorted((r for r in ok if r["ranks"] == ranks), key=lambda r: r["n_dofs_rig"])
        n = [r["n_dofs_rig"] for r in rs]
        tag = f"{ranks} rank{'s' if ranks > 1 else ''}"
        for s in STAGES:
            ax[0].plot(n, [r["time_s"][s] for r in rs], style.get(ranks, "^:"), label=f"{s}, {tag}")
        ax[1].plot(
            n,
            [_peaks(r)[0] for r in rs],
            style.get(ranks, "^:"),
            label=f"mesh + assembly + eigen, {tag}",
        )
        ax[1].plot(n, [_peaks(r)[1] for r in rs], style.get(ranks, "^:"), label=f"reduction, {tag}")
    ax[0].axhline(180, color="k", lw=0.8, ls=":")
    ax[0].set(
        xscale="log",
        yscale="log",
        xlabel="rig DOFs",
        ylabel="wall time (s)",
        title="time per stage (dotted: 3 min)",
    )
    ax[0].legend(ncol=2, fontsize=7)
    ax[1].axhline(12, color="k", lw=0.8, ls=":")
    ax[1].set(
        xscale="log",
        xlabel="rig DOFs",
        ylabel="peak memory, all ranks (GB)",
        title="peak memory per process (ru_maxrss; dotted: 12 GB)",
    )
    ax[1].legend(fontsize=7)
    serial = sorted(
        (r for r in ok if r["ranks"] == min(x["ranks"] for x in ok)), key=lambda r: r["n_dofs_rig"]
    )
    if len(serial) > 1:
        fine = serial[-1]
        n = [r["n_dofs_rig"] for r in serial[:-1]]
        for key, lab in (
            ("first_bending_in_phase_hz", "in-phase"),
            ("first_bending_out_of_phase_hz", "out-of-phase"),
        ):
            ref = fine[key]
            if ref is None:
                continue
            err = [
                abs(r[key] / ref - 1) * 100 if r[key] is not None else float("nan")
                for r in serial[:-1]
            ]
            ax[2].plot(n, err, "o-", label=f"{lab} (finest: {ref:.1f} Hz)")
        ax[2].set(
            xscale="log",
            yscale="log",
            xlabel="rig DOFs",
            ylabel="|f - f_finest| / f_finest (%)",
            title=f"first bending pair, {fine['damper']} stuck: mesh convergence",
        )
        ax[2].legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, png)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=ROOT / "results" / "bench_fe")
    ap.add_argument(
        "--sizes",
        type=float,
        nargs="+",
        default=list(DEFAULT_SIZES),
        help="rig element sizes, mm (default: %(default)s)",
    )
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--damper", default="wedge")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--part", choices=("modes", "reduce"), help=argparse.SUPPRESS)
    ap.add_argument("--size", type=float, help=argparse.SUPPRESS)
    ap.add_argument("--work", help=argparse.SUPPRESS)
    ap.add_argument("--record", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        worker(args)
        return
    out = args.out
    out.mkdir(parents=True, exist_ok=True)
    records = []
    head = (
        f"{'size':>5} {'ranks':>5} {'rig DOFs':>9} "
        + " ".join(f"{s:>9}" for s in STAGES)
        + f" {'reduce rig':>10} {'GB modes':>8} {'GB reduce':>9} {'in Hz':>7} {'out Hz':>7}"
        + f" {'load':>9}"
    )
    print(head, flush=True)
    for size in args.sizes:
        for ranks in args.ranks:
            r = run_case(size, ranks, args.damper, out)
            records.append(r)
            write_outputs(records, out)
            if r.get("failed"):
                print(f"{size:5g} {ranks:5d} failed: {r['error']}", flush=True)
                continue
            gm, gr = _peaks(r)
            print(
                f"{size:5g} {ranks:5d} {r['n_dofs_rig']:9d} "
                + " ".join(f"{r['time_s'][s]:9.1f}" for s in STAGES)
                + f" {r['time_s']['reduce_rig']:10.1f} {gm:8.2f} {gr:9.2f}"
                + f" {r['first_bending_in_phase_hz'] or float('nan'):7.1f}"
                + f" {r['first_bending_out_of_phase_hz'] or float('nan'):7.1f}"
                + f" {r['load_before']:4.1f}/{r['load_after']:<4.1f}",
                flush=True,
            )
    print(f"wrote {out / 'bench_fe.json'}, {out / 'bench_fe.csv'}, {out / 'bench_fe.png'}")


if __name__ == "__main__":
    main()
