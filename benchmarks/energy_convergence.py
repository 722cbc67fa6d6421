"""What keeps the friction energy moving as the paper-like rig's model is refined (issue 31).

Each knob of the main job (contact points per line, the global mesh size,
the mesh size at the contact points, AFT samples nt, harmonics) is moved
alone over a ladder, the others at the main job's setting
(`studies/paper_rig.toml`: 9 mm, 12 modes, harmonics 0-3, nt 64, 23 points
per line). Three cases at 30 N, each solved near its peak: the cone in
phase, the wedge in phase, the cone out of phase. Recorded per run: the
friction energy per cycle at the harmonic-1 peak (the quantity of the
damper energy tables), the peak, its frequency, the wall time, and the
contact status of every pair. Richardson extrapolation with the observed
order (`workbench/post/extrapolation.py`) on each ladder's finest three
levels gives the limit and flags ladders that are not asymptotic.

    python benchmarks/energy_convergence.py              # every ladder (cached runs reused)
    python benchmarks/energy_convergence.py --only nt    # one ladder
    python benchmarks/energy_convergence.py --report     # tables and chart from the cache only

Runs are cached in results/energy/runs.json (one entry per setting), the
model stages under results/energy/cache as a study caches them. The chart
is written to results/energy/energy_convergence.png.
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

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

OUT = ROOT / "results" / "energy"
GEOMETRY = ROOT / "geometry" / "paper_rig.toml"
FORCE_N = 30.0
# (damper, inter-blade phase deg) and the band around its peak at 30 N (Hz)
CASES = {
    "cone in phase": ("cone", 0.0, (376.0, 392.0)),
    "wedge in phase": ("wedge", 0.0, (318.0, 336.0)),
    "cone out of phase": ("cone", 180.0, (404.0, 418.0)),
}
BASE = {
    "mesh-size": 9.0,
    "modes": 12,
    "harmonics": "0-3",
    "nt": 64,
    "points-per-line": 23,
    "contact-size": 1.5,
    "weights": "midpoint",  # the contact-point rule (equal segments, midpoints): today's only one
}
# fineness h of a level (smaller is finer), as workbench/studies/fidelity uses it
FINENESS = {
    "mesh-size": lambda v: float(v),
    "contact-size": lambda v: float(v),
    "modes": lambda v: 1.0 / v,
    "harmonics": lambda v: 1.0 / int(str(v).split("-")[-1]),
    "nt": lambda v: 1.0 / v,
    "points-per-line": lambda v: 1.0 / v,
}
LADDERS = {
    "points-per-line": [11, 17, 23, 33, 45],
    "nt": [32, 64, 128, 256],
    "harmonics": ["0-1", "0-3", "0-5", "0-7"],
    "mesh-size": [14.0, 11.0, 9.0, 7.0],
    "contact-size": [3.0, 1.5, 1.0, 0.75],
}


def _harmonics(s: str) -> list[int]:
    a, b = (int(x) for x in s.split("-"))
    return list(range(a, b + 1))


def _key(case: str, setting: dict) -> str:
    return case + " | " + ", ".join(f"{k}={setting[k]}" for k in sorted(setting))


def _geometry_file(setting: dict) -> Path:
    """The paper rig with the contact mesh size (and weight rule) of ``setting``."""
    pad = setting.get("pad", 0.0)
    if (
        setting["contact-size"] == BASE["contact-size"]
        and setting["weights"] == "midpoint"
        and not pad
    ):
        return GEOMETRY
    text = GEOMETRY.read_text()
    extra = f"\n[rig.mesh]\ncontact_size_mm = {setting['contact-size']}\n"
    if pad:
        extra += f"pad_mm = {pad}\n"
    path = OUT / (f"paper_rig_c{setting['contact-size']}" + (f"_p{pad}" if pad else "") + ".toml")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text + extra)
    return path


# The cone's contact pattern (item 4): the cone in phase at the main job's setting, one
# change at a time. name -> (model options, force N)
PATTERN = {
    "30 N (main job)": ({}, 30.0),
    "20 N": ({}, 20.0),
    "15 N": ({}, 15.0),
    "9.6 N": ({}, 9.6),
    "6 N": ({}, 6.0),
    "3.84 N": ({}, 3.84),
    "contact 4x stiffer, 30 N": ({"kt_line": 16.0e10, "kn_line": 19.6e10}, 30.0),
    "contact 4x softer, 30 N": ({"kt_line": 1.0e10, "kn_line": 1.225e10}, 30.0),
    "rigid damper, 30 N": ({"rigid_damper": True}, 30.0),
    "rigid damper, 9.6 N": ({"rigid_damper": True}, 9.6),
    "rigid damper, 6 N": ({"rigid_damper": True}, 6.0),
    "preload CF x2, 30 N": ({"cf": 27200.0}, 30.0),
}


def run_one(case: str, setting: dict, extra: dict | None = None, force_n: float = FORCE_N):
    """Solve ``case`` at ``setting``; the record of the energy table's numbers."""
    import numpy as np

    import workbench as wb

    damper, phase, band = CASES[case]
    opts = dict(
        mesh_size=setting["mesh-size"],
        modes=setting["modes"],
        geometry=str(_geometry_file(setting)),
        **(extra or {}),
    )
    if damper == "cone":
        opts["points_per_line"] = setting["points-per-line"]
    t0 = time.time()
    m = wb.model(damper, out=OUT, **opts)
    t_model = time.time() - t0
    key = "band_in_phase" if phase == 0.0 else "band_out_of_phase"
    t0 = time.time()
    if extra or force_n != FORCE_N or setting.get("pad"):  # the peak moves: a wide band
        band = (300.0, 440.0) if phase == 0.0 else (395.0, 460.0)
    c = wb.frf(
        m,
        force_n=force_n,
        phase_deg=phase,
        harmonics=_harmonics(setting["harmonics"]),
        nt=setting["nt"],
        stability=False,
        **{key: list(band)},
    )
    if not c.peak_covered:  # the peak left the band (a coarse level): the wide band
        band = (300.0, 440.0) if phase == 0.0 else (395.0, 440.0)
        c = wb.frf(
            m,
            force_n=force_n,
            phase_deg=phase,
            harmonics=_harmonics(setting["harmonics"]),
            nt=setting["nt"],
            stability=False,
            **{key: list(band)},
        )
    t_solve = time.time() - t0
    s = c.summary()
    j = c.h1_peak_index
    e_pair = c.energy_mj[j] if j >= 0 else np.zeros(0)
    status = c.branch.status[j].astype(int).tolist() if j >= 0 else []
    vertex = peak_vertex(c)
    return {
        "case": case,
        "setting": setting,
        "energy_mj": s["h1_friction_energy_mj"],
        "amp_mm": s["h1_amplitude_mm"],
        "freq_hz": s["h1_peak_frequency_hz"],
        **vertex,
        **(line_motion(m, c) if damper == "cone" else {}),
        **structure_flexibility(m),
        "peak_covered": bool(c.peak_covered),
        "message": str(c.branch.message),
        "energy_raw_mj": float(c.energy_mj[j].sum()) if j >= 0 else None,
        "n_pairs": int(m.n_pairs),
        "n_dofs": int(m.n_dofs),
        "solve_s": round(t_solve, 2),
        "model_s": round(t_model, 2),
        "energy_pair_mj": [float(x) for x in e_pair],
        "status": status,
    }


