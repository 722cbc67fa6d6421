"""Study figures, tables and report sections, on synthetic results shaped like real ones.

Image regression: :func:`test_image_regression` draws a small fixed case
(the wedge's in-phase receptances and status map of :mod:`tests.synthetic`:
a fold with an unstable part, a branch that failed, all four statuses)
and compares each PNG with the reference in ``tests/data/`` by a normalised
pixel difference (RGB in 0..1): the mean absolute difference over all
pixels must stay below ``MEAN_TOL`` (2 %) and at most ``INK_TOL`` (5 %) of
the *inked* pixels (not background in either image) may differ by more than
``PIXEL_TOL`` (10 %). The second criterion is the binding one: a line
figure is mostly white, so a moved curve hardly changes the mean, while a
share of the inked pixels catches it (a 0.2 % shift of the frequencies
already changes about 10 % of them; the test after it checks that a 2 %
shift fails). The references are made with this environment's matplotlib
(3.10, Agg, the fixed style of :func:`workbench.render.common.pyplot`);
after an intended change of the figures, or a matplotlib upgrade that moves
anti-aliasing, regenerate the references with::

    UPD_REGEN_IMAGES=1 .venv/bin/python -m pytest tests/test_study_figures.py -k regression

and look at them before committing.
"""

from __future__ import annotations

import copy
import csv
import json
import os
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import assert_nonblank
from tests.synthetic import synthetic_case, synthetic_study, synthetic_sweep
from workbench.errors import InputError
from workbench.post.tables import (
    curve_set,
    energy_table,
    peak_curve,
    pick_forces,
    sci,
    stability_runs,
    status_share_curves,
    sweep_curve,
)
from workbench.render import study_figures as sf
from workbench.render.common import pyplot, save_figure
from workbench.render.report import render_html
from workbench.render.sections import build_sections
from workbench.render.status_figures import plot_status_map
from workbench.render.sweep_figures import option_label

DATA = Path(__file__).resolve().parent / "data"
MEAN_TOL = 0.02  # mean |difference| over all pixels (largest channel), fraction of full scale
INK_TOL = 0.05  # largest share of the inked pixels differing by more than PIXEL_TOL
PIXEL_TOL = 0.10
INK = 0.9  # a pixel is inked when one of its channels is darker than this


# ---- helpers ------------------------------------------------------------------------------


def image_difference(a: Path, b: Path) -> tuple[float, float]:
    """(mean absolute difference, share of inked pixels off by more than PIXEL_TOL).

    RGB in 0..1, the largest channel difference per pixel. Images of
    different sizes are as different as can be: (1.0, 1.0).
    """
    import matplotlib.image as mpimg

    x = np.asarray(mpimg.imread(str(a)), dtype=float)[..., :3]
    y = np.asarray(mpimg.imread(str(b)), dtype=float)[..., :3]
    if x.shape != y.shape:
        return 1.0, 1.0
    d = np.abs(x - y).max(axis=-1)
    ink = (x.min(axis=-1) < INK) | (y.min(axis=-1) < INK)
    return float(d.mean()), float(np.mean(d[ink] > PIXEL_TOL)) if ink.any() else 0.0


def images_match(a: Path, b: Path) -> bool:
    mean, ink_share = image_difference(a, b)
    return mean < MEAN_TOL and ink_share < INK_TOL


@pytest.fixture(scope="module")
def study():
    """3 dampers x 2 families x 3 forces; the wedge's in-phase 9.6 N branch fails part-way."""
    return synthetic_study(fail=("wedge", 0.0, 9.6))


@pytest.fixture(scope="module")
def built(study, tmp_path_factory):
    """build_sections of the comparison study, with a mode-shape PNG, a rig PNG and a timings
    table already in the folder (as the study runner may have written them)."""
    root = tmp_path_factory.mktemp("study")
    plt = pyplot()
    for name, color in (
        ("modes_in-phase", "C0"),
        ("mode_02", "C1"),
        ("first_bending", "C2"),
        ("rig_cone", "C3"),
    ):
        fig, ax = plt.subplots(figsize=(3, 2))
        ax.plot([0, 1, 2], [0, 1, 0], color=color, lw=4)
        (root / "figures").mkdir(exist_ok=True)
        save_figure(fig, root / "figures" / f"{name}.png")
    (root / "tables").mkdir(exist_ok=True)
    (root / "tables" / "timings.csv").write_text("stage,wall time (s)\nhbm,12.5\n")
    sections = build_sections(study, root)
    return root, sections


