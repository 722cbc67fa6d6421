"""Why the global mesh ladder of the paper-like rig converges slowly (issue 31): a long
ladder of the linear frequencies, with and without the blade roots refined.

The fidelity studies move the global mesh size over four to six levels, and
their peak frequencies fall almost linearly with the size instead of
levelling off. This script measures the same thing on the linear model,
where nothing else moves: `upd screen` of the cone on the pad rig
(`geometry/paper_rig_pads.toml`, 12 modes, 1.5 mm at the contact points)
at each global size, giving two frequencies per family:

* stuck: every contact pair stuck (the family's linear frequency);
* sliding: the tangential springs removed (blade bending with the damper's
  normal springs only).

Each ladder's order is fitted by least squares (free order scanned over
0.3..4, then the package's `least_squares` and `richardson` rules). The
blades meet the base along sharp re-entrant edges; the strain there is
singular (a 270-degree elastic edge: stress ~ r^-0.46), and an eigenvalue
then converges as about h^1.1 instead of the h^4 that quadratic elements
give a smooth field. `--root-size` refines the mesh along those eight edges
only (a gmsh Threshold field on them, growing back to the global size over
15 mm), to show how much of the ladder's slope comes from them. That
refinement is a measuring device of this script, not an option of the
package: the main job's meshes do not have it.

    python benchmarks/mesh_ladder.py                          # 14 11 9 8 7 6 mm
    python benchmarks/mesh_ladder.py --sizes 14 9 6 --root-size 1.5
    python benchmarks/mesh_ladder.py --report                 # table and chart only

Runs are cached in results/mesh_ladder/runs.json (one entry per size and
root size); the chart is results/mesh_ladder/mesh_ladder.png. Each screen
runs in this process (UPD_WORKERS=1) in a scratch folder that is removed
afterwards (the root refinement is not in the package's cache keys).
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
os.environ["UPD_WORKERS"] = "1"  # in this process: the root refinement below must apply

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

OUT = ROOT / "results" / "mesh_ladder"
STUDY = ROOT / "studies" / "paper_rig.toml"
GEOMETRY = ROOT / "geometry" / "paper_rig_pads.toml"
SIZES = [14.0, 11.0, 9.0, 8.0, 7.0, 6.0]
ROOT_GROWTH_MM = 15.0  # distance over which the root size grows back to the global size


def _refine_roots(root_size: float):
    """Wrap the builders' size field so the rig's blade-root edges get ``root_size`` mm."""
    import workbench.geometry.occ as occ

    original = occ.size_field

    def size_field(gmsh, point_tags, h_min, h_max, dist):
        original(gmsh, point_tags, h_min, h_max, dist)
        if gmsh.model.getCurrent() != "rig":
            return
        tol = 1e-6
        boxes = {v: gmsh.model.getBoundingBox(3, v) for _, v in gmsh.model.getEntities(3)}
        base = min(boxes, key=lambda v: boxes[v][2] + boxes[v][5])  # the lowest volume
        z_top = boxes[base][5]
        roots = []
        for _, c in gmsh.model.getEntities(1):
            x0, y0, z0, x1, y1, z1 = gmsh.model.getBoundingBox(1, c)
            if abs(z0 - z_top) > tol or abs(z1 - z_top) > tol:
                continue
            if any(
                x0 >= b[0] - tol and x1 <= b[3] + tol and y0 >= b[1] - tol and y1 <= b[4] + tol
                for v, b in boxes.items()
                if v != base
            ):
                roots.append(c)  # an edge of a blade's footprint on the base
        if len(roots) != 8:
            raise RuntimeError(f"expected the 8 blade-root edges, found {len(roots)}")
        f = gmsh.model.mesh.field
        fd = f.add("Distance")
        contact = fd - 1  # the contact points' Threshold, the last field the builder added
        f.setNumbers(fd, "CurvesList", roots)
        f.setNumber(fd, "NumPointsPerCurve", 200)
        ft = f.add("Threshold")
        f.setNumber(ft, "InField", fd)
        f.setNumber(ft, "SizeMin", root_size)
        f.setNumber(ft, "SizeMax", h_max)
        f.setNumber(ft, "DistMin", root_size)
        f.setNumber(ft, "DistMax", ROOT_GROWTH_MM)
        fm = f.add("Min")
        f.setNumbers(fm, "FieldsList", [contact, ft])
        f.setAsBackgroundMesh(fm)

    occ.size_field = size_field
    return original


def run_one(size: float, root_size: float) -> dict:
    """One screen of the cone at global ``size`` mm (``root_size`` 0: roots not refined)."""
    import workbench.geometry.occ as occ
    from workbench.cli.main import main as upd

    original = _refine_roots(root_size) if root_size > 0 else None
    scratch = Path(tempfile.mkdtemp(prefix="mesh_ladder_"))
    t0 = time.perf_counter()
    try:
        buf = io.StringIO()
        argv = ["screen", str(STUDY), "--geometry", str(GEOMETRY), "--mesh-size", f"{size:g}"]
        argv += ["--dampers", "cone", "--json", "--out", str(scratch), "-q"]
        with contextlib.redirect_stdout(buf):
            rc = upd(argv)
        if rc:
            raise RuntimeError(f"upd screen failed ({rc}) at {size} mm, root {root_size} mm")
        rows = json.loads(buf.getvalue())["rows"]
    finally:
        if original is not None:
            occ.size_field = original
        shutil.rmtree(scratch, ignore_errors=True)
    out = {"size_mm": size, "root_mm": root_size, "seconds": time.perf_counter() - t0}
    for r in rows:
        fam = "in phase" if r["phase_deg"] == 0.0 else "out of phase"
        out[f"{fam} stuck"] = r["f_stuck_hz"]
        out[f"{fam} sliding"] = r["f_slide_hz"]
    return out


def _ladders(runs: list[dict]) -> dict[tuple[float, str], list[tuple[float, float]]]:
    lad: dict[tuple[float, str], list[tuple[float, float]]] = {}
    for r in runs:
        for k, v in r.items():
            if k.endswith(("stuck", "sliding")):
                lad.setdefault((r["root_mm"], k), []).append((r["size_mm"], v))
    return {k: sorted(v) for k, v in lad.items()}


def best_fit(h, q) -> tuple[float, float, float]:
    """q = q0 + c (h / h_min)^p by least squares, p scanned over 0.3..4: (p, q0, c)."""
    import numpy as np

    h, q = np.asarray(h, float), np.asarray(q, float)
    x = h / h.min()
    best = None
    for p in np.linspace(0.3, 4.0, 371):
        A = np.column_stack([np.ones_like(x), x**p])
        c, *_ = np.linalg.lstsq(A, q, rcond=None)
        rss = float(np.sum((A @ c - q) ** 2))
        if best is None or rss < best[0]:
            best = (rss, float(p), float(c[0]), float(c[1]))
    return best[1], best[2], best[3]


def report(runs: list[dict]) -> str:
    """A table per ladder: the levels, the best free order, the fits' limits."""
    import numpy as np

    from workbench.post.extrapolation import least_squares, richardson

    lines = []
    for (root, what), pts in sorted(_ladders(runs).items()):
        h = np.array([a for a, _ in pts])
        q = np.array([b for _, b in pts])
        tag = f"roots {root:g} mm" if root else "roots not refined"
        lines.append(f"{what}, {tag}: " + ", ".join(f"{a:g} mm {b:.2f}" for a, b in pts))
        if len(pts) >= 4:
            p, q0, _ = best_fit(h, q)
            at9 = dict(pts).get(9.0)
            e9 = f"; 9 mm is {100 * (at9 - q0) / q0:+.2f} % off" if at9 else ""
            lines.append(f"  best free order {p:.2f}, limit {q0:.2f} Hz{e9}")
            ls = least_squares(h, q)
            if ls is not None:
                lines.append(f"  least squares: {ls.value:.2f} +- {ls.uncertainty:.2f} Hz")
        if len(pts) >= 3:
            est = richardson(h, q)
            lines.append(f"  package rule: {est.method}, {est.value:.2f} Hz, {est.reason or ''}")
    return "\n".join(lines)