def peak_vertex(c) -> dict:
    """The peak between continuation points: a parabola through the three points around
    the harmonic-1 maximum gives its frequency and amplitude; the energy is the parabola
    through the same three points' energies, read at that frequency."""
    import numpy as np

    j = c.h1_peak_index
    if j < 1 or j >= c.branch.n_points - 1:
        return {"energy_v_mj": None, "amp_v_mm": None, "freq_v_hz": None}
    f = np.asarray(c.freq_hz[j - 1 : j + 2], float)
    a = np.asarray(c.h1_mm[j - 1 : j + 2], float)
    e = np.asarray(c.energy_mj[j - 1 : j + 2].sum(axis=1), float)
    pa = np.polyfit(f - f[1], a, 2)
    fv = -pa[1] / (2 * pa[0]) if pa[0] < 0 else 0.0
    fv = float(np.clip(fv, f[0] - f[1], f[2] - f[1]))
    pe = np.polyfit(f - f[1], e, 2)
    return {
        "energy_v_mj": float(np.polyval(pe, fv)),
        "amp_v_mm": float(np.polyval(pa, fv)),
        "freq_v_hz": float(f[1] + fv),
    }


def line_motion(m, c) -> dict:
    """Along each contact line at the peak: the harmonic-1 amplitude of the tangential
    relative displacement (um), of the normal one (um), and the stick ratio
    kt |u_t| / (mu N0) (a pair whose spring force would exceed mu N0 must slip; the
    ratio is the slip margin of a pair held stuck), with each pair's position along the
    line (mm from its large end) and its preload N0 (N)."""
    import numpy as np

    from workbench.hbm.core.balance import HarmonicBalance
    from workbench.hbm.core.fourier import Fourier
    from workbench.hbm.core.options import SolverOptions

    b, j = c.branch, c.h1_peak_index
    if j < 0:
        return {}
    prep, a = m.prepared, m.prepared.assembled
    fourier = Fourier(tuple(b.harmonics), b.nt)
    opts = SolverOptions()
    exc = a.excitation(c.phase_deg)
    hb = HarmonicBalance(
        prep.system, exc, fourier, None, c.force_n, b.space, opts.backend, opts.dc_anchor
    )
    q = hb.response(np.asarray(b.x[j]), 2 * np.pi * float(b.freq_hz[j]))
    k = np.asarray(fourier.k)
    r = int(np.flatnonzero(k == 1)[0])
    u = np.stack([a.W @ q[r], a.W @ q[r + 1]]).reshape(2, -1, 3)  # (cos/sin, pair, t1 t2 n)
    ut = np.sqrt((u[:, :, :2] ** 2).sum(axis=(0, 2)))
    un = np.sqrt((u[:, :, 2] ** 2).sum(axis=0))
    pts = np.asarray(a.contact.points, float)
    pos = np.zeros(len(pts))
    for s in (0, 1):
        on = np.flatnonzero(a.contact.side == s)
        pos[on] = np.linalg.norm(pts[on] - pts[on[0]], axis=1)
        pos[on] += 0.5 * np.linalg.norm(pts[on[1]] - pts[on[0]])
    ratio = a.kt * ut / (a.mu * a.n0)
    return {
        "ut_um": (ut * 1e6).tolist(),
        "un_um": (un * 1e6).tolist(),
        "stick_ratio": ratio.tolist(),
        "pos_mm": (pos * (1e3 if pos.max() < 1 else 1.0)).tolist(),
        "n0_n": a.n0.tolist(),
        "kt_n_per_m": a.kt.tolist(),
    }


