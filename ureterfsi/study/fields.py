"""Field files of a run for ParaView: XDMF 3 + HDF5 at the probe times (and every k steps).

What is written (config `fields`), on the reference (ALE) mesh of each part:
  velocity      m s-1  urine velocity; the solid velocity in the wall and stent
  pressure      Pa     urine pressure; the reference pressure p_ref at the vertices of no urine cell (select the
                       urine by `subdomain` = 1: NaN there would reach the interface vertices too, as the XDMF
                       writer takes each vertex value by evaluating the P1 field in every adjacent cell)
  displacement  m      solid displacement in the wall and stent, ALE mesh displacement in the urine:
                       ParaView's "Warp By Vector" with it gives the current configuration x = X + u
  von_mises     Pa     stent von Mises stress per cell (DG0: cell mean of the probes' DG1 field), NaN off the stent
  wall_shear_stress  Pa  the stent's wall shear stress on the urine cells beside it (DG0: the mean over each cell's
                       stent facets, ureterfsi.study.stent_surface), NaN elsewhere
Nodal fields are the vertex values of the P2 (velocity, displacement) and P1 (pressure) solution.

Parts: the fully coupled run writes one part, `domain` (the whole mesh, with the cell tags as `subdomain`,
ureterfsi.mesh.tags); the one-way rung writes `urine` (its fluid submesh) and `stent` (its stent submesh; the wall
is solved in r-z, its motion is the urine's displacement on the wall). Each part is one `<part>.xdmf`
(a temporal collection) over `<part>_mesh.h5` and one `<part>_s<step>.h5` per snapshot; `fields.json` lists
parts, times, quantities with units, sizes and the time spent writing. The directory is written as
`<dir>.part` and renamed into place when the run ends; a run resumed from its checkpoint keeps the
snapshots written before it.
"""
from __future__ import annotations

import json
import os
import shutil
import time as _time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from dolfinx import fem, io
from dolfinx import log as dlog

from ureterfsi.mesh import tags
from ureterfsi.fsi import Observer
from ureterfsi.data.cf import FIELD_VARIABLES, cf_meta
from ureterfsi.workflow import paths

FORMATS = ("xdmf",)
XI = "http://www.w3.org/2001/XInclude"


def fields_dir(out_path: str | os.PathLike) -> Path:
    """Field directory of a run dataset: results/runs/<...>/<name>.nc -> results/fields/<...>/<name>/ (the last
    `runs` component replaced); a dataset outside a `runs` folder gets <name>_fields/ beside it."""
    out = Path(out_path)
    parts = list(out.parent.parts)
    if paths.RUNS in parts:
        i = len(parts) - 1 - parts[::-1].index(paths.RUNS)
        parts[i] = paths.FIELDS
        return Path(*parts) / out.stem
    return out.with_name(out.stem + "_fields")


class _Nodal:
    """P1 (vertex-value) output of a field of a mixed state, or of a function."""

    def __init__(self, name, source, mesh, shape, outside=None):
        space = (fem.VectorFunctionSpace(mesh, ("Lagrange", 1)) if shape else fem.FunctionSpace(mesh, ("Lagrange", 1)))
        self.out = fem.Function(space, name=name)
        self.source = source
        self.fill, self.fill_value = None, None
        if outside is not None:      # (cells where the field lives, value at the vertices of no such cell)
            cells, self.fill_value = outside
            dofs = space.dofmap.list.array.reshape(-1, space.dofmap.dof_layout.num_dofs)
            keep = np.zeros(self.out.x.array.size, dtype=bool)
            keep[dofs[np.asarray(cells, np.int32)].ravel()] = True
            self.fill = ~keep

    def __call__(self):
        self.out.interpolate(self.source())
        if self.fill is not None:
            self.out.x.array[self.fill] = self.fill_value
        return self.out


class _CellMean:
    """DG0 output: the cell mean of a DG field (ureterfsi.fsi.probes.CellField) over `cells`, NaN elsewhere."""

    def __init__(self, name, cell_field, mesh, cells=None):
        self.out = fem.Function(fem.FunctionSpace(mesh, ("DG", 0)), name=name)
        n = mesh.topology.index_map(mesh.topology.dim).size_local + mesh.topology.index_map(mesh.topology.dim).num_ghosts
        self.cells = np.arange(n, dtype=np.int32) if cells is None else np.asarray(cells, np.int32)
        space = cell_field.space
        self.src = space.dofmap.list.array.reshape(-1, space.dofmap.dof_layout.num_dofs)[self.cells]
        self.dst = self.out.function_space.dofmap.list.array[self.cells]
        self.field = cell_field

    def __call__(self):
        arr = self.out.x.array
        arr[:] = np.nan
        arr[self.dst] = self.field.function.x.array[self.src].mean(axis=1)
        return self.out