def chart(runs: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharex=True)
    for ax, what in zip(axes, ("in phase stuck", "in phase sliding"), strict=True):
        for (root, w), pts in sorted(_ladders(runs).items()):
            if w != what:
                continue
            label = f"blade roots refined to {root:g} mm" if root else "roots at the global size"
            h, q = [a for a, _ in pts], [b for _, b in pts]
            (line,) = ax.plot(h, q, "o-" if not root else "s--", label=label)
            if len(pts) >= 4:  # the best power law, drawn down to h = 0: where the ladder goes
                p, q0, c = best_fit(h, q)
                hh = np.linspace(0.0, max(h), 100)
                ax.plot(hh, q0 + c * (hh / min(h)) ** p, ":", color=line.get_color(), lw=1)
                ax.plot([0.0], [q0], "x", color=line.get_color(), ms=8,
                        label=f"  its limit {q0:.1f} Hz (order {p:.2f})")  # fmt: skip
        ax.set_title(f"cone, {what} (pad rig, linear)")
        ax.set_xlabel("global mesh size h (mm)")
        ax.set_ylabel("frequency (Hz)")
        ax.set_xlim(left=-0.5)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(
        "The global mesh ladder falls slowly with h; refining the blade roots' sharp edges "
        "removes much of the slope, not all"
    )
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=float, nargs="*", default=SIZES, help="global sizes, mm")
    ap.add_argument("--root-size", type=float, default=0.0, help="blade-root size, mm (0: off)")
    ap.add_argument("--report", action="store_true", help="table and chart from the cache only")
    a = ap.parse_args(argv)
    if a.root_size < 0:
        ap.error(f"--root-size = {a.root_size} is not allowed: 0 (off) or a size > 0 mm")
    if any(s <= 0 for s in a.sizes):
        ap.error(f"--sizes = {a.sizes} is not allowed: every size must be > 0 mm")
    cache = OUT / "runs.json"
    runs: list[dict] = json.loads(cache.read_text()) if cache.exists() else []
    if not a.report:
        for i, size in enumerate(a.sizes, 1):
            if any(r["size_mm"] == size and r["root_mm"] == a.root_size for r in runs):
                print(f"[{i}/{len(a.sizes)}] {size:g} mm, root {a.root_size:g}: cached")
                continue
            r = run_one(size, a.root_size)
            runs.append(r)
            OUT.mkdir(parents=True, exist_ok=True)
            cache.write_text(json.dumps(runs, indent=1))
            print(f"[{i}/{len(a.sizes)}] {size:g} mm, root {a.root_size:g}: {r['seconds']:.0f} s")
    if not runs:
        print("no runs cached yet")
        return 1
    print(report(runs))
    chart(runs, OUT / "mesh_ladder.png")
    print(f"chart: {OUT / 'mesh_ladder.png'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
