"""Nonlinear modes of a study's dampers: one backbone per damper and family, the forced
responses synthesised from it at every force, and their check against the full HBM.

For every model of a study (damper x swept value) and every phase (family),
:func:`study_backbones` follows the stuck mode that the family's excitation
drives most in its band (:func:`workbench.hbm.nlmodes.backbone.pick_mode`) with the
extended periodic motion concept, on the same reduced model, contact law,
harmonics and AFT samples as the study's cases. Each backbone is cached in
``out/cache/nlmodes/<key>.h5`` (with the excitation in ``<key>.npz``), so a
second run costs nothing. Then, per force, the single-nonlinear-mode
synthesis gives the peak; where the study has computed that case (its file
in ``out/cache/cases``), the peak of the full HBM curve and its compute
time are put beside it.

:func:`nlmode_sections` turns the rows into report sections: the
backbones (frequency, damping ratio, friction energy, contact status
against amplitude), the synthesised curves over the HBM curves, the peak
errors and the time saved, per damper and family. Figures go to
``figures/nlmodes/`` and tables to ``tables/nlmodes/`` (their own folders,
so the comparison report's own clean-up and "other figures" never see
them).
"""

from __future__ import annotations

import logging
import time
from pathlib import Path
from typing import Any

import numpy as np

from ...io import digest
from .plan import Case, plan
from .spec import StudySpec

log = logging.getLogger(__name__)

SUB = "nlmodes"


def backbone_key(case: Case, relative_range: tuple[float, float], n_steps: int, forces=None) -> str:
    """Cache key of one backbone: the model, the family, the balance settings, the code."""
    from ...io import code_version

    root = Path(__file__).resolve().parents[2]  # workbench/
    s = case.settings
    return digest(
        {
            "model": case.model_digest,
            "phase": float(case.phase_deg),
            "harmonics": list(s["harmonics"]),
            "nt": s["nt"],
            "blade": s["response-blade"],
            "band": [s["band-in-phase"], s["band-out-of-phase"], s["band-margin"]],
            "range": list(relative_range),
            "steps": int(n_steps),
            "top_force": max(forces) if forces else None,
            "code": [
                code_version(root / "hbm"),
                code_version(root / "io", ("record.py",)),
                code_version(root / "contact"),
                code_version(root / "assembly"),
            ],
        },
        16,
    )


def family_backbone(
    prep,
    case: Case,
    relative_range: tuple[float, float] = (0.05, 300.0),
    n_steps: int = 40,
    forces=None,
):
    """The backbone of ``case``'s family on a prepared model, with its excitation and band."""
    from ...hbm.nlmodes.backbone import nonlinear_mode, pick_mode
    from ...pipeline import band_for

    s = case.settings
    band = band_for(prep, case)
    model = prep.assembled
    f1 = model.excitation(case.phase_deg)
    mode = pick_mode(prep.system, f1, band)
    blade = s["response-blade"]
    nm = nonlinear_mode(
        prep.system,
        mode=mode,
        relative_range=relative_range,
        harmonics=tuple(s["harmonics"]),
        nt=s["nt"],
        outputs=model.response_dofs[blade - 1 : blade],
        output_names=(f"blade{blade}_x",),
        n_steps=n_steps,
        f1=f1,
        levels=forces,
        max_fold_points=20,  # beyond a fold the
        label=f"{case.damper} {case.phase_deg:g} deg",
    )  # synthesis is flagged anyway
    return nm, f1, band


