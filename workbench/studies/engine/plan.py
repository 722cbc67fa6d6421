"""From a study spec to a list of cases, each with the canonical parameters that key its cache.

A case's parameters split into the *model* part (geometry, mesh, reduction,
contact, damping: everything the linear model and contact layout depend
on) and the *solve* part (phase, force, band, harmonics, samples, solver
options). Cases sharing a model part share the meshing and the reduction.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ...io import digest
from .spec import OPTIONS, StudySpec

# the options in each part of a case's key: declared by each option's ``role``
# (workbench/study_options.py, a kind's options.py)
MODEL_KEYS = tuple(o.name for o in OPTIONS if o.role == "model")
SOLVE_KEYS = tuple(o.name for o in OPTIONS if o.role == "solve")


@dataclass(frozen=True)
class Case:
    """One unit of work: a damper, a phase, a force and every setting that shapes its answer."""

    damper: str
    phase_deg: float
    force_n: float
    settings: dict[str, Any]  # option name -> value (the spec, with this case's overrides)
    variant: str = ""
    model_digest: str = field(default="", compare=False)
    digest: str = field(default="", compare=False)

    @property
    def name(self) -> str:
        v = f" [{self.variant}]" if self.variant else ""
        return f"{self.damper} {self.phase_deg:g} deg {self.force_n:g} N{v}"

    def model_params(self) -> dict[str, Any]:
        """The model part of the key: the options and the contents of the files they name
        (a study file's geometry file and the default geometry/contact files), so editing a
        file recomputes what depends on it."""
        return {
            "damper": self.damper,
            **{k: self.settings[k] for k in MODEL_KEYS},
            "files": input_files_digest(self.damper, self.settings.get("geometry")),
        }

    def solve_params(self) -> dict[str, Any]:
        return {
            "phase_deg": self.phase_deg,
            "force_n": self.force_n,
            **{k: self.settings[k] for k in SOLVE_KEYS},
        }


# the nonlinear modes (hbm/nlmodes/, every file under it) do not shape a forced response
NLMODE_PACKAGE = "nlmodes"


def solver_code_version() -> str:
    """A hash of the sources that turn a reduced model into a case's curve.

    Part of every case's cache key: a change to the contact laws, the
    harmonic balance, the assembly, the model pipeline (which calls the
    solve) or this runner recomputes the cases (the meshes and reduced
    models have their own keys and stay). Sub-packages count.
    """
    from ...io import code_version

    root = Path(__file__).resolve().parents[2]  # workbench/
    parts = [code_version(root / pkg) for pkg in ("contact", "assembly")]
    # the nonlinear modes (hbm/NLMODE_PACKAGE/) do not shape a forced response
    hbm_dir = root / "hbm"
    hbm = tuple(
        str(p.relative_to(hbm_dir))
        for p in sorted(hbm_dir.rglob("*.py"))
        if p.relative_to(hbm_dir).parts[0] != NLMODE_PACKAGE
    )
    parts.insert(1, code_version(hbm_dir, hbm))
    # the HDF5 writer of a case's branch (it was hbm/io/record.py)
    parts.insert(2, code_version(root / "io", ("record.py",)))
    parts.append(code_version(root / "studies" / "engine", ("plan.py", "runner.py")))
    parts.append(code_version(root / "pipeline"))
    return digest(parts, 12)


def input_files_digest(damper: str, geometry: Any) -> str:
    """A digest of the parameter files a model of ``damper`` is built from."""
    from ...assembly.params import DEFAULT_FILE as CONTACT_FILE
    from ...geometry.params import default_files

    paths = [*default_files(damper), CONTACT_FILE]
    if geometry:
        paths.append(Path(geometry))
    return _files_digest(tuple(str(p) for p in paths))


@functools.lru_cache(maxsize=64)
def _files_digest(paths: tuple[str, ...]) -> str:
    from ...config import read_toml

    parts = []
    for p in paths:  # the parsed values: editing a comment recomputes nothing
        try:
            parts.append([p, read_toml(p)])
        except Exception:  # noqa: BLE001 - a missing or bad file fails later, where it is read
            parts.append([p, None])
    return digest(parts, 16)


def make_case(
    damper: str, phase: float, force: float, settings: dict[str, Any], variant: str = ""
) -> Case:
    c = Case(damper, float(phase), float(force), dict(settings), variant)
    md = digest({"params": c.model_params(), "code": _MODEL_CODE()})
    return dataclasses.replace(
        c,
        model_digest=md,
        digest=digest({"model": md, "solve": c.solve_params(), "code": _SOLVER_CODE()}),
    )


@functools.lru_cache(maxsize=1)
def _SOLVER_CODE() -> str:  # noqa: N802 - a constant computed once per process
    return solver_code_version()


@functools.lru_cache(maxsize=1)
def _MODEL_CODE() -> str:  # noqa: N802 - a constant computed once per process
    return model_code_version()


def disk_code_version() -> str:
    """The sources a bladed-disk case's curve depends on beyond its sector's mesh (whose
    digest has the mesher's): the solver's (:func:`solver_code_version`) and the whole FE
    package (the cyclic reduction, the damper's reduction, the pads), so that a change to
    either recomputes the cases and not only the models."""
    from ...io import code_version

    root = Path(__file__).resolve().parents[2]  # workbench/
    return digest([solver_code_version(), code_version(root / "fe")], 12)


def model_code_version() -> str:
    """A hash of the sources that make a case's model: the mesher's
    (``workbench.geometry.build.code_version``) and the reduction's
    (``workbench.fe.reduce.code_version``).

    Part of every case's model key, so of its cache key: the meshes and reduced models
    have their own keys and are made again when these change, and a curve computed on the
    old model must not be reused with them (round 17 mended the pads' tie in
    ``fe/pads.py``; the cached curves of the old tie were read back until this was in the
    key)."""
    from ...fe.reduce import code_version as fe_code
    from ...geometry.build import code_version as geometry_code

    return digest([geometry_code(), fe_code()], 12)


def plan(spec: StudySpec) -> list[Case]:
    """The cases of a comparison or a sweep study, in a stable order."""
    base = spec.as_dict()
    cases: list[Case] = []
    if spec.kind == "sweep" and spec.sweep is not None:
        for value, damper, phase, force in itertools.product(
            spec.sweep_values, spec.dampers, spec.phases, spec.forces
        ):
            s = dict(base)
            s[spec.sweep] = value
            cases.append(make_case(damper, phase, force, s, f"{spec.sweep}={value:g}"))
    else:
        for damper, phase, force in itertools.product(spec.dampers, spec.phases, spec.forces):
            cases.append(make_case(damper, phase, force, base))
    return cases
