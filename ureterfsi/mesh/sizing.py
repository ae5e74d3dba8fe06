"""How a ureter mesh is sized and optimised (paper §2.4.1): gmsh's background size field (analytic radial distance
fields at the ureter wall, the stent wall and a stricture's gap, a Distance field on the hole walls) and the
optimisation of the tetrahedra after meshing."""
from __future__ import annotations

import math

import gmsh

from ureterfsi.mesh.geometry import UreterGeometry

# choice: away from a refined region the element size grows linearly to the bulk size over
# (h_bulk - h) / GRADING (sizes at size factor 1): refinement confined to a thin layer around the holes,
# the stent and the ureter wall.
GRADING = 0.5
# choice: gmsh's default optimisation threshold 0.3 left single tetrahedra of minSICN ~0.14; the second
# pass at 0.4 lifts the minimum to ~0.3 for a few seconds.
OPTIMIZE_THRESHOLD = 0.4
# choice: the fluid element size in a stricture is at most the local gap / this many (at size factor 1), so the
# narrowed annulus keeps elements across it (the bulk size alone leaves none in a gap of a few per cent).
STRICTURE_GAP_ELEMENTS = 3.0


def _threshold(in_field: int, size: float, bulk: float, dist_min: float, width: float) -> int:
    """Size `size` up to distance dist_min, growing linearly to `bulk` at dist_min + width."""
    field = gmsh.model.mesh.field
    th = field.add("Threshold")
    for name, value in (("InField", in_field), ("SizeMin", size), ("SizeMax", bulk), ("DistMin", dist_min),
                        ("DistMax", dist_min + width)):
        field.setNumber(th, name, value)
    return th


def _math(expr: str) -> int:
    f = gmsh.model.mesh.field.add("MathEval")
    gmsh.model.mesh.field.setString(f, "F", expr)
    return f


def size_fields(cfg: dict, geom: UreterGeometry, f: float, hole_walls: list, dim: int) -> None:
    """Min of Threshold fields: hole walls, stent wall, ureter wall (at R_i(z)), and in a stricture the narrowed gap
    / STRICTURE_GAP_ELEMENTS; bulk size elsewhere (§2.4.1).

    The transition widths (h_bulk - h) / GRADING are those of size factor 1 at every level, so every
    region is refined by f and element counts grow as f^-3 (about 2.3x per level for f steps of 0.76).
    """
    s1 = cfg["mesh"]["sizes"]
    s = {k: v * f for k, v in s1.items()}
    width = {k: (s1["fluid_bulk"] - v) / GRADING for k, v in s1.items()}
    r = "Sqrt(x^2+y^2)" if dim == 3 else "x"
    if geom.occluded:
        inner = _occlusion_expr(geom)
    else:
        inner = _stricture_expr(geom, "z" if dim == 3 else "y") if geom.strictured else f"{geom.ureter_inner_radius!r}"
    fields = [_threshold(_math(f"{inner}-{r}"), s["ureter_wall"], s["fluid_bulk"], 0.0, width["ureter_wall"])]
    if geom.strictured:  # gap / n in the fluid gap, growing by GRADING per unit distance outside it
        rs = geom.stent_outer_radius if hole_walls else 0.0
        out = f"(Abs({r}-{inner})+{r}-{inner})/2+(Abs({rs!r}-{r})+{rs!r}-{r})/2"
        fields.append(_math(f"({inner}-{rs!r})*{f / STRICTURE_GAP_ELEMENTS!r}+{GRADING!r}*({out})"))
    if hole_walls:
        rm = geom.probe_radius
        half = geom.stent_outer_radius - rm
        rs = f"Sqrt((x-{geom.stent_offset!r})^2+y^2)" if geom.stent_offset else r
        fields.append(_threshold(_math(f"Abs({rs}-{rm!r})-{half!r}"), s["stent_wall"], s["fluid_bulk"], 0.0,
                                 width["stent_wall"]))
        dist = gmsh.model.mesh.field.add("Distance")
        gmsh.model.mesh.field.setNumbers(dist, "FacesList", hole_walls)
        gmsh.model.mesh.field.setNumber(dist, "NumPointsPerCurve", 40)
        # the whole hole channel (distance <= hole radius from its wall) gets the hole size
        fields.append(_threshold(dist, s["hole"], s["fluid_bulk"], geom.hole_radius, width["hole"]))
    fmin = gmsh.model.mesh.field.add("Min")
    gmsh.model.mesh.field.setNumbers(fmin, "FieldsList", fields)
    gmsh.model.mesh.field.setAsBackgroundMesh(fmin)
    for name, value in (("MeshSizeExtendFromBoundary", 0), ("MeshSizeFromPoints", 0),
                        ("MeshSizeFromCurvature", 0), ("MeshSizeMax", s["fluid_bulk"])):
        gmsh.option.setNumber(f"Mesh.{name}", value)


def _stricture_expr(geom: UreterGeometry, z: str) -> str:
    """gmsh MathEval text of R_i(z) = R_i (1 - f (1 + cos(pi m)) / 2), m = min(|z - z_s| / (l_s / 2), 1)."""
    st, ri = geom.stricture, geom.ureter_inner_radius
    a = f"(Abs({z}-{st.position!r})/{0.5 * st.length!r})"
    m = f"(({a}+1-Abs({a}-1))/2)"
    return f"({ri!r}*(1-{st.fraction!r}*0.5*(1+Cos({math.pi!r}*{m}))))"


def _occlusion_expr(geom: UreterGeometry) -> str:
    """gmsh MathEval text of the occluded lumen radius (Occlusion.radius): r_s + (R_i - r_s) sin(pi m / 2),
    m = min(max((|z - z_o| - l / 2) / t, 0), 1)."""
    occ, ri, rs = geom.occlusion, geom.ureter_inner_radius, geom.stent_outer_radius
    a = f"((Abs(z-{occ.position!r})-{0.5 * occ.length!r})/{occ.taper!r})"
    pos = f"(({a}+Abs({a}))/2)"
    m = f"(({pos}+1-Abs({pos}-1))/2)"
    return f"({rs!r}+{ri - rs!r}*Sin({0.5 * math.pi!r}*{m}))"


def hole_wall_surfaces(stent_vols: list, geom: UreterGeometry) -> list:
    """Stent boundary surfaces that are hole walls (cylinders shorter in z than a hole diameter)."""
    out = set()
    for v in stent_vols:
        for _, s in gmsh.model.getBoundary([(3, v)], combined=False, oriented=False):
            bb = gmsh.model.getBoundingBox(2, abs(s))
            if gmsh.model.getType(2, abs(s)) == "Cylinder" and bb[5] - bb[2] < 3 * geom.hole_radius:
                out.add(abs(s))
    return sorted(out)


def optimize(dim: int) -> str:
    """Netgen optimisation of the tetrahedra where gmsh was built with it (Debian's gmsh 4.8 is not);
    otherwise gmsh's own optimiser once more, on every tetrahedron of quality < OPTIMIZE_THRESHOLD, then
    node relocation."""
    if dim == 2:
        return "none"
    if "Netgen" in gmsh.option.getString("General.BuildOptions").split():
        gmsh.model.mesh.optimize("Netgen")
        return "netgen"
    gmsh.option.setNumber("Mesh.OptimizeThreshold", OPTIMIZE_THRESHOLD)
    gmsh.model.mesh.optimize("")
    gmsh.model.mesh.optimize("Relocate3D")
    return "gmsh+relocate3d"
