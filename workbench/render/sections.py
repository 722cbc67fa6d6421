"""From the results of a study to the sections of its report: figures, tables, captions.

:func:`build_sections` is what the study runner calls once every case is
computed. It decides from ``results.kind`` and the cases present what to
show, writes every figure under ``<study>/figures/`` (PNG) and every table
under ``<study>/tables/`` (CSV and markdown with the same cells), and
returns the ``sections`` of the report manifest (see
:mod:`workbench.render.report`): ``{"id", "title", "text": [...],
"figures": [{"path", "caption"}], "tables": [{"path", "caption"}]}``, paths
relative to the study folder.

What a comparison study gets (per family: in-phase, out-of-phase, any
other phase angle; per damper; every force), in the manner of "On the
efficiency of a conical under-platform damper for turbines":

1. mode shapes (``figures/modes_*.png``, written by :mod:`.modes`, if present);
2. receptances: every damper of a family overlaid (Fig. 9), then each
   damper with all its forces (Fig. 10);
3. peak amplitude vs force (Fig. 11) with tables of peak amplitude and
   resonance frequency;
4. friction energy per cycle at resonance: tables (Tables 1-2) and a figure;
5. contact status: status maps (Fig. 12) at chosen forces, shares at
   resonance vs force (Fig. 13) with their table;
6. the status and energy of every pair painted on the damper (pyvista),
   for the dampers whose geometry folder is given;
7. any other PNG in ``figures/`` or CSV in ``tables/`` that was there
   before (e.g. the rig picture written by the runner);
8. one row per case: peaks, energies, stability, cost, failures.

A sweep study (``kind == "sweep"``, ``inputs["sweep"]`` names the option)
gets instead: peak amplitude and resonance frequency vs the swept value,
the table of them, for a cone-angle sweep the friction energy next to the
analytic kinematic slip, and the receptances of each damper, family and
force with one curve per swept value. Other kinds (fidelity, robustness)
get the comparison sections drawn for their base variant.

A branch that failed part-way is drawn with what it has; the captions of
the figures it appears in say so, and why.

Re-running on the same folder rewrites the figures and tables and deletes
those of its own file names (:data:`OWN_PREFIXES`, :data:`OWN_TABLE_PREFIXES`)
that the new run did not make, so the folder matches the report; other
files are never touched. The sweep sections are in :mod:`.sweep_sections`,
the builder that collects sections, figures and tables in
:mod:`.section_builder`.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

from ..post.answer import cases_table
from ..post.results import StudyResults, family_name
from ..post.tables import (
    STUCK_TEXT,
    Table,
    base_variant,
    curve_set,
    energy_split_table,
    energy_table,
    families,
    peak_amplitude_table,
    peak_frequency_table,
    pick_forces,
    slug,
    status_shares_table,
)
from . import study_figures as sf
from .palette import damper_style, verdict_caption, verdict_counts, verdicts_shown
from .section_builder import (
    FIGURES,
    OWN_PREFIXES,
    OWN_TABLE_PREFIXES,
    TABLES,
    _Builder,
    _failures,
    _fam_slug,
    _forces_text,
    _Job,
    _peak_sentence,
    _Section,
)
from .status_figures import plot_status_map, plot_status_shares
from .status_label import EXPLAINED, cone_status_label
from .sweep_sections import _sweep

log = logging.getLogger(__name__)

MODES_PREFIX = "modes_"
# also what workbench.render.modes.render_modes names its files, if written into figures/
MODEL_PREFIX = "model_"
MODE_FILE_PREFIXES = (MODEL_PREFIX, "first_bending", MODES_PREFIX, "mode_")
_LINE_WORDS = {"-": "solid", "--": "dashed", ":": "dotted", "-.": "dash-dot"}


# ---- comparison -----------------------------------------------------------------------


def _receptances(b: _Builder, variant: str) -> None:
    r = b.results
    for p in families(r):
        fam = family_name(p)
        cases = r.select(phase_deg=p, variant=variant)
        if not cases:
            continue
        dampers = list(dict.fromkeys(c.damper for c in cases))
        sec = b.section(
            f"receptances-{_fam_slug(p)}",
            f"Receptances, {fam}",
            [
                f"Harmonic-1 amplitude of the response per newton of excitation (blade 1, x) "
                f"vs excitation frequency, forces {_forces_text(r.forces)}."
            ]
            + [_peak_sentence(curve_set(r, d, p, variant)) + "." for d in dampers],
        )
        fs = f"receptance_{_fam_slug(p)}"
        if len(dampers) > 1:
            styles = ", ".join(
                f"{d} {_LINE_WORDS.get(damper_style(d)[1], '')}".strip() for d in dampers
            )
            counts = _counts(cases)
            b.figure(
                sec,
                f"{fs}_all",
                f"{fam}: receptances (harmonic-1 amplitude / F, mm/N) of every damper and "
                f"force in one axes ({styles}, open markers along each curve); "
                f"{_verdict_words(counts, band=True)}." + _failures(cases),
                lambda path, cs=cases: sf.plot_receptance_overlay(cs, path),
            )
        for d in dampers:
            own = curve_set(r, d, p, variant)
            b.figure(
                sec,
                f"{fs}_{slug(d)}",
                f"{d} damper, {fam}: receptance, harmonic-1 amplitude / F (mm/N), for every "
                f"force; {_verdict_words(_counts(own))}." + _failures(own),
                lambda path, cs=own: sf.plot_receptances(cs, path, forces=r.forces),
            )


def _counts(cases) -> dict[int, int]:
    import numpy as np

    return verdict_counts(np.concatenate([c.branch.stability for c in cases]))


def _verdict_words(counts: dict[int, int], band: bool = False) -> str:
    return verdict_caption(counts, band)


def _peaks_and_energy(b: _Builder, variant: str) -> None:
    r = b.results
    sec = b.section(
        "peaks",
        "Vibration amplitude at resonance vs excitation",
        [
            "The resonance of each curve is its largest harmonic-1 amplitude of the "
            "response (blade x at the response point): the vibration, without the mean "
            "term, which a stuck or ratcheting damper shifts. Against the excitation "
            "force, log-log: a damper that does not dissipate (a rolling cylinder) follows "
            "the grey line of slope 1; a damper that saturates flattens. max |x(t)| and the "
            "mean term at each resonance are in the table of cases."
        ],
    )
    en = b.section(
        "friction-energy",
        "Friction energy at resonance",
        [
            "Energy dissipated by friction per cycle at the resonance of each "
            "branch, summed over every contact pair, mJ; one table per family with "
            "the dampers in rows and the forces in columns, as in the paper's "
            "Tables 1-2. An energy at or below 1e-6 times the largest of its table "
            f"or figure is round-off of contacts that do not slip: it reads "
            f"'{STUCK_TEXT}' in the tables and sits in the '{STUCK_TEXT}' strip under "
            "the figure's log axis. The rig and its in- and out-of-phase loading are "
            "symmetric about the plane between the blades, so the damper's two lines "
            "should dissipate alike; the split table gives platform 1's line minus "
            "platform 2's in percent of both. A split of more than a few per cent is an "
            "asymmetric solution: mostly the mesh's, whose two halves differ "
            "(docs/notes/mesh_symmetry.md: up to 40 % on the cone in phase, moving its "
            "peak by up to 2 %); `[rig.mesh] mirror = true` meshes the halves as mirror "
            "images."
        ],
    )
    for p in families(r):
        fam = family_name(p)
        cases = r.select(phase_deg=p, variant=variant)
        if not cases:
            continue
        fsl = _fam_slug(p)
        b.figure(
            sec,
            f"peak_amplitude_{fsl}",
            f"{fam}: vibration amplitude at resonance, harmonic 1 (mm), vs excitation force "
            "(N), one curve per damper; the marker of each peak filled when stable, hollow "
            "when unstable, half filled when unknown; crosses: failed branch." + _failures(cases),
            lambda path, cs=cases: sf.plot_peak_vs_force(cs, path),
        )
        b.table(
            sec,
            f"peak_amplitude_{fsl}",
            peak_amplitude_table(r, p, variant),
            f"{fam}: vibration amplitude at resonance, harmonic 1, mm",
        )
        b.table(
            sec,
            f"peak_frequency_{fsl}",
            peak_frequency_table(r, p, variant),
            f"{fam}: resonance frequency (of the harmonic-1 peak), Hz",
        )
        b.table(
            en,
            f"friction_energy_{fsl}",
            energy_table(r, p, variant),
            f"{fam}: friction energy per cycle at resonance, mJ",
        )
        b.table(
            en,
            f"friction_energy_split_{fsl}",
            energy_split_table(r, p, variant),
            f"{fam}: the energy's split between the two platforms' lines at resonance, "
            "% of both (0 on a symmetric solution)",
        )
        b.figure(
            en,
            f"friction_energy_{fsl}",
            f"{fam}: friction energy per cycle at resonance (mJ, log) vs excitation force "
            "(N), one curve per damper." + _failures(cases),
            lambda path, cs=cases: sf.plot_energy_vs_force(cs, path),
        )


def _status(b: _Builder, variant: str) -> None:
    r = b.results
    chosen = pick_forces(r.forces)
    sec = b.section(
        "contact-status",
        "Contact status",
        [
            f"Status of every contact pair over one period along each branch at "
            f"{_forces_text(chosen)}: pairs of platform 1 (side 0) below the dashed "
            "line, platform 2 above; pairs numbered along each line from the "
            "damper's large end (cone) or -y (cylinder), row by row for the wedge. "
            "Then the share of each status at resonance against the force."
        ],
    )
    explained = False  # the sentence on the cone's label, once
    for p in families(r):
        fam = family_name(p)
        cases = r.select(phase_deg=p, variant=variant)
        if not cases:
            continue
        for d in dict.fromkeys(c.damper for c in cases):
            own = [
                c
                for c in curve_set(r, d, p, variant)
                if any(abs(c.force_n - f) <= 1e-9 * max(1.0, f) for f in chosen)
            ]
            if not own:
                continue
            label = cone_status_label(own, curve_set(r, d, p, variant))
            if label is not None and label.footnote and not explained:
                sec.text.append(EXPLAINED)
                explained = True
            b.figure(
                sec,
                f"status_map_{_fam_slug(p)}_{slug(d)}",
                f"{d} damper, {fam}: contact status of every pair vs frequency at "
                f"{_forces_text([c.force_n for c in own])} (stuck, stick-slip, partial "
                "separation, full separation); dashed black line: the resonance."
                + (label.caption if label else "")
                + _failures(own),
                lambda path, cs=own, lb=label: plot_status_map(
                    cs,
                    path,
                    panel_notes=lb.panel_notes if lb else None,
                    footnote=lb.footnote if lb else None,
                ),
            )
        b.figure(
            sec,
            f"status_shares_{_fam_slug(p)}",
            f"{fam}: share of the contact pairs in each status at resonance vs force; "
            "colour: status, line style and marker: damper." + _failures(cases),
            lambda path, cs=cases: plot_status_shares(cs, path),
        )
        b.table(
            sec,
            f"status_shares_{_fam_slug(p)}",
            status_shares_table(r, p, variant),
            f"{fam}: share of the pairs in each status at resonance, percent",
        )


def _contact_maps(b: _Builder, variant: str, geometry_dirs: dict[str, Path]) -> None:
    from .contact_maps import render_contact_maps

    r = b.results
    sec = b.section(
        "contact-maps",
        "Status and dissipation on the damper",
        [
            "Each contact pair painted at its point on the damper (seen from above "
            "the groove, the platforms left out, platform 1's contact at the bottom) "
            "at the resonance of the highest force: its status, and its friction "
            "energy per cycle in mJ, on one colour scale for every map (grey: "
            f"{STUCK_TEXT}, at or below 1e-6 of the largest); the damper in its own colour."
        ],
    )
    mapped = []
    for p in families(r):
        for d in dict.fromkeys(c.damper for c in r.select(phase_deg=p, variant=variant)):
            own = [c for c in curve_set(r, d, p, variant) if c.branch.n_points]
            if d in geometry_dirs and own:
                mapped.append((p, d, own[-1]))
    # one energy colour scale for every map: families and dampers compare by colour
    from .contact_maps import energy_scale

    scale = energy_scale([c.energy_mj[c.h1_peak_index] for _, _, c in mapped])
    for p, d, c in mapped:
        fam = family_name(p)
        stem = b.fig_dir / f"contact_{_fam_slug(p)}_{slug(d)}"
        base = f"{d} damper, {fam}, F = {c.force_n:g} N, at resonance"
        entries = [
            {
                "path": f"{FIGURES}/{stem.name}_status.png",
                "caption": f"{base}: contact status of every pair (stuck, stick-slip, "
                "partial or full separation) on the damper surface." + _failures([c]),
            },
            {
                "path": f"{FIGURES}/{stem.name}_energy.png",
                "caption": f"{base}: friction energy per cycle of every pair, mJ." + _failures([c]),
            },
        ]
        sec.figures.extend(entries)
        b.jobs.append(
            _Job(
                lambda c=c, g=geometry_dirs[d], s=stem: render_contact_maps(c, g, s, scale=scale),
                sec,
                entries,
                optional=True,
            )
        )


# ---- the answer (the report's first screen) -------------------------------------------


def _answer(b: _Builder, variant: str) -> None:
    """Which damper vibrates least at the highest force, by how much, how sure; the headline
    chart (harmonic-1 peak against force, every family) beside it."""
    from ..post.answer import answer, answer_table

    r = b.results
    ans = answer(r, variant)
    if not ans["rows"]:
        return
    sec = b.section("answer", "The answer", ans["sentences"])
    sec.kind, sec.notes = "answer", list(ans["sure"])
    b.table(
        sec,
        "answer",
        answer_table(ans["rows"]),
        f"At F = {ans['force_n']:g} N on each blade, the resonance of each curve: its largest "
        "harmonic-1 amplitude of blade 1 (x), least first; max |x(t)| and the mean of x at "
        "that same point",
        name_files=False,
    )
    cases = r.select(variant=variant)
    b.figure(
        sec,
        "answer_peak_vs_force",
        "Vibration amplitude at resonance (harmonic 1) against the force, one panel per "
        "family; peak marker filled: stable, hollow: unstable, half: unknown." + _failures(cases),
        lambda path, cs=cases: sf.plot_answer(cs, path),
    )


# ---- sweeps ---------------------------------------------------------------------------


def _screen(b: _Builder, rows: list[dict[str, Any]]) -> None:
    """The linear coupling screen of every model (workbench.assembly.screen)."""
    from ..post.screen_table import table as screen_table

    head, body = screen_table(rows)
    f_max = rows[0].get("f_max_n")
    sec = b.section(
        "screen",
        "Coupling screen (linear, seconds)",
        [
            "How much each damper stiffens each family when it sticks, from the linear stuck "
            "and sliding limits of the same reduced models: k2/k = 1 - (f_sliding/f_stuck)^2. "
            "The rig bound is the same with a rigid damper and 1000x stiffer contact, the most "
            "coupling this rig allows. Slip and separation onset are the excitation per blade "
            "at which the first pair slips or lifts off in the stuck linear response. A "
            "single-mode friction model gives the force up to which the peak stays level, "
            "(4/pi) Q k2/k times the slip onset (Q = 1/(2 damping)), and the predicted growth "
            f"of the peak from 0.32 Fmax to Fmax (Fmax = {f_max:g} N). A damper whose k2/k is "
            "a few per cent cannot level a peak off, whatever mu and the centrifugal load. "
            "These are estimates of the nonlinear curves below, not results: separation, "
            "several slipping pairs and mode-shape changes are not in them."
        ],
    )
    b.table(
        sec,
        "screen",
        Table(tuple(head), tuple(tuple(r) for r in body)),
        "Coupling screen of every damper and family",
    )
    cases = [c for c in b.results.cases if not c.variant]
    if cases and b.results.kind != "sweep":
        from .screen_figures import plot_screen_vs_curves

        b.figure(
            sec,
            "screen_vs_curves",
            "The screen's single-mode estimate of the peak against the force (dotted: linear "
            "up to the slip onset, then levelling off) and the harmonic balance's harmonic-1 "
            "peaks (solid, markers); a short bar: the screen's separation onset, which the "
            "estimate ignores.",
            lambda path, rows=rows, cs=cases: plot_screen_vs_curves(rows, cs, path),
        )


# ---- figures found on disk, the cases table -------------------------------------------


def _mode_caption(stem: str) -> str:
    """'first_bending' -> 'First bending, in-phase and out-of-phase'; 'mode_03' -> 'Mode 3';
    'modes_in-phase' -> 'Mode shape, in-phase'."""
    if stem.startswith(MODEL_PREFIX):
        return (
            f"The rig with the {stem[len(MODEL_PREFIX) :]} damper seated in the groove; "
            "contact points marked on both platforms"
        )
    if stem.startswith("first_bending"):
        return (
            "First bending, in-phase and out-of-phase: deformed rig and damper coloured "
            "by displacement magnitude"
        )
    if stem.startswith(MODES_PREFIX):
        return (
            f"First bending with the {stem[len(MODES_PREFIX) :].replace('_', ' ')} damper "
            "stuck, in-phase (left) and out-of-phase (right): deformed shapes coloured by "
            "displacement magnitude"
        )
    tail = stem[len("mode_") :]
    name = f"Mode {int(tail)}" if tail.isdigit() else "Mode " + tail.replace("_", " ")
    return name + ": deformed rig and damper coloured by displacement magnitude"


def _found_files(b: _Builder) -> tuple[_Section | None, _Section | None]:
    """Sections (not yet placed) for files already in the study folder when we start.

    Mode shapes (``figures/modes_*.png``, and ``first_bending.png`` and
    ``mode_<k>.png`` as :func:`workbench.render.modes.render_modes` names
    them) get their own section; any other PNG in ``figures/`` and any CSV
    in ``tables/`` that this module does not write go to "Other figures and
    tables", so the report shows everything the study produced.
    """
    pngs = sorted(p for p in b.fig_dir.glob("*.png") if not p.name.startswith("."))
    csvs = sorted(p for p in b.tab_dir.glob("*.csv") if not p.name.startswith("."))
    modes = [p for pre in MODE_FILE_PREFIXES for p in pngs if p.name.startswith(pre)]
    other = [p for p in pngs if not p.name.startswith((*MODE_FILE_PREFIXES, *OWN_PREFIXES))]
    other_tables = [p for p in csvs if not p.name.startswith(OWN_TABLE_PREFIXES)]
    mode_sec = other_sec = None
    if modes:
        mode_sec = _Section(
            "modes",
            "The model: rig, dampers, first bending modes",
            [
                "Each damper seated in the groove between the two platforms, "
                "and the first bending modes of the blades with it stuck: "
                "in-phase (the facing platform edges move radially relative to "
                "each other) and out-of-phase (they open and close the groove)."
            ],
        )
        for p in modes:
            mode_sec.figures.append(
                {"path": f"{FIGURES}/{p.name}", "caption": _mode_caption(p.stem) + "."}
            )
    if other or other_tables:
        other_sec = _Section("other-figures", "Other figures and tables")
        for p in other:
            other_sec.figures.append(
                {"path": f"{FIGURES}/{p.name}", "caption": p.stem.replace("_", " ")}
            )
        for p in other_tables:
            other_sec.tables.append(
                {"path": f"{TABLES}/{p.name}", "caption": p.stem.replace("_", " ")}
            )
    return mode_sec, other_sec


def _cases(b: _Builder) -> None:
    r = b.results
    notes = sf.failure_notes(r.cases)
    n_ok = sum(1 for c in r.cases if c.branch.completed and not c.branch.failed)
    counts = _counts(r.cases)
    words = ", ".join(f"{counts.get(v.code, 0)} {v.label}" for v in verdicts_shown(counts))
    text = [
        f"{len(r.cases)} cases, {n_ok} completed. Points by stability verdict (Hill's "
        f"method): {words}. Amplitudes at the resonance, the largest harmonic-1 "
        "amplitude of each curve; max |x(t)| and the mean of x at that same point."
    ]
    text += notes
    text += [f"Peak NOT reached, {c.case_id}: {c.peak_note()}." for c in r.uncovered()]
    sec = b.section("cases", "Cases", text)
    b.table(
        sec,
        "cases",
        cases_table(r),
        "Every case: resonance, vibration amplitude with max |x(t)| and the mean term, "
        "friction energy, stability at the peak and the points of each verdict, cost, curve",
    )


# ---- entry point ----------------------------------------------------------------------


def build_sections(
    results: StudyResults, study_dir: Path, *, geometry_dirs: dict[str, Path] | None = None
) -> list[dict]:
    """Write every figure and table of a study and return the report's ``sections``.

    ``study_dir`` is the study folder (figures go to ``figures/``, tables
    to ``tables/``; paths in the result are relative to it).
    ``geometry_dirs`` maps a damper name to its geometry folder (the one
    holding ``damper.msh`` and ``geometry.h5``): the status and energy of
    the pairs are painted on those dampers.
    """
    study_dir = Path(study_dir)
    geometry_dirs = {k: Path(v) for k, v in (geometry_dirs or {}).items()}
    b = _Builder(results, study_dir)
    b.fig_dir.mkdir(parents=True, exist_ok=True)
    b.tab_dir.mkdir(parents=True, exist_ok=True)
    if not results.cases:
        b.section("cases", "Cases", ["The study has no case."])
        return [s.as_dict() for s in b.sections]
    modes, other = _found_files(b)
    if results.kind != "sweep" or not results.inputs.get("sweep"):
        _answer(b, base_variant(results))
    if modes is not None:
        b.sections.append(modes)
    if results.extras.get("screen"):
        _screen(b, results.extras["screen"])
    option = results.inputs.get("sweep")
    if results.kind == "sweep" and option:
        _sweep(b, str(option), geometry_dirs)
    else:
        variant = base_variant(results)
        if len({c.variant for c in results.cases}) > 1:
            b.section(
                "variant",
                "Variant shown",
                [
                    f"The figures below show the cases of variant "
                    f"{variant or '(base settings)'!s}; the table of cases lists all."
                ],
            )
        _receptances(b, variant)
        _peaks_and_energy(b, variant)
        _status(b, variant)
        if geometry_dirs:
            _contact_maps(b, variant, geometry_dirs)
    if other is not None:
        b.sections.append(other)
    _cases(b)
    b.run()
    b.remove_stale()
    log.info(
        "wrote %d figures and %d tables under %s",
        sum(len(s.figures) for s in b.sections),
        sum(len(s.tables) for s in b.sections),
        study_dir,
    )
    return [s.as_dict() for s in b.sections]
