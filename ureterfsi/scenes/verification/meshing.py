"""The gmsh models of the verification scenes: the current model in quadratic tetrahedra, the quarter annulus (its
surface, or its curved second-order mesh)."""
from __future__ import annotations

import gmsh
from dolfinx.io import gmshio
from mpi4py import MPI


def quadratic_tetrahedra(h):
    """The current gmsh model meshed at uniform size h with quadratic tetrahedra, as dolfinx (mesh, cell tags,
    facet tags)."""
    gmsh.option.setNumber("Mesh.MeshSizeMin", h)
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    gmsh.model.mesh.generate(3)
    gmsh.model.mesh.setOrder(2)
    return gmshio.model_to_mesh(gmsh.model, MPI.COMM_WORLD, 0, gdim=3)


def quarter_annulus_model(name, Ri, Ro):
    """In a new gmsh model `name`: the quarter annulus Ri < r < Ro, x, y >= 0 (built-in kernel); returns its
    surface and {1: inner arc, 2: outer arc, 3: x = 0 line, 4: y = 0 line}."""
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add(name)
    geo = gmsh.model.geo
    c = geo.addPoint(0, 0, 0)
    p1, p2, p3, p4 = (geo.addPoint(Ri, 0, 0), geo.addPoint(Ro, 0, 0), geo.addPoint(0, Ro, 0), geo.addPoint(0, Ri, 0))
    curves = {4: geo.addLine(p1, p2), 2: geo.addCircleArc(p2, c, p3), 3: geo.addLine(p3, p4),
              1: geo.addCircleArc(p4, c, p1)}
    surf = geo.addPlaneSurface([geo.addCurveLoop([curves[4], curves[2], curves[3], curves[1]])])
    return surf, curves


def quarter_annulus_mesh(Ri, Ro, h, order=2):
    """Quarter annulus Ri < r < Ro, x, y >= 0 (gmsh, curved second-order geometry).
    Facets: 1 inner arc, 2 outer arc, 3 x = 0 line, 4 y = 0 line; cells 1."""
    gmsh.initialize()
    try:
        surf, curves = quarter_annulus_model("quarter-annulus", Ri, Ro)
        geo = gmsh.model.geo
        geo.synchronize()
        gmsh.model.addPhysicalGroup(2, [surf], 1)
        for tag, curve in sorted(curves.items()):
            gmsh.model.addPhysicalGroup(1, [curve], tag)
        gmsh.option.setNumber("Mesh.MeshSizeMin", h)
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        gmsh.model.mesh.generate(2)
        gmsh.model.mesh.setOrder(order)
        mesh, ct, ft = gmshio.model_to_mesh(gmsh.model, MPI.COMM_WORLD, 0, gdim=2)
    finally:
        gmsh.finalize()
    return mesh, ct, ft
