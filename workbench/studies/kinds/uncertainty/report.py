"""The uncertainty study's report sections (text, figure and table references).

Plain inputs: the design, the analysis (``workbench.studies.kinds.uncertainty.compute.analyse``),
the schedule record and the figures drawn by
``workbench.studies.kinds.uncertainty.figures``.
"""

from __future__ import annotations

from typing import Any

from ....post.uncertainty import Design


def uncertainty_sections(
    force_n: float,
    design: Design,
    a: dict[str, Any],
    sched: dict[str, Any],
    figures: list[dict[str, str]],
) -> list[dict[str, Any]]:
    """The report's sections: inputs and design, distributions, sensitivity, computation."""
    figs = {f["id"]: f for f in figures}

    def pick(*ids: str) -> list[dict[str, str]]:
        return [{"path": figs[i]["path"], "caption": figs[i]["caption"]} for i in ids if i in figs]

    n_ab = len(design.ab_rows)
    setup = [
        f"Every damper in every family at {force_n:g} N, under a Saltelli design "
        f"of N = {design.n_base} base points of a scrambled Sobol sequence (seed "
        f"{design.seed}): {design.n_rows} cases per damper and family. The distributions "
        f"and percentiles use its {n_ab} A and B rows (quasi-random draws of the joint "
        "distribution); the Sobol indices (SALib) use every row.",
        "Uncertain inputs: " + "; ".join(f"{k}: {v}" for k, v in a["inputs"].items()) + ".",
        "The seat tilt misaligns one side's seat: the preload along that side's line or face "
        "tilts with the initial gap and vanishes at one end when the gap exceeds the static "
        "approach (workbench/studies/kinds/uncertainty/imperfection.py). The FE reduction is "
        "shared by all samples of a damper.",
    ]
    eff = sched.get("efficiency")
    run = (
        [
            f"The last run that computed cases: {sched.get('n_computed', 0)} cases on "
            f"{sched.get('ranks', 1)} rank(s), "
            f"schedule {sched.get('schedule')}: wall {sched.get('wall_s', 0):.1f} s, busy "
            f"{sched.get('busy_s', 0):.1f} s, efficiency "
            f"{(eff if eff == eff else float('nan')):.2f}."
        ]
        if sched.get("n_computed")
        else ["Every case was found in the cache."]
    )
    return [
        {
            "id": "uq-setup",
            "title": "Inputs and design",
            "text": setup,
            "tables": [{"path": "tables/uncertainty_inputs.csv", "caption": "uncertain inputs"}],
        },
        {
            "id": "uq-dist",
            "title": "Distributions of the response",
            "text": [
                "Peak amplitude, resonance frequency and friction energy per cycle at the peak "
                "over the samples, per damper and family; the 95th percentile decides which "
                "damper is robust."
            ],
            "figures": pick("violins", "exceedance"),
            "tables": [
                {
                    "path": "tables/uncertainty_answer.csv",
                    "caption": "per family, the dampers ranked by their "
                    "95th-percentile peak over the "
                    "samples every damper solved (p95_common; p95: each damper's own solved "
                    "samples), P(peak > threshold) and the input that drives the spread "
                    "(largest total Sobol index, with its bootstrap half-width; "
                    "driver_contenders: the inputs whose index interval reaches the driver's, "
                    "not told apart with these samples; negligible_inputs: total index "
                    "below 0.05 with its half-width)",
                },
                {
                    "path": "tables/uncertainty_stats.csv",
                    "caption": "statistics over the A and B rows (thresholds: "
                    + ", ".join(
                        f"{f} {t:.4g} mm" for f, t in a["thresholds_mm"].items() if t is not None
                    )
                    + "; solves stopped early are missing)",
                },
            ],
        },
        {
            "id": "uq-sens",
            "title": "Sensitivity",
            "text": [
                "Sobol first-order (S1) and total-order (ST) indices of each output (SALib, "
                "with 95% bootstrap half-widths); the input with the largest ST drives the "
                "spread."
            ],
            "figures": pick("tornado", "scatter"),
            "tables": [{"path": "tables/uncertainty_indices.csv", "caption": "Sobol indices"}],
        },
        {
            "id": "uq-run",
            "title": "Computation",
            "text": run,
            "figures": pick("schedule"),
            "tables": [],
        },
    ]
