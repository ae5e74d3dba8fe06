"""The materials of the verification scenes: the study's urine, ureter wall and stent, and its reference pressure
(the numbers of config/config.yaml); SI units."""
from __future__ import annotations

from ureterfsi.fsi import LinearElastic, MooneyRivlin, NewtonianFluid

URINE = NewtonianFluid(density=1050.0, dynamic_viscosity=1.3e-3)
URETER_WALL = MooneyRivlin(c10=6.0e4, c01=2.0e4, c20=1.2e5, c02=2.0e4, c11=6.0e4, bulk_modulus=1.0e9,
                           density=1040.0)
STENT = LinearElastic(youngs_modulus=4.22e6, poisson_ratio=0.058, density=1261.1)
REFERENCE_PRESSURE = 130.0