# ---- numbers and tables ------------------------------------------------------------------


def test_sci_writes_like_the_paper():
    assert sci(0.0114) == "1.1e-2"
    assert sci(2.3e-22) == "2.3e-22"
    assert sci(0.33) == "3.3e-1"
    assert sci(12.0) == "1.2e1"
    assert sci(0.0) == "0" and sci(float("nan")) == "n/a"
    assert float(sci(5.83e-2)) == pytest.approx(5.8e-2)


def test_stability_runs_join_and_cover_the_branch():
    stable = np.array([1, 1, 1, 0, 0, 1, 1, 0, 1], bool)
    runs = stability_runs(stable)
    # consecutive runs share a point, the first starts at 0 and the last ends at the end
    assert runs[0][0].start == 0 and runs[-1][0].stop == stable.size
    for (a, _), (b, _) in zip(runs[:-1], runs[1:], strict=True):
        assert b.start == a.stop - 1
    # a segment is unstable when either end is: [0-2] s, [2-5] u, [5-6] s, [6-8] u
    assert [(s.start, s.stop, ok) for s, ok in runs] == [
        (0, 3, True),
        (2, 6, False),
        (5, 7, True),
        (6, 9, False),
    ]
    assert stability_runs(np.ones(4, bool)) == [(slice(0, 4), True)]
    assert stability_runs(np.zeros(0, bool)) == []


def test_peaks_follow_the_physics_of_each_damper(study):
    # the rolling cylinder in-phase is linear: peak amplitude proportional to the force
    cyl = peak_curve(curve_set(study, "cylinder", 0.0))
    ratio = cyl.amp_mm / cyl.force_n
    assert np.ptp(ratio) / ratio.mean() < 1e-3
    assert np.all(cyl.energy_mj < 1e-15)  # round-off only: no slip
    # the cone dissipates: its peak receptance falls by more than 5x from 0.96 N to 30 N
    cone = peak_curve(curve_set(study, "cone", 0.0))
    rec = cone.amp_mm / cone.force_n
    assert rec[0] / rec[-1] > 5.0
    assert np.all(np.diff(cone.energy_mj) > 0)  # energy grows with force
    wedge = peak_curve(curve_set(study, "wedge", 0.0))
    assert wedge.failed.tolist() == [False, True, False]


def test_energy_table_is_tables_1_2(study):
    t = energy_table(study, 180.0)
    assert t.header == (
        "damper: friction energy per cycle (mJ) at force",
        "0.96 N",
        "9.6 N",
        "30 N",
    )
    assert [r[0] for r in t.rows] == ["cone", "cylinder", "wedge"]
    for row in t.rows:
        for cell, c in zip(row[1:], curve_set(study, row[0], 180.0), strict=True):
            expected = c.energy_mj[c.h1_peak_index].sum()  # at the resonance (harmonic-1 peak)
            assert float(cell) == pytest.approx(expected, rel=0.005)  # three significant digits
    md = t.markdown_text()
    assert md.splitlines()[1] == "|---|---:|---:|---:|"
    # the failed in-phase branch is marked in its cell
    cell = energy_table(study, 0.0).rows[2][2]
    assert cell.endswith("(failed)")


def test_energy_split_table_gives_each_lines_share(study):
    """Platform 1's line minus platform 2's, % of both, at the harmonic-1 peak; a contact
    that does not slip (the stuck cylinder in phase) has no split."""
    from workbench.post.tables import STUCK_TEXT, energy_split_table

    for phase in (0.0, 180.0):
        t = energy_split_table(study, phase)
        assert t.header[0].startswith("damper: energy on platform 1's line")
        for row in t.rows:
            for cell, c in zip(row[1:], curve_set(study, row[0], phase), strict=True):
                e = c.energy_mj[c.h1_peak_index]
                e1, e2 = e[c.side == 0].sum(), e[c.side == 1].sum()
                if e1 + e2 <= 1e-3:
                    assert cell.startswith(STUCK_TEXT), (row[0], phase, cell)
                    continue
                value = float(cell.split()[0])
                assert value == pytest.approx((e1 - e2) / (e1 + e2) * 100, abs=0.05)
                assert c.summary()["h1_friction_energy_split_pct"] == pytest.approx(
                    (e1 - e2) / (e1 + e2) * 100, rel=1e-12
                )


