"""The base setting against the extrapolated limit: one row per case and quantity.

A fidelity study whose base setting is a production job's (the paper rig's
``make run``: studies/fidelity_paper_rig.toml) answers "how far is that job
from the converged model?". Per condition and quantity this module gives

* the error of the base against the limit of every knob at once
  (``workbench.post.fidelity.combined_limits``), with the limit's
  uncertainty, ONLY where that limit is trusted (``trusted``); elsewhere
  no number, the reason instead;
* per knob, the base's error against that knob's own Richardson limit (the
  other knobs at the base, so the base is a level of that ladder; where the
  ladder holds another knob away from the base, as the points per line at
  ``points-contact-mesh-size``, its level at the base's value of the knob),
  again only where the knob's finest levels extrapolate or bound it;
* the base's error against the reference (every knob at its finest level),
  which is no limit but a measured difference.

It writes ``tables/fidelity_base_vs_limit.json`` (machine-readable, for
docs/FINDINGS.md) and ``.csv``, and returns the report section. Plain data
on the study's settings and JSON summary; the chart is
:func:`workbench.studies.kinds.fidelity.figures.plot_base_vs_limit`.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from ....io import write_json
from ....io.csv_rows import write_rows_csv
from ....post.fidelity import NOT_APPLICABLE, QUANTITIES, Setting, setting_value


def _pct(num: float | None, den: float | None) -> float | None:
    if num is None or den is None or den == 0 or not math.isfinite(num):
        return None
    return abs(num) / abs(den) * 100.0


def base_vs_limit(
    base: Setting,
    summary: dict[str, Any],
    conditions: list[str],
    production: Setting | None = None,
) -> dict[str, dict[str, dict[str, Any]]]:
    """condition -> quantity -> the base's value, its errors and the limits (see module doc).

    Errors and uncertainties in percent of the limit; ``limit`` and
    ``uncertainty`` in the quantity's units. ``error_vs_limit_pct`` and
    ``uncertainty_pct`` are None where the limit is not trusted
    (``trusted`` False, ``reason`` says why; ``asymptotic``: every knob
    extrapolated, none only bounded). With ``production`` (the base
    setting on the production job's own model, see the ``production-geometry``
    option) each row also has ``production``: its value, its error against the
    same limit (``error_vs_limit_pct``, and ``signed_error_pct``: above the limit
    positive) and its difference from the base in percent of the base.
    """
    out: dict[str, dict[str, dict[str, Any]]] = {}
    for cond in conditions:
        out[cond] = {}
        for q, _, unit in QUANTITIES:
            v = setting_value(base, cond, q)
            lim = summary["limit"].get(cond, {}).get(q, {})
            trusted = bool(lim.get("trusted")) and v is not None
            knobs: dict[str, Any] = {}
            for knob, by_cond in summary["knob_limits"].items():
                e = by_cond.get(cond, {}).get(q)
                if e is None or e["reason"] == NOT_APPLICABLE or e["method"] == "not applicable":
                    continue
                # the knob's own error of the base: its ladder's level at the base's value
                # of the knob (the base, or that value where the ladder holds other knobs;
                # the base's own value where the ladder has no such level)
                at = e["pivot"] if e.get("pivot") is not None else v
                ok = bool(e["trusted"]) and at is not None and e["value"] is not None
                knobs[knob] = {
                    "limit": e["value"] if ok else None,
                    "uncertainty": e["uncertainty"] if ok else None,
                    "order": e["order"],
                    "asymptotic": bool(e["asymptotic"]),
                    "trusted": bool(e["trusted"]),
                    "method": e["method"],
                    "at": e.get("pivot_label") if e.get("pivot") is not None else "base",
                    "error_vs_limit_pct": _pct(at - e["value"], e["value"]) if ok else None,
                    "uncertainty_pct": _pct(e["uncertainty"], e["value"]) if ok else None,
                    "reason": e["reason"],
                }
            out[cond][q] = {
                "unit": unit,
                "base": v,
                "limit": lim.get("value") if trusted else None,
                "uncertainty": lim.get("uncertainty") if trusted else None,
                "asymptotic": trusted and bool(lim.get("asymptotic")),
                "trusted": trusted,
                "bounded": list(lim.get("bounded", [])) if trusted else [],
                "error_vs_limit_pct": base.limit_errors.get(cond, {}).get(q) if trusted else None,
                "uncertainty_pct": _pct(lim.get("uncertainty"), lim.get("value"))
                if trusted
                else None,
                "reason": "" if trusted else (lim.get("reason") or "no value to compare"),
                "error_vs_reference_pct": base.errors.get(cond, {}).get(q),
                "knobs": knobs,
            }
            if production is not None:
                out[cond][q]["production"] = _production_row(
                    production, cond, q, v, lim.get("value") if trusted else None
                )
    return out


def _production_row(
    production: Setting, cond: str, q: str, base: float | None, limit: float | None
) -> dict[str, Any]:
    """The production model's value at ``cond``, its error against ``limit`` (None: not
    trusted) and its difference from the base setting on this study's model."""
    p = setting_value(production, cond, q)
    # a limit of 0 (a stuck damper's energy): nothing is relative to it
    signed = None if p is None or not limit else (p - limit) / abs(limit) * 100.0
    return {
        "value": p,
        "error_vs_limit_pct": None if signed is None else abs(signed),
        "signed_error_pct": signed,
        "vs_base_pct": None
        if p is None or base is None or base == 0
        else (p - base) / abs(base) * 100.0,
    }


