"""The robustness study's report sections: the failure map, how methods failed, HBM vs time.

Plain inputs: the classified cell records and time-check records of
``workbench.studies.kinds.robustness.compute`` and the method descriptions.
"""

from __future__ import annotations

from typing import Any


def robustness_sections(
    tol: float, methods: dict[str, str], energy_tol: float, cells: list[dict], checks: list[dict]
) -> list[dict]:
    """The report's sections. ``tol``: the peak tolerance (percent); ``methods``: the study's
    methods in order (the first is the reference) -> description; ``energy_tol``: the energy
    balance a point may miss by and still be a periodic solution."""
    ref = next(iter(methods))
    meth = "; ".join(f"{m}: {d}" for m, d in methods.items())
    text_map = [
        "Every hard case (rows of the table of cases) is solved with every method. A cell is "
        f"'ok' (green) when the branch reached the band end and its peak lies within "
        f"{tol:g} % of the reference method's ('{ref}') in amplitude (the peak "
        "frequency's deviation, in per cent of the band width, is in the tables); 'wrong "
        "answer' (orange) when it reached the band end with a peak further off, or with a "
        f"point whose energy balance is off by more than {energy_tol:g} (not a periodic "
        "solution); 'failed' (red) when the solver stopped before the band end (the "
        "frequency reached is shown). Cell text: Newton iterations (over the accepted points) "
        "and wall time (on a shared machine: compare orders of magnitude, not per cents).",
        "Methods: " + meth + ".",
    ]
    failures = []
    for c in cells:
        if c["status"] == "failed":
            failures.append(
                f"{c['method']} on {c['case']}: {c['message']} (reached "
                f"{_f(c['freq_reached_hz'])} Hz, {100 * c['band_fraction']:.0f} % "
                f"of the band, {c['n_points']} points kept)"
            )
        elif c["status"] == "wrong":
            why = []
            if c["amp_dev_pct"] is not None and abs(c["amp_dev_pct"]) > tol:
                why.append(
                    f"its peak is {c['amp_dev_pct']:+.3g} % in amplitude and "
                    f"{c['freq_dev_pct']:+.3g} % of the band in frequency off the "
                    "reference's"
                )
            er = c.get("energy_residual_max")
            if er is not None and er > energy_tol:
                why.append(f"a point's energy balance is off by {er:.2g} (not a solution)")
            failures.append(
                f"{c['method']} on {c['case']}: reached the band end but " + " and ".join(why)
            )
    sections = [
        {
            "id": "map",
            "title": "Failure map",
            "text": text_map,
            "figures": [
                {
                    "path": "figures/robustness_map.png",
                    "caption": "Methods x hard cases: green ok, orange wrong answer, red "
                    "failed; text: Newton iterations, wall time, and the peak deviation or "
                    "the frequency reached.",
                },
                {
                    "path": "figures/robustness_curves.png",
                    "caption": "Each hard case: the branch of every method (peak response "
                    "of blade 1 against frequency); a failed branch ends with a cross; a grey "
                    "underlay marks points Hill does not call stable (unstable or unknown).",
                },
            ],
            "tables": [
                {
                    "path": "tables/robustness_cases.csv",
                    "caption": "The hard cases (reference method's branch: turning points "
                    "found as sign changes of the frequency increment, share of "
                    "separated pair-points, Hill-unstable points).",
                },
                {"path": "tables/robustness_cells.csv", "caption": "Every cell."},
            ],
        },
        {
            "id": "failures",
            "title": "How the methods failed",
            "text": failures or ["Every method succeeded on every hard case."],
            "tables": [
                {
                    "path": "tables/robustness_failures.csv",
                    "caption": "Failed cells and wrong answers.",
                }
            ]
            if failures
            else [],
        },
    ]
    if checks:
        text = [
            "The harmonic balance is checked by time integration (Newmark, 1024 steps per "
            "period, the same contact law) started on the HBM orbit at its suspect points: "
            "the peak, turning points, a Hill-unstable point and a separated point. The "
            "dense time integration is limited to 200 DOFs, so this is done on small "
            "models, not on the rig cases (300-900 DOFs): "
            + "; ".join(f"{ch['model']} ({ch['n_dofs']} DOFs): {ch['why']}" for ch in checks)
            + ".",
            "A Hill-unstable orbit is expected to be left by the time integration (it "
            "lands on another, stable orbit): a large difference there confirms Hill's "
            "verdict. Near a fold several periodic solutions coexist at one frequency, "
            "and the fold point itself is only marginally stable: a time integration "
            "started there may settle on another solution of the same branch; the "
            "table gives the HBM solution nearest to the time integration at that "
            "frequency and the difference to it. A time integration that does not "
            "repeat within its period budget is marked as not converged (its last "
            "period is compared).",
            "Hill's verdict is unknown where its selection of Floquet exponents cannot be "
            "trusted: the count check fails, a dropped exponent of the other verdict nearly "
            "made the cut, or the most centred eigenvectors and the exponents of the strip "
            "|Im| <= w/2 reach opposite verdicts (with a stick-slip Jacobian neither is exact "
            "away from a fold). Such points are listed apart in the summary and drawn dotted "
            "grey.",
        ]
        sections.append(
            {
                "id": "time",
                "title": "Harmonic balance against time integration",
                "text": text,
                "figures": [
                    {
                        "path": "figures/hbm_vs_time.png",
                        "caption": "HBM branches (unstable: dashed; stability unknown: "
                        "dotted grey) and the "
                        "steady time-integration amplitudes at suspect points.",
                    }
                ],
                "tables": [
                    {"path": "tables/hbm_vs_time.csv", "caption": "HBM against time integration."}
                ],
            }
        )
    return sections


def _f(v: Any) -> str:
    return "-" if v is None else f"{v:.5g}"
