"""The bladed-disk study's report sections: the answer (worst EO per damper, best damper per
EO), the charts and the tables. Plain inputs: the answer rows of
``workbench.studies.kinds.bladed_disk.compute``."""

from __future__ import annotations

from typing import Any


def bladed_disk_sections(
    n_blades: int,
    eos: list[int],
    eo_nd: dict[str, dict[str, Any]],
    worst: list[dict],
    best: list[dict],
    failed: list[dict],
    at_edge: list[dict],
) -> list[dict]:
    """The report's sections. ``eo_nd``: EO -> its ND and direction; ``worst``: per damper
    and force the worst EO and peak; ``best``: per EO and force the damper with the smallest
    peak; ``failed``: the cases whose branch stopped before the band end."""
    maps = ", ".join(
        f"EO {e} -> ND {eo_nd[str(e)]['nd']} ({eo_nd[str(e)]['direction']})" for e in eos
    )
    text = [
        f"One sector of a tuned disk of {n_blades} blades, its damper seated between this "
        "sector's platform and the next one's, is solved by harmonic balance under each "
        "engine order (EO): harmonic h of the response lives at nodal diameter (ND) h EO mod "
        "N, a forward or backward travelling wave (docs/DISK_HBM.md). Each case is a forced "
        "response over 0.9..1.1 times the first stuck frequency of the EO's ND; its peak is "
        "the largest amplitude of the response point along the excitation.",
        "Engine orders and the ND of their harmonic-1 excitation: " + maps + ".",
        "Worst EO per damper (largest peak): "
        + "; ".join(
            f"{w['damper']} at {w['force_n']:g} N: EO {w['worst_eo']}, "
            f"{w['worst_peak_m'] * 1e6:.3g} µm at {w['peak_hz']:.1f} Hz"
            for w in worst
        )
        + ".",
        "Best damper per EO (smallest peak): "
        + "; ".join(f"EO {b['eo']} at {b['force_n']:g} N: {b['best_damper']}" for b in best)
        + ".",
        "Stability is not computed on a sector (its Hill matrix only sees its own travelling "
        "wave).",
    ]
    if failed:
        text.append(
            "Cases that stopped before the band end (their peak is the largest amplitude "
            "reached, a lower bound: the worst EO of that damper and force may be one of "
            "these): "
            + "; ".join(
                f"{c['damper']} EO {c['eo']} {c['force_n']:g} N: {c['message']}" for c in failed
            )
            + "."
        )
    if at_edge:
        text.append(
            "Cases whose largest amplitude is on the first or last point of their band (the "
            "resonance lies outside 0.9..1.1 times the stuck frequency, e.g. a damper that "
            "rolls or slides freely; their peak is a lower bound): "
            + "; ".join(
                f"{c['damper']} EO {c['eo']} {c['force_n']:g} N at {c['peak_hz']:.1f} Hz"
                for c in at_edge
            )
            + "."
        )
    return [
        {
            "id": "answer",
            "title": "Which engine order is worst, which damper is best",
            "text": text,
            "figures": [
                {
                    "path": "figures/bladed_disk_peaks.png",
                    "caption": "Per damper, the peak response (µm) against engine order, "
                    "one line per force.",
                },
                {
                    "path": "figures/bladed_disk_energy.png",
                    "caption": "Per damper, the friction energy per sector and cycle at the "
                    "peak (mJ) against engine order, one line per force.",
                },
                {
                    "path": "figures/bladed_disk_fan.png",
                    "caption": "Fan diagram with the damper stuck (first families), each "
                    "case's peak frequency at its ND (crosses), and the engine-order line "
                    "f = EO x speed through each damper's worst crossing.",
                },
            ],
            "tables": [
                {
                    "path": "tables/bladed_disk_worst.csv",
                    "caption": "Per damper and force: the worst EO, its ND and direction, "
                    "the worst peak (m) and its frequency (Hz).",
                },
                {
                    "path": "tables/bladed_disk_best.csv",
                    "caption": "Per EO and force: the damper with the smallest peak, and "
                    "every damper's peak (m).",
                },
                {"path": "tables/bladed_disk_cases.csv", "caption": "Every case."},
            ],
        }
    ]