def test_status_shares_and_forces(study):
    forces, shares = status_share_curves(curve_set(study, "cone", 0.0))
    total = sum(shares.values())
    np.testing.assert_allclose(total, 1.0)
    assert shares["stick_slip"][-1] > shares["stick_slip"][0]  # more slip at higher force
    assert pick_forces([0.096, 9.6, 30.0]) == [9.6, 30.0]
    assert pick_forces([1.0, 2.0, 5.0]) == [1.0, 5.0]
    assert pick_forces([3.0]) == [3.0]


def test_figures_refuse_mixed_cases(study, tmp_path):
    with pytest.raises(InputError, match="one damper and one family"):
        sf.plot_receptances(study.select(phase_deg=0.0), tmp_path / "x.png")
    with pytest.raises(InputError, match="one family"):
        sf.plot_peak_vs_force(study.cases, tmp_path / "x.png")


def test_option_labels_come_from_the_study_options():
    assert option_label("cf") == ("centrifugal force on the damper", "N")
    assert option_label("cone-angle") == ("cone semi-angle", "deg")
    assert option_label("mu") == ("friction coefficient", "-")


# ---- the report sections ----------------------------------------------------------------


def test_every_figure_is_written_and_nonblank(built):
    root, sections = built
    figures = [f for s in sections for f in s["figures"]]
    assert len(figures) >= 20
    for f in figures:
        assert_nonblank(root / f["path"])
        assert f["caption"]
    ids = [s["id"] for s in sections]
    # the answer first (the report's first screen), then the model
    assert ids[:2] == ["answer", "modes"] and ids[-1] == "cases" and "other-figures" in ids
    assert ids.index("other-figures") == len(ids) - 2
    modes = sections[1]
    assert [f["path"] for f in modes["figures"]] == [
        "figures/first_bending.png",
        "figures/modes_in-phase.png",
        "figures/mode_02.png",
    ]
    assert modes["figures"][2]["caption"].startswith("Mode 2:")
    other = sections[ids.index("other-figures")]
    assert [f["path"] for f in other["figures"]] == ["figures/rig_cone.png"]
    assert [t["path"] for t in other["tables"]] == ["tables/timings.csv"]
    for fam in ("in-phase", "out-of-phase"):
        for d in ("cone", "cylinder", "wedge"):
            assert (root / "figures" / f"receptance_{fam}_{d}.png").is_file()
            assert (root / "figures" / f"status_map_{fam}_{d}.png").is_file()
        for stem in (
            "receptance_{}_all",
            "peak_amplitude_{}",
            "friction_energy_{}",
            "status_shares_{}",
        ):
            assert (root / "figures" / f"{stem.format(fam)}.png").is_file()


def test_failed_branch_is_drawn_and_explained(built, study):
    root, sections = built
    failed = study.select(damper="wedge", phase_deg=0.0, force_n=9.6)[0]
    assert failed.branch.n_points > 10
    caps = [
        f["caption"]
        for s in sections
        for f in s["figures"]
        if "receptance_in-phase_wedge" in f["path"]
    ]
    assert len(caps) == 1 and "failed" in caps[0] and "DIVERGED_LINE_SEARCH" in caps[0]
    cases = next(s for s in sections if s["id"] == "cases")
    assert any("DIVERGED_LINE_SEARCH" in t for t in cases["text"])


