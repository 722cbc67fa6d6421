"""The fidelity study's tables, charts and report sections (text only, no solving).

Writes the CSV/JSON tables and the per-knob and Pareto charts of a finished
fidelity study and returns the report's headline, timings and sections;
the study (``workbench.studies.kinds.fidelity.compute``) writes them into manifest.json
and report.html. Takes the plain :class:`~workbench.post.fidelity.Setting`
records and the study's JSON summary.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ....io import write_json
from ....io.csv_rows import write_rows_csv
from ....post.fidelity import (
    NO_LADDER,
    NOT_APPLICABLE,
    QUANTITIES,
    STAGES,
    Setting,
    ladder_self_errors,
    level_label,
    limit_uncertainty_pct,
)
from ....post.knobs import KNOBS


def write_csv(path: Path, rows: list[dict[str, Any]], cols: list[str] | None = None) -> Path:
    """The fidelity tables: four significant digits are plenty for errors and times."""
    return write_rows_csv(path, rows, cols, digits=4)


def condition_rows(settings: list[Setting]) -> list[dict[str, Any]]:
    """One row per setting and condition: values and errors."""
    rows = []
    for st in settings:
        for cond, r in st.results.items():
            s = r.refined_peak()
            row = {"label": st.label, "role": st.role, "condition": cond, "failed": r.branch.failed}
            for q, _, _ in QUANTITIES:
                row[q] = s.get(q)
                row[f"err_{q}_pct"] = st.errors.get(cond, {}).get(q)
                row[f"err_lim_{q}_pct"] = st.limit_errors.get(cond, {}).get(q)
            row["hbm_s"] = round(float(r.timings.get("hbm", 0.0)), 3)
            rows.append(row)
    return rows


def fidelity_outputs(
    out: Path,
    settings: list[Setting],
    ladders: dict[str, list[Setting]],
    ref: Setting,
    front: list[Setting],
    summary: dict[str, Any],
    conditions: list[str],
    tolerance: float | None,
    wall_s: float = 0.0,
    production: Setting | None = None,
) -> tuple[list[str], dict[str, float], list[dict[str, Any]]]:
    """Write the tables (CSV, JSON) and charts; return the report's (head, timings, sections)."""
    from .figures import plot_knob, plot_pareto

    tables, figs = out / "tables", out / "figures"
    rows = summary["settings"]
    cols = [
        "label",
        "role",
        *KNOBS,
        "geometry_s",
        "reduction_s",
        "assembly_s",
        "hbm_s",
        "time_s",
        "err_peak_amplitude_mm_pct",
        "err_peak_frequency_hz_pct",
        "err_friction_energy_mj_pct",
        "max_error_pct",
        "err_lim_peak_amplitude_mm_pct",
        "err_lim_peak_frequency_hz_pct",
        "err_lim_friction_energy_mj_pct",
        "max_error_vs_limit_pct",
        "on_front",
        "failed",
    ]
    write_csv(tables / "fidelity_settings.csv", rows, cols)
    write_csv(tables / "fidelity_cases.csv", condition_rows(settings))
    write_json(tables / "fidelity_settings.json", rows)
    by_label = {r["label"]: r for r in rows}
    front_rows = [by_label[s.label] for s in front]
    write_csv(
        tables / "fidelity_pareto.csv",
        front_rows,
        [
            "label",
            "time_s",
            "max_error_pct",
            "err_peak_amplitude_mm_pct",
            "err_peak_frequency_hz_pct",
            "err_friction_energy_mj_pct",
        ],
    )

    conds = list(conditions)
    sections = [_setup_section(summary, ref, conds)]
    self_err = ladder_self_errors(ladders)
    for knob, lad in ladders.items():
        fig = plot_knob(
            knob,
            [dict(s.members).get(knob, level_label(knob, s.values[knob])) for s in lad],
            [s.time_s for s in lad],
            {
                q: {c: [s.errors.get(c, {}).get(q) for s in lad] for c in conds}
                for q, _, _ in QUANTITIES
            },
            figs / f"fidelity_{knob}.png",
            held=", ".join((summary.get("held") or {}).get(knob, {}).values()),
        )
        trows = []
        for s, own in zip(lad, self_err[knob], strict=True):
            r = by_label[s.label]
            for c in conds:
                trows.append(
                    {
                        "level": level_label(knob, s.values[knob]),
                        "condition": c,
                        **{f"{q} error %": s.errors.get(c, {}).get(q) for q, _, _ in QUANTITIES},
                        **{
                            f"{q} error vs limit %": s.limit_errors.get(c, {}).get(q)
                            for q, _, _ in QUANTITIES
                        },
                        "worst error vs the knob's finest level %": own,
                        "time s": r["time_s"],
                        "failed": "; ".join(s.failed),
                    }
                )
        write_csv(tables / f"fidelity_{knob}.csv", trows)
        sections.append(
            {
                "id": f"knob-{knob}",
                "title": f"Knob: {knob}",
                "text": [
                    f"{knob} moved over {len(lad)} levels, the other knobs at the base "
                    "setting"
                    + "".join(
                        f" but {', '.join(h.values())}"
                        for h in [(summary.get("held") or {}).get(knob, {})]
                        if h
                    )
                    + ". Errors relative to the reference, in percent; time is the "
                    "whole cost of the setting (geometry + reduction + assembly + HBM of "
                    f"every condition), s. Log-log; errors below {1e-4:g} % are drawn at "
                    f"{1e-4:g} % (open markers). Against the reference, a one-knob setting "
                    "also carries the errors of the other knobs at their base levels; the "
                    "table's last error column compares each level with this knob's own "
                    "finest level instead (the error this knob alone makes)."
                ],
                "figures": [
                    {
                        "path": str(fig.relative_to(out)),
                        "caption": f"error vs compute time when only {knob} changes",
                    }
                ],
                "tables": [
                    {
                        "path": f"tables/fidelity_{knob}.csv",
                        "caption": f"{knob}: errors per condition and time",
                    }
                ],
            }
        )
    sections.append(_limits_section(summary, tables))
    sections.append(_base_section(out, settings, summary, conds, production))
    tol = tolerance
    picked = (summary.get("picked") or {}).get("picked")
    cand = [s for s in settings if s.role != "reference"]
    fig = plot_pareto(
        [
            {
                "label": s.label,
                "group": (s.members[0][0] if s.members else s.role),
                "time_s": s.time_s,
                **{q: s.error(q) for q, _, _ in QUANTITIES},
                "worst": s.error(),
            }
            for s in cand
        ],
        figs / "fidelity_pareto.png",
        tolerance_pct=tol,
        picked=picked["label"] if picked else None,
        reference_time_s=ref.time_s,
    )
    sections.append(
        {
            "id": "pareto",
            "title": "All settings and the Pareto front",
            "text": [
                f"Every measured setting (one knob moved, the base, and any verified "
                f"combination) against its compute time; each panel's line is the Pareto "
                f"front of that error (no setting is both cheaper and more accurate). The "
                f"last panel is the worst of the three errors over every condition, the "
                f"measure the tolerance uses. Front: {', '.join(summary['pareto_front'])}."
            ],
            "figures": [{"path": str(fig.relative_to(out)), "caption": "error vs time, all knobs"}],
            "tables": [
                {"path": "tables/fidelity_pareto.csv", "caption": "the Pareto front (worst error)"},
                {
                    "path": "tables/fidelity_settings.csv",
                    "caption": "every setting: "
                    "knob levels, charged time per stage (s), worst errors (%)",
                },
            ],
        }
    )
    sections.append(_pick_section(summary, tol))
    if summary["failures"]:
        sections.append(
            {
                "id": "failures",
                "title": "Failed solves",
                "text": [
                    "These cases stopped early; their points are kept, and the "
                    "settings they belong to have no error and are never "
                    "picked:"
                ]
                + summary["failures"],
                "figures": [],
                "tables": [],
            }
        )
    sections.append(
        {
            "id": "cases",
            "title": "Every case",
            "text": ["One row per setting and condition: the peak values and their errors."],
            "figures": [],
            "tables": [{"path": "tables/fidelity_cases.csv", "caption": "every case"}],
        }
    )
    head = [
        f"{damper_line(summary)}",
        f"reference: {_kv(summary['reference'])}",
        f"Pareto front (worst error): {', '.join(summary['pareto_front'])}",
    ]
    head.append(_reference_vs_limit(by_label.get(ref.label, {}), summary["limit"]))
    if summary.get("picked"):
        head.append(summary["picked"]["reason"])
    timings = {
        "wall time of this run (before the report)": wall_s,
        **{
            f"{s} (charged, summed over the settings)": sum(x.times.get(s, 0.0) for x in settings)
            for s in STAGES
        },
    }
    return head, timings, sections


