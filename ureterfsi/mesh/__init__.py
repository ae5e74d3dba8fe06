"""The ureter's geometry, tags and meshes.

geometry    ureter/stent/hole geometry from the configuration, analytic volumes
tags        integer tags of the subdomains and boundaries of every mesh
build       gmsh meshes (full, half, quarter, axisymmetric) with sidecar statistics
io          the .msh reader
"""
__all__ = ["build", "geometry", "io", "tags"]
