"""The mistuning study's report sections: the answer (which damper keeps the worst blade
lowest, the amplification factors with and without it), the charts and the tables. Plain
inputs: the summary, statistics and answer rows of
``workbench.studies.kinds.mistuning.write``."""

from __future__ import annotations

from typing import Any


def mistuning_sections(
    summary: dict[str, Any],
    stats: list[dict],
    answer: list[dict],
    configs: list[tuple[str, str]],
) -> list[dict]:
    """The report's sections for a mistuning study's ``summary``."""
    n_b, bound = summary["n_blades"], summary["whitehead_bound"]
    labels = dict(configs)
    maps = ", ".join(
        f"EO {e} -> ND {v['nd']} ({v['direction']})" for e, v in summary["eo_nd"].items()
    )
    text = [
        f"A disk of {n_b} blades assembled from its cyclic sector's reduction, every blade's "
        "stiffness scaled by (1 + df)^2 for a blade frequency deviation df, and the dampers "
        'between neighbouring platforms (docs/STUDIES.md, "Mistuning study"). '
        f"{summary['n_patterns']} patterns of df, standard deviation "
        f"{summary['std_percent']:g} % ({summary['sampling']} design, seed {summary['seed']}, "
        "normal deviates by the inverse CDF), and the tuned disk (df = 0) as the reference. "
        "Per damper three configurations: no damper and the damper stuck (linear responses, "
        "every blade's peak found on a frequency scan and refined), and the damper in "
        "friction at each force (harmonic balance of the whole mistuned disk).",
        "Engine orders and the nodal diameter of their harmonic-1 excitation: " + maps + ".",
        "The amplification factor (AF) of a pattern is its worst blade's peak over the tuned "
        "disk's peak in the same configuration (damper, EO, force). Whitehead's bound "
        f"(1 + sqrt(N)) / 2 = {bound:.3f} holds for a linear disk with one mode per blade.",
    ]
    for r in answer:
        text.append(
            f"EO {r['eo']} at {r['force_n']:g} N: {r['best_damper']} keeps the worst blade "
            f"lowest, {r['worst_peak_m_p95'] * 1e6:.3g} µm at the 95th percentile of the "
            f"patterns ({r['worst_peak_m_p95_without_damper'] * 1e6:.3g} µm without a damper). "
            f"Its AF in friction: {r['af_p95']:.3f} (95th percentile), {r['af_max']:.3f} "
            f"(max); without the damper {r['af_p95_without_damper']:.3f} and "
            f"{r['af_max_without_damper']:.3f}; stuck {r['af_p95_stuck']:.3f} and "
            f"{r['af_max_stuck']:.3f}."
        )
    linear_over = [r for r in stats if r["config"] in ("none", "stuck") and r["n_above_whitehead"]]
    if linear_over:
        text.append(
            "Linear configurations with patterns above Whitehead's bound (the bound assumes "
            "one mode per blade; several modes per blade can exceed it): "
            + "; ".join(
                f"{r['damper']} EO {r['eo']} {labels[r['config']]}: {r['n_above_whitehead']}"
                for r in linear_over
            )
            + "."
        )
    low = [r for r in stats if r["n_lower_bound"] or r["tuned_lower_bound"]]
    if low:
        text.append(
            "Patterns whose curve stopped early or peaks on its band edge (their peak and AF "
            "are lower bounds; ringed in the comparison chart): "
            + "; ".join(
                f"{r['damper']} EO {r['eo']} {labels[r['config']]}: {r['n_lower_bound']}"
                + (" (the tuned disk's too)" if r["tuned_lower_bound"] else "")
                for r in low
            )
            + "."
        )
    if summary.get("failed"):
        text.append(
            f"{len(summary['failed'])} friction sweeps stopped before their band end "
            "(tables/mistuning_af.csv, column stopped_early)."
        )
    sched = summary.get("schedule") or {}
    if sched.get("wall_s"):
        text.append(
            f"This run computed {summary['n_computed']} of {summary['n_tasks']} tasks on "
            f"{summary['ranks']} rank(s) (shared-counter schedule): wall "
            f"{sched['wall_s']:.1f} s, busy {sched['busy_s']:.1f} s, efficiency "
            f"{sched['efficiency']:.2f}; {summary['n_reused']} reused from the cache."
        )
    return [
        {
            "id": "mistuning",
            "title": "How much the damper protects the worst blade of a mistuned disk",
            "text": text,
            "figures": [
                {
                    "path": "figures/mistuning_af_compare.png",
                    "caption": "Per damper and EO: every pattern's amplification factor per "
                    "configuration (dots), the 95th percentile (bar) and the maximum "
                    "(triangle), Whitehead's bound dashed; below, the worst blade's peak per "
                    "newton of force (µm/N, log scale).",
                },
                {
                    "path": "figures/mistuning_af_hist.png",
                    "caption": "Histograms of the amplification factor over the patterns per "
                    "configuration, the 95th percentiles dotted, Whitehead's bound dashed.",
                },
                {
                    "path": "figures/mistuning_worst_response.png",
                    "caption": "Per damper and configuration, the worst pattern's forced "
                    "response of every blade per newton of force (grey; the worst blade "
                    "thick; the tuned disk dashed).",
                },
            ],
            "tables": [
                {
                    "path": "tables/mistuning_answer.csv",
                    "caption": "Per EO and force: the damper whose worst blade is lowest "
                    "(95th percentile, m), its AF in friction, without the damper and stuck.",
                },
                {
                    "path": "tables/mistuning_stats.csv",
                    "caption": "Per damper, EO and configuration: the tuned peak (m/N), the "
                    "AF's mean, median, 95th percentile and maximum, the worst pattern.",
                },
                {"path": "tables/mistuning_af.csv", "caption": "Every pattern's AF."},
                {
                    "path": "tables/mistuning_peaks.csv",
                    "caption": "Every blade's peak in every pattern and configuration.",
                },
            ],
        }
    ]