def limit_rows(summary: dict[str, Any]) -> list[dict[str, Any]]:
    """One row per knob (and "all knobs"), condition and quantity: the limit estimate."""
    rows = []
    for knob, lim in summary["knob_limits"].items():
        for c, qs in lim.items():
            for q, e in qs.items():
                rows.append(
                    {
                        "knob": knob,
                        "condition": c,
                        "quantity": q,
                        "finest level": e["finest"],
                        "limit": e["value"],
                        "uncertainty": e["uncertainty"],
                        "observed order": e["order"],
                        "asymptotic": e["asymptotic"],
                        "trusted": e["trusted"],
                        "method": e["method"],
                        "why not asymptotic": e["reason"],
                    }
                )
    for c, qs in summary["limit"].items():
        for q, e in qs.items():
            rows.append(
                {
                    "knob": "all knobs (reference + corrections)",
                    "condition": c,
                    "quantity": q,
                    "finest level": None,
                    "limit": e["value"],
                    "uncertainty": e["uncertainty"],
                    "observed order": None,
                    "asymptotic": e["asymptotic"],
                    "trusted": e["trusted"],
                    "method": "sum of the knobs' corrections",
                    "why not asymptotic": e["reason"],
                }
            )
    return rows


def _base_section(
    out: Path,
    settings: list[Setting],
    summary: dict[str, Any],
    conds: list[str],
    production: Setting | None = None,
) -> dict[str, Any]:
    """The base setting (and the production model's, if any) against the limit: its chart,
    tables and section (report_base.py)."""
    from .figures import plot_base_per_knob, plot_base_vs_limit, stuck_cases
    from .report_base import base_section, base_vs_limit

    base = next(s for s in settings if s.role == "base")
    table = base_vs_limit(base, summary, conds, production)
    qs = [q for q, _, _ in QUANTITIES]
    stuck = {q: stuck_cases(table, q) for q in qs}  # named on the chart, never drawn
    trusted = {q: [c for c in conds if table[c][q]["trusted"] and c not in stuck[q]] for q in qs}

    def worst_trusted(st: Setting, q: str) -> float | None:
        es = [st.limit_errors.get(c, {}).get(q) for c in trusted[q]]
        es = [e for e in es if e is not None]
        return max(es) if es else None

    points = [
        {
            "label": s.label,
            "group": s.members[0][0] if s.role == "knob" and s.members else s.role,
            "time_s": s.time_s,
            **{q: worst_trusted(s, q) for q in qs},
        }
        for s in settings
        if s.role != "base"
    ]
    marks: dict[str, Any] = {
        "time_s": base.time_s,
        "untrusted": {q: [c for c in conds if c not in trusted[q] + stuck[q]] for q in qs},
        "stuck": stuck,
    }
    for q in qs:
        marks[q] = [
            (c, table[c][q]["error_vs_limit_pct"], table[c][q]["uncertainty_pct"])
            for c in trusted[q]
            if table[c][q]["error_vs_limit_pct"] is not None
        ]
        if production is not None:
            marks.setdefault("production", {})[q] = [
                (c, table[c][q]["production"]["error_vs_limit_pct"], table[c][q]["uncertainty_pct"])
                for c in trusted[q]
                if table[c][q]["production"]["error_vs_limit_pct"] is not None
            ]
    if production is not None:
        marks["production_time_s"] = production.time_s
    fig = plot_base_vs_limit(points, marks, out / "figures" / "fidelity_base_vs_limit.png")
    per_knob = plot_base_per_knob(table, out / "figures" / "fidelity_base_per_knob.png")
    return base_section(out, table, summary, conds, [fig, per_knob])