def study_backbones(
    spec: StudySpec,
    out: str | Path,
    *,
    prepared: dict | None = None,
    cases: list[Case] | None = None,
    relative_range=(0.05, 300.0),
    n_steps: int = 40,
    force: bool = False,
    comm=None,
) -> dict[str, Any]:
    """Backbones of every model and family of ``spec``, syntheses at its forces, HBM checks.

    Returns ``{"rows": [...], "backbones": [...], "timings": {...}}``: one
    row per case (damper, variant, family, force; synthesised peak and its
    validity; the HBM peak, error and time when the case is computed), one
    entry per backbone (label, cache file, compute time, summary). Models
    not in ``prepared`` are prepared from the study's FE cache. Rank 0 only
    under MPI (the others return empty results).
    """
    from ...hbm.nlmodes.record import NlModeBranch
    from ...hbm.nlmodes.synthesis import synthesize
    from ...pipeline import prepare_model
    from ...post.results import CaseResult, family_name

    out = Path(out)
    cases = plan(spec) if cases is None else cases
    prepared = dict(prepared or {})
    groups: dict[tuple[str, float], list[Case]] = {}
    for c in cases:
        groups.setdefault((c.model_digest, float(c.phase_deg)), []).append(c)
    ndir = out / "cache" / SUB

    def files(cs: list[Case]) -> tuple[Path, Path, bool]:
        """The backbone's cache files and whether it is to be read from them."""
        key = backbone_key(cs[0], relative_range, n_steps, [c.force_n for c in cs])
        h5, npz = ndir / f"{key}.h5", ndir / f"{key}.npz"
        return h5, npz, h5.is_file() and npz.is_file() and not force

    if comm is not None and comm.size > 1:
        # the backbones run on rank 0, but loading (or building) a model is collective:
        # every rank prepares the models the curves did not (all cases cached), together
        for (md, _ph), cs in groups.items():
            if md not in prepared and not files(cs)[2]:
                prepared[md] = prepare_model(cs[0], out, comm=comm)
    ndir.mkdir(parents=True, exist_ok=True)

    def label_of(c0: Case) -> str:
        return f"{c0.damper}, {family_name(c0.phase_deg)}" + (
            f" [{c0.variant}]" if c0.variant else ""
        )

    def compute(md: str, cs: list[Case]) -> dict[str, Any]:
        """One backbone, computed and written to its cache files."""
        c0 = cs[0]
        h5, npz, _ = files(cs)
        t0 = time.perf_counter()
        log.info("backbone %s: computing", label_of(c0))
        if md not in prepared:
            prepared[md] = prepare_model(c0, out)
        nm, f1, band = family_backbone(
            prepared[md], c0, relative_range, n_steps, forces=[c.force_n for c in cs]
        )
        nm.timings["wall"] = time.perf_counter() - t0
        nm.save(h5)
        from ...io import atomic_path

        with atomic_path(npz) as tmp, open(tmp, "wb") as fh:
            np.savez(fh, f1=f1, band=np.asarray(band, float))
        log.info(
            "backbone %s: %d points, %.1f s (%s)",
            label_of(c0),
            nm.n_points,
            nm.timings["total"],
            nm.message,
        )
        return {"backbone": label_of(c0)}

    # the backbones still to compute, handed out to the ranks (the largest models first)
    todo = [(md, cs) for (md, _ph), cs in groups.items() if not files(cs)[2]]
    if comm is not None and comm.size > 1 and todo:
        from .schedule import run_tasks

        todo.sort(key=lambda t: -getattr(getattr(prepared.get(t[0]), "assembled", None),
                                         "n_pairs", 0))  # fmt: skip
        run_tasks(len(todo), lambda k: compute(*todo[k]), comm, desc="backbones")
    if comm is not None and comm.rank != 0:
        return {"rows": [], "backbones": [], "timings": {}}
    rows: list[dict[str, Any]] = []
    backbones: list[dict[str, Any]] = []
    timings: dict[str, float] = {}
    for (md, _ph), cs in groups.items():
        c0 = cs[0]
        h5, npz, cached = files(cs)
        label = label_of(c0)
        if not cached:
            compute(md, cs)
        nm = NlModeBranch.load(h5)
        with np.load(npz) as z:
            f1, band = z["f1"], tuple(float(v) for v in z["band"])
        t_nm = float(nm.timings.get("total", 0.0))
        timings[label] = t_nm
        backbones.append(
            {
                "label": label,
                "damper": c0.damper,
                "variant": c0.variant,
                "phase_deg": c0.phase_deg,
                "family": family_name(c0.phase_deg),
                "file": str(h5.relative_to(out)),
                "seconds": t_nm,
                "band_hz": list(band),
                **nm.summary(),
            }
        )
        for c in cs:
            t0 = time.perf_counter()
            syn = synthesize(nm, f1, c.force_n, 0, band) if nm.n_points >= 2 else None
            t_syn = time.perf_counter() - t0
            row: dict[str, Any] = {
                "label": label,
                "damper": c.damper,
                "variant": c.variant,
                "family": family_name(c.phase_deg),
                "phase_deg": c.phase_deg,
                "force_n": c.force_n,
                "case_digest": c.digest,
                "syn_peak_frequency_hz": syn.peak_freq_hz if syn else None,
                "syn_peak_amplitude_mm": syn.peak_amplitude * 1e3 if syn else None,
                "valid": bool(syn.valid) if syn else False,
                "reasons": "; ".join(syn.reasons) if syn else "no backbone",
                "syn_seconds": t_syn,
                "hbm_peak_frequency_hz": None,
                "hbm_peak_amplitude_mm": None,
                "hbm_seconds": None,
                "error_pct": None,
                "freq_error_pct": None,
                # harmonic 1 alone: the vibration without the mean term (the peak above is
                # max|x| over the period, which includes it)
                "syn_h1_mm": syn.peak_h1 * 1e3 if syn else None,
                "hbm_h1_mm": None,
                "h1_error_pct": None,
            }
            cfile = out / "cache" / "cases" / f"{c.digest}.h5"
            if cfile.is_file():
                cr = CaseResult.load(cfile)
                i = cr.peak_index
                if i >= 0:
                    row["hbm_peak_frequency_hz"] = float(cr.freq_hz[i])
                    row["hbm_peak_amplitude_mm"] = float(cr.amp_mm[i])
                    row["hbm_seconds"] = float(
                        cr.timings.get("hbm", cr.branch.timings.get("total", 0.0))
                    )
                    row["hbm_h1_mm"] = float(cr.h1_mm[cr.h1_peak_index])
                    if syn:
                        row["h1_error_pct"] = 100 * (row["syn_h1_mm"] / row["hbm_h1_mm"] - 1)
                        row["error_pct"] = 100 * (
                            syn.peak_amplitude * 1e3 / row["hbm_peak_amplitude_mm"] - 1
                        )
                        row["freq_error_pct"] = 100 * (
                            syn.peak_freq_hz / row["hbm_peak_frequency_hz"] - 1
                        )
            rows.append(row)
    return {"rows": rows, "backbones": backbones, "timings": timings}


