"""The model pipeline: options -> geometry -> reduction -> assembled system (see :mod:`.model`)."""

from .model import (
    PreparedModel,
    band_for,
    contact_params_for,
    geometry_dir,
    geometry_request,
    load_geometry,
    prepare_model,
    solve_case,
)

__all__ = [
    "PreparedModel",
    "band_for",
    "contact_params_for",
    "geometry_dir",
    "geometry_request",
    "load_geometry",
    "prepare_model",
    "solve_case",
]