def _limits_section(summary: dict[str, Any], tables: Path) -> dict[str, Any]:
    write_csv(tables / "fidelity_limits.csv", limit_rows(summary))
    choices = sorted(  # modelling choices (the rigid damper): no limit to estimate
        k
        for k, lim in summary["knob_limits"].items()
        if all(e["reason"] == NO_LADDER for qs in lim.values() for e in qs.values())
    )
    flagged = sorted(
        {
            k
            for k, lim in summary["knob_limits"].items()
            for qs in lim.values()
            for e in qs.values()
            if not e["trusted"] and k not in choices and e["reason"] != NOT_APPLICABLE
        }
    )
    text = [
        "Errors against the limit: each knob's converged value is estimated from its "
        "finest three levels (the other knobs at the base) by Richardson extrapolation with "
        "the observed order p (q = q0 + C h^p; h: mesh size in mm, 1/modes, 1/H, 1/nt, "
        "1/points); its uncertainty is 1.25 |q_finest - q0| (Roache's grid convergence "
        "index). The limit of every knob at once is the reference plus each knob's "
        "correction q0 - q_finest (the knobs' errors assumed to add), its uncertainty the "
        "sum of theirs. The 'vs limit' columns of the tables measure every setting, the "
        "reference included, against it. Where a knob's finest levels oscillate without "
        "growing, or converge faster than p = 8, nothing is extrapolated but the limit is "
        "bounded: the finest level, +- 1.25 times the finest three levels' spread (method "
        "'bounded'; such a knob adds that bound to the uncertainty and no correction). "
        "A ladder of four or more levels that its finest three cannot read is fitted by "
        "least squares over all its levels instead (q0 + C h^p at p = 1 and 2, the better "
        "kept; uncertainty: the correction x 1.25, the fit's scatter, its miss at the "
        "finest level and the two orders' disagreement, tripled where the scatter exceeds "
        "the mean step; method 'least squares'). Where such a ladder's finest three "
        "oscillate with differences that shrink and a finest step that is not its largest, "
        "three times its data range bounds the limit instead if that band is narrower "
        "(method 'bounded'). A knob that meshes the model anew at every level (contact "
        "mesh size, points per line) is bounded by the global mesh ladder's scatter about "
        "its trend where its finest three oscillate within it, and no band of such a knob "
        "or of the mesh is narrower than 1.25 times that scatter. "
        "Differences at round-off: converged, the finest level +- the largest difference. "
        "Where they grow, fit no power law or give p below 0.5 (and no fit), or there are "
        "fewer than three levels, nothing is extrapolated or bounded: that knob contributes "
        "no correction, the flag 'trusted' is false and no uncertainty is given, so the "
        "error is then against the finest level, as before. The tolerance pick uses the "
        "errors against the limit where it is trusted and against the reference elsewhere "
        "(its reason says which).",
        "Knobs neither extrapolated nor bounded for some condition or quantity: "
        + (", ".join(flagged) if flagged else "none")
        + "."
        + (
            " Modelling choices, not ladders towards a limit (the reference's choice "
            f"stands): {', '.join(choices)}."
            if choices
            else ""
        ),
    ]
    return {
        "id": "limits",
        "title": "Errors against the extrapolated limit",
        "text": text,
        "figures": [],
        "tables": [
            {
                "path": "tables/fidelity_limits.csv",
                "caption": "limit estimates: per knob and all knobs, with order, "
                "uncertainty (quantity units), the asymptotic and trusted flags",
            }
        ],
    }


