"""Pictures: pyvista off-screen 3-D views and matplotlib 2-D figures, the HTML report.

Importing this package imports neither pyvista nor matplotlib; each module
imports its plotting library inside its functions, so the numerics never
load GL.
"""
