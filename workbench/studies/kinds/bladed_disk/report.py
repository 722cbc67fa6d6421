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
        "Stability is not computed along the curves (a sector's Hill matrix only sees its own "
        "travelling wave); each damper's worst peak is checked as a state of the whole disk "
        "(next section).",
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


def extra_sections(
    dampers: list[str], screen: list[dict], fields: list[dict], wcases: list[dict], paths: dict
) -> list[dict]:
    """The screen per nodal diameter, the contact status and the sector field at each
    damper's worst peak. ``screen``: rows of ``nd_screen``; ``fields``: the worst-peak field
    records; ``wcases``: the worst cases' records; ``paths``: the figures written."""
    nds = sorted({int(r["nd"]) for r in screen})
    by = {(r["damper"], int(r["nd"])): r for r in screen}
    text = [
        "The rig's coupling screen at every nodal diameter: on the sector model of each ND "
        "the first family's frequency with every contact pair stuck (springs kt, kt, kn) "
        "and with the tangential springs removed (the damper sliding freely, the normal "
        "springs kept), the family being the mode with the largest receptance from the "
        "excitation to the response point; k2/k = 1 - (f_sliding / f_stuck)^2 is the share "
        "of the stuck mode's stiffness the sticking damper adds. A damper can only hold a "
        "resonance down as far as it stiffens it; a k2/k near zero (or slightly negative: "
        "the stuck damper's mass without stiffness) means it rolls or slides with the "
        "platforms and adds no friction damping there. As on the rig, the screen also "
        "gives the force per blade at which the first pair slips (f_slip_n) or opens "
        "(f_sep_n) in the stuck linear response near the family's resonance, and the "
        "single-mode estimate f_cap_n = (4/pi) Q k2/k f_slip_n (Q = 1/(2 x 0.005)) of the "
        "force up to which the peak stays level; below f_slip_n the damper stays stuck and "
        "the peak is the stuck linear one.",
        "k2/k per ND "
        + ", ".join(str(k) for k in nds)
        + ": "
        + "; ".join(
            f"{d} " + " ".join(f"{by[(d, k)]['k2_over_k']:.3f}" for k in nds if (d, k) in by)
            for d in dampers
        )
        + ".",
    ]
    figures = []
    if "k2k" in paths:
        figures.append(
            {
                "path": "figures/bladed_disk_k2k.png",
                "caption": "Left: k2/k against nodal diameter, one line per damper; grey "
                "bands the NDs the study's engine orders excite, rings each damper's worst "
                "EO at the largest force. Middle: the stuck (solid) and sliding (dashed) "
                "first-family frequencies (Hz). Right: the force per blade at which the "
                "first pair slips in the stuck linear response (N), the study's forces "
                "dotted.",
            }
        )
    if "status" in paths:
        figures.append(
            {
                "path": "figures/bladed_disk_status.png",
                "caption": "Contact status of every pair along each damper's worst case "
                "(its worst EO at the largest force), frequency on x, the peak dashed; the "
                "title counts the pairs of each status at the peak.",
            }
        )
    if "fields" in paths:
        figures.append(
            {
                "path": "figures/bladed_disk_worst_fields.png",
                "caption": "The sector at each damper's worst peak: colour the largest "
                "displacement over the period (mm), shape the displacement at the instant the "
                "response point is farthest out (exaggerated), the undeformed sector in grey; "
                "the VTU files hold every harmonic's field.",
            }
        )
    for f in fields:
        text.append(
            f"{f['damper']} worst peak (EO {f['eo']}, ND {f['nd']}, {f['force_n']:g} N, "
            f"{f['peak_hz']:.1f} Hz): {f['peak_m'] * 1e3:.4f} mm at the response point; the "
            f"field expanded from the solution gives {f['field_peak_m'] * 1e3:.4f} mm there "
            f"(relative difference {f['field_rel_err']:.1e}); {f['vtu'].split('/')[-1]}."
        )
        s = f.get("stability")
        if s:
            text.append(
                f"{f['damper']} worst peak as a state of the whole disk (every ND, every "
                f"damper; Hill's method at that one point): {s['verdict']}, largest real part "
                f"of the Floquet exponents {s['max_real']:.3g} 1/s "
                f"({s['max_real_over_w']:.2e} of the angular frequency)"
                + (f"; {s['note']}" if s["note"] else "")
                + "."
            )
    for c in wcases:
        counts = ", ".join(f"{v} {k}" for k, v in c["status_at_peak"].items() if v)
        text.append(f"{c['damper']} at its worst peak: {counts}.")
    return [
        {
            "id": "screen_nd",
            "title": "Coupling screen per nodal diameter, contact status and field at the "
            "worst peak",
            "text": text,
            "figures": figures,
            "tables": [
                {
                    "path": "tables/bladed_disk_screen.csv",
                    "caption": "Per damper and ND: stuck and sliding first-family "
                    "frequencies (Hz), k2/k and f_stuck/f_sliding.",
                }
            ],
        }
    ]