def rows(table: dict[str, dict[str, dict[str, Any]]]) -> list[dict[str, Any]]:
    """Flat rows of :func:`base_vs_limit` for the CSV: all knobs, then each knob."""
    out = []
    for cond, qs in table.items():
        for q, d in qs.items():
            every = {
                "condition": cond,
                "quantity": q,
                "limit of": "all knobs",
                "base": d["base"],
                "knob's error at": "",
                "limit": d["limit"],
                "uncertainty": d["uncertainty"],
                "error vs limit %": d["error_vs_limit_pct"],
                "uncertainty %": d["uncertainty_pct"],
                "trusted": d["trusted"],
                "bounded by": ", ".join(d["bounded"]),
                "error vs reference %": d["error_vs_reference_pct"],
                "why not trusted": d["reason"],
            }
            out.append(every)
            pr = d.get("production")
            if pr is not None:  # the same limit, the production model's value and error
                out.append(
                    dict(
                        every,
                        **{
                            "limit of": "all knobs (production model)",
                            "base": pr["value"],
                            "error vs limit %": pr["signed_error_pct"],
                            "error vs reference %": None,
                        },
                    )
                )
            for knob, k in d["knobs"].items():
                out.append(
                    {
                        "condition": cond,
                        "quantity": q,
                        "limit of": knob,
                        "base": d["base"],
                        "knob's error at": k.get("at", "base"),
                        "limit": k["limit"],
                        "uncertainty": k["uncertainty"],
                        "error vs limit %": k["error_vs_limit_pct"],
                        "uncertainty %": k["uncertainty_pct"],
                        "trusted": k["trusted"],
                        "bounded by": knob if k["method"] == "bounded" else "",
                        "error vs reference %": None,
                        "why not trusted": k["reason"],
                    }
                )
    return out


def _pm(e: float | None, u: float | None) -> str:
    return f"{e:.3g} % +- {u:.2g} %" if u is not None else f"{e:.3g} %"


def _cell(d: dict[str, Any]) -> str:
    """All knobs (or why not), then each knob whose limit is trusted."""
    e = d["error_vs_limit_pct"]
    if e is not None:
        head = _pm(e, d["uncertainty_pct"])
    else:
        bad = [k for k, v in d["knobs"].items() if v["error_vs_limit_pct"] is None]
        head = "no trusted limit" + (f" ({', '.join(bad)} not trusted)" if bad else "")
    if e is not None and d["bounded"]:
        head += f" (not from three levels: {', '.join(d['bounded'])})"
    tag = {"bounded": " (bound)", "least squares": " (least squares)"}
    per = [
        f"{k} {_pm(v['error_vs_limit_pct'], v['uncertainty_pct'])}" + tag.get(v["method"], "")
        for k, v in d["knobs"].items()
        if v["error_vs_limit_pct"] is not None
    ]
    return head + (f"; against each knob's own limit: {', '.join(per)}" if per else "")