class _WallShear:
    """DG0 output: the stent's wall shear stress on the urine cells beside it
    (ureterfsi.study.stent_surface.StentSurface.cell_magnitude), NaN elsewhere."""

    def __init__(self, surface, mesh):
        self.out = fem.Function(fem.FunctionSpace(mesh, ("DG", 0)), name="wall_shear_stress")
        self.surface = surface

    def __call__(self):
        cells, values = self.surface.cell_magnitude()
        arr = self.out.x.array
        arr[:] = np.nan
        arr[self.out.function_space.dofmap.list.array[cells]] = values
        return self.out


class Part:
    """One mesh of the field output and its fields {quantity: callable -> output fem.Function}."""

    def __init__(self, name: str, mesh, fields: dict, static: dict | None = None):
        self.name, self.mesh, self.fields, self.static = name, mesh, fields, static or {}


def _static_tags(mesh, cell_tags):
    f = fem.Function(fem.FunctionSpace(mesh, ("DG", 0)), name="subdomain")
    f.x.array[:] = np.nan
    f.x.array[f.function_space.dofmap.list.array[cell_tags.indices]] = cell_tags.values
    return f


def coupled_parts(pb, stent, quantities, reference_pressure: float, surface=None) -> list[Part]:
    """Part `domain` of a fully coupled run (ureterfsi.study.coupled): the whole mesh; `stent` a CoupledStent or None,
    `surface` its StentSurface or None; the pressure is reference_pressure (Pa) off the urine (its dofs there are
    pinned to 0 by the solver)."""
    mesh, ct = pb.mesh, pb.scene.cell_tags
    gdim = mesh.geometry.dim
    fluid = np.unique(np.concatenate([ct.find(t) for t in pb.scene.fluid.tags]))
    makers = {
        "velocity": lambda: _Nodal("velocity", lambda: pb.field("velocity"), mesh, (gdim,)),
        "pressure": lambda: _Nodal("pressure", lambda: pb.field("pressure"), mesh, (),
                                   outside=(fluid, reference_pressure)),
        "displacement": lambda: _Nodal("displacement", lambda: pb.field("displacement"), mesh, (gdim,)),
        "von_mises": lambda: _CellMean("von_mises", stent.von_mises, mesh, ct.find(tags.STENT)),
        "wall_shear_stress": lambda: _WallShear(surface, mesh),
    }
    wanted = [q for q in quantities if (q != "von_mises" or stent is not None)
              and (q != "wall_shear_stress" or surface is not None)]
    return [Part("domain", mesh, {q: makers[q]() for q in wanted}, {"subdomain": _static_tags(mesh, ct)})]


def oneway_parts(pb, stent, quantities, surface=None) -> list[Part]:
    """Parts `urine` (the fluid submesh of the one-way rung; the stent's wall shear stress from `surface`, its
    StentSurface, or None) and `stent` (its QuasiStaticStent, or None)."""
    mesh = pb.mesh
    gdim = mesh.geometry.dim
    makers = {"velocity": lambda: _Nodal("velocity", lambda: pb.field("velocity"), mesh, (gdim,)),
              "pressure": lambda: _Nodal("pressure", lambda: pb.field("pressure"), mesh, ()),
              "displacement": lambda: _Nodal("displacement", lambda: pb.field("displacement"), mesh, (gdim,))}
    if surface is not None:
        makers["wall_shear_stress"] = lambda: _WallShear(surface, mesh)
    parts = [Part("urine", mesh, {q: makers[q]() for q in quantities if q in makers})]
    if stent is not None:
        smesh = stent.mesh
        sf = {}
        if "displacement" in quantities:
            sf["displacement"] = _Nodal("displacement", lambda: stent.u, smesh, (smesh.geometry.dim,))
        if "von_mises" in quantities:
            sf["von_mises"] = _CellMean("von_mises", stent.von_mises, smesh)
        if sf:
            parts.append(Part("stent", smesh, sf))
    return parts