def test_html_contains_every_figure_and_table(built):
    root, sections = built
    html = render_html({"title": "synthetic", "sections": sections}, root)
    pngs = sorted(p.relative_to(root).as_posix() for p in (root / "figures").glob("*.png"))
    csvs = sorted(p.relative_to(root).as_posix() for p in (root / "tables").glob("*.csv"))
    mds = sorted(p.relative_to(root).as_posix() for p in (root / "tables").glob("*.md"))
    assert len(pngs) >= 20 and len(csvs) >= 9
    for p in pngs:
        assert f"data-file='{p}'" in html, p
    listed = {t["path"] for s in sections for t in s["tables"]}
    assert listed == set(csvs)
    # every table of ours also as markdown (timings.csv is the runner's)
    assert {m[:-3] for m in mds} == {c[:-4] for c in csvs} - {"tables/timings"}
    # the cells of every table are in the page
    for c in csvs:
        with (root / c).open() as fh:
            rows = list(csv.reader(fh))
        assert len(rows) >= 2
        for cell in rows[1]:
            if cell:
                assert f"<td>{cell}</td>" in html or f"<th>{cell}</th>" in html, (c, cell)


def test_one_damper_one_family_one_force(tmp_path):
    r = synthetic_study(dampers=("cone",), phases=(180.0,), forces=(9.6,))
    sections = build_sections(r, tmp_path)
    figures = [f["path"] for s in sections for f in s["figures"]]
    assert not any(p.endswith("_all.png") for p in figures)  # no overlay of one damper
    assert "figures/receptance_out-of-phase_cone.png" in figures
    assert "figures/status_map_out-of-phase_cone.png" in figures
    for p in figures:
        assert_nonblank(tmp_path / p)
    table = (tmp_path / "tables" / "friction_energy_out-of-phase.csv").read_text().splitlines()
    assert len(table) == 2 and table[1].startswith("cone,")


def test_any_phase_family_gets_its_own_files(tmp_path):
    c = synthetic_case("cone", 180.0, 9.6)
    c90 = copy.deepcopy(c)
    c90.phase_deg = 90.0
    r = synthetic_study(dampers=("cone",), phases=(180.0,), forces=(9.6,))
    r.cases.append(c90)
    sections = build_sections(r, tmp_path)
    titles = [s["title"] for s in sections]
    assert "Receptances, phase 90 deg" in titles
    assert (tmp_path / "figures" / "receptance_phase-90deg_cone.png").is_file()


