"""gmsh builders for the blade rig and the cone, cylinder and wedge dampers.

Importing this package does not import gmsh; the builders do.
"""

from .records import BuiltGeometry, ContactSet

__all__ = ["BuiltGeometry", "ContactSet"]