def cost_rows(res: dict[str, Any]) -> list[dict[str, Any]]:
    """Per damper and family: backbone time, HBM time of its computed curves, worst errors."""
    out = []
    for bb in res["backbones"]:
        rs = [r for r in res["rows"] if r["label"] == bb["label"]]
        done = [r for r in rs if r["hbm_seconds"] is not None]
        t_h = sum(r["hbm_seconds"] for r in done)
        t_n = bb["seconds"] + sum(r["syn_seconds"] for r in rs)
        ev = [abs(r["error_pct"]) for r in done if r["valid"] and r["error_pct"] is not None]
        ea = [abs(r["error_pct"]) for r in done if r["error_pct"] is not None]
        e1 = [abs(r["h1_error_pct"]) for r in done if r["valid"] and r["h1_error_pct"] is not None]
        out.append(
            {
                "label": bb["label"],
                "n_forces": len(rs),
                "n_hbm": len(done),
                "n_valid": sum(1 for r in rs if r["valid"]),
                "backbone_s": round(t_n, 3),
                "hbm_s": round(t_h, 3),
                "time_ratio": round(t_n / t_h, 4) if t_h > 0 else None,
                "max_error_valid_pct": round(max(ev), 3) if ev else None,
                "max_error_all_pct": round(max(ea), 3) if ea else None,
                "max_h1_error_valid_pct": round(max(e1), 3) if e1 else None,
                "damping_max": bb.get("damping_max"),
                "f_stuck_hz": bb.get("f_stuck_hz"),
                "freq_last_hz": bb.get("freq_last_hz"),
                "message": bb.get("message", ""),
            }
        )
    return out