def _reference_vs_limit(row: dict[str, Any], limit: dict[str, Any]) -> str:
    """One line: the reference's error against the limit per quantity, +- its uncertainty."""
    parts = []
    for q, name, _ in QUANTITIES:
        e, u = row.get(f"err_lim_{q}_pct"), limit_uncertainty_pct(limit, q)
        flag = all(c.get(q, {}).get("trusted") for c in limit.values())
        if e is None:
            parts.append(f"{name} n/a")
        elif flag and u is not None:
            parts.append(f"{name} {e:.3g} % (+- {u:.2g} %)")
        else:
            parts.append(f"{name} {e:.3g} % (not trusted: against the finest levels)")
    return "reference vs the extrapolated limit (worst condition): " + "; ".join(parts)


def damper_line(summary: dict[str, Any]) -> str:
    return (
        f"{summary['damper']}: {summary['n_settings']} settings x "
        f"{len(summary['conditions'])} conditions ({', '.join(summary['conditions'])}); "
        f"{summary['n_computed']} cases computed, {summary['n_reused']} reused"
    )


def _kv(d: dict[str, Any]) -> str:
    return ", ".join(str(v) for v in d.values())  # the level labels name their knob


def _setup_section(summary: dict[str, Any], ref: Setting, conds: list[str]) -> dict[str, Any]:
    knobs = "; ".join(f"{k}: {', '.join(v)}" for k, v in summary["knobs"].items())
    return {
        "id": "setup",
        "title": "Setup and reference",
        "text": [
            damper_line(summary) + ".",
            f"Base setting: {_kv(summary['base'])}. Levels tried, one knob at a time: {knobs}.",
            f"Reference (every varied knob at its finest level at once): "
            f"{_kv(summary['reference'])}; its charged time {ref.time_s:.1f} s.",
            "Errors: |q - q_ref| / |q_ref| in percent for the peak amplitude (mm), the resonance "
            "frequency (Hz) and the friction energy per cycle at the peak (mJ), at every "
            "condition. Where q_ref is 0 (a damper stuck at the peak dissipates nothing) no "
            "error is relative to it: that quantity has no error at that condition (0 % if "
            "the setting's value is 0 too) and is left out of the worst error.",
            "Times: geometry and reduction are the compute times recorded when those "
            "stages were built (a stage shared by several settings is charged to each, as a user "
            "running that setting alone would pay it), assembly and HBM as measured when the "
            "setting was solved; the machine may have been shared, so times are indicative.",
        ],
        "figures": [],
        "tables": [],
    }