def base_section(
    out: Path,
    table: dict[str, dict[str, dict[str, Any]]],
    summary: dict[str, Any],
    conditions: list[str],
    figures: list[Path],
) -> dict[str, Any]:
    """Write the tables of :func:`base_vs_limit`'s ``table`` and return the report section
    "the base against the limit"."""
    tables = out / "tables"
    write_json(
        tables / "fidelity_base_vs_limit.json",
        {
            "study": summary["study"],
            "base": summary["base"],
            "reference": summary["reference"],
            "production_geometry": summary.get("production_geometry", ""),
            "note": "errors and uncertainties in percent of the limit; limit and uncertainty "
            "in the quantity's unit; None where the limit is not trusted (trusted false); "
            "asymptotic: every knob extrapolated from its finest three levels; bounded: the "
            "knobs whose limit is instead bounded by their finest levels' spread (no "
            "correction, their bound in the uncertainty) or fitted by least squares over "
            "four or more levels",
            "cases": table,
        },
    )
    write_rows_csv(tables / "fidelity_base_vs_limit.csv", rows(table), digits=4)
    text = [
        "The base setting ("
        + ", ".join(str(v) for v in summary["base"].values())
        + ") against the extrapolated limit of every knob at once, per case: error in "
        "percent of the limit, +- the limit's uncertainty. 'no trusted limit': some knob's "
        "finest levels neither extrapolate nor bound a limit for that case and quantity (the "
        "table says which and why), so no error against a limit is given; 'not from three "
        "levels': a knob whose limit is bounded by its finest levels' spread or fitted by "
        "least squares over all its levels (docs/STUDIES.md). The table also gives, per knob, "
        "the base's error against that knob's own limit (the other knobs at the base), and "
        "the base's error against the reference (every knob at its finest level: a measured "
        "difference, not a limit).",
    ]
    for knob, held in (summary.get("held") or {}).items():
        text.append(
            f"The {knob} ladder holds {', '.join(held.values())} (not the base's), so that "
            "no level refines the mesh at the lines; its error of the base is read at the "
            f"base's {knob} there, and its correction of the limit is taken there."
        )
    for cond in conditions:
        for q, name, _ in QUANTITIES:
            text.append(f"{cond}, {name}: {_cell(table[cond][q])}.")
    if summary.get("production_geometry"):
        text.append(
            "The production job's own model ("
            + Path(summary["production_geometry"]).name
            + ") at the base setting, against the same limit (signed: above the limit "
            "positive; +- the limit's uncertainty):"
        )
        for cond in conditions:
            for q, name, unit in QUANTITIES:
                d = table[cond][q]
                pr = d["production"]
                if pr["value"] is None:
                    cell = "no value (the solve failed or found no peak)"
                elif pr["signed_error_pct"] is None:
                    cell = f"{pr['value']:.4g} {unit}, no trusted limit"
                else:
                    cell = (
                        f"{pr['value']:.4g} {unit}, {pr['signed_error_pct']:+.3g} % "
                        f"+- {d['uncertainty_pct']:.2g} %"
                    )
                text.append(f"{cond}, {name}: {cell}.")
    sec: dict[str, Any] = {
        "id": "base-vs-limit",
        "title": "The base setting against the limit",
        "text": text,
        "figures": [],
        "tables": [
            {
                "path": "tables/fidelity_base_vs_limit.csv",
                "caption": "the base against the limit: all knobs and each knob, per case "
                "and quantity (limit and uncertainty in the quantity's unit, errors in %)",
            }
        ],
    }
    captions = [
        "every setting's error against the extrapolated limit of every knob vs its compute "
        "time; the base per case with the limit's uncertainty",
        "the base's error against each knob's own limit per case, with that limit's "
        "uncertainty (crosses: not trusted, no error)",
    ]
    for fig, cap in zip(figures, captions, strict=False):
        sec["figures"].append({"path": str(fig.relative_to(out)), "caption": cap})
    return sec


__all__ = ["base_section", "base_vs_limit", "rows"]
