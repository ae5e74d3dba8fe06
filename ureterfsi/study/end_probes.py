"""The end conditions' quantities of a run (ureterfsi.scenes.ends): the pelvic and bladder pressures (the normal
stress f0 the kidney and bladder end faces see) and the reflux, the volume of urine that has moved toward the kidney
through the kidney end face since t = 0, inside the stent lumen and in the annulus around it (the whole lumen
without a stent): V(t) = int_0^t max(-Q_in(s), 0) ds per part, Q_in the part's inflow (trapezoidal rule over
the steps). Fluxes and volumes are the whole ureter's (the modelled fraction's times its symmetry factor). A part's
backflow counts only above REFLUX_FLOOR times the face's flux scale (the largest |Q_lumen| + |Q_annulus| so far,
the step's included): a flux at round-off (a state at rest: ~1e-20 m^3/s against the ~1e-6 m^3/s the wave drives)
carries no reflux."""
from __future__ import annotations

import numpy as np
import xarray as xr

from ureterfsi.data.cf import cf_meta
from ureterfsi.fsi import Observer
from ureterfsi.mesh import tags
from ureterfsi.mesh.geometry import SYMMETRY_FRACTION

NAMES = ("pelvic_pressure", "bladder_pressure", "stent_lumen_reflux_volume", "annulus_reflux_volume")
# a backflow below this fraction of the face's flux scale is round-off: far above the assembly's (1e-14 of the
# scale at rest) and below what the Newton tolerances resolve (relative 1e-8 of the state)
REFLUX_FLOOR = 1.0e-9


class RefluxVolumes:
    """V_j(t) = int_0^t max(-Q_j, 0) dt per part j of a face (trapezoidal over the records), the backflows below
    REFLUX_FLOOR times the face's flux scale (max over the records so far of sum_j |Q_j|) taken as 0."""

    def __init__(self, parts: int):
        self.volumes = [0.0] * parts
        self.scale = 0.0
        self.last = None          # (time, inflows Q_j) of the last record

    def backflow(self, q: float) -> float:
        return -q if -q > REFLUX_FLOOR * self.scale else 0.0

    def add(self, t: float, inflows) -> list:
        """Record the parts' inflows Q_j at time t; the volumes up to t."""
        self.scale = max(self.scale, sum(abs(q) for q in inflows))
        if self.last is not None:
            t0, q0 = self.last
            self.volumes = [v + 0.5 * (t - t0) * (self.backflow(a) + self.backflow(b))
                            for v, a, b in zip(self.volumes, q0, inflows)]
        self.last = (t, list(inflows))
        return list(self.volumes)

    def state(self) -> dict:
        return {"volumes": self.volumes, "scale": self.scale, "last": self.last}

    def load_state(self, state: dict) -> None:
        self.volumes, self.scale = list(state["volumes"]), state["scale"]
        self.last = None if state["last"] is None else (state["last"][0], list(state["last"][1]))


class EndProbes(Observer):
    """Records NAMES after every accepted step of the problem `pb`: kidney face `inlet`, bladder face `outlet`,
    `fraction` the modelled fraction's symmetry factor (1 / mesh.geometry.SYMMETRY_FRACTION). The kidney face's
    flux is the engine's (fsi.end_conditions.FaceFlux, the one its conditions use), in the parts of the scene's
    flux_split (the stent lumen; none: all of it the annulus's)."""

    def __init__(self, pb, inlet: int, outlet: int, fraction: float):
        self.pb, self.fraction = pb, fraction
        self.inlet = pb.end_conditions.face_flux([inlet])
        self.faces = [self._boundary(inlet), self._boundary(outlet)]
        self.series = {name: [] for name in NAMES}
        self.reflux = RefluxVolumes(2)

    def _boundary(self, tag):
        return next(ob for ob in self.pb.scene.open_boundaries if tag in ob.tags)

    def observe(self, problem, step: int) -> None:
        pb, s = self.pb, self.series
        for name, ob in zip(NAMES[:2], self.faces):
            f0 = pb.end_conditions.normal_stress(ob)
            s[name].append(float(getattr(f0, "value", f0)))
        parts = self.inlet.recorded
        lumen, annulus = parts if len(parts) == 2 else (0.0, parts[0])
        volumes = self.reflux.add(pb.time, [-self.fraction * lumen, -self.fraction * annulus])
        for name, v in zip(NAMES[2:], volumes):
            s[name].append(v)

    def state(self) -> dict:
        return {"series": self.series, "reflux": self.reflux.state()}

    def load_state(self, state: dict) -> None:
        self.series = state["series"]
        self.reflux.load_state(state["reflux"])

    def variables(self) -> dict:
        """{name: CF-annotated DataArray over `time`}."""
        out = {}
        for name in NAMES:
            units, long_name = cf_meta(name)
            out[name] = xr.DataArray(np.asarray(self.series[name]), dims="time",
                                     attrs={"units": units, "long_name": long_name})
        return out


def ends_probes(pb, symmetry: str) -> EndProbes:
    """EndProbes of a ureter run: faces INLET (kidney) and OUTLET (bladder), the lumen the scene's flux_split
    (scenes.ends.lumen_indicator)."""
    return EndProbes(pb, tags.INLET, tags.OUTLET, 1.0 / SYMMETRY_FRACTION[symmetry])
