"""The engine's solver options (MonolithicFSI): discretisation, Newton, linear solvers, mesh motion, coupling."""
from __future__ import annotations

from dataclasses import dataclass

from .linear_solvers import KRYLOV, MUMPS_WORKSPACE_PERCENT, Mumps

# the values of the options that name a choice
CHOICES = {"mesh_motion_coupling": ("monolithic", "segregated"), "predictor": ("quadratic", "linear", "constant"),
           "solid_block": ("condensed", "whole"), "coupling_scheme": ("monolithic", "partitioned"),
           "sweep_convergence": ("contraction", "residual"), "krylov_forcing": ("fixed", "eisenstat_walker"),
           "jacobian_sparsity": ("couplings", "mixed_element"), "urine_step": ("newton", "linearly_implicit")}


@dataclass
class SolverOptions:
    """The options of a MonolithicFSI (the study sets them from its configuration: study.options.solver_options)."""
    velocity_degree: int = 2
    pressure_degree: int = 1
    quadrature_degree: int = 4
    mesh_motion: str = "harmonic"       # harmonic | elastic
    mesh_stiffening: float = 1.0        # exponent q of (V_mean / V_cell)^q
    # exponent chi of the deformation-dependent stiffening J^-chi of the monolithic mesh motion (0: a linear
    # extension, its Jacobian assembled once; > 0: nonlinear, for large swings: physics.mesh_motion_residual)
    mesh_jacobian_stiffening: float = 0.0
    newton_rtol: float = 1e-8           # residual reduction relative to the step's first residual
    newton_atol: float = 1e-10          # absolute residual norm
    # stagnation exit: every field's Newton increment below this fraction of the field's max norm
    newton_stol: float = 1e-11
    # converged also needs every field's last increment <= this fraction of its max norm (None: residual alone):
    # one residual norm mixes rows of different scales, where a solid's stiff rows can hide an unconverged fluid
    newton_field_rtol: float | None = None
    # SI units: a field increment below it counts as converged (a field at rest holds round-off, no scale of its own)
    newton_increment_floor: float = 1e-10
    newton_max_iterations: int = 15
    # Newton's initial guess: "quadratic" / "linear" extrapolation of the last three / two steps or the
    # "constant" previous state
    predictor: str = "linear"
    reuse_jacobian: bool = False        # keep the factorisation while Newton contracts fast enough
    reuse_contraction: float = 0.3      # refactorise when ||R_k|| / ||R_k-1|| exceeds this
    # a direct package (mumps, superlu_dist, superlu, umfpack: LU of the Newton system) or "fieldsplit": Krylov
    # with a Schur-complement block preconditioner (fluid-alone scenes with segregated mesh motion only, see
    # linear_solvers.SchurFieldsplit), whose memory grows ~linearly with the mesh
    # or "block_gauss_seidel": GMRES with a solid -> mesh -> flow block Gauss-Seidel preconditioner, MUMPS LU on
    # each block (coupled FSI scenes, monolithic mesh motion; ureterfsi.fsi.linear_solvers)
    linear_solver: str = "mumps"
    # MUMPS ICNTL(14): workspace margin over MUMPS's estimate, per cent, of every MUMPS factorisation the
    # strategies create (whole system, flow block, each block_gauss_seidel split, the mesh-motion LU)
    mumps_workspace_percent: int = MUMPS_WORKSPACE_PERCENT
    # MUMPS ICNTL(22): every MUMPS factor on disk (out of core) instead of in memory: the same factors, for a fraction
    # of the memory (a run larger than the memory it was given; study runs: --out-of-core 1)
    mumps_out_of_core: bool = False
    # segregated mesh-motion problems with more unknowns than this are solved by conjugate gradients with
    # ICC(0) instead of LU, whose factor is as large as the flow block's; None: always LU
    mesh_motion_direct_max_unknowns: int | None = None
    # CG + ICC(0) mesh motion: residual reduction relative to the preconditioned right-hand side ||B b||, i.e.
    # to the whole displacement, not to its change in a step: small enough that the mesh velocity's error
    # rtol |d| / dt stays far below the flow's velocities
    mesh_motion_rtol: float = 1e-9
    krylov_rtol: float = 1e-8           # Krylov solvers: relative residual of each linear solve
    krylov_max_iterations: int = 400    # Krylov solvers: more is a failed linear solve (Newton step retried)
    # block_gauss_seidel: "fixed" solves every Newton system to krylov_rtol; "eisenstat_walker" is an inexact
    # Newton, each solve to eta_k in [krylov_rtol, ETA_MAX] (newton.Newton._forcing)
    krylov_forcing: str = "fixed"
    # block_gauss_seidel: a linear solve with more Krylov iterations than this refactorises the kept solid and
    # mesh blocks at the next fresh Jacobian
    krylov_refactorise_iterations: int = 10
    # "monolithic": mesh-motion rows solved with the physics (needed whenever a solid moves the fluid
    # boundary); "segregated": fluid-alone scenes whose boundary motion is prescribed - the mesh motion
    # is a linear problem of its own (factorised once) solved before each step, and the Newton system
    # holds velocity and pressure only (no shape derivatives, a much cheaper Jacobian).
    mesh_motion_coupling: str = "monolithic"
    # a fluid-alone step (segregated): "newton" on the full residual, or "linearly_implicit": BDF2 with the convecting
    # velocity extrapolated, one linear system per step (fsi.linearly_implicit; Newton its fallback)
    urine_step: str = "newton"
    # a coupled scene's step: "monolithic" (Newton on the whole system, `linear_solver`) or "partitioned" (block
    # Gauss-Seidel sweeps solid -> mesh -> flow on the same residual, a kept LU per block: fsi.partitioned)
    coupling_scheme: str = "monolithic"
    block_iterations: int = 3           # partitioned: updates of the solid and flow blocks per sweep, at most
    anderson_depth: int = 5             # partitioned: sweeps mixed by Anderson acceleration (0: plain sweeps)
    anderson_reuse: int = 0             # partitioned: the mixing keeps anderson_depth x this of earlier steps' sweeps
    # partitioned: a block's LU is refreshed when its iteration contracts by less than this (reuse_contraction is
    # Newton's: a sweep's inner iterations are capped and Anderson mixing carries on, so a looser test pays)
    block_reuse_contraction: float = 0.5
    # partitioned: the wall's LU is refreshed at a step's start once the steps since its last refresh have needed
    # this many sweeps, summed, beyond a step with fresh LUs (a stale LU's cost in sweeps outweighs a refresh's: rent
    # or buy; the urine's LU too when it is the stale one, fsi.sweep_policy.RefreshSchedule); 0: contraction tests only
    block_refresh_sweeps: int = 4
    # partitioned: the solid block's LU, "condensed" (the velocity eliminated through the kinematic rows, exact:
    # fsi.condensation) or "whole" (the block as it stands)
    solid_block: str = "condensed"
    # partitioned, solid_block "condensed": the quadrature degree of the wall's kept Jacobian (None: the residual's
    # quadrature_degree). It only steers the wall's updates, whose fixed point is the residual's: a cheaper rule
    # leaves the discrete solution as it is
    wall_jacobian_quadrature_degree: int | None = None
    # partitioned: a step has converged when the bound rho / (1 - rho) ||G(x) - x|| of the sweeps' contraction says
    # every field is within newton_field_rtol of the step's solution ("contraction"), or when Newton's residual test
    # holds and the last sweep changed no field by more than newton_field_rtol ("residual")
    sweep_convergence: str = "residual"
    # coupled Newton system's matrix: "couplings" stores the (cell region, field pair) couplings its forms have
    # (ureterfsi.fsi.sparsity); "mixed_element" every dof of a cell with every other (the same matrix)
    jacobian_sparsity: str = "couplings"

    def mumps(self) -> Mumps:
        """How the strategies make their MUMPS factorisations."""
        return Mumps(self.mumps_workspace_percent, self.mumps_out_of_core)

    def coupled_solution(self) -> str:
        """How a coupled scene's step is solved, in words (a run's provenance)."""
        core = ", MUMPS out of core" if self.mumps_out_of_core else ""
        if self.coupling_scheme == "partitioned":
            return (f"partitioned sweeps wall -> mesh -> urine of the monolithic residual ({self.solid_block} wall LU, "
                    f"Anderson depth {self.anderson_depth}, {self.sweep_convergence} stop{core})")
        return f"Newton + {self.linear_solver}{core}"

    def check_choices(self) -> None:
        """ValueError naming the first option of CHOICES whose value is none of its choices."""
        for key, allowed in CHOICES.items():
            value = getattr(self, key)
            if value not in allowed:
                names = ", ".join(repr(a) for a in allowed[:-1]) + f" or {allowed[-1]!r}"
                raise ValueError(f"{key} {names}, got {value!r}")

    def check(self, fluid: bool = True, solid: bool = True, prescribed_motion: bool = False) -> None:
        """ValueError on a value outside its choices (check_choices) or on options that do not go together, for a
        scene with (or without) a fluid region, solid regions and a prescribed ALE map (Scene.mesh_motion)."""
        self.check_choices()
        segregated = self.mesh_motion_coupling == "segregated"
        if segregated and (solid or not fluid):
            raise ValueError("segregated mesh motion needs a fluid-alone scene (its boundary motion prescribed)")
        if prescribed_motion and not segregated:
            raise ValueError("Scene.mesh_motion (a prescribed ALE map) needs mesh_motion_coupling 'segregated'")
        if self.linear_solver == "fieldsplit" and not segregated:
            raise ValueError("linear_solver 'fieldsplit' preconditions the fluid-alone (v, p) system: it needs "
                             "mesh_motion_coupling 'segregated'; use a direct solver for coupled FSI")
        if self.linear_solver in KRYLOV and segregated:
            raise ValueError(f"linear_solver {self.linear_solver!r} preconditions the coupled FSI system: it needs "
                             "mesh_motion_coupling 'monolithic'")
        if self.mesh_jacobian_stiffening < 0.0:
            raise ValueError(f"mesh_jacobian_stiffening >= 0, got {self.mesh_jacobian_stiffening!r}")
        if self.mesh_jacobian_stiffening and (segregated or self.coupling_scheme != "monolithic"
                                              or self.linear_solver in KRYLOV):
            raise ValueError("mesh_jacobian_stiffening > 0 (a nonlinear mesh motion) needs mesh_motion_coupling "
                             "'monolithic', coupling_scheme 'monolithic' and a direct linear_solver (the others keep "
                             "the mesh block's operator fixed)")
        if self.coupling_scheme == "partitioned" and (segregated or not fluid or not solid):
            raise ValueError("coupling_scheme 'partitioned' splits a coupled scene (a fluid and a solid region) with "
                             "mesh_motion_coupling 'monolithic'")