def _quiet_write(path, comm, mesh=None, functions=(), time=0.0):
    """XDMFFile write of a mesh and/or functions; dolfinx's warning about a function file without its mesh
    (the index written by FieldWriter.finish points every snapshot to the part's mesh file) is silenced."""
    level = dlog.get_log_level()
    dlog.set_log_level(dlog.LogLevel.ERROR)
    try:
        with io.XDMFFile(comm, str(path), "w") as fh:
            if mesh is not None:
                fh.write_mesh(mesh)
            for f in functions:
                fh.write_function(f, time)
    finally:
        dlog.set_log_level(level)


class FieldWriter(Observer):
    """Writes the parts' fields at `times` (within 1e-9 s) and, if every_steps > 0, every that many steps."""

    def __init__(self, directory, parts: list[Part], times, every_steps: int, comm):
        self.final = Path(directory)
        self.stage = self.final.with_name(self.final.name + ".part")
        self.parts, self.times, self.every = parts, [float(t) for t in times], int(every_steps)
        self.comm = comm
        self.snapshots: list[tuple[int, float]] = []
        self.write_time = 0.0
        self._meshes_written = False

    def _due(self, step, t):
        return any(abs(t - tk) < 1e-9 for tk in self.times) or (self.every > 0 and step % self.every == 0)

    def observe(self, problem, step: int) -> None:
        t = float(problem.time)
        if step == 0 and self.comm.rank == 0 and self.stage.exists():
            shutil.rmtree(self.stage)      # a fresh run (not resumed): no stale snapshots
        if not self._due(step, t):
            return
        tic = _time.perf_counter()
        if not self._meshes_written:
            if self.comm.rank == 0:
                self.stage.mkdir(parents=True, exist_ok=True)
            self.comm.Barrier()
            for p in self.parts:
                _quiet_write(self.stage / f"{p.name}_mesh.xdmf", self.comm, p.mesh, list(p.static.values()))
            self._meshes_written = True
        for p in self.parts:
            _quiet_write(self.stage / f"{p.name}_s{step:06d}.xdmf", self.comm, None,
                         [make() for make in p.fields.values()], t)
        self.snapshots = [s for s in self.snapshots if s[0] != step] + [(step, t)]
        self.write_time += _time.perf_counter() - tic

    def state(self) -> dict:
        return {"snapshots": self.snapshots, "write_time": self.write_time}

    def cannot_resume(self, state: dict) -> str:
        """The snapshots written before the checkpoint must still be staged (a resumed run writes only the later
        ones, and finish() indexes them all)."""
        need = [self.stage / f"{p.name}_mesh.xdmf" for p in self.parts] if state["snapshots"] else []
        need += [self.stage / f"{p.name}_s{int(s):06d}.xdmf" for s, _ in state["snapshots"] for p in self.parts]
        missing = [f for f in need if not f.exists()]
        if missing:
            return (f"its field snapshots are gone ({missing[0]}{f' and {len(missing) - 1} more' if len(missing) > 1 else ''}"
                    f" missing)")
        return ""

    def load_state(self, state: dict) -> None:
        self.snapshots = [(int(s), float(t)) for s, t in state["snapshots"]]
        self.write_time = float(state["write_time"])

    def finish(self, dataset_path) -> dict:
        """Write each part's XDMF index and fields.json, rename the directory into place; return the dataset
        attributes (fields_path relative to the dataset's folder, format, size, times, write time)."""
        tic = _time.perf_counter()
        if not self.snapshots:
            raise ValueError(f"fields: no snapshot was written into {self.final} (no probe time in the run's "
                             f"window and fields.every_steps = 0)")
        manifest = None
        if self.comm.rank == 0:
            for p in self.parts:
                self._index(p)
            for f in self.stage.glob("*_s*.xdmf"):
                f.unlink()
            for p in self.parts:
                (self.stage / f"{p.name}_mesh.xdmf").unlink()
            self.write_time += _time.perf_counter() - tic
            size = sum(f.stat().st_size for f in self.stage.iterdir() if f.name != "fields.json")
            manifest = {
                "format": "xdmf",
                "configuration": "reference (ALE) mesh; Warp By Vector with `displacement` gives the current one",
                "parts": {p.name: {"file": f"{p.name}.xdmf", "quantities": list(p.fields) + list(p.static)}
                          for p in self.parts},
                "units": {q: cf_meta(q, FIELD_VARIABLES)[0] for p in self.parts for q in p.fields}
                | {q: cf_meta(q, FIELD_VARIABLES)[0] for q in ("subdomain", "time")},
                "long_names": {q: cf_meta(q, FIELD_VARIABLES)[1] for p in self.parts for q in p.fields},
                "steps": [s for s, _ in sorted(self.snapshots)],
                "times": [t for _, t in sorted(self.snapshots)],
                "size_bytes": size,
                "write_time_s": round(self.write_time, 3),
            }
            tmp = self.stage / "fields.json.part"
            tmp.write_text(json.dumps(manifest, indent=2) + "\n")
            os.replace(tmp, self.stage / "fields.json")
            if self.final.exists():
                old = self.final.with_name(self.final.name + ".old")
                shutil.rmtree(old, ignore_errors=True)
                os.replace(self.final, old)
                os.replace(self.stage, self.final)
                shutil.rmtree(old)
            else:
                os.replace(self.stage, self.final)
        manifest = self.comm.bcast(manifest, root=0)
        rel = os.path.relpath(self.final, Path(dataset_path).parent)
        return {"fields_path": rel, "fields_format": "xdmf", "fields_size_bytes": manifest["size_bytes"],
                "fields_times": json.dumps(manifest["times"]), "fields_write_time_s": manifest["write_time_s"]}

    def _index(self, part: Part) -> None:
        """<part>.xdmf: one temporal collection; every time grid holds the part's topology and geometry (from
        its mesh file), its static cell fields and that snapshot's attributes, with units."""
        mesh_root = ET.parse(self.stage / f"{part.name}_mesh.xdmf").getroot()
        uniform = next(g for g in mesh_root.iter("Grid") if g.get("GridType") == "Uniform")
        topo_geom = [uniform.find("Topology"), uniform.find("Geometry")]
        static = [a for a in mesh_root.iter("Attribute")]
        ET.register_namespace("xi", XI)
        root = ET.Element("Xdmf", {"Version": "3.0"})
        domain = ET.SubElement(root, "Domain")
        coll = ET.SubElement(domain, "Grid", {"Name": part.name, "GridType": "Collection",
                                              "CollectionType": "Temporal"})
        for step, t in sorted(self.snapshots):
            snap = ET.parse(self.stage / f"{part.name}_s{step:06d}.xdmf").getroot()
            grid = ET.SubElement(coll, "Grid", {"Name": f"{part.name}_{step}", "GridType": "Uniform"})
            grid.extend(topo_geom)
            ET.SubElement(grid, "Time", {"Value": repr(t)})
            for attr in static + list(snap.iter("Attribute")):
                units, long_name = cf_meta(attr.get("Name"), FIELD_VARIABLES)
                a = ET.SubElement(grid, "Attribute", dict(attr.attrib))
                ET.SubElement(a, "Information", {"Name": "units", "Value": units})
                ET.SubElement(a, "Information", {"Name": "long_name", "Value": long_name})
                a.extend(attr.findall("DataItem"))
        ET.indent(root)
        tmp = self.stage / f"{part.name}.xdmf.part"
        tmp.write_text('<?xml version="1.0"?>\n<!DOCTYPE Xdmf SYSTEM "Xdmf.dtd" []>\n'
                       + ET.tostring(root, encoding="unicode") + "\n")
        os.replace(tmp, self.stage / f"{part.name}.xdmf")


def field_writer(cfg: dict, out_path, parts_of, end: float, comm) -> FieldWriter | None:
    """The run's FieldWriter from config `fields` (None if disabled): parts_of(quantities) builds the parts;
    snapshots at time.probe_times within [0, end] and every fields.every_steps steps. A run that would write none
    is refused here, before its solve."""
    fc = cfg["fields"]
    if not fc["enabled"]:
        return None
    times = [t for t in cfg["time"]["probe_times"] if t <= end + 1e-9]
    if not times and not fc["every_steps"]:
        raise ValueError(f"fields: no snapshot would be written: no time.probe_times within the run's 0-{end:g} s "
                         f"and fields.every_steps = 0 (set fields.every_steps > 0 or fields.enabled: false)")
    return FieldWriter(fields_dir(out_path), parts_of(list(fc["quantities"])), times, fc["every_steps"], comm)
