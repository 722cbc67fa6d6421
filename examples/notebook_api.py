"""The Python API in one script: a cone damper from geometry to figures, then your own matrices.

Run it as a script or paste it cell by cell into a notebook::

    .venv/bin/python examples/notebook_api.py [OUT]      # default OUT: results/notebook

It meshes a coarse rig (14 mm) with the cone, reduces it (Craig-Bampton,
4 fixed-interface modes, rigid damper: about 30 s the first time, cached
after), computes the out-of-phase response at two forces, and draws the
receptances and the contact status. ``tests/test_api.py`` runs it and
checks the numbers it prints against the figures it draws.
"""

import sys
from pathlib import Path

import workbench as wb

out = Path(sys.argv[1] if len(sys.argv) > 1 else "results/notebook")

# 1. rig + damper -> reduced, coupled model (every stage cached under out/cache)
m = wb.model("cone", mesh_size=14, modes=4, rigid_damper=True, out=out)
print(f"model: {m.n_dofs} generalised DOFs, {m.n_pairs} contact pairs")
for row in m.inputs():  # every value used, with its unit and where it came from
    print(f"  {row['option']:15s} {row['value']!s:8s} {row['unit']:10s} ({row['source']})")

# 2. forced responses: one curve per force (N per blade), out of phase
curves = [wb.frf(m, force_n=f, phase_deg=180.0, harmonics=[0, 1, 2]) for f in (3.84, 30.0)]
for c in curves:
    s = c.summary()
    print(
        f"{c.force_n:5g} N: peak {s['peak_amplitude_mm']:.4g} mm at "
        f"{s['peak_frequency_hz']:.2f} Hz, friction energy {s['friction_energy_mj']:.3g} mJ"
    )

# 3. figures: matplotlib Figure objects; written only when asked
fig = wb.receptance_figure(curves)  # in a notebook, the cell shows it
fig.savefig(out / "receptance.png")
wb.status_figure(curves, path=out / "status.png")

# 4. your own reduced matrices (any FE code): the upd frf model files
branches = wb.frf_curves(Path(wb.__file__).parents[1] / "studies/examples/sdof_jenkins.toml")
wb.frf_figure(branches, path=out / "sdof_frf.png")
print("figures:", ", ".join(p.name for p in sorted(out.glob("*.png"))))
