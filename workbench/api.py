"""The workbench from Python: a few calls from a damper to its curves and figures.

``import workbench as wb`` exposes these names (loaded on first use, so the
import itself stays light)::

    m = wb.model("cone", mesh_size=14, modes=12, out="results/nb")  # mesh, reduce, assemble
    c = wb.frf(m, force_n=30, phase_deg=180)      # one forced response (a CaseResult)
    c.freq_hz, c.amp_mm, c.energy_mj              # Hz, mm, mJ per cycle per pair
    fig = wb.receptance_figure([c])               # a matplotlib Figure (nothing written)
    wb.receptance_figure([c], path="r.png")       # ... or a PNG

Options are those of ``upd study`` with underscores (``mesh_size``, ``mu``,
``cf``, ``kt_line``, ``harmonics``, ``nt``, ...; ``upd study --help`` lists
them), checked the same way: a bad value is an :class:`InputError` naming
it. Every stage is cached under ``out/cache`` exactly as a study caches it,
so a second call with the same inputs is quick.

No function here changes matplotlib's backend or rcParams: figures are
plain :class:`matplotlib.figure.Figure` objects, shown inline by Jupyter.
``docs/API.md`` walks through it; ``examples/notebook_api.py`` runs in the
tests.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .errors import InputError

SOURCE = "python API"


@dataclass
class Model:
    """A rig with one damper, reduced and assembled: what :func:`frf` solves.

    ``settings`` are the resolved study options (dashed names); ``prepared``
    the runner's record (geometry, assembled model, harmonic balance
    system); ``out`` the folder that caches it.
    """

    damper: str
    settings: dict[str, Any]
    source: dict[str, str]
    prepared: Any
    out: Path

    @property
    def n_pairs(self) -> int:
        return int(self.prepared.assembled.n_pairs)

    @property
    def n_dofs(self) -> int:
        return int(self.prepared.assembled.n)

    def inputs(self) -> list[dict[str, Any]]:
        """The model's inputs as used: ``{option, value, unit, source}`` per option.

        Options left unset show the geometry or contact file's value and name
        that file (as the report's Inputs table does).
        """
        from .post.inputs import used_inputs
        from .studies.engine.plan import MODEL_KEYS

        return [
            r
            for r in used_inputs(self.settings, self.source, "comparison")
            if r["option"] in MODEL_KEYS
        ]


def _options(options: dict[str, Any]) -> dict[str, Any]:
    from .studies.engine.spec import BY_NAME

    out = {}
    for key, v in options.items():
        name = key.replace("_", "-")
        if name not in BY_NAME:
            from .errors import did_you_mean

            raise InputError(
                key,
                v,
                "an upd study option with underscores (mesh_size, mu, ...)",
                did_you_mean(name, BY_NAME),
            )
        out[name] = v
    return out


def model(damper: str = "cone", *, out: str | Path = "results/notebook", **options: Any) -> Model:
    """Mesh the rig and ``damper``, reduce both (Craig-Bampton) and couple them.

    ``options``: model options of ``upd study`` with underscores, e.g.
    ``mesh_size=14`` (mm), ``modes=12``, ``mu=0.5``, ``cf=10e3`` (N),
    ``kt_line=6e10`` (N/m per m), ``damping=0.002``. Solve options
    (``harmonics``, ``nt``, ...) given here become the defaults of :func:`frf`.
    """
    from .pipeline import prepare_model
    from .studies.engine.plan import plan
    from .studies.engine.spec import resolve

    values = _options(options)
    values.update(dampers=[damper], phases=[180.0], forces=[1.0])
    spec = resolve(values, SOURCE)
    case = plan(spec)[0]
    out = Path(out)
    prep = prepare_model(case, out)
    return Model(damper, dict(case.settings), dict(spec.source), prep, out)


def frf(m: Model, force_n: float, phase_deg: float = 180.0, **options: Any):
    """The forced response of ``m`` at one force (N per blade) and inter-blade phase (deg).

    ``options``: solve options of ``upd study`` (``harmonics``, ``nt``,
    ``max_points``, ``stability``, ``band_in_phase``, ``band_out_of_phase``,
    ``band_margin``, ``response_blade``). Returns a
    :class:`workbench.post.results.CaseResult` (``freq_hz``, ``amp_mm``,
    ``receptance_mm_per_n``, ``energy_mj``, ``summary()``, ``branch``).
    """
    from .errors import check_range
    from .pipeline import solve_case
    from .studies.engine.plan import MODEL_KEYS, make_case
    from .studies.engine.spec import BY_NAME, check_option

    values = _options(options)
    for k in values:
        if k in MODEL_KEYS:
            raise InputError(
                k.replace("-", "_"),
                values[k],
                "a solve option here",
                "model options go to wb.model()",
            )
    settings = dict(m.settings)
    for k, v in values.items():
        settings[k] = check_option(BY_NAME[k], v)
    force = check_range("force_n", force_n, 0.0, lo_open=True, unit="N")
    phase = check_range("phase_deg", phase_deg, -360.0, 360.0, unit="deg")
    case = make_case(m.damper, phase, force, settings)
    return solve_case(m.prepared, case)


def _forces(curves: Sequence[Any]) -> list[float]:
    return sorted({c.force_n for c in curves})


def receptance_figure(
    curves: Sequence[Any], path: str | Path | None = None, title: str | None = None
):
    """Receptance (mm/N) against frequency, one curve per force: a Figure, or the PNG path."""
    from .render.study_figures import plot_receptances

    return plot_receptances(list(curves), path, forces=_forces(curves), title=title)


def status_figure(curves: Sequence[Any], path: str | Path | None = None, title: str | None = None):
    """Contact status of every pair along the curves (one panel per curve)."""
    from .render.status_figures import plot_status_map

    return plot_status_map(list(curves), path, title=title)


def energy_figure(curves: Sequence[Any], path: str | Path | None = None, title: str | None = None):
    """Friction energy per cycle at resonance against the force (mJ)."""
    from .render.study_figures import plot_energy_vs_force

    return plot_energy_vs_force(list(curves), path, title=title)


def peak_figure(curves: Sequence[Any], path: str | Path | None = None, title: str | None = None):
    """Peak response against the force (mm)."""
    from .render.study_figures import plot_peak_vs_force

    return plot_peak_vs_force(list(curves), path, title=title)


def study(
    file: str | Path | None = None,
    *,
    out: str | Path = "results/study",
    force: bool = False,
    **options: Any,
):
    """Run a study (a study TOML and/or options) as ``upd study`` does; the StudyResults."""
    from .studies.engine.runner import run_study
    from .studies.engine.spec import load_study

    spec = load_study(file, _options(options))
    return run_study(spec, Path(out), force=force)


def load_results(path: str | Path):
    """A study's ``results.h5`` (or its folder) as StudyResults (docs/RESULTS.md)."""
    from .post.results import StudyResults

    p = Path(path)
    return StudyResults.load(p / "results.h5" if p.is_dir() else p)


def frf_model(path: str | Path):
    """A ``upd frf`` model TOML (matrices from any FE code) as an FrfModel."""
    from .hbm.io.modelfile import load_frf_model

    return load_frf_model(path)


def frf_curves(frf_model_or_path: Any) -> list[Any]:
    """Every level of a ``upd frf`` model: one :class:`workbench.hbm.Branch` per level."""
    from .hbm import frequency_response

    fm = (
        frf_model(frf_model_or_path)
        if isinstance(frf_model_or_path, (str, Path))
        else frf_model_or_path
    )
    return [
        frequency_response(
            fm.system,
            fm.f1,
            lev,
            fm.band_hz,
            fm.outputs,
            harmonics=fm.harmonics,
            nt=fm.nt or None,
            options=fm.options,
            output_names=fm.output_names,
            label=f"level {lev:g}",
        )
        for lev in fm.levels
    ]


def frf_figure(
    branches: Sequence[Any],
    path: str | Path | None = None,
    *,
    unit_scale: float = 1.0,
    unit: str = "m",
    title: str = "",
):
    """Amplitude per newton against frequency for ``upd frf`` branches (log axis)."""
    from .render.curves import plot_frf

    return plot_frf(
        list(branches), path, unit_scale=unit_scale, unit=unit, title=title, per_level=True
    )


def read_matrices(files: dict[str, str | Path], dof_map: str | Path | None = None):
    """Reduced matrices from Nastran, Abaqus, Matrix Market or Harwell-Boeing files."""
    from .readers import read_matrices as _read

    return _read(files, dof_map)


__all__ = [
    "Model",
    "model",
    "frf",
    "receptance_figure",
    "status_figure",
    "energy_figure",
    "peak_figure",
    "study",
    "load_results",
    "frf_model",
    "frf_curves",
    "frf_figure",
    "read_matrices",
]


def sector_frf(
    damper: str = "cone",
    eo: int = 1,
    force_n: float = 10.0,
    *,
    n_blades: int | None = None,
    geometry_file: str | Path | None = None,
    out: str | Path = "results/disk",
    modes: int = 10,
    band_hz: tuple[float, float] | None = None,
    harmonics: tuple[int, ...] = (0, 1, 2, 3),
    overrides: dict[str, Any] | None = None,
):
    """One bladed-disk sector's forced response under engine order ``eo`` (docs/DISK_HBM.md).

    Builds (or reads from ``out``) the sector of ``geometry_file``'s section with
    ``damper`` for ``n_blades`` blades (default ``geometry/disk.toml``), reduces it per
    nodal diameter (``modes`` fixed-interface modes) and follows the response to a
    harmonic-1 force ``force_n`` (N) on every blade, sector ``j`` lagging ``j 2 pi eo /
    N``. Returns ``(branch, info)``: a :class:`workbench.hbm.forced.branch.Branch`
    (output 0: the response point along the excitation direction, m) and a dict with
    the ND and direction (forward/backward/standing) of each harmonic and the stuck
    frequencies. An ``eo`` above N/2 maps onto its ND.
    """
    from .assembly.params import load_contact_params
    from .geometry.disk_build import build_disk_sector
    from .hbm.core.sector import check_engine_order
    from .pipeline.sector import build_sector_model, nds_for, sector_forced_response

    check_engine_order(eo, n_blades if isinstance(n_blades, int) and n_blades >= 2 else 2)
    rec = build_disk_sector(
        damper,
        Path(out),
        geometry_file=None if geometry_file is None else Path(geometry_file),
        n_blades=n_blades,
        overrides=overrides,
    )
    eo = check_engine_order(eo, rec.n_blades)
    cp = load_contact_params(geometry_file=geometry_file)
    model = build_sector_model(rec, cp, nds_for(eo, rec.n_blades, harmonics), n_modes=modes)
    return sector_forced_response(model, eo, force_n, band_hz, harmonics)
