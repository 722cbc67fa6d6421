"""Assembly of rig + damper + contact pairs + preload + excitation.

Importing this package imports neither dolfinx nor gmsh.
"""
