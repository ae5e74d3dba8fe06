"""The paper's design rule for the peristaltic load, checked by the solver, and a calibration rule.

Paper §2.4.2: "The force of the Gaussian pulse was chosen to create a 1 mm deformation perpendicular to
the ureter wall." The paper gives no Mooney-Rivlin coefficients; config/config.yaml chose them so that
the exact plane-strain inflation of the wall tube gives ~1 mm. This module

* `plane_strain_estimate`: that exact plane-strain number (incompressible tube R_i < R < R_o, outward
  dead traction p0 per reference area on the OUTER surface, inner surface free);
* `wall_response`: the same quantity from the FSI engine on the real load - the axisymmetric (r-z)
  wall-only scene (ureterfsi.scenes.wall_rz.WallModel), rectangle [R_i, R_o] x [0, L], Mooney-Rivlin
  mixed u-pi, both ends z = 0, L fixed, the travelling Gaussian outward dead traction of the config on the
  outer surface, inner surface traction-free. The urine pressure is left out: it is ~10^2 Pa (reference pressure 130 Pa plus the
  peristaltic pressure differences) against a peak load of 5e4 Pa, a < 0.3 % perturbation.
  mode "static": the pulse frozen with its centre at mid-length (steady solve, the worst case away from
  the clamped ends); mode "transient": the travelling load with inertia (BDF2) over the time window,
  recording the maximum radial displacement over time and z;
* `calibrate`: a common scale factor s on the five Mooney-Rivlin coefficients (the shape of the
  J-curve and the bulk modulus unchanged) such that the static solver displacement equals
  `ureter.design_wall_displacement`, and, as the alternative, the load scale that meets it with the
  configured coefficients.

Only the config sections `geometry`, `ureter`, `peristalsis` and `time` are read (the workflow rule
`calibration` passes just these).

    python -m ureterfsi.study.calibration [config.yaml [overlay.yaml ...]] [--json PATH] [--no-transient]
"""
from __future__ import annotations

import argparse
import logging
import math
import sys
import time as _time
from dataclasses import asdict, dataclass, field

import numpy as np
from scipy.optimize import brentq

from ureterfsi.config import DEFAULT_CONFIG, load_config_files
from ureterfsi.fsi import Observer, SolverOptions, TimeIntegrator, TimeSettings
from ureterfsi.data.provenance import provenance_attrs, write_json
from ureterfsi.scenes.wall_rz import WallModel, wall_material, wall_radii
from ureterfsi.scenes.verification import mooney_rivlin_tube_pressure


# ------------------------------------------------------------------------------------------------
# exact plane strain
# ------------------------------------------------------------------------------------------------
def plane_strain_outer_radius(Ri, Ro, mat, outer_dead_load) -> tuple[float, float]:
    """Deformed (r_i, r_o) of the incompressible plane-strain tube under an outward dead load p0 per
    reference area on the outer surface (P N = p0 N), inner surface free.

    Incompressibility: r^2 = R^2 + a, a = r_i^2 - R_i^2. Radial equilibrium gives
    sigma_r(r_o) - sigma_r(r_i) = int (sigma_t - sigma_r) dr / r, which is
    ureterfsi.scenes.verification.mooney_rivlin_tube_pressure(r_i); here sigma_r(r_i) = 0 and the Cauchy traction
    on the deformed outer surface is p0 R_o / r_o (force per unit length p0 R_o dTheta = sigma_r r_o dtheta)."""
    def ro_of(ri):
        return math.sqrt(Ro**2 + ri**2 - Ri**2)

    def f(ri):
        return mooney_rivlin_tube_pressure(ri, Ri, Ro, mat) - outer_dead_load * Ro / ro_of(ri)

    ri = brentq(f, Ri * (1.0 + 1e-12), 3.0 * Ri, xtol=1e-15 * Ri, rtol=1e-14)
    return ri, ro_of(ri)


