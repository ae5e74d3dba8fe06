"""Material laws of the physics blocks (paper §2.2-2.3). SI units."""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class NewtonianFluid:
    """Incompressible Newtonian fluid, sigma = -p I + mu (grad v + grad v^T) (paper eqs. 1-3)."""
    density: float            # kg/m^3
    dynamic_viscosity: float  # Pa s


@dataclass(frozen=True)
class MooneyRivlin:
    """Five-parameter Mooney-Rivlin solid with volumetric penalty (paper eq. 19).

    W = C10(I1b-3) + C01(I2b-3) + C20(I1b-3)^2 + C02(I2b-3)^2 + C11(I1b-3)(I2b-3) + kappa/2 (J-1)^2,
    I1b = J^(-2/3) I1, I2b = J^(-4/3) I2. Solved in mixed displacement-pressure form (no locking).
    """
    c10: float
    c01: float
    c20: float = 0.0
    c02: float = 0.0
    c11: float = 0.0
    bulk_modulus: float = 1.0e9   # Pa
    density: float = 1000.0       # kg/m^3

    @property
    def shear_modulus(self) -> float:
        """Initial (small-strain) shear modulus mu0 = 2 (C10 + C01)."""
        return 2.0 * (self.c10 + self.c01)


@dataclass(frozen=True)
class LinearElastic:
    """Isotropic elastic solid from E, nu. kinematics: 'linear' (Hooke, small strain) or
    'st_venant_kirchhoff' (S = lambda tr(E) I + 2 mu E, Green-Lagrange E; geometrically nonlinear)."""
    youngs_modulus: float
    poisson_ratio: float
    density: float
    kinematics: str = "linear"

    def __post_init__(self):
        if self.kinematics not in ("linear", "st_venant_kirchhoff"):
            raise ValueError(f"LinearElastic.kinematics: 'linear' or 'st_venant_kirchhoff', got {self.kinematics!r}")

    @property
    def lame_mu(self) -> float:
        return self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))

    @property
    def lame_lambda(self) -> float:
        nu = self.poisson_ratio
        return self.youngs_modulus * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
