"""Does the mesh's asymmetry scatter the cone's ladders? The pad fidelity study's cone
cases on mirror-image meshes (issue 31).

The rig, the damper and the contact points are symmetric about the plane between the
blades, and so is the loading of each family (in phase: the mirror image of the motion is
the motion half a period later; out of phase: the motion itself), so each of the
damper's two contact lines should dissipate half the friction energy. On the pad
study's meshes (`studies/fidelity_paper_rig_pads.toml`, gmsh meshing each body whole)
the cone's in-phase split between the lines reaches 40 % of the total (rms 14 % over the
study's 23 settings at 30 N), and the two settings whose split exceeds 30 % are the
points ladder's outliers. This script runs the same study, restricted to the cone (in
and out of phase, 9.6 and 30 N; knobs mesh size, contact mesh size, points per line),
twice: on whole meshes (`[rig.mesh] mirror = false`) and with `[rig.mesh] mirror = true`
(the half x >= 0 of each body meshed and mirrored: `workbench/geometry/mirror.py`). It
prints per setting and case the energy split, the energy, the harmonic-1 peak and its
frequency on both, then each knob's limit as the package reads it (mirror | whole).

    python benchmarks/mirror_fidelity.py            # runs both (about 16 min) and reports
    python benchmarks/mirror_fidelity.py --report   # the table and chart only

The runs are results/mirror_fidelity/mirror and .../whole (the mirror variant's geometry
file is written beside them); the chart is results/mirror_fidelity/mirror_fidelity.png.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

for _k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ.setdefault(_k, "1")
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

STUDY = ROOT / "studies" / "fidelity_paper_rig_pads.toml"
PADS = ROOT / "geometry" / "paper_rig_pads.toml"
OUT = ROOT / "results" / "mirror_fidelity"
OPTIONS = {
    "dampers": ["cone"],
    "damper-phases": ["cone 0", "cone 180"],
    "knobs": ["mesh-size", "contact-mesh-size", "points-per-line"],
    "production-geometry": None,
}
VARIANTS = ("mirror", "whole")  # [rig.mesh] mirror = true / false
QS = ("friction_energy_mj", "peak_amplitude_mm", "peak_frequency_hz")


def geometry_file(out: Path, variant: str) -> Path:
    """The pad rig's geometry file with ``[rig.mesh] mirror`` set for the variant (true for
    "mirror", false for "whole"), written into ``out``."""
    from benchmarks.geometry_variant import with_mirror

    return with_mirror(
        PADS, variant == "mirror", out / f"paper_rig_pads_{variant}.toml", "mirror_fidelity.py"
    )


def _spec(out: Path, variant: str):
    from workbench.studies.engine.spec import load_study

    return load_study(STUDY, dict(OPTIONS, geometry=str(geometry_file(out, variant))))


def case_rows(out: Path, variant: str) -> list[dict]:
    """Per setting and case: the energy of each line at the harmonic-1 peak, its split
    ((line 1 - line 2) / total, %), the peak quantities the fidelity study reads."""
    from workbench.post.fidelity import setting_value
    from workbench.studies.kinds.fidelity.compute import _Computer
    from workbench.studies.kinds.fidelity.ladders import plan_settings

    spec = _spec(out, variant)
    comp = _Computer(spec, out / variant, False)
    settings, _ = plan_settings(spec, comp.dampers)
    if comp.todo(settings):  # not run, or run by code whose case keys differ from this one's
        raise SystemExit(
            f"{out / variant} has no complete run for this code: run "
            "benchmarks/mirror_fidelity.py without --report (it reuses what still matches)"
        )
    rows = []
    for st in settings:
        comp.load(st)
        for cond, r in st.results.items():
            i = r.h1_peak_index
            if i < 0 or r.branch.failed:
                continue
            e = r.energy_mj[i]
            e0, e1 = float(e[r.side == 0].sum()), float(e[r.side == 1].sum())
            split = (e0 - e1) / (e0 + e1) * 100 if e0 + e1 > 1e-9 else None
            row = {"setting": st.label, "case": f"cone {cond}", "E_line1": e0, "E_line2": e1,
                   "split_pct": split}  # fmt: skip
            row.update({q: setting_value(st, cond, q) for q in QS})
            rows.append(row)
    return rows


def run(out: Path, variant: str) -> float:
    from workbench.studies.kinds.fidelity.compute import run_fidelity

    t0 = time.perf_counter()
    run_fidelity(_spec(out, variant), out / variant)
    return time.perf_counter() - t0


def limits(out: Path, variant: str) -> dict:
    return json.loads((out / variant / "fidelity.json").read_text())["knob_limits"]


def report(out: Path) -> None:
    mirrored = case_rows(out, "mirror")
    whole = {(r["setting"], r["case"]): r for r in case_rows(out, "whole")}
    print(f"{'setting':30s} {'case':20s} {'split %':>15s} {'energy mJ':>17s} "
          f"{'peak max|x| mm':>17s} {'frequency Hz':>17s}   (mirror / whole)")  # fmt: skip
    for r in mirrored:
        w = whole.get((r["setting"], r["case"]), {})

        def pair(k: str, fmt: str, r=r, w=w) -> str:
            a, b = r.get(k), w.get(k)
            return " / ".join("-" if v is None else format(v, fmt) for v in (a, b))

        print(f"{r['setting'][:30]:30s} {r['case']:20s} {pair('split_pct', '+6.1f'):>15s} "
              f"{pair('friction_energy_mj', '.3f'):>17s} {pair('peak_amplitude_mm', '.4f'):>17s} "
              f"{pair('peak_frequency_hz', '.2f'):>17s}")  # fmt: skip
    for name, rows in (("mirror", mirrored), ("whole", list(whole.values()))):
        split = [abs(r["split_pct"]) for r in rows if r["split_pct"] is not None]
        print(f"largest |split|, {name} meshes: {max(split):.2g} % over {len(split)} cases")
    lm, lw = limits(out, "mirror"), limits(out, "whole")
    print("\nknob limits (mirror | whole): value +- uncertainty, method, order")
    for knob in OPTIONS["knobs"]:
        for cond in sorted(lm[knob]):
            for q in QS:
                a, b = lm[knob][cond][q], lw[knob][cond][q]

                def cell(e) -> str:
                    if not e["trusted"]:
                        return f"n.t. ({e['method']})"
                    u = e["uncertainty"] / abs(e["value"]) * 100 if e["value"] else 0.0
                    o = "" if e["order"] is None else f", p {e['order']:.2g}"
                    return f"{e['value']:.4g} +- {u:.2g} % ({e['method']}{o})"

                print(f"  {knob:18s} {cond:18s} {q:20s} {cell(a):45s} | {cell(b)}")
    _chart(out, mirrored, whole)


def _chart(out: Path, mirrored: list[dict], whole: dict) -> None:
    """Per knob (columns): the energy split between the lines, the peak and the energy
    (rows) of the cone in phase at 30 N along its ladder, mirrored and whole meshes."""
    from workbench.post.fidelity import knob_h
    from workbench.render.common import pyplot, save_figure
    from workbench.studies.kinds.fidelity.ladders import plan_settings

    _, ladders = plan_settings(_spec(out, "whole"), ["cone"])
    plt = pyplot()
    case = "cone 0 deg 30 N"
    rows = [("split_pct", "energy split between the lines, %"),
            ("peak_amplitude_mm", "peak max|x|, mm"),
            ("friction_energy_mj", "friction energy per cycle, mJ")]  # fmt: skip
    fig, axes = plt.subplots(3, 3, figsize=(13, 10), sharex="col")
    by = {(r["setting"], r["case"]): r for r in mirrored}
    for j, knob in enumerate(OPTIONS["knobs"]):
        lad = ladders[knob]
        hs = [knob_h(knob, st.values[knob]) for st in lad]
        for i, (q, ylabel) in enumerate(rows):
            ax = axes[i][j]
            for src, style, name in ((by, "o-", "mirror-symmetric meshes"),
                                     (whole, "s--", "whole meshes")):  # fmt: skip
                ys = [src.get((st.label, case), {}).get(q) for st in lad]
                ax.plot(hs, [float("nan") if y is None else y for y in ys], style, label=name)
            if q == "split_pct":
                ax.axhline(0.0, color="0.5", lw=0.8)
            ax.set_ylabel(ylabel)
            ax.grid(True, alpha=0.3)
            if i == 0:
                ax.set_title(knob, fontsize=10)
        xlabel = {"mesh-size": "global mesh size h, mm",
                  "contact-mesh-size": "element size at the contacts, mm",
                  "points-per-line": "1 / points per line (at 0.75 mm)"}  # fmt: skip
        axes[2][j].set_xlabel(xlabel[knob])
    axes[0][0].legend(fontsize=8)
    fig.suptitle("The cone in phase at 30 N (pad rig) along three ladders, on mirror-symmetric "
                 "and on whole meshes\n(each ladder's finest level is its leftmost point; a "
                 "split of 0 is what the symmetric rig and loading give)", fontsize=11)  # fmt: skip
    fig.tight_layout(rect=(0, 0, 1, 0.94))
    path = save_figure(fig, out / "mirror_fidelity.png")
    print(f"\nchart: {path}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--report", action="store_true", help="table and chart only (no run)")
    ap.add_argument("--out", type=Path, default=OUT, help="the run's folder")
    a = ap.parse_args()
    from workbench.log import setup

    setup()
    if not a.report:
        for variant in VARIANTS:
            print(f"{variant} meshes: ran in {run(a.out, variant):.0f} s")
    report(a.out)


if __name__ == "__main__":
    main()