def plane_strain_estimate(cfg, load_scale=1.0, coefficient_scale=1.0) -> float:
    """Exact plane-strain outer-wall displacement r_o - R_o (m) of the wall tube under a uniform outward
    dead traction equal to the peak load `peristalsis.peak_traction` (times load_scale)."""
    Ri, Ro = wall_radii(cfg)
    p0 = load_scale * cfg["peristalsis"]["peak_traction"]
    _, ro = plane_strain_outer_radius(Ri, Ro, wall_material(cfg, coefficient_scale), p0)
    return ro - Ro


# ------------------------------------------------------------------------------------------------
# the solver on the r-z wall
# ------------------------------------------------------------------------------------------------
@dataclass
class WallResponse:
    mode: str                           # static | transient
    max_radial_displacement: float      # m, max of u_r on the outer surface (over z, and t if transient)
    z_at_max: float                     # m
    time_at_max: float | None           # s (transient); None for static
    deformed_outer_radius: float        # m, R_o + u_r at the maximum
    max_inner_radial_displacement: float  # m, max of u_r on the inner surface (same instant)
    load_scale: float
    coefficient_scale: float
    pulse_centre: float | None          # m, static: the frozen centre
    mesh: dict = field(default_factory=dict)   # cells along r / z, cells, dofs, element
    cost: dict = field(default_factory=dict)   # wall time, Newton iterations, factorisations, steps

    def as_dict(self):
        return asdict(self)


def _result_static(model: WallModel, load_scale, coefficient_scale, wall0) -> WallResponse:
    umax, z, uin = model.radial_extrema()
    pb = model.problem
    return WallResponse("static", umax, z, None, model.Ro + umax, uin, load_scale, coefficient_scale,
                        float(model.centre.value), model.mesh_info(),
                        {"wall_time_s": _time.perf_counter() - wall0, "setup_time_s": model.setup_time,
                         "newton_iterations": model.newton_iterations, **pb.counters})


def wall_response(cfg, load_scale=1.0, coefficient_scale=1.0, mode="static", nr=4, nz=None, end=None,
                  dt=None, centre=None, model: WallModel | None = None) -> WallResponse:
    """Solver-based wall displacement under the configured peristaltic load (see the module docstring).

    nr: cells through the wall thickness (nz defaults to square cells, L/h); static: `centre` of the
    frozen pulse (m, default mid-length); transient: window end, dt (default cfg["time"]).
    `model`: reuse a static WallModel (continuation from its state)."""
    wall0 = _time.perf_counter()
    if mode == "static":
        model = model or WallModel(cfg, nr=nr, nz=nz)
        model.solve_static(load_scale, coefficient_scale, 0.5 * model.length if centre is None else centre)
        return _result_static(model, load_scale, coefficient_scale, wall0)
    if mode != "transient":
        raise ValueError(f"mode 'static' or 'transient', got {mode!r}")

    # modified Newton (the factorisation is kept while Newton contracts): the load moves 0.2 mm a step
    model = WallModel(cfg, nr=nr, nz=nz, travelling=True,
                      options=SolverOptions(newton_rtol=1e-10, newton_atol=1e-12, newton_max_iterations=25,
                                            reuse_jacobian=True, reuse_contraction=0.3))
    model.load_scale.value, model.coefficient_scale.value = load_scale, coefficient_scale
    tcfg = cfg["time"]
    end = tcfg["end"] if end is None else end
    dt = tcfg["dt"] if dt is None else dt

    class Peak(Observer):
        def __init__(self):
            self.best = (-np.inf, 0.0, 0.0, 0.0)

        def observe(self, problem, step):
            umax, z, uin = model.radial_extrema()
            if umax > self.best[0]:
                self.best = (umax, z, problem.time, uin)

    peak = Peak()
    integ = TimeIntegrator(model.problem, TimeSettings(end=end, dt=dt), observers=[peak])
    records = integ.run()
    umax, z, t, uin = peak.best
    pb = model.problem
    return WallResponse("transient", umax, z, t, model.Ro + umax, uin, load_scale, coefficient_scale, None,
                        model.mesh_info(),
                        {"wall_time_s": _time.perf_counter() - wall0, "setup_time_s": model.setup_time,
                         "steps": len(records), "dt": dt, "end": end,
                         "newton_iterations": int(sum(r.newton_iterations for r in records)), **pb.counters})