def _pick_section(summary: dict[str, Any], tol: float | None) -> dict[str, Any]:
    if tol is None:
        return {
            "id": "pick",
            "title": "Tolerance pick",
            "text": ["No tolerance given (run with --tolerance 1% to pick the cheapest setting)."],
            "figures": [],
            "tables": [],
        }
    pick = summary["picked"]
    text = [pick["reason"]]
    p = pick.get("picked")
    if p:
        text.append(
            "Picked: " + ", ".join(p[k] for k in KNOBS) + "; errors: "
            f"amplitude {p['err_peak_amplitude_mm_pct']:.3g} %, frequency "
            f"{p['err_peak_frequency_hz_pct']:.3g} %, energy "
            f"{p['err_friction_energy_mj_pct']:.3g} %; time {p['time_s']:.1f} s."
        )
    for c in summary["combinations"]:
        if "label" in c:
            e = c["max_error_pct"]
            text.append(
                f"Combination {c['shift'] + 1} (per knob, the coarsest level within "
                f"{tol:g} % of that knob's own finest level, {c['shift']} level(s) "
                "finer; in brackets that error): "
                f"{', '.join(c['levels'].values())}; {c['note']}; measured worst "
                f"error {'n/a' if e is None else f'{e:.3g} %'}, "
                f"{'meets' if c['meets'] else 'does not meet'} the tolerance; "
                f"{c['time_s']:.1f} s."
            )
        else:
            text.append(f"Combination: {c['note']}.")
    return {
        "id": "pick",
        "title": f"Tolerance pick ({tol:g} %)",
        "text": text,
        "figures": [],
        "tables": [],
    }
