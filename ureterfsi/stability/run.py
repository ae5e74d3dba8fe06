"""One case of the stability matrix: build the scene, run it to its end or its first limit, and classify the
outcome from the engine's exceptions and the integrator's records (docs/stability.md lists the limits)."""
from __future__ import annotations

import logging
import math
import tempfile
import time as _time
from dataclasses import asdict
from pathlib import Path

import numpy as np
import xarray as xr
from mpi4py import MPI

from ureterfsi.data.checked import MESH_SIDECAR, read_json
from ..fsi import MonolithicFSI, NewtonDivergence, TimeIntegrator, TimeSettings
from ..fsi.integrator import MeshInversion, StepFailure
from ureterfsi.mesh.geometry import UreterGeometry
from ureterfsi.mesh.build import build_mesh
from ureterfsi.mesh.io import load_mesh
from ureterfsi.data.cf import annotate
from ureterfsi.data.provenance import provenance_attrs
from ..scenes.ureter import pulse_centre, ureter_scene
from ..study.oneway import fluid_problem, wall_history
from ..study.options import solver_options
from .cases import SCENES, case_setup, settings
from .dataset import SERIES, CaseScalars
from .limits import StabilityLimit
from .naming import Case, format_value
from .observer import StabilityObserver

log = logging.getLogger("ureterfsi.stability")


def _newton_failure(message: str, history, obs, t: float) -> StabilityLimit:
    """A step (or the initial state) Newton could not solve: limit "nan" for a non-finite residual, else
    "newton"; the place is the largest entry of the last Newton residual."""
    name, val, where = obs.largest_residual()
    limit = "newton" if math.isfinite(history[-1]) and math.isfinite(val) else "nan"
    return StabilityLimit(limit, message, t, where,
                          f"largest entry {val:.3e} of the last Newton residual, in the {name} rows, at", val)


def _nanmin(values) -> float:
    v = np.asarray(values, dtype=float)
    v = v[~np.isnan(v)]
    return float(v.min()) if v.size else math.nan


def _place(where) -> str:
    r, z = where
    if not (math.isfinite(r) and math.isfinite(z)):
        return "an unknown place"
    return f"(r, z) = ({r * 1e3:.2f}, {z * 1e3:.2f}) mm"


def _region(where, geom, stented: bool = False) -> str:
    r, _ = where
    if not math.isfinite(r):
        return ""
    R = geom.ureter_inner_radius
    if r > R * (1 + 1e-9):
        return "wall"
    if r >= R * (1 - 1e-9):
        return "urine-wall interface"
    if not stented:
        return "urine"
    return ("urine in the stent lumen" if r < geom.stent_inner_radius else "urine in a side hole"
            if r <= geom.stent_outer_radius else "urine in the annulus")



