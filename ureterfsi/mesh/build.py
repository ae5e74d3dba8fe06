"""Conforming gmsh meshes of the stented ureter (paper §2.1 geometry, Table 1 hole pairs, §2.4.1 mesh).

One OpenCASCADE model per (model, level, symmetry): ureter wall tube, fluid lumen, stent tube (coaxial, or its
axis displaced along x by geometry.stent_offset) with radial side holes on the y axis, or alternating y and x
(geometry.hole_arrangement), fragmented into a conforming multi-region tetrahedral mesh. Cells and
facets are gmsh physical groups numbered as in `ureterfsi.mesh.tags`; every boundary facet and every interface
facet carries exactly one tag. "half" keeps x >= 0, or y >= 0 for an offset stent (the x = 0 plane is no mirror
then); "quarter" keeps x, y >= 0 and refuses an offset stent. "axisymmetric" (model 1 only) is the r-z section, r = x, z = y.

choice: the paper meshes with COMSOL (boundary-layer prisms, §2.4.1); here all elements are simplices,
sized by analytic radial distance fields (exact, no sampling) and a Distance field on the hole walls
(ureterfsi.mesh.sizing).
"""
from __future__ import annotations

import math
import time

import gmsh
import numpy as np

from ureterfsi.mesh import tags
from ureterfsi.mesh.geometry import (SYMMETRY_FRACTION, StentModel, UreterGeometry, hole_pair_axes, hole_pair_positions,
                                lumen_area, occluded_holes, subdomain_volumes)
from ureterfsi.mesh.io import group_elements, write_msh
from ureterfsi.mesh.quality import simplex_measure, cell_quality, hole_channels, hole_resolution
from ureterfsi.mesh.sizing import hole_wall_surfaces, optimize, size_fields
from ureterfsi.data.provenance import provenance_attrs, write_json

# choice: rotation of the z-cylinders about z (seam line at 225 deg, inside the removed part of every
# symmetric model) and of the hole cylinders about y (seam at x = -a; an x-axis hole is the y-axis one turned by
# +90 deg about z, seam at y = -a), so no seam lies on a cut plane.
SEAM_ANGLE_Z = 1.25 * math.pi
SEAM_ANGLE_HOLE = -0.5 * math.pi
# choice: the strictured wall profile is an interpolating spline through this many points of the cosine bump
# (ureterfsi.mesh.geometry.Stricture.bump), one of them at its centre, so the narrowest radius is exact.
STRICTURE_SPLINE_POINTS = 41


def _request(cfg: dict, model: str, level: str, symmetry: str):
    """Validate a mesh request; return geometry, stent model, hole-pair positions and size factor."""
    if str(model) not in cfg["models"]:
        raise ValueError(f"unknown model {model!r}; configured models: {sorted(cfg['models'])}")
    if level not in cfg["mesh"]["levels"]:
        raise ValueError(f"unknown mesh level {level!r}; configured levels: {list(cfg['mesh']['levels'])}")
    if symmetry not in SYMMETRY_FRACTION:
        raise ValueError(f"unknown symmetry {symmetry!r}; use full, half, quarter or axisymmetric")
    geom, sm = UreterGeometry.from_config(cfg), StentModel.from_config(cfg, model)
    if symmetry == "axisymmetric" and sm.stent:
        raise ValueError(f"model {model} has a stent with side holes on the y axis: it is not axisymmetric; "
                         "axisymmetric meshes exist only for the stent-free model")
    if symmetry == "quarter" and geom.stent_offset:
        raise ValueError(f"geometry.stent_offset: {geom.stent_offset} m breaks the x = 0 mirror plane, so the quarter "
                         "model cannot be posed; use symmetry half (y >= 0)")
    if not sm.stent and sm.holes:
        raise ValueError(f"model {model} has {sm.holes} side holes but no stent")
    if sm.holes % 2:
        raise ValueError(f"model {model}: side holes come in opposite pairs, {sm.holes} is odd")
    if geom.occluded and not sm.stent:
        raise ValueError(f"model {model} has no stent: a complete occlusion closes the annulus onto the stent")
    if occluded_holes(geom, sm).size:
        raise ValueError(f"model {model}: a side-hole pair lies under the occlusion's span {geom.occlusion.span} m")
    z = hole_pair_positions(geom, sm)
    a = geom.hole_radius
    if sm.holes and a >= geom.stent_inner_radius:
        raise ValueError(f"hole radius {a} m must be smaller than the stent inner radius {geom.stent_inner_radius} m")
    if z.size and (z.min() - a <= 0 or z.max() + a >= geom.length):
        raise ValueError(f"model {model}: a side hole cuts a stent end face (hole_end_clearance too small)")
    if z.size > 1 and np.diff(z).min() <= 2 * a:
        raise ValueError(f"model {model}: neighbouring side holes overlap (pair spacing <= hole diameter)")
    return geom, sm, z, float(cfg["mesh"]["levels"][level]["size_factor"])


