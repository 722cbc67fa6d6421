"""upd-workbench: finite element and harmonic balance workbench for turbine
under-platform friction dampers (wedge, cylinder, cone).

The sub-packages follow the data flow::

    analytic  -> closed-form cone kinematics (design stage, no FE)
    geometry  -> gmsh rig and damper meshes with matched contact nodes
    fe        -> dolfinx/SLEPc modes and Craig-Bampton ReducedModel (HDF5)
    contact   -> node-to-node 3-D friction law, vectorised
    hbm       -> AFT, residual/Jacobian, SNES corrector, continuation, Hill
    assembly  -> rig + damper + contact pairs + preload + excitation
    studies   -> study TOML runner: cases, cache, resume, MPI
    post      -> receptances, energies, contact status, tables
    render    -> pyvista / matplotlib figures and the HTML report
    cli       -> the ``upd`` command

Nothing below ``fe`` imports dolfinx or gmsh.
"""

__version__ = "0.1.0"
