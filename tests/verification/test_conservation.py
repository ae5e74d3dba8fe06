"""Volume conservation (verification 4): under a travelling wall load, the change of the fluid volume
V(t) = int_fluid J dV (axisymmetric weight 2 pi r) equals minus the time integral of the net outflow
Q = int_{inlet+outlet} (v - w).n da, n da = J F^-T N dA.

The engine's mesh velocity is the BDF derivative w = (b0 u + b1 u_n + b2 u_nm1)/dt, and the
discrete continuity equation (with q = 1 in the pressure space, exact quadrature) makes
int_{boundary} v.n da vanish, with v = w on the fluid-solid interface. So the flux is the BDF
derivative of the volume up to the nonlinearity of V in u: integrating Q with the same BDF weights
(V_n = (-dt Q_n - b1 V_n-1 - b2 V_n-2) / b0) reproduces V(t); the trapezoidal rule does not (it is
inconsistent with the first, Backward-Euler, step and with the BDF2 derivative).
"""
from __future__ import annotations

import numpy as np
import pytest

from helpers.engine_cases import VolumeFluxObserver, Quantities, tube_problem
from ureterfsi.fsi import TimeIntegrator, TimeSettings


def volume_balance(records):
    """(V - V0, volume from the BDF-integrated flux - V0, same with the trapezoidal rule)."""
    t = np.asarray(records["t"])
    V = np.asarray(records["volume"])
    Q = np.asarray(records["inlet"]) + np.asarray(records["outlet"])
    bdf = np.asarray(records["bdf"])
    dt = np.asarray(records["dt"])
    Vb = np.empty_like(V)
    Vb[0] = V[0]
    for n in range(1, len(V)):
        b0, b1, b2 = bdf[n]
        Vb[n] = (-dt[n] * Q[n] - b1 * Vb[n - 1] - b2 * (Vb[n - 2] if n >= 2 else 0.0)) / b0
    trap = np.concatenate([[0.0], np.cumsum(0.5 * (Q[1:] + Q[:-1]) * np.diff(t))])
    return V - V[0], Vb - V[0], -trap


# measured error / displaced volume (BDF weights): 6.2e-4 (dt 0.01), 1.1e-4 (0.005), 2.4e-5 (0.0025);
# trapezoid: 0.19, 0.10, 0.054 (first order)
@pytest.mark.parametrize("end, dt", [(0.3, 0.005), pytest.param(0.3, 0.0025, marks=pytest.mark.slow)])
def test_fluid_volume_change_equals_integrated_boundary_flux(end, dt):
    pb, case = tube_problem()
    obs = VolumeFluxObserver(Quantities(pb))
    TimeIntegrator(pb, TimeSettings(end=end, dt=dt), [obs]).run()
    dV, dV_bdf, dV_trap = volume_balance(obs.records)
    displaced = np.abs(dV).max()
    err_bdf = np.abs(dV - dV_bdf).max()
    err_trap = np.abs(dV - dV_trap).max()
    print(f"\nV0 = {obs.records['volume'][0]:.6e} m^3, displaced volume max|V - V0| = {displaced:.4e} m^3, "
          f"final V - V0 = {dV[-1]:.4e} m^3")
    print(f"balance error, BDF weights: {err_bdf:.3e} m^3 = {err_bdf / displaced:.2e} of displaced")
    print(f"balance error, trapezoid:   {err_trap:.3e} m^3 = {err_trap / displaced:.2e} of displaced")
    # the wave displaces a measurable volume (the wall bulges by about 4 % of the radius)
    assert displaced > 1e-2 * obs.records["volume"][0]
    assert err_bdf < 1e-3 * displaced
    # both ends take part: fluid is drawn in through both while the bulge grows
    assert min(obs.records["inlet"]) < 0 and min(obs.records["outlet"]) < 0