def nlmode_sections(res: dict[str, Any], out: str | Path) -> list[dict]:
    """Report sections for the backbones and the synthesis check (figures, tables, text)."""
    from ...hbm.nlmodes.record import NlModeBranch
    from ...io.csv_rows import write_rows_csv
    from ...post.results import CaseResult
    from ...render.nlmode_figures import plot_backbones, plot_synthesis, plot_synthesis_errors

    out = Path(out)
    if not res or not res.get("backbones"):
        return []
    fdir, tdir = out / "figures" / SUB, out / "tables" / SUB
    fdir.mkdir(parents=True, exist_ok=True)
    tdir.mkdir(parents=True, exist_ok=True)
    bbs = {b["label"]: NlModeBranch.load(out / b["file"]) for b in res["backbones"]}
    sec_bb: dict[str, Any] = {
        "id": "nlmodes",
        "title": "Nonlinear modes: backbones (extended periodic motion)",
        "text": [
            "Each damper's family mode followed in modal amplitude with a negative "
            "mass-proportional damping -xi M q' that makes its free motion periodic (Krack "
            "2015), on the same reduced model, contact law, harmonics and AFT as the forced "
            "responses. The modal damping ratio D = xi / (2 w) includes the assembly's own "
            "viscous damping (D equals it while every pair sticks). Where D peaks the damper "
            "works best; where the frequency has dropped to its sliding value the damper no "
            "longer carries load. Horizontal axis: the response-blade amplitude of the mode "
            "at that modal amplitude."
        ],
        "figures": [],
        "tables": [],
    }
    families = list(dict.fromkeys(b["family"] for b in res["backbones"]))
    for fam in families:
        pairs = [
            (b["damper"] + (f" [{b['variant']}]" if b["variant"] else ""), bbs[b["label"]])
            for b in res["backbones"]
            if b["family"] == fam
        ]
        name = f"backbone_{fam.replace(' ', '_')}"
        plot_backbones(
            pairs, fdir / f"{name}.png", unit_scale=1e3, unit="mm", title=f"nonlinear modes, {fam}"
        )
        sec_bb["figures"].append(
            {
                "path": f"figures/{SUB}/{name}.png",
                "caption": (
                    f"{fam}: frequency, modal damping ratio, friction energy per cycle and (first "
                    "damper) share of contact pairs in each status against the response amplitude."
                ),
            }
        )
    bb_rows = [
        {
            k: b.get(k)
            for k in (
                "label",
                "f_stuck_hz",
                "freq_last_hz",
                "damping_first",
                "damping_max",
                "freq_at_damping_max_hz",
                "mac_min",
                "n_points",
                "seconds",
                "completed",
                "message",
            )
        }
        for b in res["backbones"]
    ]
    write_rows_csv(tdir / "backbones.csv", bb_rows)
    sec_bb["tables"].append(
        {
            "path": f"tables/{SUB}/backbones.csv",
            "caption": (
                "Backbones: stuck and last frequency, damping ratio at the start and its maximum "
                "(and where), smallest MAC against the low-amplitude shape, cost"
            ),
        }
    )
    sec_syn: dict[str, Any] = {
        "id": "nlmodes-synthesis",
        "title": "Forced responses from the nonlinear modes against the full HBM",
        "text": [
            "Single-nonlinear-mode synthesis: at each force the forced response follows from "
            "the backbone (a[(w^2 - W^2)^2 + (xi w + c (W - w))^2]^(1/2) = |psi^H f|, friction "
            "share of the damping rate independent, viscous share c proportional to W) in "
            "microseconds. It is checked automatically at its peak: the shape against the "
            "low-amplitude one (MAC >= 0.9), no other linear mode within 5 % of the "
            "frequency, a backbone that does not fold back in amplitude (modal interaction), "
            "the other modes adding less than 1 % to the peak (their stuck linear response), "
            "higher harmonics below 20 %, damping ratio below 0.15. Where it is flagged not "
            "valid the full HBM is the answer."
        ],
        "figures": [],
        "tables": [],
    }
    rows = res["rows"]
    for b in res["backbones"]:
        rs = [r for r in rows if r["label"] == b["label"]]
        nm = bbs[b["label"]]
        from ...hbm.nlmodes.synthesis import synthesize

        with np.load(out / b["file"].replace(".h5", ".npz")) as z:
            f1, band = z["f1"], tuple(float(v) for v in z["band"])
        if nm.n_points < 2:
            continue
        syns = [synthesize(nm, f1, r["force_n"], 0, band) for r in rs]
        hbm = []
        for r in rs:
            cfile = out / "cache" / "cases" / f"{r['case_digest']}.h5"
            hbm.append(CaseResult.load(cfile).branch if cfile.is_file() else None)
        name = "synthesis_" + b["label"].replace(", ", "_").replace(" ", "_").replace(
            "[", ""
        ).replace("]", "").replace("=", "")
        plot_synthesis(
            nm,
            syns,
            fdir / f"{name}.png",
            hbm=hbm,
            unit_scale=1e3,
            unit="mm",
            band_hz=band,
            title=f"{b['label']}: synthesis (solid) and full HBM",
            level_unit="N",
        )
        sec_syn["figures"].append(
            {
                "path": f"figures/{SUB}/{name}.png",
                "caption": (
                    f"{b['label']}: forced responses from the nonlinear mode (solid; dotted where "
                    "flagged not valid), the full HBM curves (dashed) and the backbone (black)."
                ),
            }
        )
    if any(r["error_pct"] is not None for r in rows):
        plot_synthesis_errors(rows, fdir / "synthesis_errors.png")
        sec_syn["figures"].append(
            {
                "path": f"figures/{SUB}/synthesis_errors.png",
                "caption": (
                    "Peak amplitude error of the synthesis against the full HBM "
                    "per force (o: valid, "
                    "x: flagged not valid); the dashed line is 2 %."
                ),
            }
        )
    cols = (
        "label",
        "force_n",
        "hbm_peak_amplitude_mm",
        "syn_peak_amplitude_mm",
        "error_pct",
        "hbm_peak_frequency_hz",
        "syn_peak_frequency_hz",
        "freq_error_pct",
        "hbm_h1_mm",
        "syn_h1_mm",
        "h1_error_pct",
        "valid",
        "reasons",
        "hbm_seconds",
    )
    write_rows_csv(tdir / "synthesis.csv", [{k: r.get(k) for k in cols} for r in rows])
    sec_syn["tables"].append(
        {
            "path": f"tables/{SUB}/synthesis.csv",
            "caption": ("Every force: HBM and synthesised peak, error, validity and why not"),
        }
    )
    cost = cost_rows(res)
    write_rows_csv(tdir / "cost.csv", cost)
    sec_syn["tables"].append(
        {
            "path": f"tables/{SUB}/cost.csv",
            "caption": (
                "Per damper and family: time of the backbone and its syntheses against "
                "the full HBM curves it replaces, worst peak error where valid and overall"
            ),
        }
    )
    tot_n = sum(c["backbone_s"] for c in cost)
    tot_h = sum(c["hbm_s"] for c in cost)
    if tot_h > 0:
        ev = [c["max_error_valid_pct"] for c in cost if c["max_error_valid_pct"] is not None]
        e1 = [c["max_h1_error_valid_pct"] for c in cost if c["max_h1_error_valid_pct"] is not None]
        sec_syn["text"].append(
            f"{len(cost)} backbones took {tot_n:.1f} s against {tot_h:.1f} s for the "
            f"{sum(c['n_hbm'] for c in cost)} full HBM curves (ratio {tot_n / tot_h:.3f}); "
            + (
                f"worst peak error where valid {max(ev):.2f} % in max|x|"
                + (f", {max(e1):.2f} % in the harmonic-1 amplitude" if e1 else "")
                + "."
                if ev
                else "no synthesis is flagged valid."
            )
        )
    return [sec_bb, sec_syn]