@pytest.mark.parametrize(
    "option,values", [("cf", (50.0, 100.0, 200.0)), ("cone-angle", (5.0, 10.0, 15.0, 20.0))]
)
def test_sweep_sections(tmp_path, option, values):
    r = synthetic_sweep(option, values, dampers=("cone", "wedge"))
    sections = build_sections(r, tmp_path)
    figures = [f["path"] for s in sections for f in s["figures"]]
    assert f"figures/sweep_{option}.png" in figures
    assert (f"figures/sweep_{option}_energy_slip.png" in figures) == (option == "cone-angle")
    for p in figures:
        assert_nonblank(tmp_path / p)
    with (tmp_path / "tables" / f"sweep_{option}.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 2 * 2 * len(values)  # dampers x families x values
    cone = [row for row in rows if row["damper"] == "cone" and row["family"] == "in-phase"]
    assert [float(row[option]) for row in cone] == list(values)
    sc = sweep_curve(r.select(damper="cone", phase_deg=0.0), option)
    np.testing.assert_allclose(
        [float(row["vibration amplitude, harmonic 1 (mm)"]) for row in cone],
        sc.amp_mm,
        rtol=1e-3,  # four significant digits
    )
    if option == "cf":
        # a larger preload holds the contacts longer: less slip, higher peak
        assert np.all(np.diff(sc.amp_mm) > 0)


def test_sections_manifest_is_json(built):
    _, sections = built
    back = json.loads(json.dumps(sections))
    assert back == sections
    for s in sections:
        keys = {"id", "title", "text", "figures", "tables"}
        assert set(s) == (keys | {"kind", "notes"} if s["id"] == "answer" else keys)


# ---- image regression --------------------------------------------------------------------


def _regression_case():
    """The fixed small case: wedge, in-phase, three forces (seed 0), 9.6 N failing."""
    r = synthetic_study(
        dampers=("wedge",), phases=(0.0,), forces=(0.96, 9.6, 30.0), fail=("wedge", 0.0, 9.6)
    )
    return r, curve_set(r, "wedge", 0.0)


REGRESSION = {
    "ref_receptance_wedge_in-phase.png": lambda cases, forces, path: sf.plot_receptances(
        cases, path, forces=forces
    ),
    "ref_status_map_wedge_in-phase.png": lambda cases, forces, path: plot_status_map(
        cases[1:], path
    ),
}


@pytest.mark.parametrize("name", sorted(REGRESSION))
def test_image_regression(tmp_path, name):
    """Compare with tests/data/<name>; UPD_REGEN_IMAGES=1 rewrites the reference."""
    r, cases = _regression_case()
    out = REGRESSION[name](cases, r.forces, tmp_path / name)
    ref = DATA / name
    if os.environ.get("UPD_REGEN_IMAGES") == "1":
        DATA.mkdir(exist_ok=True)
        ref.write_bytes(out.read_bytes())
    assert ref.is_file(), f"missing reference {ref}: run with UPD_REGEN_IMAGES=1"
    mean, ink_share = image_difference(out, ref)
    assert mean < MEAN_TOL and ink_share < INK_TOL, (
        f"{name} differs from its reference: mean {mean:.4f} (< {MEAN_TOL}), inked pixels "
        f"changed {ink_share:.4f} (< {INK_TOL}); if intended, regenerate with "
        "UPD_REGEN_IMAGES=1"
    )


def test_image_regression_catches_a_visible_change(tmp_path):
    """The same figure with the resonances moved 2 % up in frequency must fail the check."""
    r, cases = _regression_case()
    moved = copy.deepcopy(cases)
    for c in moved:
        c.branch.freq_hz = c.branch.freq_hz * 1.02
    a = sf.plot_receptances(moved, tmp_path / "moved.png", forces=r.forces)
    ref = DATA / "ref_receptance_wedge_in-phase.png"
    assert ref.is_file()
    mean, ink_share = image_difference(a, ref)
    assert not images_match(a, ref), (mean, ink_share)
    assert ink_share > 2 * INK_TOL  # not a near miss
    # the unchanged drawing passes: the check is not simply strict
    b = sf.plot_receptances(cases, tmp_path / "same.png", forces=r.forces)
    assert images_match(b, ref)


def test_a_branch_that_failed_at_its_first_point(tmp_path):
    """No point at all: every figure still draws, the captions and the tables say so."""
    from workbench.hbm.forced.branch import _ARRAYS

    r = synthetic_study(dampers=("cone", "wedge"), phases=(0.0,), forces=(9.6, 30.0))
    dead = r.select(damper="wedge", force_n=30.0)[0]
    for name in _ARRAYS:
        setattr(dead.branch, name, getattr(dead.branch, name)[:0])
    dead.branch.failed, dead.branch.completed = True, False
    dead.branch.message = "no converged point at the band's start"
    sections = build_sections(r, tmp_path)
    for f in (f for s in sections for f in s["figures"]):
        assert_nonblank(tmp_path / f["path"])
    caps = " ".join(f["caption"] for s in sections for f in s["figures"])
    assert "failed after 0 points" in caps and "no converged point" in caps
    table = (tmp_path / "tables" / "friction_energy_in-phase.csv").read_text()
    assert "n/a (failed)" in table


def test_rerun_keeps_the_folder_in_step(tmp_path):
    """A second run with fewer cases removes our stale files and keeps everyone else's."""
    build_sections(
        synthetic_study(dampers=("cone", "wedge"), phases=(0.0,), forces=(9.6,)), tmp_path
    )
    assert (tmp_path / "figures" / "receptance_in-phase_wedge.png").is_file()
    (tmp_path / "figures" / "rig.png").write_bytes(
        (tmp_path / "figures" / "receptance_in-phase_wedge.png").read_bytes()
    )
    sections = build_sections(
        synthetic_study(dampers=("cone",), phases=(180.0,), forces=(9.6,)), tmp_path
    )
    shown = {f["path"] for s in sections for f in s["figures"]}
    on_disk = {p.relative_to(tmp_path).as_posix() for p in (tmp_path / "figures").glob("*")}
    assert shown == on_disk and "figures/rig.png" in shown
    assert not (tmp_path / "tables" / "friction_energy_in-phase.csv").exists()
    assert (tmp_path / "tables" / "friction_energy_out-of-phase.md").is_file()
