"""The registry of damper shapes: one module per shape in this package, found by name.

A shape is a module ``workbench/geometry/shapes/<name>.py`` that defines
``SHAPE = DamperShape(...)`` (its parameter record, how it seats in the
groove, which parameter to blame when it does not fit, how gmsh draws it,
its figure style and the study options that reach its parameters) plus its
default parameters ``geometry/<name>.toml`` (table ``[<name>]``). Nothing
else names a shape: the CLI, the studies, the figures and the tests ask
this registry (:func:`names`, :func:`get`). Modules are found by
:mod:`pkgutil` on first use, so importing the registry imports no shape and
no gmsh.
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from ...errors import check_choice

Blame = tuple[str, float, str]  # (parameter, its value, the allowed range), for an InputError


@dataclass(frozen=True)
class DamperShape:
    """One damper shape: everything the pipeline needs to know about it.

    ``seat(params, groove, rig) -> dict`` places the damper tangent to both
    platform planes (mm; ``groove`` is the rig layout of
    :func:`workbench.geometry.layout.make_layout`) and returns its
    placement, contact points, frames, weights, volume and extent (see
    :mod:`.cylinder` for the keys). ``fit_blame(gp, groove, placement,
    lo_ok, hi_ok, half_w)`` names the parameters to blame when the contacts
    start above the platform tip, reach below its root, or run off its
    width (three :data:`Blame`); ``hit_blame(gp, groove, placement, x_max)``
    the one to blame when the damper hits the blades. ``draw(gmsh, layout,
    members, point_tags) -> volume tag`` draws it in gmsh with the contact
    points embedded (filling the physical groups ``members``).
    """

    name: str  # the damper's name: TOML table [name], file geometry/<name>.toml
    params: type  # frozen record of its dimensions (workbench.config.param fields)
    contact: str  # "line" (point pairs along lines) or "face" (pairs spread over faces)
    seat: Callable[[Any, dict, Any], dict]
    fit_blame: Callable[..., tuple[Blame, Blame, Blame]]
    hit_blame: Callable[..., Blame]
    draw: Callable[..., int]
    style: tuple[str, str, str]  # colour, line style, marker of the damper in every figure
    # study option -> (field of the params record it sets, type), e.g. "points-per-line"
    study_options: dict[str, tuple[str, type]] = field(default_factory=dict)
    order: int = 100  # position in the damper list (the default of a study's dampers)
    description: str = ""


_REGISTRY: dict[str, DamperShape] | None = None


def _discover() -> dict[str, DamperShape]:
    found = []
    for info in pkgutil.iter_modules(__path__):
        if info.name.startswith("_"):
            continue
        mod = importlib.import_module(f"{__name__}.{info.name}")
        shape = getattr(mod, "SHAPE", None)
        if isinstance(shape, DamperShape):
            if shape.name != info.name:
                raise RuntimeError(
                    f"{mod.__name__}: SHAPE.name is '{shape.name}', expected "
                    f"'{info.name}' (the module's name)"
                )
            found.append(shape)
    found.sort(key=lambda s: (s.order, s.name))
    return {s.name: s for s in found}


def all_shapes() -> tuple[DamperShape, ...]:
    """Every registered shape, in damper-list order."""
    global _REGISTRY
    if _REGISTRY is None:
        _REGISTRY = _discover()
    return tuple(_REGISTRY.values())


def names() -> tuple[str, ...]:
    """The damper names, in order (cone, cylinder, wedge, then any added shape)."""
    return tuple(s.name for s in all_shapes())


def get(name: str, param: str = "damper") -> DamperShape:
    """The shape called ``name``; InputError naming ``param`` if there is none."""
    shapes = {s.name: s for s in all_shapes()}
    return shapes[check_choice(param, name, tuple(shapes))]


def rediscover() -> tuple[str, ...]:
    """Search the package again (after a shape module was added at run time); the names."""
    global _REGISTRY
    _REGISTRY = None
    return names()


__all__ = ["Blame", "DamperShape", "all_shapes", "get", "names", "rediscover"]
