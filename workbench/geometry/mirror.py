"""Mirror-image meshes: the half x >= 0 of a body meshed, then mirrored about x = 0.

The rig, every damper and the contact points are symmetric about the plane x = 0
between the blades, and so is the loading of each family (out of phase: the
motion is its own mirror image; in phase: the mirror image of the motion is the
motion half a period later), so each contact line should carry the same friction
energy. gmsh meshes a body as a whole, and its two halves then differ: on the
paper-like rig with pads that alone split the cone's in-phase energy between its
two lines by up to 40 %, scattering its peaks by up to 2 % from one mesh to the next
(docs/notes/mesh_symmetry.md). With ``[rig.mesh] mirror = true`` the builders of
:mod:`workbench.geometry.occ` draw and mesh the half x >= 0 only (the base's half,
blade 2, the damper's half, the side-2 contact points) and :func:`mirror_model`
adds its mirror image: node for node, the nodes on the plane shared, the same
physical groups (names and tags) as a whole build, so nothing downstream changes.
"""

from __future__ import annotations

from typing import Any

import numpy as np

PLANE_TOL_MM = 1e-7  # a node within this of x = 0 lies on the mirror plane (CAD in mm)
# node orders of the mirrored elements (two corners swapped, the edge nodes with them):
# gmsh 10-node tetrahedron (type 11): edges 01 12 20 30 32 31; 6-node triangle (type 9):
# edges 01 12 20; 4-node tetrahedron (4), 3-node triangle (2)
FLIP = {11: [0, 2, 1, 3, 6, 5, 4, 7, 9, 8], 9: [0, 2, 1, 5, 4, 3], 4: [0, 2, 1, 3], 2: [0, 2, 1]}
# a group of the half (side 2) -> the group of its mirror image (side 1); the other groups
# (base, clamped, excitation, response, damper) take both halves
MIRRORED_GROUP = {
    "blade_2": "blade_1",
    "contact_face_2": "contact_face_1",
    "contact_nodes_2": "contact_nodes_1",
}


def mirror_model(gmsh: Any, group_tags: dict[str, int], what: str) -> None:
    """Replace the current gmsh model (meshed, the half x >= 0) by a new model holding its
    mesh and the mirror image of it about x = 0, with the same physical groups.

    Each entity of the half becomes a discrete entity with its nodes and elements, and,
    unless it lies in the plane, a second one with the mirrored nodes (new tags; those on
    the plane are shared) and the mirrored elements (two corners swapped, so their
    orientation stays positive). ``group_tags``: physical tag of every group name (those
    of :data:`MIRRORED_GROUP`'s images included). Node and element tags are renumbered
    1..n (dolfinx reads the nodes by tag)."""
    tags, xyz, _ = gmsh.model.mesh.getNodes()
    xyz = xyz.reshape(-1, 3)
    if float(xyz[:, 0].min()) < -PLANE_TOL_MM:
        raise AssertionError(f"internal: the half {what} reaches x = {xyz[:, 0].min():g} mm")
    n_max = int(tags.max())
    plane = np.zeros(n_max + 1, bool)
    plane[tags[np.abs(xyz[:, 0]) <= PLANE_TOL_MM]] = True
    image = np.arange(n_max + 1, dtype=np.int64) + n_max  # node tag -> its image's tag
    image[plane] = np.flatnonzero(plane)
    ents = []
    for dim, tag in gmsh.model.getEntities():
        nt, nx, _ = gmsh.model.mesh.getNodes(dim, tag)
        et, etags, enodes = gmsh.model.mesh.getElements(dim, tag)
        els = [(int(t), np.asarray(e, np.int64), np.asarray(n, np.int64))
               for t, e, n in zip(et, etags, enodes, strict=True)]  # fmt: skip
        ents.append((dim, tag, np.asarray(nt, np.int64), np.asarray(nx).reshape(-1, 3), els))
    groups = []
    for dim, ptag in gmsh.model.getPhysicalGroups():
        members = [int(t) for t in gmsh.model.getEntitiesForPhysicalGroup(dim, ptag)]
        groups.append((dim, ptag, gmsh.model.getPhysicalName(dim, ptag), members))
    e_off = max((int(e.max()) for *_, els in ents for _, e, _ in els if len(e)), default=0)

    gmsh.model.add(f"{gmsh.model.getCurrent()}_mirrored")
    new: dict[tuple[int, int], tuple[int, int | None]] = {}  # (dim, tag) -> (half, image)
    for dim, tag, nt, nx, els in ents:
        a = gmsh.model.addDiscreteEntity(dim)
        gmsh.model.mesh.addNodes(dim, a, nt.tolist(), nx.ravel().tolist())
        for t, e, n in els:
            gmsh.model.mesh.addElementsByType(a, t, e.tolist(), n.tolist())
        used = np.unique(np.concatenate([n for _, _, n in els])) if els else nt
        if bool(np.all(plane[used])) and bool(np.all(plane[nt])):
            new[(dim, tag)] = (a, None)  # in the plane: its own image
            continue
        b = gmsh.model.addDiscreteEntity(dim)
        keep = ~plane[nt]
        mx = nx[keep] * np.array([-1.0, 1.0, 1.0])
        gmsh.model.mesh.addNodes(dim, b, image[nt[keep]].tolist(), mx.ravel().tolist())
        for t, e, n in els:
            conn = image[n]
            if t in FLIP:
                conn = conn.reshape(-1, len(FLIP[t]))[:, FLIP[t]]
            gmsh.model.mesh.addElementsByType(b, t, (e + e_off).tolist(), conn.ravel().tolist())
        new[(dim, tag)] = (a, b)
    out: dict[tuple[int, str], list[int]] = {}
    for dim, _, name, members in groups:
        half = [new[(dim, t)][0] for t in members]
        images = [m for t in members if (m := new[(dim, t)][1]) is not None]
        if name in MIRRORED_GROUP:
            out[(dim, name)] = half
            out[(dim, MIRRORED_GROUP[name])] = images
        else:
            out[(dim, name)] = half + images
    for (dim, name), members in sorted(out.items(), key=lambda kv: group_tags[kv[0][1]]):
        gmsh.model.addPhysicalGroup(dim, members, group_tags[name])
        gmsh.model.setPhysicalName(dim, group_tags[name], name)
    gmsh.model.mesh.renumberNodes()
    gmsh.model.mesh.renumberElements()


def keep_half(gmsh: Any, vols: list[tuple[int, int]]) -> list[int]:
    """Cut the volumes ``vols`` ((3, tag) pairs, OpenCASCADE) to the half-space x >= 0;
    returns the tags of what is left (synchronised)."""
    occ = gmsh.model.occ
    big = 1e4  # mm: beyond any rig
    box = occ.addBox(0.0, -big, -big, big, 2 * big, 2 * big)
    cut, _ = occ.intersect(vols, [(3, box)])
    occ.synchronize()
    return [t for d, t in cut if d == 3]


__all__ = ["FLIP", "MIRRORED_GROUP", "keep_half", "mirror_model"]
