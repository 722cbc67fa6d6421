"""Small gmsh models with known answers, for tests, examples and benchmarks.

* :func:`beam_msh`: a clamped rectangular beam (Euler-Bernoulli and
  Timoshenko references in :func:`cantilever_bending_hz`).
* :func:`block_msh`: a free rectangular block (mass and inertia known).
* :func:`toy_rig`: two clamped blades on a base with a block damper between
  their inner faces, as a complete :class:`~workbench.geometry.BuiltGeometry`
  (contact lines, excitation and response points embedded as mesh nodes).
  It exercises the whole FE stage without the real geometry builders.

All lengths in metres; meshes are second order (10-node tetrahedra).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..errors import check_int, check_range
from ..io import atomic_path, digest

STEEL = {"E_pa": 197e9, "nu": 0.3, "rho_kg_m3": 7800.0}


@contextmanager
def _gmsh(name: str):
    """A silent gmsh session (the geometry stage's: it restores Ctrl-C on exit)."""
    from ..geometry.occ import gmsh_session

    with gmsh_session() as gmsh:
        gmsh.model.add(name)
        yield gmsh


def _mesh_and_write(gmsh, path: Path, lc: float) -> Path:
    gmsh.option.setNumber("Mesh.CharacteristicLengthMax", lc)
    gmsh.option.setNumber("Mesh.CharacteristicLengthMin", lc / 4)
    gmsh.model.mesh.generate(3)
    gmsh.model.mesh.setOrder(2)
    with atomic_path(path) as tmp:
        gmsh.write(str(tmp.with_suffix(".msh")))
        tmp.with_suffix(".msh").replace(tmp)
    return path


def _points_in(gmsh, pts: Sequence[Sequence[float]]):
    return [(0, gmsh.model.occ.addPoint(*map(float, p))) for p in pts]


def _box_faces(gmsh, x0, x1, tol=1e-5):
    """Surface tags lying entirely inside the box [x0, x1] (OCC pads bounding boxes)."""
    return [
        t
        for _, t in gmsh.model.getEntitiesInBoundingBox(
            x0[0] - tol, x0[1] - tol, x0[2] - tol, x1[0] + tol, x1[1] + tol, x1[2] + tol, 2
        )
    ]


def beam_msh(
    path: str | Path,
    *,
    length: float = 0.2,
    width: float = 0.02,
    thickness: float = 0.01,
    lc: float = 0.005,
    points: Sequence[Sequence[float]] = (),
) -> Path:
    """A beam x in [0, thickness], y in [0, width], z in [0, length], clamped at z = 0.

    Physical groups: volume "beam", surface "clamped". ``points`` become mesh nodes.
    """
    check_range("lc", lc, 0.0, lo_open=True, unit="m")
    path = Path(path)
    with _gmsh("beam") as gmsh:
        occ = gmsh.model.occ
        box = occ.addBox(0, 0, 0, thickness, width, length)
        occ.fragment([(3, box)], _points_in(gmsh, points))
        occ.synchronize()
        vols = [t for _, t in gmsh.model.getEntities(3)]
        gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, vols), "beam")
        clamp = _box_faces(gmsh, (0, 0, 0), (thickness, width, 0))
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, clamp), "clamped")
        return _mesh_and_write(gmsh, path, lc)


def block_msh(
    path: str | Path,
    *,
    size: Sequence[float] = (0.02, 0.016, 0.01),
    origin: Sequence[float] = (0.0, 0.0, 0.0),
    lc: float = 0.004,
    points: Sequence[Sequence[float]] = (),
    name: str = "damper",
) -> Path:
    """A free block ``origin + [0, size]``; physical volume ``name``; ``points`` embedded."""
    check_range("lc", lc, 0.0, lo_open=True, unit="m")
    path = Path(path)
    with _gmsh("block") as gmsh:
        occ = gmsh.model.occ
        box = occ.addBox(*map(float, origin), *map(float, size))
        occ.fragment([(3, box)], _points_in(gmsh, points))
        occ.synchronize()
        vols = [t for _, t in gmsh.model.getEntities(3)]
        gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, vols), name)
        return _mesh_and_write(gmsh, path, lc)


def cantilever_bending_hz(
    length: float,
    thickness: float,
    E: float,
    rho: float,
    nu: float,
    mode: int = 1,
    timoshenko: bool = True,
) -> float:
    """Bending frequency (Hz) of a clamped-free rectangular beam, bending across ``thickness``.

    Euler-Bernoulli: ``f = (b_n L)^2 / (2 pi L^2) sqrt(E I / (rho A))`` with
    ``b_1 L = 1.8751``, ``b_2 L = 4.6941``. With ``timoshenko`` the first-order
    shear and rotary-inertia correction for a cantilever,
    ``f_T ~ f_EB (1 - (b_n r)^2 (1 + E/(kappa G)) / 2)``, r the radius of
    gyration, kappa = 10 (1 + nu) / (12 + 11 nu) (Cowper, rectangle), is applied.
    """
    bl = {1: 1.875104068711961, 2: 4.694091132974175, 3: 7.854757438237613}[mode]
    r = thickness / math.sqrt(12.0)  # radius of gyration of the section
    f = bl**2 / (2 * math.pi * length**2) * math.sqrt(E / rho) * r
    if timoshenko:
        G = E / (2 * (1 + nu))
        kappa = 10 * (1 + nu) / (12 + 11 * nu)
        f *= 1 - 0.5 * (bl * r / length) ** 2 * (1 + E / (kappa * G))
    return f


