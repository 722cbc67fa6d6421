"""How much does meshing alone move the main job's numbers? The same setting meshed anew
with other gmsh random seeds (issue 31).

The fidelity studies read each knob's ladder against a noise floor: what re-meshing alone
moves a value. Until now that floor was inferred from the global mesh ladder's scatter
about its trend. This script measures it directly: the main job's cone cases
(`studies/paper_rig.toml`: 9 mm, 1.5 mm at the contacts, 12 modes, harmonics 0-3, nt 64,
23 points per line; in and out of phase at 9.6 and 30 N) at the same setting, meshed with
gmsh's `Mesh.RandomSeed` 1 (gmsh's default: the main job's own mesh) to N. The seed
changes the mesh, not its sizes (the node counts differ by about 0.5 %). Each seed is run
on whole meshes (as the main job) and on mirror-image meshes (`[rig.mesh] mirror =
true`), and the script prints per case and quantity the mean, the standard deviation and
the range over the seeds, with the energy split between the two lines.

The seed is a measuring device of this script (a wrapper of the builders' size field),
not an option of the package: the package's cache keys do not know it, so each run gets
a scratch folder of its own.

    python benchmarks/remesh_noise.py              # seeds 1-5, both variants (about 15 min)
    python benchmarks/remesh_noise.py --seeds 6    # one more seed
    python benchmarks/remesh_noise.py --report     # table and chart from the cache

Runs are cached in results/remesh_noise/runs.json (one entry per variant and seed); the
chart is results/remesh_noise/remesh_noise.png.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

for _k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ.setdefault(_k, "1")
os.environ["UPD_WORKERS"] = "1"  # in this process: the seed below must apply
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

OUT = ROOT / "results" / "remesh_noise"
STUDY = ROOT / "studies" / "paper_rig.toml"
GEOMETRY = ROOT / "geometry" / "paper_rig.toml"
VARIANTS = ("whole", "mirror")
QS = (
    ("h1_amplitude_mm", "harmonic-1 peak, mm"),
    ("h1_peak_frequency_hz", "its frequency, Hz"),
    ("h1_friction_energy_mj", "friction energy per cycle, mJ"),
)


def _geometry(variant: str, scratch: Path) -> Path:
    from benchmarks.geometry_variant import with_mirror

    return with_mirror(
        GEOMETRY, variant == "mirror", scratch / f"paper_rig_{variant}.toml", "remesh_noise.py"
    )


@contextlib.contextmanager
def _seeded(seed: int):
    """Every gmsh mesh made inside the block uses ``Mesh.RandomSeed = seed``."""
    import workbench.geometry.occ as occ

    original = occ.size_field

    def size_field(gmsh, *args, **kwargs):
        original(gmsh, *args, **kwargs)
        gmsh.option.setNumber("Mesh.RandomSeed", seed)

    occ.size_field = size_field
    try:
        yield
    finally:
        occ.size_field = original


def run_one(variant: str, seed: int) -> dict:
    """The main job's cone cases on one mesh realisation: per case the summary's numbers."""
    from workbench.cli.main import main as upd
    from workbench.post.results import StudyResults

    scratch = Path(tempfile.mkdtemp(prefix="remesh_noise_"))
    t0 = time.perf_counter()
    try:
        argv = ["study", str(STUDY), "--geometry", str(_geometry(variant, scratch))]
        argv += ["--dampers", "cone", "--forces", "9.6,30", "--no-nonlinear-modes"]
        argv += ["--no-stability", "--out", str(scratch / "run"), "-q"]
        with _seeded(seed), contextlib.redirect_stdout(io.StringIO()):
            rc = upd(argv)
        if rc:
            raise RuntimeError(f"upd study failed ({rc}): {variant}, seed {seed}")
        cases = {}
        for c in StudyResults.load(scratch / "run" / "results.h5").cases:
            s = c.summary()
            name = f"cone {'in' if c.phase_deg == 0.0 else 'out of'} phase {c.force_n:g} N"
            cases[name] = {q: s[q] for q, _ in QS}
            cases[name]["split_pct"] = s["h1_friction_energy_split_pct"]
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    return {"variant": variant, "seed": seed, "seconds": time.perf_counter() - t0,
            "cases": cases}  # fmt: skip


def load_runs() -> list[dict]:
    f = OUT / "runs.json"
    return json.loads(f.read_text()) if f.is_file() else []


def save_runs(runs: list[dict]) -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    tmp = OUT / "runs.json.part"
    tmp.write_text(json.dumps(runs, indent=1))
    tmp.replace(OUT / "runs.json")


def stats(runs: list[dict]) -> dict:
    """(variant, case, quantity) -> (mean, sample std, max - min, n) over the seeds."""
    import numpy as np

    out = {}
    for v in VARIANTS:
        rs = [r for r in runs if r["variant"] == v]
        if not rs:
            continue
        for case in rs[0]["cases"]:
            for q in [q for q, _ in QS] + ["split_pct"]:
                x = np.array([r["cases"][case][q] for r in rs if r["cases"][case][q] is not None])
                if len(x) < 2:
                    continue
                out[(v, case, q)] = (float(x.mean()), float(x.std(ddof=1)),
                                     float(x.max() - x.min()), len(x))  # fmt: skip
    return out


def report(runs: list[dict]) -> None:
    st = stats(runs)
    print(f"{'case':26s} {'quantity':22s} " + "  ".join(
        f"{v + ': mean, sd (%), range (%)':>40s}" for v in VARIANTS))  # fmt: skip
    cases = sorted({c for (_, c, _) in st})
    for case in cases:
        for q, _ in [*QS, ("split_pct", "")]:
            cells = []
            for v in VARIANTS:
                s = st.get((v, case, q))
                if s is None:
                    cells.append(f"{'-':>40s}")
                    continue
                mean, sd, rng, n = s
                if q == "split_pct":  # already a percentage: give it in points
                    cells.append(f"{mean:+10.2f} {sd:9.2f} pt {rng:9.2f} pt (n {n})")
                else:
                    cells.append(f"{mean:10.4g} {sd / abs(mean) * 100:8.3f} % "
                                 f"{rng / abs(mean) * 100:8.3f} % (n {n})")  # fmt: skip
            print(f"{case:26s} {q:22s} " + "  ".join(cells))
    for v in VARIANTS:
        t = [r["seconds"] for r in runs if r["variant"] == v]
        if t:
            print(f"{v}: {len(t)} runs, {min(t):.0f}-{max(t):.0f} s each")
    _chart(runs, st)


def _chart(runs: list[dict], st: dict) -> None:
    from workbench.render.common import pyplot, save_figure

    plt = pyplot()
    cases = sorted({c for (_, c, _) in st})
    fig, axes = plt.subplots(1, len(QS), figsize=(13, 4.8))
    for ax, (q, title) in zip(axes, QS, strict=True):
        for k, v in enumerate(VARIANTS):
            for j, case in enumerate(cases):
                xs = [r["cases"][case][q] for r in runs if r["variant"] == v]
                if not xs:
                    continue
                # one reference for both variants, the mirror meshes' mean: the whole
                # meshes' points show their scatter and their offset from it
                ref = st.get(("mirror", case, q), st.get((v, case, q), (xs[0],)))[0]
                dev = [(x - ref) / abs(ref) * 100 for x in xs]
                ax.plot([j + (k - 0.5) * 0.3] * len(dev), dev, "os"[k], ms=5, alpha=0.8,
                        color=("#d62728", "#1f77b4")[k],
                        label=f"{v} meshes" if j == 0 else None)  # fmt: skip
        ax.axhline(0.0, color="0.5", lw=0.8)
        ax.set_xticks(range(len(cases)))
        ax.set_xticklabels([c.replace("cone ", "").replace(" phase ", " phase\n")
                            for c in cases], fontsize=8)  # fmt: skip
        ax.set_ylabel("deviation from the mirror meshes' mean, %")
        ax.set_title(title, fontsize=10)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=8)
    n = max(st[k][3] for k in st)
    fig.suptitle(f"The main job's cone cases meshed anew with {n} gmsh seeds (same sizes): "
                 "what meshing alone moves", fontsize=11)  # fmt: skip
    fig.tight_layout(rect=(0, 0, 1, 0.93))
    print(f"chart: {save_figure(fig, OUT / 'remesh_noise.png')}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3, 4, 5],
                    help="gmsh random seeds (1: gmsh's default, the main job's mesh)")  # fmt: skip
    ap.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=VARIANTS)
    ap.add_argument("--report", action="store_true", help="table and chart only (no run)")
    ap.add_argument("--one", nargs=2, metavar=("VARIANT", "SEED"), help=argparse.SUPPRESS)
    a = ap.parse_args()
    from workbench.log import setup

    setup()
    if a.one:  # a child process: one run, its record on stdout
        print(json.dumps(run_one(a.one[0], int(a.one[1]))))
        return
    runs = load_runs()
    if not a.report:
        import subprocess

        for v in a.variants:
            for seed in a.seeds:
                if any(r["variant"] == v and r["seed"] == seed for r in runs):
                    continue
                # one process per run: a process that builds and solves several models in
                # turn keeps growing (24 GB after nine runs here)
                cmd = [sys.executable, __file__, "--one", v, str(seed)]
                p = subprocess.run(cmd, capture_output=True, text=True, check=False)
                if p.returncode:
                    raise SystemExit(f"{v}, seed {seed} failed:\n{p.stderr[-2000:]}")
                r = json.loads(p.stdout.strip().splitlines()[-1])
                runs.append(r)
                save_runs(runs)
                print(f"{v} meshes, seed {seed}: {r['seconds']:.0f} s", flush=True)
    report(runs)


if __name__ == "__main__":
    main()
