"""The bladed-disk study's per-damper results besides the cases: the coupling screen per
nodal diameter and the field at the worst peak.

One task per damper, after the cases, spread over the ranks like them
(:func:`damper_post`), kept in ``out/cache/bladed_disk/post_<digest>.json``
(the digest covers the sector, the contact parameters, the reduction's
sizes, the solver sources and the worst case's own cache key), so a rerun
costs nothing:

* the screen (:func:`workbench.pipeline.sector_post.nd_screen`) at every ND
  0..N/2: the first family's frequency stuck and sliding and
  ``k2/k = 1 - (f_sliding / f_stuck)^2``, milliseconds on the sector model the
  rank already holds;
* the worst case (the damper's worst EO at the largest force): the sector's
  displacement at its peak, expanded exactly from the stored unknowns through
  each harmonic's ND basis (:func:`workbench.pipeline.sector_post.peak_field`),
  written as ``cases/bladed_disk_<damper>_worst_peak.vtu``. The response point's
  amplitude along the excitation recomputed from that field is kept beside the
  case's peak (``field_peak_m``): they agree to round-off when the rebuilt basis
  is the one the case was solved on;
* Hill's stability of that peak point as a state of the whole disk
  (:func:`workbench.pipeline.sector_post.full_disk_stability`: the sector's
  travelling wave on every sector and damper, polished by Newton on the whole
  disk, then ARPACK): the verdict for that one point, a few seconds.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from ....io import digest


def post_key(case_key_worst: str, sector_digest: str, cp, spec, zeta: float, record: int) -> str:
    """The cache key of one damper's screen and worst-peak field (``zeta``, ``record``: the
    cases' damping ratio and record version)."""
    from ....io import code_version
    from ...engine.plan import disk_code_version

    return digest(
        {
            "kind": "bladed_disk_post",
            "sector": sector_digest,
            "contact": repr(cp),
            "sector_modes": int(spec.bladed_disk.sector_modes),
            "damper_modes": int(spec.bladed_disk.damper_modes),
            "zeta": float(zeta),
            "harmonics": [int(h) for h in spec.harmonics],
            "worst": case_key_worst,
            "code": disk_code_version(),
            "post_code": code_version(Path(__file__).parent, ("post.py",)),
            "record": int(record),
        }
    )


def vtu_path(out: Path, damper: str) -> Path:
    return Path(out) / "cases" / f"bladed_disk_{damper}_worst_peak.vtu"


def damper_post(model, rec, worst: dict | None, spec, out: Path, zeta: float) -> dict[str, Any]:
    """The screen rows of every ND and, for the worst case ``worst`` (a case record with its
    ``x_peak``), the VTU of the sector at its peak and the field's check."""
    from ....fe.cyclic import assemble_sector
    from ....hbm.core.fourier import Fourier, default_nt
    from ....pipeline.sector_post import (
        full_disk_stability,
        nd_screen,
        peak_field,
        period_max,
        sector_vtk,
    )

    t0 = time.perf_counter()
    n_b = int(model.n_blades)
    rows = [{"damper": rec.damper, **nd_screen(model, k, zeta)} for k in range(n_b // 2 + 1)]
    res: dict[str, Any] = {"damper": rec.damper, "screen": rows, "worst": None}
    if worst is not None and worst.get("x_peak"):
        H = tuple(int(h) for h in spec.harmonics)
        cs = assemble_sector(rec, with_damper=False)
        fields = peak_field(
            cs, model, int(worst["eo"]), H, np.array(worst["x_peak"]), spec.bladed_disk.sector_modes
        )
        d = np.asarray(rec.excitation_direction, dtype=float)
        rn = int(np.argmin(np.linalg.norm(cs.coords - rec.response_point[None, :], axis=1)))
        f = Fourier(H, default_nt(H))
        Y = np.zeros(f.nh)
        k = list(int(v) for v in f.k)
        for h, (c, s) in fields.items():
            Y[k.index(h)] = c[rn] @ d
            if h:
                Y[k.index(h) + 1] = s[rn] @ d
        field_peak = float(f.amplitude(Y[:, None])[0])
        # the instant of the period at which the response point is farthest out
        tt = 2 * np.pi * np.arange(512) / 512
        y_t = sum(
            (c[rn] @ d) * np.cos(h * tt) + (s[rn] @ d) * np.sin(h * tt)
            for h, (c, s) in fields.items()
        )
        t_star = float(tt[int(np.argmax(np.abs(y_t)))])
        pts, cells, types = sector_vtk(rec, cs.coords)
        n = len(pts)
        pd = {}
        for h, (c, s) in sorted(fields.items()):
            if h == 0:
                pd["disp_mean_mm"] = c[:n] * 1e3
            else:
                pd[f"disp_h{h}_cos_mm"] = c[:n] * 1e3
                pd[f"disp_h{h}_sin_mm"] = s[:n] * 1e3
        pd["disp_h1_amp_mm"] = np.hypot(pd["disp_h1_cos_mm"], pd["disp_h1_sin_mm"])
        pd["disp_at_peak_instant_mm"] = 1e3 * sum(
            c[:n] * np.cos(h * t_star) + s[:n] * np.sin(h * t_star) for h, (c, s) in fields.items()
        )
        pd["disp_max_mm"] = period_max({h: (c[:n], s[:n]) for h, (c, s) in fields.items()}) * 1e3
        pd["resp_dir_h1_amp_mm"] = np.abs(pd["disp_h1_cos_mm"] @ d + 1j * pd["disp_h1_sin_mm"] @ d)
        from ....io.vtk_out import write_vtu

        path = write_vtu(
            vtu_path(out, rec.damper),
            pts,
            cells,
            types,
            point_data=pd,
            field_data={
                "freq_hz": float(worst["peak_hz"]),
                "force_n": float(worst["force_n"]),
                "eo": int(worst["eo"]),
                "nd": int(worst["nd"]),
                "peak_m": float(worst["peak_m"]),
                "response_node": rn,
                "peak_instant_rad": t_star,
            },
        )
        res["worst"] = {
            "damper": rec.damper,
            "eo": int(worst["eo"]),
            "nd": int(worst["nd"]),
            "force_n": float(worst["force_n"]),
            "peak_m": float(worst["peak_m"]),
            "peak_hz": float(worst["peak_hz"]),
            "field_peak_m": field_peak,
            "field_rel_err": abs(field_peak - worst["peak_m"]) / max(abs(worst["peak_m"]), 1e-300),
            "max_disp_m": float(pd["disp_max_mm"].max() * 1e-3),
            "vtu": str(path),
            "response_node": rn,
            # Hill's method on the whole disk at this point (every ND, every damper)
            "stability": full_disk_stability(
                model,
                int(worst["eo"]),
                H,
                float(worst["force_n"]),
                np.array(worst["x_peak"]),
                float(worst["peak_hz"]),
            ),
        }
    res["wall_s"] = time.perf_counter() - t0
    return res