def fidelity_entry(comp, base, ref, out: str | Path):
    """The fidelity ladder's "nonlinear-mode synthesis" entry (a ``fidelity.Setting``).

    The base setting's model; one backbone per phase of the conditions
    (cached like :func:`study_backbones`); each condition's peak amplitude,
    resonance frequency and friction energy per cycle at the peak from the
    single-nonlinear-mode synthesis, compared with the reference setting.
    Time: the base setting's geometry, reduction and assembly, plus the
    backbones and syntheses (charged as its "hbm" stage). A synthesis that
    flags itself not valid keeps its errors (the chart shows what it costs
    to trust it anyway) and says so in ``failed``-free ``members``.
    """
    from ...hbm.nlmodes.record import NlModeBranch
    from ...hbm.nlmodes.synthesis import synthesize
    from ...pipeline import prepare_model
    from ...post.fidelity import QUANTITIES, Setting

    out = Path(out)
    st = Setting("nonlinear-mode synthesis", dict(base.values), "nlmode")
    st.members.append(("method", "nonlinear-mode synthesis"))
    st.times = {k: float(v) for k, v in base.times.items()}
    st.times["hbm"] = 0.0
    cases = comp.cases(base)
    ndir = out / "cache" / SUB
    ndir.mkdir(parents=True, exist_ok=True)
    by_phase: dict[float, tuple] = {}
    prep = None
    invalid: list[str] = []
    forces = [f for _, _, f in comp.conditions]
    for (_, p, f), c, cond in zip(comp.conditions, cases, comp.names, strict=True):
        if p not in by_phase:
            key = backbone_key(c, (0.05, 300.0), 40, forces)
            h5, npz = ndir / f"{key}.h5", ndir / f"{key}.npz"
            if h5.is_file() and npz.is_file():
                nm = NlModeBranch.load(h5)
                with np.load(npz) as z:
                    f1, band = z["f1"], tuple(float(v) for v in z["band"])
            else:
                if prep is None:
                    prep = prepare_model(c, out)
                nm, f1, band = family_backbone(prep, c, forces=forces)
                nm.save(h5)
                from ...io import atomic_path

                with atomic_path(npz) as tmp, open(tmp, "wb") as fh:
                    np.savez(fh, f1=f1, band=np.asarray(band, float))
            st.times["hbm"] += float(nm.timings.get("total", 0.0))
            by_phase[p] = (nm, f1, band)
        nm, f1, band = by_phase[p]
        rr = ref.results.get(cond)
        sr = rr.summary() if rr is not None and not rr.branch.failed else {}
        t0 = time.perf_counter()
        s = synthesize(nm, f1, f, 0, band) if nm.n_points >= 2 else None
        st.times["hbm"] += time.perf_counter() - t0
        if s is None:
            st.errors[cond] = {q: None for q, _, _ in QUANTITIES}
            continue
        if not s.valid:
            invalid.append(f"{cond}: {'; '.join(s.reasons)}")
        k = int(np.clip(np.searchsorted(nm.amplitude, s.peak_modal_amplitude), 1, nm.n_points - 1))
        e_pk = (
            float(
                np.interp(
                    s.peak_modal_amplitude,
                    nm.amplitude[k - 1 : k + 1],
                    nm.friction_energy[k - 1 : k + 1].sum(axis=1),
                )
            )
            * 1e3
        )
        mine = {
            "peak_amplitude_mm": s.peak_amplitude * 1e3,
            "peak_frequency_hz": s.peak_freq_hz,
            "friction_energy_mj": e_pk,
        }
        st.errors[cond] = {
            q: (abs(mine[q] - sr[q]) / abs(sr[q]) * 100.0 if sr.get(q) not in (None, 0) else None)
            for q, _, _ in QUANTITIES
        }
    if invalid:
        st.members.append(("not valid", "; ".join(invalid)))
    return st