def toy_rig(
    out_dir: str | Path,
    *,
    lc: float = 0.004,
    n_per_line: int = 5,
    blade_length: float = 0.1,
    blade_thickness: float = 0.005,
    gap: float = 0.02,
    width: float = 0.02,
    contact_height: float = 0.075,
    damper_height: float = 0.008,
    material: dict[str, float] | None = None,
):
    """Two blades on a base with a block damper between them; returns a BuiltGeometry.

    Axes as in the workbench: x from blade 1 to blade 2, y along the damper,
    z up the blades; base bottom clamped. The damper is a block filling the
    gap between the blades' inner faces (x = -gap/2 and +gap/2) around
    ``contact_height``; the contact lines run along y on those faces with
    ``n_per_line`` points each. The frames follow
    :mod:`workbench.geometry.records`: n from the platform into the damper
    (+x on blade 1, -x on blade 2), t1 = +y, t2 = n x t1.
    """
    from ..geometry.records import BuiltGeometry, ContactSet

    check_range("lc", lc, 0.0, lo_open=True, unit="m")
    n_per_line = check_int("n_per_line", n_per_line, 2, 200)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    material = dict(material or STEEL)
    g2, t, L = gap / 2, blade_thickness, blade_length
    ys = np.linspace(0.15 * width, 0.85 * width, n_per_line)
    pts = np.array([[-g2, y, contact_height] for y in ys] + [[g2, y, contact_height] for y in ys])
    side = np.repeat([0, 1], n_per_line)
    dy = ys[1] - ys[0]
    wt = np.full(n_per_line, dy)
    wt[[0, -1]] = dy / 2
    weight = np.concatenate([wt, wt])
    frames = np.empty((len(pts), 3, 3))
    for k, s in enumerate(side):
        n = np.array([1.0, 0, 0]) if s == 0 else np.array([-1.0, 0, 0])
        t1 = np.array([0, 1.0, 0])
        frames[k] = [t1, np.cross(n, t1), n]
    exc = np.array([[-g2 - t, width / 2, 0.6 * L], [g2 + t, width / 2, 0.6 * L]])
    resp = np.array([[-g2 - t / 2, width / 2, L], [g2 + t / 2, width / 2, L]])

    rig_msh = out / "rig.msh"
    with _gmsh("toy_rig") as gmsh:
        occ = gmsh.model.occ
        hb = 0.02
        base = occ.addBox(-g2 - t - 0.01, 0, -hb, gap + 2 * t + 0.02, width, hb)
        b1 = occ.addBox(-g2 - t, 0, 0, t, width, L)
        b2 = occ.addBox(g2, 0, 0, t, width, L)
        ptags = _points_in(gmsh, np.vstack([pts, exc, resp]))
        _, omap = occ.fragment([(3, base), (3, b1), (3, b2)], ptags)
        occ.synchronize()
        for name, k in (("base", 0), ("blade_1", 1), ("blade_2", 2)):
            tags = [tg for d, tg in omap[k] if d == 3]
            gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, tags), name)
        clamp = _box_faces(gmsh, (-1, -1, -hb), (1, 1, -hb))
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, clamp), "clamped")
        for k, x in ((1, -g2), (2, g2)):
            faces = _box_faces(gmsh, (x, 0, 0), (x, width, L))
            gmsh.model.setPhysicalName(
                2, gmsh.model.addPhysicalGroup(2, faces), f"contact_face_{k}"
            )
        _mesh_and_write(gmsh, rig_msh, lc)
    z0 = contact_height - damper_height / 2
    damper_msh = block_msh(
        out / "damper.msh", size=(gap, width, damper_height), origin=(-g2, 0, z0), lc=lc, points=pts
    )
    vol = gap * width * damper_height
    params = {
        "toy_rig": dict(
            lc=lc,
            n_per_line=n_per_line,
            blade_length=blade_length,
            blade_thickness=blade_thickness,
            gap=gap,
            width=width,
            contact_height=contact_height,
            damper_height=damper_height,
        ),
        "material": material,
    }
    return BuiltGeometry(
        damper="block",
        rig_msh=rig_msh,
        damper_msh=damper_msh,
        contact=ContactSet(points=pts, frames=frames, side=side, weight=weight, kind="line"),
        excitation_points=exc,
        response_points=resp,
        excitation_direction=np.array([1.0, 0, 0]),
        response_direction=np.array([1.0, 0, 0]),
        damper_volume_m3=vol,
        damper_mass_kg=vol * material["rho_kg_m3"],
        damper_centroid=np.array([0.0, width / 2, contact_height]),
        material=material,
        params=params,
        digest=digest(params),
        stats={},
    )