# ------------------------------------------------------------------------------------------------
# calibration
# ------------------------------------------------------------------------------------------------
def _solve_scale(response, target, slope, s0=1.0, u0=None, rtol=1e-3, max_solves=12):
    """Root of response(s) = target for a monotone response, secant on (log s, log u) safeguarded by a
    bracket (bisection in log s when the secant leaves it). `slope`: a guess of d log u / d log s for the
    first step (-1 for a stiffness scale, +1 for a load scale). Returns (s, u, history [(s, u)])."""
    history = []

    def f(s):
        u = response(s)
        history.append((s, u))
        return math.log(u / target)

    ls0 = math.log(s0)
    f0 = f(s0) if u0 is None else math.log(u0 / target)
    if u0 is not None:
        history.append((s0, u0))
    if abs(f0) <= rtol:
        return s0, history[-1][1], history
    ls1 = ls0 - f0 / slope
    f1 = f(math.exp(ls1))
    lo = hi = None  # bracket in log s with f(lo) and f(hi) of opposite signs

    def update(ls, fv):
        nonlocal lo, hi
        pts = [p for p in (lo, hi, (ls, fv)) if p is not None]
        neg = [p for p in pts if p[1] < 0]
        pos = [p for p in pts if p[1] > 0]
        if neg and pos:
            lo = min(neg, key=lambda p: abs(p[1]))
            hi = min(pos, key=lambda p: abs(p[1]))

    update(ls0, f0)
    update(ls1, f1)
    a, fa, b, fb = ls0, f0, ls1, f1
    while abs(fb) > rtol and len(history) < max_solves:
        ls = b - fb * (b - a) / (fb - fa) if fb != fa else b - 0.5 * fb
        if lo is not None:
            left, right = sorted((lo[0], hi[0]))
            if not (left < ls < right):
                ls = 0.5 * (left + right)
        elif abs(ls - b) > 1.0:  # no bracket yet: at most a factor e per step
            ls = b + math.copysign(1.0, ls - b)
        fs = f(math.exp(ls))
        update(ls, fs)
        a, fa, b, fb = b, fb, ls, fs
    if abs(fb) > rtol:
        raise RuntimeError(f"calibration did not reach rtol {rtol} in {max_solves} solves: {history}")
    return math.exp(b), history[-1][1], history


def calibrate(cfg, target=None, nr=4, nz=None, rtol=1e-3, centre=None, model: WallModel | None = None) -> dict:
    """Calibration rule of the design displacement (default `ureter.design_wall_displacement`) with the
    static frozen pulse: (1) a common scale s of C10, C01, C20, C02, C11 (bulk modulus kept) at the
    configured load; (2) alternatively the load scale at the configured coefficients. A few static
    solves each, continued from the previous state. `centre`: frozen pulse centre (m, default mid-length).
    Returns both with the achieved displacements."""
    target = cfg["ureter"]["design_wall_displacement"] if target is None else target
    wall0 = _time.perf_counter()
    model = model or WallModel(cfg, nr=nr, nz=nz)
    zc = 0.5 * model.length if centre is None else centre
    base = model.solve_static(1.0, 1.0, zc)[0]

    s, u_s, hist_s = _solve_scale(lambda s: model.solve_static(1.0, s)[0], target, -1.0, 1.0, base, rtol)
    model.solve_static(1.0, 1.0)
    lam, u_l, hist_l = _solve_scale(lambda q: model.solve_static(q, 1.0)[0], target, 1.0, 1.0, base, rtol)
    model.solve_static(1.0, 1.0)
    u = cfg["ureter"]
    names = ("c10", "c01", "c20", "c02", "c11")
    return {
        "target": target,
        "pulse_centre": zc,
        "configured_displacement": base,
        "coefficient_scale": s,
        "coefficient_scale_displacement": u_s,
        "calibrated_coefficients": {k: s * u[k] for k in names},
        "coefficient_scale_history": hist_s,
        "load_scale": lam,
        "load_scale_displacement": u_l,
        "calibrated_peak_traction": lam * cfg["peristalsis"]["peak_traction"],
        "load_scale_history": hist_l,
        "rtol": rtol,
        "mesh": model.mesh_info(),
        "wall_time_s": _time.perf_counter() - wall0,
    }