def structure_flexibility(m) -> dict:
    """The structure's compliance at each pair in units of the pair's spring's
    (workbench/assembly/flexibility.py): ``kg_t`` (t1), ``kg_n`` per pair and their means."""
    from workbench.assembly.flexibility import pair_structure_to_spring

    kg = pair_structure_to_spring(m.prepared.assembled)
    return {
        "kg_t": kg[:, 0].tolist(),
        "kg_n": kg[:, 2].tolist(),
        "kg_t_mean": float(kg[:, 0].mean()),
        "kg_n_mean": float(kg[:, 2].mean()),
    }


def load() -> dict:
    p = OUT / "runs.json"
    return json.loads(p.read_text()) if p.is_file() else {}


def save(runs: dict) -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "runs.json").write_text(json.dumps(runs, indent=1))


def ladder_settings(knob: str) -> list[dict]:
    return [dict(BASE, **{knob: v}) for v in LADDERS[knob]]


def compute(knobs: list[str], cases: list[str]) -> dict:
    runs = load()
    for knob in knobs:
        for case in cases:
            if knob == "points-per-line" and CASES[case][0] != "cone":
                continue
            for setting in ladder_settings(knob):
                k = _key(case, setting)
                if k in runs:
                    continue
                print(f"run {k}", flush=True)
                runs[k] = r = run_one(case, setting)
                save(runs)
                print(
                    f"  E {r['energy_v_mj']} mJ  A {r['amp_v_mm']} mm  f {r['freq_v_hz']} Hz"
                    f"  solve {r['solve_s']} s  model {r['model_s']} s  {r['message']}",
                    flush=True,
                )
    return runs


def pattern(runs: dict) -> dict:
    """The cone in phase under each PATTERN variant (cached in ``runs``)."""
    for name, (extra, force) in PATTERN.items():
        k = "pattern | " + name
        if k not in runs:
            print(f"run {k}", flush=True)
            runs[k] = run_one("cone in phase", dict(BASE), extra, force)
            save(runs)
    return runs


def add_flexibility(runs: dict) -> dict:
    """structure_flexibility for cached runs that lack it (the models are cached)."""
    import workbench as wb

    for k, r in runs.items():
        if "kg_t_mean" in r or k.startswith("pattern"):
            continue
        st = r["setting"]
        damper = CASES[r["case"]][0]
        opts = dict(mesh_size=st["mesh-size"], modes=st["modes"], geometry=str(_geometry_file(st)))
        if damper == "cone":
            opts["points_per_line"] = st["points-per-line"]
        r.update(structure_flexibility(wb.model(damper, out=OUT, **opts)))
        save(runs)
    return runs


# points per line with the contact mesh size scaled so that n h stays the main job's
# 23 x 1.5 mm: the node's compliance against its spring (k g ~ 1 / (n h)) is then held,
# and only the quadrature of the line changes
SAME_KG = [(12, 2.875), (17, 2.03), (23, 1.5), (33, 1.05), (45, 0.767)]


def same_kg(runs: dict) -> dict:
    """The cone, both families, at the SAME_KG settings (cached in ``runs``)."""
    for case in ("cone in phase", "cone out of phase"):
        for n, h in SAME_KG:
            setting = dict(BASE, **{"points-per-line": n, "contact-size": h})
            k = _key(case, setting)
            if k not in runs:
                print(f"run {k}", flush=True)
                runs[k] = run_one(case, setting)
                save(runs)
    return runs


