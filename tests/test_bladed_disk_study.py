"""The bladed-disk study kind (issue 29, item 5) on a tiny disk: 6 blades, the coarse
paper-like mesh, one damper, two engine orders (EO 1 forward and EO 5 backward, both at
ND 1), one force. Its peaks are the sector forced response's own, its answer table is the
argmax of its peaks, a second run reuses every case, and bad input is refused in one line
naming the option."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

from workbench.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
STUDY = """
name = "bd_tiny"
kind = "bladed_disk"
dampers = ["cylinder"]
forces = [30.0]
geometry = "{geometry}"
mesh-size = 25.0
contact-mesh-size = 8.0
damper-mesh-size = 10.0
contact-points = 3
harmonics = [0, 1, 2, 3]
damping = 0.005
n-blades = 6
eos = [1, 5]
sector-modes = 4
damper-modes = 3
fan-families = 2
"""


def _spec(tmp: Path, **change: str):
    from workbench.studies.engine.spec import load_study

    text = STUDY.format(geometry=ROOT / "geometry" / "paper_rig.toml")
    for k, v in change.items():
        text = "\n".join(
            f"{k} = {v}" if line.startswith(f"{k} =") else line for line in text.splitlines()
        )
    path = tmp / "study.toml"
    path.write_text(text)
    return load_study(path)


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    from workbench.studies.kinds import get

    tmp = tmp_path_factory.mktemp("bd")
    spec = _spec(tmp)
    out = tmp / "out"
    t0 = time.perf_counter()
    first = get("bladed_disk").run(spec, out, False)
    t1 = time.perf_counter()
    second = get("bladed_disk").run(spec, out, False)
    t2 = time.perf_counter()
    return spec, out, first, second, (t1 - t0, t2 - t1)


def test_peaks_are_the_sector_forced_response(study):
    """Each case's peak (amplitude, frequency, friction energy) is sector_forced_response's
    on the same sector model (to the 9 digits of the CSV); EO 5 of 6 blades is ND 1
    travelling backward."""
    import csv

    from workbench.assembly.params import load_contact_params
    from workbench.geometry.disk_build import DiskSector
    from workbench.hbm.core.options import SolverOptions
    from workbench.pipeline.sector import build_sector_model, sector_forced_response
    from workbench.studies.kinds.bladed_disk.compute import DC_WEIGHT

    spec, out, first, _, _ = study
    assert first["eo_nd"] == {
        "1": {"nd": 1, "direction": "forward"},
        "5": {"nd": 1, "direction": "backward"},
    }
    rows = list(csv.DictReader(open(out / "tables" / "bladed_disk_cases.csv")))
    assert [(int(r["eo"]), r["direction"]) for r in rows] == [(1, "forward"), (5, "backward")]
    rec = DiskSector.load(out / "cache" / "disk" / "cylinder" / "disk.h5")
    cp = load_contact_params(geometry_file=spec.geometry)
    # the study's modal damping is its `damping` option
    model = build_sector_model(rec, cp, None, n_modes=4, n_damper_modes=3, zeta=float(spec.damping))
    opts = SolverOptions(dc_weight=DC_WEIGHT)
    for r in rows:
        br, _ = sector_forced_response(model, int(r["eo"]), 30.0, None, (0, 1, 2, 3), options=opts)
        i = int(br.out_amp[:, 0].argmax())
        assert float(r["peak_m"]) == pytest.approx(br.out_amp[i, 0], rel=1e-8)
        assert float(r["peak_hz"]) == pytest.approx(br.freq_hz[i], rel=1e-8)  # CSV: 9 digits
        assert float(r["friction_energy_j"]) == pytest.approx(br.friction_energy[i].sum(), rel=1e-8)
        assert float(r["friction_energy_j"]) > 0.0  # 30 N: the cylinder slips at the peak


def test_answer_is_the_argmax_and_the_results_carry_units(study):
    import h5py

    _, out, first, _, _ = study
    with h5py.File(out / "bladed_disk.h5") as h:
        peaks = h["peak_m"][0, 0]
        eos = list(h["eos"][:])
        assert h["peak_m"].attrs["unit"] == "m"
        assert h["friction_energy_j"].attrs["unit"] == "J"
        assert h["fan_stuck_hz/cylinder"].attrs["unit"] == "Hz"
    (w,) = first["worst"]
    assert w["worst_eo"] == eos[int(np.argmax(peaks))]
    assert w["worst_peak_m"] == peaks.max()
    assert [b["best_damper"] for b in first["best"]] == ["cylinder", "cylinder"]
    for name in ("peaks", "energy", "fan"):
        assert (out / "figures" / f"bladed_disk_{name}.png").stat().st_size > 10_000
    assert (out / "report.html").is_file()


def test_second_run_reuses_every_case(study):
    _, _, first, second, (t_first, t_second) = study
    assert first["n_computed"] == 2 and first["n_reused"] == 0
    assert second["n_computed"] == 0 and second["n_reused"] == 2
    assert second["worst"] == first["worst"]
    assert t_second < t_first


@pytest.mark.parametrize(
    "change, name",
    [({"eos": "[-1]"}, "eos"), ({"eos": "[1.5]"}, "eos"), ({"n-blades": "1"}, "n-blades")],
)
def test_bad_input_names_the_option(tmp_path, change, name):
    with pytest.raises(InputError) as e:
        _spec(tmp_path, **change)
    assert e.value.param.startswith(name)
    assert "\n" not in str(e.value)


def test_screen_per_nd_is_the_rigs_screen_generalised(study):
    """k2/k per ND: the stuck family is the case's own first stuck frequency at that ND; the
    sliding limit lies below the stuck one except where the cylinder rolls (ND 0: k2/k ~ 0,
    the rig's in-phase rolling finding, slightly negative: the stuck cylinder adds mass, no
    stiffness); the damper stiffens the family more as the inter-blade phase grows."""
    import csv

    _, out, first, _, _ = study
    rows = list(csv.DictReader(open(out / "tables" / "bladed_disk_screen.csv")))
    assert [int(r["nd"]) for r in rows] == [0, 1, 2, 3]
    k2k = np.array([float(r["k2_over_k"]) for r in rows])
    st = np.array([float(r["stuck_hz"]) for r in rows])
    sl = np.array([float(r["sliding_hz"]) for r in rows])
    np.testing.assert_allclose(k2k, 1 - (sl / st) ** 2, atol=1e-8)  # CSV: 9 digits
    assert abs(k2k[0]) < 0.005  # ND 0: the cylinder rolls
    assert np.all(k2k[1:] > 0.3) and np.all(st[1:] > sl[1:])
    assert np.all(np.diff(k2k) > 0)
    # the case's stuck frequency (its band's centre) is the screen's stuck family at ND 1
    case = next(c for c in csv.DictReader(open(out / "tables" / "bladed_disk_cases.csv")))
    assert float(case["stuck_hz"]) == pytest.approx(st[1], rel=1e-8)
    assert first["screen"][1]["k2_over_k"] == pytest.approx(k2k[1], rel=1e-8)
    assert (out / "figures" / "bladed_disk_k2k.png").stat().st_size > 10_000
    # the rig's onset forces: a case that slips at its peak is above the stuck response's
    # slip onset (below it the stuck linear solution would hold everywhere), and its
    # friction holds the peak below the stuck linear one (stuck receptance times force)
    (w,) = first["worst"]
    row = first["screen"][w["nd"]]
    assert 0 < row["f_slip_n"] <= w["force_n"]
    assert w["worst_peak_m"] < row["stuck_peak_m_per_n"] * w["force_n"]


def test_worst_peak_field_and_status(study):
    """The sector field at the worst peak, expanded from the stored unknowns, gives the
    case's peak at the response point (VTU included); the status at the peak counts every
    pair, and a slipping pair goes with friction energy."""
    import json

    import pyvista as pv

    _, out, first, _, _ = study
    (w,) = first["worst"]
    (f,) = first["worst_peak_field"]
    assert (f["eo"], f["force_n"]) == (w["worst_eo"], w["force_n"])
    assert f["field_peak_m"] == pytest.approx(w["worst_peak_m"], rel=1e-9)
    g = pv.read(f["vtu"])
    assert g.n_points > 1000 and int(g.field_data["eo"][0]) == w["worst_eo"]
    rn = int(g.field_data["response_node"][0])
    # the period's largest |u| at the response node is at least its peak along the excitation
    assert g.point_data["disp_max_mm"][rn] >= w["worst_peak_m"] * 1e3 * (1 - 1e-9)
    u = np.asarray(g.point_data["disp_at_peak_instant_mm"])[rn]
    assert abs(u[0]) == pytest.approx(w["worst_peak_m"] * 1e3, rel=1e-4)  # x: the excitation
    r = np.hypot(g.points[:, 0], g.points[:, 2])
    bore = r < r.min() + 1e-9  # the clamped bore does not move
    assert bore.sum() > 10 and np.all(np.asarray(g.point_data["disp_max_mm"])[bore] == 0.0)
    cases = [json.loads(p.read_text()) for p in (out / "cache" / "bladed_disk").glob("*.json")]
    cases = [c for c in cases if "status_at_peak" in c]
    assert len(cases) == 2
    for c in cases:
        n_pairs = len(c["side"])
        assert sum(c["status_at_peak"].values()) == n_pairs
        i = int(np.argmax(c["amp_m"]))
        assert c["status_at_peak"]["stick-slip"] == sum(s == 1 for s in c["status"][i])
        slips = c["status_at_peak"]["stick-slip"] + c["status_at_peak"]["partial separation"]
        assert (c["friction_energy_j"] > 1e-9) == (slips > 0)
    assert (out / "figures" / "bladed_disk_status.png").stat().st_size > 10_000


def test_worst_peak_on_the_whole_disk(study):
    """The worst peak's travelling wave put on every sector and damper solves the whole
    disk up to the AFT's sampling (a wrong phase convention leaves an O(1) residual); Newton
    polishes it to round-off, the response point keeps its amplitude to 1e-3, and Hill's
    method on the whole disk gives a verdict with its count check passed."""
    _, _, first, _, _ = study
    (f,) = first["worst_peak_field"]
    s = f["stability"]
    assert s["mapped_residual"] < 1e-2
    assert s["polished_residual"] < 1e-10
    assert s["disk_peak_m"] == pytest.approx(f["peak_m"], rel=1e-3)
    assert s["verdict"] in ("stable", "unstable") and s["count_ok"], s
    assert (s["verdict"] == "unstable") == (s["max_real"] > 0)