def design_check(cfg, u_max) -> dict:
    target = cfg["ureter"]["design_wall_displacement"]
    tol = cfg["ureter"]["design_tolerance"]
    rel = u_max / target - 1.0
    return {"target": target, "tolerance": tol, "relative_deviation": rel, "meets_design_rule": abs(rel) <= tol}


# ------------------------------------------------------------------------------------------------
# report
# ------------------------------------------------------------------------------------------------
# frozen-pulse centres of the static scan, fractions of L (dense around the near-end maximum)
CENTRE_SCAN = (0.5, 0.4, 0.3, 0.2, 0.16, 0.14, 0.13, 0.125, 0.12, 0.11, 0.1, 0.08, 0.06, 0.04)


def report(cfg, nr=4, transient=True, transient_end=None, refine=True) -> dict:
    """Everything of the calibration study as one JSON-serialisable dict."""
    Ri, Ro = wall_radii(cfg)
    out = {"inputs": {k: cfg[k] for k in SECTIONS},
           "wall": {"inner_radius": Ri, "outer_radius": Ro},
           "neglected": "urine pressure on the inner surface (~1e2 Pa vs the 5e4 Pa peak load)"}
    out["plane_strain_estimate"] = plane_strain_estimate(cfg)
    model = WallModel(cfg, nr=nr)
    static = wall_response(cfg, model=model)
    out["static"] = static.as_dict()
    out["static_design_check"] = design_check(cfg, static.max_radial_displacement)
    if refine:
        fine = wall_response(cfg, nr=2 * nr)
        out["static_refined"] = fine.as_dict()
        out["static_mesh_change"] = fine.max_radial_displacement / static.max_radial_displacement - 1.0
    out["calibration"] = calibrate(cfg, model=model)
    # the frozen pulse elsewhere: mid-length is not quite the worst case (the scene is symmetric about
    # z = L/2, so half the tube suffices)
    scan = []
    for frac in CENTRE_SCAN:
        umax, z, uin = model.solve_static(1.0, 1.0, frac * model.length)
        scan.append({"pulse_centre": frac * model.length, "max_radial_displacement": umax, "z_at_max": z,
                     "max_inner_radial_displacement": uin})
    model.solve_static(1.0, 1.0, 0.5 * model.length)
    out["static_centre_scan"] = scan
    worst = max(scan, key=lambda e: e["max_radial_displacement"])
    out["static_worst_centre"] = worst
    out["static_worst_design_check"] = design_check(cfg, worst["max_radial_displacement"])
    if transient:
        tr = wall_response(cfg, mode="transient", nr=nr, end=transient_end)
        out["transient"] = tr.as_dict()
        out["transient_design_check"] = design_check(cfg, tr.max_radial_displacement)
    return out