def _profile_face(geom: UreterGeometry, radius, dim: int) -> int:
    """OCC plane surface between the axis and r = radius(z), 0 <= z <= L: in the x-z plane (dim 3, to be
    revolved about z) or the r-z section (dim 2, r = x, z = y). Straight lines outside the stricture, over it
    two interpolating splines (STRICTURE_SPLINE_POINTS in all) meeting at its centre, a mesh vertex."""
    occ, L, st = gmsh.model.occ, geom.length, geom.stricture
    point = (lambda r, z: occ.addPoint(r, 0.0, z)) if dim == 3 else (lambda r, z: occ.addPoint(r, z, 0.0))
    a, b = st.position - 0.5 * st.length, st.position + 0.5 * st.length
    zs = np.linspace(a, b, STRICTURE_SPLINE_POINTS)
    spline = [point(float(radius(z)), float(z)) for z in zs]
    p_in, p_out = point(float(radius(0.0)), 0.0), point(float(radius(L)), L)
    axis_in, axis_out = point(0.0, 0.0), point(0.0, L)
    curves = [occ.addLine(axis_in, p_in)]
    if a > 0.0:
        curves.append(occ.addLine(p_in, spline[0]))
    else:
        spline[0] = p_in
    if b >= L:
        spline[-1] = p_out
    mid = STRICTURE_SPLINE_POINTS // 2
    curves += [occ.addSpline(spline[:mid + 1]), occ.addSpline(spline[mid:])]
    if b < L:
        curves.append(occ.addLine(spline[-1], p_out))
    curves += [occ.addLine(p_out, axis_out), occ.addLine(axis_out, axis_in)]
    return occ.addPlaneSurface([occ.addCurveLoop(curves)])


