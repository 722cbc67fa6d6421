"""The cone's status-map label (issue 31, item 4): the slide at the middle of the contact
lines against mu N0 / kt, computed from a case record, and where the report shows it.

The synthetic case below has two lines of 9 pairs, preload 900 N per side (100 N a pair),
kt_total 1.8e9 N/m (1e8 a pair), kn_total 3.6e9 N/m (2e8 a pair), mu 0.3: the slip limit
of a pair is mu N0 / kt = 0.3 * 100 / 1e8 = 0.3 um. Its solved unknowns ``x`` hold, at the
harmonic-1 peak, tangential motion (t1 cos 0.3 um, t1 sin 0.4 um: amplitude 0.5 um) at the
5 central pairs of each line and normal motion (cos 0.1 um at the centre, sin 0.35 um at
the 2 pairs of each end): slide 0.5 um, ratio 5/3, normal load swing
2e8 * 0.1e-6 / 100 = 0.2 at the centre and 2e8 * 0.35e-6 / 100 = 0.7 at the ends.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.synthetic import synthetic_study
from workbench.errors import InputError
from workbench.hbm.core.fourier import Fourier
from workbench.hbm.forced.branch import Branch
from workbench.post.line_slide import centre_slide, limit_crossing, slip_limit_m
from workbench.post.results import CaseResult
from workbench.render.sections import build_sections
from workbench.render.status_figures import plot_status_map
from workbench.render.status_label import EXPLAINED, FINDINGS, NOTE, cone_status_label

N_LINE = 9
HARMONICS = (0, 1, 2)


def _inputs(n_pairs: int, per_side: float, kt_total: float, kn_total: float) -> dict:
    e = lambda v: {"value": v, "unit": "", "source": "test", "label": "", "group": "contact"}  # noqa: E731
    return {
        "mu": e(0.3),
        "preload_per_side": e(per_side),
        "kt_total": e(kt_total),
        "kn_total": e(kn_total),
        "n_pairs": e(n_pairs),
    }


def _motion(n_line: int, scale: float = 1.0, harmonics=HARMONICS) -> np.ndarray:
    """(nh, n_pairs, 3) harmonics of the relative displacement, see the module."""
    f = Fourier(tuple(harmonics), 16)
    n = 2 * n_line
    u = np.zeros((f.nh, n, 3))
    c, s = f.index(1, "c"), f.index(1, "s")
    u[f.index(0, "0")] = 5e-6  # the mean: not part of any amplitude
    u[f.index(2, "c")] = 4e-6  # harmonic 2: not part of the harmonic-1 amplitude
    k = (n_line - 5) // 2
    centre, ends = slice(k, k + 5), [0, 1, n_line - 2, n_line - 1]  # disjoint for 9 or more
    for line in (0, 1):
        on = np.arange(line * n_line, (line + 1) * n_line)
        u[c, on[centre], 0] = 0.3e-6 * scale
        u[s, on[centre], 0] = 0.4e-6 * scale
        u[c, on[centre], 2] = 0.1e-6
        u[s, on[ends], 2] = 0.35e-6
        u[c, on[ends], 1] = 9e-6  # the ends slide a lot: not part of the centre's slide
    return u


def line_case(
    force_n: float = 30.0,
    *,
    scale: float = 1.0,
    damper: str = "cone",
    phase_deg: float = 0.0,
    geometry: str | None = "/x/geometry/paper_rig.toml",
) -> CaseResult:
    """Three points, the middle one the harmonic-1 peak; other points hold other motion."""
    n = 2 * N_LINE
    f = Fourier(HARMONICS, 16)
    x = np.stack([_motion(N_LINE, 7.0), _motion(N_LINE, scale), _motion(N_LINE, 9.0)])
    br = Branch(
        level=force_n,
        band_hz=(380.0, 390.0),
        harmonics=HARMONICS,
        nt=16,
        output_names=("blade1_x",),
        freq_hz=np.array([383.0, 384.0, 385.0]),
        stable=np.ones(3, bool),
        out_amp=np.array([[1e-4], [2e-4], [1e-4]]),
        out_h1=np.array([[1e-4], [2e-4], [1e-4]]),
        out_harm=np.zeros((3, f.nh, 1)),
        status=np.ones((3, n), np.int8),
        friction_energy=np.zeros((3, n)),
        x=x.reshape(3, -1),
        completed=True,
    )
    pts = np.array([[s, y, 0.0] for s in (-1.0, 1.0) for y in np.linspace(0, 0.04, N_LINE)])
    return CaseResult(
        damper=damper,
        phase_deg=phase_deg,
        force_n=force_n,
        branch=br,
        points=pts,
        side=np.repeat([0, 1], N_LINE),
        params={"geometry": geometry},
        inputs=_inputs(n, 900.0, 1.8e9, 3.6e9),
    )


# ---- the numbers -------------------------------------------------------------------------


def test_slide_and_swing_equal_the_hand_values():
    s = centre_slide(line_case())
    assert s is not None
    assert s.limit_um == pytest.approx(0.3, rel=1e-12)
    assert s.slide_um == pytest.approx(0.5, rel=1e-12)
    assert s.ratio == pytest.approx(5.0 / 3.0, rel=1e-12)
    assert s.swing_centre == pytest.approx(0.2, rel=1e-12)
    assert s.swing_ends == pytest.approx(0.7, rel=1e-12)
    assert s.peak_mm == pytest.approx(0.2)


def test_the_slip_limit_is_the_pairs_mu_n0_over_kt():
    """Per pair: N0 = 900 / 9 = 100 N, kt = 1.8e9 / 18 = 1e8 N/m."""
    assert slip_limit_m(line_case()) == pytest.approx(0.3 * 100.0 / 1e8, rel=1e-12)


@pytest.mark.parametrize(
    "spoil",
    [
        lambda c: setattr(c.branch, "space", "physical"),  # unknowns are not the contacts
        lambda c: setattr(c.branch, "x", c.branch.x[:, :-3]),  # a direction left out
        lambda c: c.inputs.pop("kt_total"),
        lambda c: setattr(c, "side", np.r_[np.zeros(10, int), np.ones(8, int)]),  # unequal lines
        lambda c: setattr(c.branch, "harmonics", (0, 2, 3)),  # no harmonic 1
    ],
)
def test_no_number_without_the_data(spoil):
    c = line_case()
    spoil(c)
    assert centre_slide(c) is None


def test_limit_crossing_names_the_neighbouring_forces():
    slides = [centre_slide(line_case(f, scale=f / 10.0)) for f in (30.0, 0.96, 9.6)]
    assert [round(s.ratio, 6) for s in slides] == [5.0, 0.16, 1.6]
    assert limit_crossing(slides) == (0.96, 9.6)
    assert limit_crossing(slides[1:2]) is None


# ---- the label ---------------------------------------------------------------------------


def test_label_on_the_paper_rig_explains_and_points_to_the_note():
    cases = [line_case(9.6, scale=0.5), line_case(30.0)]
    lb = cone_status_label(cases, [line_case(3.84, scale=0.3)] + cases)
    assert lb is not None
    assert lb.panel_notes[1].splitlines() == [
        "centre slide 0.50 um = 1.67 x mu N0/kt (0.30 um)",
        "normal load swing: centre 20 %, ends 70 %",
    ]
    assert lb.panel_notes[0].startswith("centre slide 0.25 um = 0.83 x")
    assert "between 9.6 and 30 N" in lb.footnote  # ratio 0.83 at 9.6 N, 1.67 at 30 N
    for text in (lb.footnote, lb.caption):
        assert NOTE in text and FINDINGS in text and "paper-like rig" in text


def test_label_off_the_paper_rig_gives_only_the_computed_numbers():
    lb = cone_status_label([line_case(geometry=None)])
    assert lb is not None and lb.footnote is None
    assert lb.panel_notes[0].startswith("centre slide 0.50 um = 1.67 x")
    assert NOTE not in lb.caption and "paper-like" not in lb.caption


@pytest.mark.parametrize(
    "kw",
    [dict(damper="wedge"), dict(damper="cylinder"), dict(phase_deg=180.0)],
)
def test_no_label_where_it_was_not_measured(kw):
    assert cone_status_label([line_case(**kw)]) is None


def test_panel_notes_must_match_the_panels(tmp_path):
    with pytest.raises(InputError, match="panel_notes"):
        plot_status_map([line_case()], tmp_path / "x.png", panel_notes=["a", "b"])


# ---- in the report -----------------------------------------------------------------------


def _study(geometry: str | None):
    """Cone and wedge, both families, two forces; every case on ``geometry``, the cone's
    cases carrying the contact displacements of :func:`_motion` on their 23 pairs a line
    (ratio = force / 10: 0.96 at 9.6 N, 3.0 at 30 N)."""
    r = synthetic_study(dampers=("cone", "wedge"), forces=(9.6, 30.0))
    for c in r.cases:
        c.params["geometry"] = geometry
        if c.damper == "cone":
            n = len(c.side)
            u = _motion(n // 2, c.force_n / 10.0 / (5.0 / 3.0), c.branch.harmonics)
            c.branch.x = np.broadcast_to(u.reshape(-1), (c.branch.n_points, u.size)).copy()
            c.inputs = _inputs(n, 100.0 * n / 2, 1e8 * n, 2e8 * n)
    return r


def _status_section(sections):
    return next(s for s in sections if s["id"] == "contact-status")


def _caption(sec, stem):
    return next(f["caption"] for f in sec["figures"] if f["path"].endswith(f"/{stem}.png"))


def test_the_report_labels_the_cone_in_phase_map_only(tmp_path):
    sec = _status_section(build_sections(_study("/w/geometry/paper_rig.toml"), tmp_path))
    assert sec["text"].count(EXPLAINED) == 1
    cone = _caption(sec, "status_map_in-phase_cone")
    assert NOTE in cone and FINDINGS in cone and "mu N0/kt" in cone
    assert "between 9.6 and 30 N" in cone
    for stem in (
        "status_map_out-of-phase_cone",
        "status_map_in-phase_wedge",
        "status_map_out-of-phase_wedge",
    ):
        cap = _caption(sec, stem)
        assert NOTE not in cap and "mu N0/kt" not in cap, stem
    assert (tmp_path / "figures" / "status_map_in-phase_cone.png").is_file()


def test_the_heavy_rig_report_has_the_numbers_but_not_the_explanation(tmp_path):
    sec = _status_section(build_sections(_study(None), tmp_path))
    assert EXPLAINED not in sec["text"]
    cone = _caption(sec, "status_map_in-phase_cone")
    assert "mu N0/kt" in cone and NOTE not in cone