# contact pads (workbench/fe/pads.py): the contact-size ladder with every pair tied to a
# rigid pad of a fixed width, at the rig's contact stiffness (not recalibrated)
PAD_SIZES = [3.0, 1.5, 1.0, 0.75]


# the rig's contact stiffness (geometry/paper_rig.toml), scaled by --pad-scale
STIFFNESS = {
    "cone": {"kt_line": 4.0e10, "kn_line": 4.9e10},
    "wedge": {"kt_face": 7.5e11, "kn_face": 9.15e11},
}


def _pad_limits(case: str, rows: list) -> None:
    """Richardson on a pad ladder: order, limit +- U and the main job's (1.5 mm) error."""
    from workbench.post.extrapolation import richardson

    rows = [(h, r) for h, r in rows if r]
    base = dict(rows).get(BASE["contact-size"])
    for key, name in (("energy_v_mj", "E"), ("amp_v_mm", "A"), ("freq_v_hz", "f")):
        est = richardson([h for h, _ in rows], [r[key] for _, r in rows])
        line = f"  {case} {name}: "
        if est.asymptotic:
            err = 100 * (base[key] / est.value - 1)
            line += (
                f"order {est.order:.2f}, limit {est.value:.4g} +- {est.uncertainty:.2g}, "
                f"1.5 mm off by {err:+.2f} % (+- {100 * est.uncertainty / est.value:.2f} %)"
            )
        else:
            line += f"not asymptotic ({est.reason})"
        print(line)


def pads(
    runs: dict, width: float, cases: list[str], sizes: list[float], scale: float = 1.0
) -> dict:
    """The contact-size ladder with pads of ``width`` mm (cached in ``runs``), printed;
    ``scale`` multiplies the contact stiffness (the calibration with pads)."""

    def setting_of(h):
        st = dict(BASE, **{"contact-size": h, "pad": width})
        if scale != 1.0:
            st["kscale"] = scale
        return st

    for case in cases:
        damper = CASES[case][0]
        extra = {k: scale * v for k, v in STIFFNESS[damper].items()} if scale != 1.0 else None
        for h in sizes:
            setting = setting_of(h)
            k = _key(case, setting)
            if k not in runs:
                print(f"run {k}", flush=True)
                runs[k] = run_one(case, setting, extra)
                save(runs)
    print(f"\nContact size with {width:g} mm pads, stiffness x {scale:g} (E mJ / A mm / f Hz)")
    for case in cases:
        _pad_limits(case, [(h, runs.get(_key(case, setting_of(h)))) for h in sizes])
        for h in sizes:
            r = runs.get(_key(case, setting_of(h)))
            if r:
                print(
                    f"| {case} | {h:g} | {r['energy_v_mj'] or r['energy_mj']:.2f} / "
                    f"{r['amp_v_mm'] or r['amp_mm']:.4f} / {r['freq_v_hz'] or r['freq_hz']:.1f} | "
                    f"{r['kg_t_mean']:.3f} | {r['model_s']:.0f} + {r['solve_s']:.0f} s |"
                )
    return runs


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="*", default=list(LADDERS), help="ladders to run")
    ap.add_argument("--cases", nargs="*", default=list(CASES), help="cases to run")
    ap.add_argument("--report", action="store_true", help="tables and chart from the cache only")
    ap.add_argument("--same-kg", action="store_true", help="points per line at a fixed n h")
    ap.add_argument("--flex", action="store_true", help="structure flexibility of cached runs")
    ap.add_argument("--pattern", action="store_true", help="the cone's contact pattern variants")
    ap.add_argument("--pad", type=float, default=0.0, help="contact-size ladder with pads, mm")
    ap.add_argument("--pad-sizes", type=float, nargs="*", default=PAD_SIZES, help="mm")
    ap.add_argument("--pad-scale", type=float, default=1.0, help="contact stiffness factor")
    a = ap.parse_args(argv)
    runs = load() if a.report else compute(a.only, a.cases)
    if a.pattern:
        runs = pattern(runs)
    if a.same_kg:
        runs = same_kg(runs)
    if a.pad:
        runs = pads(runs, a.pad, a.cases, a.pad_sizes, a.pad_scale)
        return 0
    if a.flex:
        runs = add_flexibility(runs)
    from energy_convergence_report import pattern_table, report, same_kg_table

    report(runs, BASE, LADDERS, FINENESS, CASES, _key, OUT)
    pattern_table(runs, PATTERN)
    same_kg_table(runs, SAME_KG, BASE, _key)
    return 0


if __name__ == "__main__":
    sys.exit(main())