def _occlusion_profiles(geom: UreterGeometry) -> tuple:
    """(lumen, outer) profiles of an occluded wall as lists of (r, z) point lists from z = 0 to z = L (each list a
    line if of two points, else an interpolating spline through STRICTURE_SPLINE_POINTS // 2 + 1 points of a taper,
    Occlusion.radius). The lumen's tapers go on past the stent's outer radius r_s (which they cross at the contact's
    ends, inside a spline: a transversal crossing) to the stent's mid-wall radius, and run there under the contact:
    fused with the stent's outer cylinder, the lumen's surface is r_s over the contact (_solids)."""
    occ, ri, rs, L = geom.occlusion, geom.ureter_inner_radius, geom.stent_outer_radius, geom.length
    thick = geom.ureter_outer_radius - ri
    z0, z1 = occ.contact
    lo, hi = occ.span
    r_low = geom.probe_radius
    s_low = 2.0 / math.pi * math.asin((r_low - rs) / (ri - rs))
    s = np.linspace(1.0, 0.0, STRICTURE_SPLINE_POINTS // 2 + 1)

    def taper(s, shift):   # upstream taper from s[0] to s[-1], downstream mirrored
        r = rs + (ri - rs) * np.sin(0.5 * math.pi * s) + shift
        up = [(float(a), float(z0 - b * occ.taper)) for a, b in zip(r, s)]
        return up, [(a, z0 + z1 - z) for a, z in reversed(up)]

    def profile(s, shift):
        up, down = taper(s, shift)
        return [[(ri + shift, 0.0), up[0]], up, [up[-1], down[0]], down, [down[-1], (ri + shift, L)]]

    return profile(np.r_[s, s_low], 0.0), profile(s, thick)


def _segments_face(segments: list) -> int:
    """OCC plane surface in the x-z plane between the axis and a profile (r, z) given as point lists from z = 0 to
    z = L (_occlusion_profiles), to be revolved about z."""
    occ = gmsh.model.occ
    ends = {}

    def point(r, z):
        key = (round(r, 15), round(z, 15))
        if key not in ends:
            ends[key] = occ.addPoint(r, 0.0, z)
        return ends[key]

    axis_in, axis_out = occ.addPoint(0.0, 0.0, 0.0), occ.addPoint(0.0, 0.0, segments[-1][-1][1])
    curves = [occ.addLine(axis_in, point(*segments[0][0]))]
    for seg in segments:
        tags_ = [point(*p) for p in seg] if len(seg) == 2 else \
            [point(*seg[0])] + [occ.addPoint(r, 0.0, z) for r, z in seg[1:-1]] + [point(*seg[-1])]
        curves.append(occ.addLine(*tags_) if len(seg) == 2 else occ.addSpline(tags_))
    curves += [occ.addLine(point(*segments[-1][-1]), axis_out), occ.addLine(axis_out, axis_in)]
    return occ.addPlaneSurface([occ.addCurveLoop(curves)])


def _revolved(geom: UreterGeometry, radius) -> list:
    """Solid of revolution about z of the face under r = radius(z), seam at SEAM_ANGLE_Z (as zcyl)."""
    return _revolve(_profile_face(geom, radius, 3))


def _revolve(face: int) -> list:
    """Solid of revolution about z of an x-z face, seam at SEAM_ANGLE_Z (as zcyl)."""
    occ = gmsh.model.occ
    occ.rotate([(2, face)], 0, 0, 0, 0, 0, 1, SEAM_ANGLE_Z)
    return [d for d in occ.revolve([(2, face)], 0, 0, 0, 0, 0, 1, 2 * math.pi) if d[0] == 3]


def _solids(geom: UreterGeometry, sm: StentModel, z_holes: np.ndarray, axes: np.ndarray, symmetry: str) -> dict:
    """OCC solids fragmented into conforming regions; returns cell tag -> OCC volume tags."""
    occ, L, xs = gmsh.model.occ, geom.length, geom.stent_offset

    def zcyl(r, x0=0.0):
        tag = occ.addCylinder(x0, 0, 0, 0, 0, L, r)
        occ.rotate([(3, tag)], x0, 0, 0, 0, 0, 1, SEAM_ANGLE_Z)
        return [(3, tag)]

    def keep(dimtags):  # the x >= 0 (half; y >= 0 for an offset stent) or x, y >= 0 (quarter) part
        if symmetry == "full":
            return dimtags
        big = 2 * geom.ureter_outer_radius
        if xs:
            box = occ.addBox(-big, 0, -0.1 * L, 2 * big, big, 1.2 * L)
        else:
            y0 = 0.0 if symmetry == "quarter" else -big
            box = occ.addBox(0, y0, -0.1 * L, big, big - y0, 1.2 * L)
        return occ.intersect(dimtags, [(3, box)])[0]

    if geom.occluded:   # the lumen fused with the stent's outer cylinder: r_s where the wall lies on the stent
        inner, wall = _occlusion_profiles(geom)
        outer = keep(_revolve(_segments_face(wall)))
        lumen = keep(occ.fuse(_revolve(_segments_face(inner)), zcyl(geom.stent_outer_radius))[0])
    elif geom.strictured:
        outer, lumen = keep(_revolved(geom, geom.outer_radius)), keep(_revolved(geom, geom.inner_radius))
    else:
        outer, lumen = keep(zcyl(geom.ureter_outer_radius)), keep(zcyl(geom.ureter_inner_radius))
    tools = [outer, lumen]
    if sm.stent:
        holes = []
        for z, axis in zip(z_holes, axes):
            ro = 1.5 * geom.stent_outer_radius
            tag = occ.addCylinder(xs, -ro, z, 0, 2 * ro, 0, geom.hole_radius)
            occ.rotate([(3, tag)], xs, 0, z, 0, 1, 0, SEAM_ANGLE_HOLE)
            if axis == 0:
                occ.rotate([(3, tag)], xs, 0, z, 0, 0, 1, 0.5 * math.pi)
            holes.append((3, tag))
        tube = occ.cut(zcyl(geom.stent_outer_radius, xs), zcyl(geom.stent_inner_radius, xs) + holes)[0]
        # choice: in a stricture the stent's outer cylinder is fragmented with the fluid too, so each hole mouth is
        # a mesh face and the algebraic ALE map's still region (r <= stent outer radius: stent lumen and holes) ends
        # on faces; without them its clipped weight folds the cells across the mouth of a hole under a 0.2 mm gap
        # (min J -0.31; with them 0.49, docs/stricture.md). Unstrictured meshes stay as they were (pinned).
        if geom.strictured:
            tools.append(keep(zcyl(geom.stent_outer_radius, xs)))
        tools.append(keep(tube))
    _, pieces = occ.fragment(tools[0], [d for t in tools[1:] for d in t])
    occ.synchronize()
    n0, n1 = len(tools[0]), len(tools[0]) + len(tools[1])
    inside = lambda part: {t for dts in part for _, t in dts}  # noqa: E731
    everything, lumen_set = inside(pieces[:n0]), inside(pieces[n0:n1])
    stent = inside(pieces[len(pieces) - len(tools[-1]):]) if sm.stent else set()
    return {tags.URETER: sorted(everything - lumen_set), tags.FLUID: sorted(lumen_set - stent),
            tags.STENT: sorted(stent)}


def _facet_groups(regions: dict, dim: int, geom: UreterGeometry) -> dict:
    """Facet tag -> boundary entities: interfaces by shared ownership, exterior faces by position."""
    owner: dict[int, list] = {}
    for cell_tag, ents in regions.items():
        for e in ents:
            for _, f in gmsh.model.getBoundary([(dim, e)], combined=False, oriented=False):
                owner.setdefault(abs(f), []).append(cell_tag)
    tol, L = 1e-3 * geom.hole_radius, geom.length  # OCC bounding boxes are padded by ~1e-7 m
    ends = {tags.FLUID: (tags.INLET, tags.OUTLET), tags.URETER: (tags.URETER_ENDS,) * 2,
            tags.STENT: (tags.STENT_ENDS,) * 2}
    interface = {frozenset((tags.FLUID, tags.URETER)): tags.FLUID_URETER,
                 frozenset((tags.FLUID, tags.STENT)): tags.FLUID_STENT,
                 frozenset((tags.URETER, tags.STENT)): tags.URETER_STENT}
    groups: dict[int, list] = {}
    box = _sampled_box if geom.strictured or geom.occluded else gmsh.model.getBoundingBox
    for f, cells in owner.items():
        if cells == [tags.FLUID, tags.FLUID]:    # a hole mouth (strictured meshes): inside the fluid, untagged
            continue
        x0, y0, z0, x1, y1, z1 = box(dim - 1, f)
        if dim == 2:  # r-z section: r = x, z = y
            x0, y0, z0, x1, y1, z1 = x0, None, y0, x1, None, y1
        if len(cells) == 2:
            key = interface.get(frozenset(cells))
            if key is None:
                raise RuntimeError(f"unexpected interface between cell tags {cells}")
        elif abs(z1) < tol or abs(z0 - L) < tol:
            key = ends[cells[0]][abs(z1) >= tol]
        elif abs(x0) < tol and abs(x1) < tol:
            key = tags.AXIS if dim == 2 else tags.SYMMETRY_X
        elif dim == 3 and abs(y0) < tol and abs(y1) < tol:
            key = tags.SYMMETRY_Y
        elif cells[0] == tags.URETER:
            key = tags.URETER_OUTER
        else:
            raise RuntimeError(f"boundary entity {f} of cell tag {cells[0]} is not classified")
        groups.setdefault(key, []).append(f)
    return groups


def _sampled_box(dim: int, entity: int) -> tuple:
    """Bounding box of points sampled on an entity's parametrisation (9 per parameter): tight where OCC pads the
    boxes of spline-bounded faces by ~5e-6 m (the strictured wall), more than _facet_groups' tolerance."""
    lo, hi = (np.asarray(b, dtype=float) for b in gmsh.model.getParametrizationBounds(dim, entity))
    axes = np.meshgrid(*(np.linspace(a, b, 9) for a, b in zip(lo, hi)), indexing="ij")
    xyz = np.asarray(gmsh.model.getValue(dim, entity, np.stack([a.ravel() for a in axes], 1).ravel())).reshape(-1, 3)
    return (*xyz.min(axis=0), *xyz.max(axis=0))


def _axisymmetric(geom: UreterGeometry) -> dict:
    """r-z section of the stent-free model: fluid [0, Ri] x [0, L], ureter wall [Ri, Ro] x [0, L] (the faces under
    R_i(z) and between R_i(z), R_o(z) when strictured)."""
    occ, L = gmsh.model.occ, geom.length
    if geom.strictured:
        outer, lumen = _profile_face(geom, geom.outer_radius, 2), _profile_face(geom, geom.inner_radius, 2)
        _, pieces = occ.fragment([(2, outer)], [(2, lumen)])
        occ.synchronize()
        fluid = {t for _, t in pieces[1]}
        return {tags.FLUID: sorted(fluid), tags.URETER: sorted({t for _, t in pieces[0]} - fluid)}
    fluid = occ.addRectangle(0, 0, 0, geom.ureter_inner_radius, L)
    wall = occ.addRectangle(geom.ureter_inner_radius, 0, 0, geom.ureter_outer_radius - geom.ureter_inner_radius, L)
    _, pieces = occ.fragment([(2, fluid)], [(2, wall)])
    occ.synchronize()
    return {tags.FLUID: [t for _, t in pieces[0]], tags.URETER: [t for _, t in pieces[1]]}


def build_mesh(cfg: dict, model: str, level: str, symmetry: str, msh_path, sidecar_path) -> dict:
    """Build, check and write one mesh (.msh 4.1, physical groups only) and its JSON sidecar (§2.4.1)."""
    geom, sm, z_holes, f = _request(cfg, str(model), level, symmetry)
    axes = hole_pair_axes(geom, sm)
    dim = 2 if symmetry == "axisymmetric" else 3
    t0 = time.perf_counter()
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.option.setNumber("Mesh.RandomSeed", 1)
        gmsh.model.add(f"model{model}_{level}_{symmetry}")
        regions = _axisymmetric(geom) if dim == 2 else _solids(geom, sm, z_holes, axes, symmetry)
        regions = {k: v for k, v in regions.items() if v}
        facets = _facet_groups(regions, dim, geom)
        for tag, ents in regions.items():
            gmsh.model.setPhysicalName(dim, gmsh.model.addPhysicalGroup(dim, ents, tag), tags.CELL_NAMES[tag])
        for tag, ents in facets.items():
            gmsh.model.setPhysicalName(dim - 1, gmsh.model.addPhysicalGroup(dim - 1, ents, tag),
                                       tags.FACET_NAMES[tag])
        size_fields(cfg, geom, f, hole_wall_surfaces(regions.get(tags.STENT, []), geom) if dim == 3 else [], dim)
        gmsh.model.mesh.generate(dim)
        optimizer = optimize(dim) if cfg["mesh"]["optimize"] else "none"
        gmsh.model.mesh.renumberNodes()
        gmsh.model.mesh.renumberElements()
        wall_time = time.perf_counter() - t0

        node_tags, xyz, _ = gmsh.model.mesh.getNodes()
        coords = np.zeros((int(node_tags.max()), 3))
        coords[node_tags.astype(np.int64) - 1] = xyz.reshape(-1, 3)
        cells = {tags.CELL_NAMES[t]: group_elements(dim, t) for t in regions}
        names = ("fluid", "ureter", "stent")
        if dim == 3:
            analytic = subdomain_volumes(geom, sm, SYMMETRY_FRACTION[symmetry])
        else:
            analytic = {"fluid": lumen_area(geom) if geom.strictured else geom.ureter_inner_radius * geom.length,
                        "ureter": (geom.ureter_outer_radius - geom.ureter_inner_radius) * geom.length,
                        "stent": 0.0}
        measured = {k: (simplex_measure(cells[k], coords) if k in cells else 0.0) for k in names}
        stent_facets = group_elements(2, tags.FLUID_STENT) if tags.FLUID_STENT in facets else None
        channels = hole_channels(coords, stent_facets, geom.stent_offset) if stent_facets is not None else []
        info = {
            "model": str(model), "level": level, "symmetry": symmetry, "size_factor": f,
            "element_type": "triangle" if dim == 2 else "tetrahedron",
            "cells": {k: int(len(v)) for k, v in cells.items()},
            "cells_total": int(sum(len(v) for v in cells.values())),
            "nodes": int(node_tags.size),
            "quality_minSICN": cell_quality(dim),
            "measure": "area" if dim == 2 else "volume",
            "subdomain_measure": {k: {"mesh": measured[k], "analytic": analytic[k],
                                      "rel_error": (measured[k] / analytic[k] - 1) if analytic[k] else 0.0}
                                  for k in names},
            "hole_pair_z": [float(z) for z in z_holes],
            "hole_pair_axis": ["xy"[a] for a in axes],
            "stent_offset": geom.stent_offset,
            "hole_channels_found": len(channels),
            "hole_channels": channels,
            **(hole_resolution(coords, stent_facets, 2 * geom.hole_radius, geom.stent_offset) if channels else {}),
            "facet_tags": {tags.FACET_NAMES[t]: int(len(group_elements(dim - 1, t))) for t in sorted(facets)},
            "optimizer": optimizer,
            "mesh_wall_time_s": wall_time,
            "gmsh_version": gmsh.__version__,
        }
        write_msh(msh_path)
    finally:
        gmsh.finalize()
    info.update(provenance_attrs(cfg))
    write_json(sidecar_path, info)
    return info
