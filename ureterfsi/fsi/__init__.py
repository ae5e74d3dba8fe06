"""Scene-agnostic FSI engine: physics blocks (UFL forms), monolithic ALE coupling, time integration."""
from .jitlog import demote_compiler_logs
from .end_conditions import Compartment, Valve, Waveform
from .integrator import Observer, SolveFailure, StepRecord, TimeIntegrator, TimeSettings
from .linear_solvers import BlockGaussSeidel
from .materials import LinearElastic, MooneyRivlin, NewtonianFluid
from .newton import NewtonDivergence
from .options import SolverOptions
from .problem import MonolithicFSI
from .scene import (BodyForce, DirichletCondition, FluidRegion, FollowerPressure, OpenBoundary, Scene, SolidRegion,
                    SurfaceLoad)

demote_compiler_logs()

__all__ = [
    "BlockGaussSeidel", "BodyForce", "Compartment", "DirichletCondition", "FluidRegion", "FollowerPressure",
    "LinearElastic", "MonolithicFSI", "MooneyRivlin", "NewtonDivergence", "NewtonianFluid", "Observer", "OpenBoundary", "Scene",
    "SolidRegion", "SolveFailure", "SolverOptions", "StepRecord", "SurfaceLoad", "TimeIntegrator", "TimeSettings",
    "Valve", "Waveform",
]