def format_report(r: dict) -> str:
    mm = 1e3
    lines = ["Design rule check (paper §2.4.2: peak load -> ~1 mm wall deformation)"]
    d = r["static_design_check"]
    lines.append(f"  target {d['target'] * mm:.3f} mm +- {100 * d['tolerance']:.0f} %")
    lines.append(f"  plane-strain estimate (exact, uniform load):   {r['plane_strain_estimate'] * mm:.4f} mm")
    s = r["static"]
    m = s["mesh"]
    lines.append(f"  solver, static frozen pulse at z = {s['pulse_centre'] * mm:.1f} mm: max u_r = "
                 f"{s['max_radial_displacement'] * mm:.4f} mm at z = {s['z_at_max'] * mm:.2f} mm "
                 f"(inner {s['max_inner_radial_displacement'] * mm:.4f} mm), r_o = {s['deformed_outer_radius'] * mm:.4f} mm")
    lines.append(f"    mesh {m['cells_r']} x {m['cells_z']} ({m['cells']} cells, {m['dofs']} dofs), "
                 f"{s['cost']['wall_time_s']:.1f} s, {s['cost']['newton_iterations']} Newton its")
    if "static_refined" in r:
        f = r["static_refined"]
        lines.append(f"    refined {f['mesh']['cells_r']} x {f['mesh']['cells_z']}: "
                     f"{f['max_radial_displacement'] * mm:.4f} mm (change {100 * r['static_mesh_change']:+.3f} %)")
    lines.append(f"    deviation {100 * d['relative_deviation']:+.1f} % -> "
                 f"{'MEETS' if d['meets_design_rule'] else 'DOES NOT MEET'} the design rule")
    w = r["static_worst_centre"]
    lines.append(f"  solver, static pulse scanned over {len(r['static_centre_scan'])} centres: worst "
                 f"{w['max_radial_displacement'] * mm:.4f} mm (centre {w['pulse_centre'] * mm:.2f} mm, "
                 f"peak at z = {w['z_at_max'] * mm:.2f} mm; by symmetry also at L - z)")
    if "transient" in r:
        t = r["transient"]
        lines.append(f"  solver, transient travelling pulse: max u_r = {t['max_radial_displacement'] * mm:.4f} mm "
                     f"at z = {t['z_at_max'] * mm:.2f} mm, t = {t['time_at_max']:.3f} s "
                     f"({t['cost']['steps']} steps, {t['cost']['wall_time_s']:.1f} s) -> "
                     f"{'meets' if r['transient_design_check']['meets_design_rule'] else 'does not meet'}")
    c = r["calibration"]
    lines.append(f"  calibration to {c['target'] * mm:.3f} mm (static):")
    lines.append(f"    coefficient scale s = {c['coefficient_scale']:.4f} -> {c['coefficient_scale_displacement'] * mm:.4f} mm "
                 f"({len(c['coefficient_scale_history'])} solves): "
                 + ", ".join(f"{k} = {v:.4g}" for k, v in c["calibrated_coefficients"].items()) + " Pa")
    lines.append(f"    or load scale {c['load_scale']:.4f} -> peak traction {c['calibrated_peak_traction']:.5g} Pa, "
                 f"{c['load_scale_displacement'] * mm:.4f} mm ({len(c['load_scale_history'])} solves)")
    return "\n".join(lines)


SECTIONS = ("geometry", "ureter", "peristalsis", "time")   # the only config sections read here


def write_report(cfg, path, **kwargs) -> dict:
    """Run `report`, add provenance (hash of the sections used), write JSON atomically; returns it."""
    r = report(cfg, **kwargs)
    r["provenance"] = provenance_attrs({k: cfg[k] for k in SECTIONS})
    write_json(path, r)
    return r


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m ureterfsi.study.calibration", description=__doc__.split("\n")[0])
    ap.add_argument("configs", nargs="*", default=[str(DEFAULT_CONFIG)])
    ap.add_argument("--json", help="write the report as JSON (atomically)")
    ap.add_argument("--cells-through-wall", type=int, default=4)
    ap.add_argument("--no-transient", action="store_true")
    ap.add_argument("--transient-end", type=float, default=None, help="s (default time.end)")
    ap.add_argument("--no-refine", action="store_true", help="skip the refined-mesh static check")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.WARNING, format="%(asctime)s %(levelname)s %(message)s")
    cfg = load_config_files(args.configs)
    kw = dict(nr=args.cells_through_wall, transient=not args.no_transient, transient_end=args.transient_end,
              refine=not args.no_refine)
    r = write_report(cfg, args.json, **kw) if args.json else report(cfg, **kw)
    print(format_report(r))
    return 0


if __name__ == "__main__":
    sys.exit(main())
