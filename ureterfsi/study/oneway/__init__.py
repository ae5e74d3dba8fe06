"""One-way coupled rung of the fidelity ladder: wall -> urine -> stent.

The fully coupled rung (ureterfsi.study.coupled) solves wall, urine and stent in one Newton system. This rung
solves them in sequence, each with the engine's own physics blocks:

1. **wall**: the ureter wall alone in the axisymmetric r-z formulation (exact for the wall of every
   model: the geometry and the load are axisymmetric), Mooney-Rivlin with inertia, travelling
   Gaussian load (ureterfsi.scenes.wall_rz.WallModel) and, with an end condition posed, the urine pressure the
   ends give (config.end_pressures.wall_pressure: assumed a priori); its inner- and outer-surface motion is
   recorded at every step. Neglected: the rest of the urine pressure on the inner wall, measured in the fluid step
   (`one_way_max_wall_pressure_deviation`, |p - p_ref| against the 5e4 Pa load; `one_way_wall_pressure_mismatch`,
   the slab-mean pressure against the assumed one, refused beyond ends.one_way_pressure_tolerance).
2. **urine**: the fluid alone on the fluid part of the 3D mesh, ALE, with the recorded inner-wall
   motion prescribed (velocity and mesh displacement) and the stent held rigid; the mesh moves by a
   closed-form radial blend of the wall motion (radial_blend) or by a segregated extension problem.
3. **stent**: quasi-static linear elasticity on the stent part of the mesh, loaded by the urine's
   consistent nodal reaction forces on the fluid-stent interface (the residual of the fluid equations
   at the interface velocity dofs); stiffness matrix factorised once. Neglected: the stent deformation
   in the fluid domain (`one_way_max_stent_displacement` against the hole diameter) and the stent
   inertia (first bending frequency of the clamped 50 mm silicone tube ~46 Hz against the ~2 Hz of
   the load: dynamic amplification < 0.2 %).

wall    step 1: the r-z wall and its recorded motion (WallHistory, wall_history, RecordedWall, WALL_MOTION)
urine   step 2: the urine alone with the wall's motion, the mesh-motion choice (fluid_problem)
stent   step 3: the quasi-static stent (QuasiStaticStent)
rung    the run: write_wall_motion, pose, run, OneWayDiagnostics, WallPressureRefused
"""
from ureterfsi.study.oneway.wall import RecordedWall, WALL_MOTION, WallHistory, wall_history
from ureterfsi.study.oneway.urine import (JacobianMinimum, MeshMotionChoice, MeshMotionRefused, NO_MINIMUM,
                                          fluid_problem, inner_wall_motion, map_min_jacobian, predicted_min_jacobian,
                                          radial_blend)
from ureterfsi.study.oneway.stent import QuasiStaticStent
from ureterfsi.study.oneway.rung import OneWayDiagnostics, WallPressureRefused, pose, run, write_wall_motion

__all__ = [
    "JacobianMinimum", "MeshMotionChoice", "MeshMotionRefused", "NO_MINIMUM", "OneWayDiagnostics", "QuasiStaticStent",
    "RecordedWall", "WALL_MOTION", "WallHistory", "fluid_problem", "inner_wall_motion", "map_min_jacobian", "pose",
    "predicted_min_jacobian", "radial_blend", "run", "wall_history", "WallPressureRefused", "write_wall_motion"
]
