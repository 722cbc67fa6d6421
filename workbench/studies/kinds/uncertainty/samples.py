"""The uncertainty study's samples: distributions from the study, one case per design row.

:func:`study_distributions` reads and checks the uncertain inputs'
distributions; :func:`plan_samples` turns each design row of each damper
and family into a runner case (its settings the row's absolute values,
its digest also covering the seat tilt and the imperfection model);
:func:`prepare_sample` re-makes only what a sample changes on its damper's
base model (contact values, preloads, damping): nothing is re-meshed or
re-reduced.
"""

from __future__ import annotations

import dataclasses
import functools
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ....errors import InputError
from ....io import digest
from ....post.uncertainty import Design, Distribution
from ...engine.plan import Case, make_case
from ...engine.spec import StudySpec
from .options import uq_distribution


def study_distributions(spec: StudySpec) -> dict[str, Distribution]:
    """The distributions of the study's uncertain inputs (``uq-inputs``), checked."""
    out: dict[str, Distribution] = {}
    for name in spec.uncertainty.uq_inputs:
        out[name] = uq_distribution(spec, name)
    if not out:
        raise InputError("uq-inputs", spec.uncertainty.uq_inputs, "at least one uncertain input")
    return out


@functools.lru_cache(maxsize=1)
def imperfection_code() -> str:
    from ....io import code_version

    return code_version(Path(__file__).resolve().parent, ("imperfection.py",))


@dataclass(frozen=True)
class Sample:
    """One design row of one damper and family: its case and its seat tilt."""

    case: Case
    row: int
    tilt_deg: float
    inputs: dict[str, float]  # the row's values by input name (physical units)


def nominal_contact(spec: StudySpec):
    """The nominal contact parameters: the study's options, else geometry/contact.toml (a
    study's geometry file's ``[contact]`` table is not read here)."""
    from ....assembly.params import load_contact_params
    from ....post.provenance import contact_args  # the options' map to the contact fields

    return load_contact_params(**{**contact_args(spec.as_dict()), "geometry_file": None})


def sample_settings(base: dict[str, Any], nominal, x: dict[str, float]) -> dict[str, Any]:
    """The study settings of one sample: absolute contact values and damping."""
    s = dict(base)
    s["mu"] = float(x.get("mu", nominal.mu))
    s["cf"] = float(nominal.cf_n * x.get("cf", 1.0))
    kt, kn = x.get("kt", 1.0), x.get("kn", 1.0)
    s["kt-line"] = float(nominal.kt_line_n_per_m2 * kt)
    s["kt-face"] = float(nominal.kt_face_n_per_m3 * kt)
    s["kn-line"] = float(nominal.kn_line_n_per_m2 * kn)
    s["kn-face"] = float(nominal.kn_face_n_per_m3 * kn)
    s["damping"] = float(x.get("damping", base["damping"]))
    return s


def sample_case(
    damper: str, phase: float, force: float, settings: dict[str, Any], tilt_deg: float, variant: str
) -> Case:
    """A runner case whose digest also covers the seat tilt and the imperfection model."""
    c = make_case(damper, phase, force, settings, variant)
    d = (
        c.digest
        if tilt_deg == 0.0
        else digest(
            {"case": c.digest, "seat_tilt_deg": float(tilt_deg), "model": imperfection_code()}
        )
    )
    return dataclasses.replace(c, digest=d)


# only the study-wide settings that shape a sample's answer enter its case: the
# uncertainty options themselves do not (a sample's values are in its settings)
_UQ_OPTIONS = (
    "uq-inputs",
    "uq-mu",
    "uq-cf",
    "uq-kt",
    "uq-kn",
    "uq-damping",
    "uq-seat-tilt",
    "uq-samples",
    "uq-seed",
    "uq-threshold",
    "uq-schedule",
)


def base_settings(spec: StudySpec) -> dict[str, Any]:
    s = spec.as_dict()
    for k in _UQ_OPTIONS + ("name", "kind", "dampers", "phases", "forces"):
        s.pop(k, None)
    return s


def plan_samples(spec: StudySpec, design: Design) -> list[Sample]:
    """Every sample of the study: damper x family x design row, in a stable order."""
    if len(spec.forces) != 1:
        raise InputError(
            "forces", spec.forces, "exactly one excitation level, N, for an uncertainty study"
        )
    nominal = nominal_contact(spec)
    base = base_settings(spec)
    force = float(spec.forces[0])
    out = []
    for damper in spec.dampers:
        for phase in spec.phases:
            for r in range(design.n_rows):
                x = {k: float(design.values[r, j]) for j, k in enumerate(design.names)}
                s = sample_settings(base, nominal, x)
                tilt = float(x.get("seat-tilt", 0.0))
                s["seat-tilt"] = tilt
                c = sample_case(damper, phase, force, s, tilt, f"s{r}")
                out.append(Sample(c, r, tilt, x))
    return out


def prepare_sample(base_prep, case: Case, tilt_deg: float):
    """The base model of the damper with this sample's contact values, preloads and damping.

    Nothing is re-meshed or re-reduced: ``W``, ``M`` and ``K`` are the base
    model's. With the nominal values and no tilt this is exactly the model
    ``pipeline.prepare_model`` builds for the case.
    """
    from ....assembly.model import pair_params
    from ....hbm.core.system import System
    from ....pipeline import PreparedModel, contact_params_for
    from .imperfection import open_share, tilted_preloads

    t0 = time.perf_counter()
    base = base_prep.assembled
    cp = contact_params_for(case)
    contact = base.contact
    beta = float(base_prep.geometry.params["rig"]["platform"]["angle_deg"])
    pairs = pair_params(contact, cp, beta)
    n0 = tilted_preloads(contact.points, contact.side, pairs["kn"], pairs["n0"], tilt_deg)
    model = dataclasses.replace(
        base,
        **{**pairs, "n0": n0},
        info={
            **base.info,
            "total_preload_n": float(n0.sum()),
            "open_share_at_rest": open_share(n0, contact.side),
        },
    )
    contacts = model.contact_elements()
    system = System(M=model.M, K=model.K, zeta=case.settings["damping"], contacts=contacts)
    timings = {"assembly (sample)": time.perf_counter() - t0}
    return PreparedModel(base_prep.geometry, base_prep.geometry_dir, model, system, {}, timings, cp)
