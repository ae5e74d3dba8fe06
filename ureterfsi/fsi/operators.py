"""Cartesian (2D plane / 3D) and axisymmetric (r-z) differential operators behind the physics blocks.

Axisymmetric scenes use a 2D mesh with coordinates (r, z) = (x[0], x[1]) and vector fields
(a_r, a_z) without swirl. Every operator returns the 3D tensor of the axisymmetric field in
cylindrical components (r, theta, z), so the same physics blocks serve both; `weight` is the
volume/area measure factor (2 pi r, so integrals are the true 3D values; 1 otherwise).
"""
from __future__ import annotations

import math

import ufl


class Operators:
    def __init__(self, mesh, axisymmetric: bool = False):
        self.mesh = mesh
        self.axisymmetric = axisymmetric
        self.gdim = mesh.geometry.dim
        if axisymmetric and self.gdim != 2:
            raise ValueError("axisymmetric scenes need a 2D (r, z) mesh")
        x = ufl.SpatialCoordinate(mesh)
        self.r = x[0] if axisymmetric else None
        self.weight = 2.0 * math.pi * x[0] if axisymmetric else 1.0
        self.dim = 3 if axisymmetric else self.gdim

    def identity(self):
        return ufl.Identity(self.dim)

    def vec(self, a):
        """3-vector (a_r, 0, a_z) of an axisymmetric field; `a` itself otherwise."""
        if not self.axisymmetric:
            return a
        return ufl.as_vector([a[0], 0.0, a[1]])

    def grad(self, a):
        """Gradient of a vector field (3x3 in axisymmetric form, with hoop term a_r / r)."""
        if not self.axisymmetric:
            return ufl.grad(a)
        g = ufl.grad(a)
        return ufl.as_tensor([[g[0, 0], 0.0, g[0, 1]],
                              [0.0, a[0] / self.r, 0.0],
                              [g[1, 0], 0.0, g[1, 1]]])

    def grad_scalar(self, f):
        if not self.axisymmetric:
            return ufl.grad(f)
        g = ufl.grad(f)
        return ufl.as_vector([g[0], 0.0, g[1]])

    def normal(self):
        return self.vec(ufl.FacetNormal(self.mesh))
