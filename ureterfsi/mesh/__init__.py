"""The ureter's geometry, tags and meshes.

geometry    ureter/stent/hole geometry from the configuration, analytic volumes
tags        integer tags of the subdomains and boundaries of every mesh
build       gmsh meshes (full, half, quarter, axisymmetric) with sidecar statistics
sizing      the element sizes of a mesh (gmsh's size fields) and the optimisation of its tetrahedra
quality     the measures of a built mesh: cell quality, hole channels, resolution across a hole
io          .msh files: read_msh, the one writer, load_mesh (dolfinx), mirror_mesh
"""
__all__ = ["build", "geometry", "io", "quality", "sizing", "tags"]