def run_case(cfg: dict, case: Case, mesh_path=None, end: float | None = None) -> xr.Dataset:
    """Run one case of the matrix and return its dataset (dims `step` and `halving`; scalars per case).

    mesh_path: the mesh of the case (r-z at the case's level; built in a temporary directory if None, as
    the hole_elements cases always are: their mesh sizes are the case's);
    end: override of the simulated time (short CI runs). Never raises for a failing case: the failure
    is the outcome, with its diagnosis.
    """
    wall0 = _time.perf_counter()
    st = settings(cfg)
    setup = case_setup(cfg, case)
    ccfg, params = setup["cfg"], dict(setup["parameters"])
    if end is not None:
        params["end_time"] = float(end)
    comm = MPI.COMM_WORLD
    geom = UreterGeometry.from_config(cfg)
    pb = obs = integrator = None
    failure: StabilityLimit | None = None
    cells = dofs = 0
    sidecar = {}
    holes = setup["scene"] == "holes"
    try:
        with tempfile.TemporaryDirectory() as tmp:
            if mesh_path is None or holes:
                mesh_path = Path(tmp) / "mesh.msh"
                if comm.rank == 0:
                    build_mesh(ccfg, setup["model"], setup["level"], setup["symmetry"], mesh_path,
                               Path(tmp) / "mesh.json")
                comm.Barrier()
            mesh, ct, ft = load_mesh(mesh_path, comm)
            side = Path(mesh_path).with_suffix(".json")
            if side.exists():
                sidecar = read_json(side, MESH_SIDECAR)
        cells = mesh.topology.index_map(mesh.topology.dim).size_global
        if holes:
            history = wall_history(ccfg, params["end_time"], setup["dt"])
            pb, _, _ = fluid_problem(ccfg, mesh, ct, ft, history, axisymmetric=False)
        else:
            pb = MonolithicFSI(ureter_scene(ccfg, mesh, ct, ft, axisymmetric=True,
                                            peristalsis=ccfg["peristalsis"]), solver_options(ccfg))
        dofs = pb.W.dofmap.index_map.size_global * pb.W.dofmap.index_map_bs
        obs = StabilityObserver(pb, st, wall0)
        log.info("case %s: %d cells, %d dofs, dt %g s, end %g s", case.name, cells, dofs, setup["dt"],
                 params["end_time"])
        integrator = TimeIntegrator(pb, TimeSettings(
            end=params["end_time"], dt=setup["dt"], max_halvings=ccfg["solver"]["max_step_halvings"],
            min_ale_jacobian=st["min_ale_jacobian"]), [obs])
        try:
            pb.fill("pressure", ccfg["fluid"]["reference_pressure"])
            pb.solve_steady()
        except NewtonDivergence as err:
            failure = _newton_failure(f"initial state (steady, fluid at rest) failed: {err}", err.history, obs,
                                      pb.time)
        else:
            integrator.run()
    except StabilityLimit as err:
        failure = err
    except MeshInversion as err:      # the state of the last step
        jmin, where = obs.min_jacobian()
        failure = StabilityLimit("ale_inversion", str(err), err.time, where,
                                 f"smallest ALE Jacobian {jmin:.3e} at the fluid vertex", jmin)
    except StepFailure as err:        # not accepted: the time is the end of its last attempt
        failure = (_newton_failure(str(err), err.cause.history, obs, integrator.failed_attempts[-1].time)
                   if integrator is not None else StabilityLimit("newton", str(err)))
    except Exception as err:  # noqa: BLE001 - a case must never crash the matrix
        log.exception("case %s raised", case.name)
        t = pb.time if pb is not None else math.nan
        failure = StabilityLimit("exception", f"{type(err).__name__}: {err}", t)
    wall = _time.perf_counter() - wall0

    series = obs.series if obs is not None else {k: [] for k in SERIES}
    records = integrator.records if integrator is not None else []
    attempts = integrator.failed_attempts if integrator is not None else []
    n = len(series["time"])
    data = {k: ("step", np.asarray(series[k], dtype=float)) for k in SERIES if k != "time"}
    vol, vb = np.asarray(series["fluid_volume"], float), np.asarray(series["volume_from_flux"], float)
    data["volume_balance_error"] = ("step", np.abs(vol - vb))
    its = np.zeros(n)
    swall = np.zeros(n)
    for r in records[: max(n - 1, 0)]:
        its[r.step], swall[r.step] = r.newton_iterations, r.wall_time
    data["newton_iterations"] = ("step", its)
    data["step_wall_time"] = ("step", swall)
    data["halving_time"] = ("halving", np.asarray([a.time for a in attempts], dtype=float))

    displaced = float(np.nanmax(np.abs(vol - vol[0]))) if n else math.nan
    # a case without a wave (zero load) displaces nothing: its balance error is then measured against
    # the displacement the design rule asks of the pulse (volume of a Gaussian bulge of the design height)
    sigma = ccfg["peristalsis"]["width"] / (2 * math.sqrt(2 * math.log(2))) \
        if ccfg["peristalsis"]["width_measure"] == "fwhm" else ccfg["peristalsis"]["width"]
    nominal = 2 * math.pi * geom.ureter_inner_radius * cfg["ureter"]["design_wall_displacement"] \
        * sigma * math.sqrt(2 * math.pi)
    ref = displaced if displaced > 1e-6 * nominal else nominal
    verr = float(np.nanmax(np.abs(vol - vb)) / ref) if n else math.nan
    ke = np.asarray(series["kinetic_energy"], float)
    bound = np.asarray(series["energy_bound"], float)
    if failure is None and n and verr > st["volume_tolerance"]:
        k = int(np.nanargmax(np.abs(vol - vb)))
        failure = StabilityLimit("volume", f"volume balance error {verr:.3e} of the displaced volume exceeds "
                                 f"stability.volume_tolerance = {st['volume_tolerance']:g} (largest at t = "
                                 f"{series['time'][k]:.6g} s)", series["time"][k])
    if failure is None and n and series["time"][-1] < params["end_time"] - 1e-9 * setup["dt"]:
        failure = StabilityLimit("exception", f"run stopped at t = {series['time'][-1]:.6g} s before the end")

    ttime = failure.time if failure is not None else math.nan
    zc = pulse_centre(ccfg["peristalsis"], ttime) if math.isfinite(ttime) else math.nan
    diagnosis = ""
    if failure is not None:
        where = failure.where
        region = _region(where, geom, stented=holes)
        diagnosis = f"{failure.limit}: {failure}"
        if math.isfinite(where[0]):
            what = failure.what or "place"
            diagnosis += f" [where: {what} {_place(where)}, {region}; pulse centre at z = {zc * 1e3:.2f} mm]"
        elif math.isfinite(zc):
            diagnosis += f" [pulse centre at z = {zc * 1e3:.2f} mm]"
    scalars = CaseScalars(
        axis=case.axis if case.axis != "baseline" else "baseline",
        value_label="" if case.value is None else format_value(case.value),
        outcome="stable" if failure is None else "failed",
        limit="none" if failure is None else failure.limit,
        diagnosis=diagnosis,
        failure_time=ttime,
        failure_r=failure.where[0] if failure is not None else math.nan,
        failure_z=failure.where[1] if failure is not None else math.nan,
        pulse_centre_at_failure=zc,
        scene=setup["scene"],
        time_step=params["time_step"], mesh_level=params["mesh_level"], cells=cells, dofs=dofs,
        hole_elements=params["hole_elements"], is_baseline=params["is_baseline"],
        hole_elements_measured=float(sidecar.get("hole_elements_across", math.nan)),
        hole_channels_found=int(sidecar.get("hole_channels_found", 0)),
        mesh_min_quality=float(sidecar.get("quality_minSICN", {}).get("min", math.nan)),
        bulk_ratio=params["bulk_ratio"], density_ratio=params["density_ratio"],
        peak_traction=params["peak_traction"], wave_speed=params["wave_speed"],
        wave_width=params["wave_width"], dynamic_viscosity=params["dynamic_viscosity"],
        end_time=params["end_time"],
        reached_time=series["time"][-1] if n else math.nan,
        steps=max(n - 1, 0),
        max_kinetic_energy=float(np.nanmax(ke)) if n else math.nan,
        # from the first step on (at t = 0 the bound is E(0) itself)
        max_energy_ratio=float(np.nanmax(ke[1:] / np.where(bound[1:] > 0, bound[1:], np.nan))) if n > 1
        else math.nan,
        displaced_volume=displaced,
        volume_error=verr,
        # an inverted mesh is not an accepted state (not in the series): its Jacobian is the failure's
        min_jacobian=_nanmin(list(series["min_ale_jacobian"]) + (
            [failure.value] if failure is not None and failure.limit == "ale_inversion" else [])),
        peak_displacement=float(np.nanmax(series["max_displacement"])) if n else math.nan,
        peak_speed=float(np.nanmax(series["max_speed"])) if n else math.nan,
        total_newton_iterations=int(its.sum()),
        mean_newton_iterations=float(its[1:].mean()) if n > 1 else math.nan,
        max_newton_iterations=int(its.max()) if n else 0,
        step_halvings=sum(a.halved for a in attempts),
        factorisations=pb.counters["factorisations"] if pb is not None else 0,
        wall_time=wall,
        wall_time_per_step=float(swall[1:].mean()) if n > 1 else math.nan,
    )
    ds = xr.Dataset({k: ((), v) for k, v in asdict(scalars).items()} | data,
                    coords={"step": np.arange(n), "time": ("step", np.asarray(series["time"], float))})
    ds = ds.assign_coords(case=case.name)
    annotate(ds)
    ds.attrs.update(provenance_attrs(ccfg, title=f"ureterfsi stability case {case.name}", case=case.name,
                                     model=setup["model"], symmetry=setup["symmetry"], mesh_level=setup["level"],
                                     energy_safety=st["energy_safety"], volume_tolerance=st["volume_tolerance"],
                                     min_ale_jacobian_limit=st["min_ale_jacobian"],
                                     solver=f"{SCENES[setup['scene']]}; Newton + "
                                            f"{ccfg['solver']['linear_solver']}",
                                     processes=comm.size))
    log.info("case %s: %s %s (%.1f s)", case.name, scalars.outcome, diagnosis, wall)
    return ds


