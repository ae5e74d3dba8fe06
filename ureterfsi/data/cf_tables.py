"""The tables of the one CF metadata registry (re-exported by ureterfsi.data.cf, its public path): name ->
(UDUNITS units, long_name) of the run and study files (VARIABLES) and, each in its own words, of the field files, the
wall motion, the design parameters, the rung check, the GCI and the ladder (templated entries built by a function
here), and the CF standard names. Plain data: imports nothing."""
from __future__ import annotations

# name -> (units, long_name) of the run files (ureterfsi.study, ureterfsi.study.oneway), the study datasets
# (ureterfsi.analyses.aggregate) and the stability matrix (ureterfsi.stability)
VARIABLES = {
    "time": ("s since 2000-01-01 00:00:00", "simulated time from the start of the run (the epoch is t = 0)"),
    "outlet_flux": ("m3 s-1", "volumetric flow rate through the outlet (bladder side), positive out of the ureter"),
    "inlet_flux": ("m3 s-1", "volumetric flow rate through the inlet (kidney side), positive into the ureter"),
    "outlet_mean_pressure": ("Pa", "area-mean urine pressure on the outlet end face (current area)"),
    "inlet_mean_pressure": ("Pa", "area-mean urine pressure on the inlet end face (current area)"),
    "pressure_drop": ("Pa", "pressure drop along the segment, inlet minus outlet area-mean end-face pressure"),
    "peak_pressure_drop": ("Pa", "maximum over the run of |inlet minus outlet area-mean end-face pressure|"),
    "mean_pressure_drop": ("Pa", "time mean over the run of the inlet minus outlet area-mean end-face pressure"),
    "outlet_mean_axial_velocity": ("m s-1", "mean axial (z) velocity over the outlet face (paper §3.2 measure)"),
    "fluid_volume": ("m3", "volume of the urine domain"),
    "fluid_volume_rate": ("m3 s-1", "rate of change of the urine domain's volume the continuity rows balance, "
                                    "int J tr(Grad w F^-1) dX (w the BDF mesh velocity): inlet_flux - outlet_flux"),
    "max_wall_displacement": ("m", "maximum over the wall probe line of |radial displacement| of the ureter outer wall "
                                   "(reference outer surface R_o(z), narrowed by a stricture, meridian y = 0)"),
    "stent_max_von_mises": ("Pa", "maximum von Mises stress over the stent volume"),
    "stent_max_von_mises_x": ("m", "x of the maximum stent von Mises stress (reference configuration)"),
    "stent_max_von_mises_y": ("m", "y of the maximum stent von Mises stress (reference configuration)"),
    "stent_max_von_mises_z": ("m", "z of the maximum stent von Mises stress (reference configuration)"),
    "hole_flux": ("m3 s-1", "volumetric flow rate through each side hole, positive from the stent lumen outward"),
    "hole_gross_exchange": ("m3 s-1", "gross exchange through each side hole, the mean over the hole channel's sections "
                                      "R = const of the integral of |u.n| (= |hole_flux| for a one-way flow)"),
    "hole_gross_exchange_volume": ("m3", "integral over time of the gross exchange through each side hole"),
    "hole_net_volume": ("m3", "integral over time of the volumetric flow rate through each side hole, positive from "
                              "the stent lumen outward"),
    "hole_active": ("1", "1 if the side hole's gross exchange volume exceeds active_hole_fraction times the mean "
                         "over the holes (an active hole), else 0"),
    "active_hole_fraction": ("1", "a hole is active when its gross exchange volume exceeds this times the mean over "
                                  "the holes (stent_surface.active_hole_fraction)"),
    "low_wss_threshold": ("Pa", "time-averaged wall shear stress below which a stent surface counts as low-shear "
                                "(stent_surface.low_wss_threshold)"),
    **{f"{region}_{key}": (units, f"{what} on {where}")
       for region, where in (("stent_outer", "the stent's outer surface"), ("stent_lumen", "the stent's lumen"),
                             ("hole_wall", "the wall of each side hole"))
       for key, units, what in (
           ("wss", "Pa", "area-mean wall shear stress |sigma_f n - (n.sigma_f n) n| (current configuration)"),
           ("tawss", "Pa", "area-mean time-averaged wall shear stress (1/T) integral |tau_w| dt"),
           ("osi", "1", "area-mean oscillatory shear index 1/2 (1 - |integral tau_w dt| / integral |tau_w| dt)"),
           ("low_wss_area_fraction", "1", "area fraction whose time-averaged wall shear stress is below "
                                          "low_wss_threshold"))},
    "outlet_lumen_flux": ("m3 s-1", "volumetric flow rate through the outlet inside the stent lumen, positive out of "
                                    "the ureter"),
    "inlet_lumen_flux": ("m3 s-1", "volumetric flow rate through the inlet inside the stent lumen, positive into the "
                                   "ureter"),
    "pelvic_pressure": ("Pa", "normal stress on the kidney end face: the renal pelvis pressure (ends.kidney)"),
    "bladder_pressure": ("Pa", "normal stress on the bladder end face: the bladder pressure, through the "
                               "vesicoureteral junction if it is a valve (ends.bladder)"),
    "stent_lumen_reflux_volume": ("m3", "volume of urine moved toward the kidney through the kidney end face inside "
                                        "the stent lumen since t = 0 (time integral of the reversed inflow)"),
    "annulus_reflux_volume": ("m3", "volume of urine moved toward the kidney through the kidney end face outside the "
                                    "stent (the whole lumen without a stent) since t = 0"),
    "obstruction_flux": ("m3 s-1", "volumetric flow rate in +z through the plane of the obstruction's centre (the flux "
                                   "through the layer of cells it crosses, consistent with the continuity rows)"),
    "obstruction_lumen_flux": ("m3 s-1", "part of obstruction_flux inside the stent (closer than the stent's mid-wall "
                                         "radius to its axis)"),
    "obstruction_lumen_fraction": ("1", "share of the flow past the obstruction's centre inside the stent, integral "
                                        "|Q_lumen| dt over integral |Q_lumen| dt + integral |Q - Q_lumen| dt"),
    "obstruction": ("1", "kind of obstruction of the design point: occlusion (complete), stricture (partial) or none"),
    "obstruction_position": ("m", "axial position of the obstruction's centre (NaN: none)"),
    "hole_proximal": ("1", "1 for a side hole upstream (kidney side) of the obstruction's centre, 0 downstream, NaN "
                           "without an obstruction"),
    "rung": ("1", "fidelity rung that solved the design point (one_way, or fully_coupled where escalated)"),
    "reference": ("1", "name of a reference run of the design study (design_studies.<study>.references)"),
    "reference_model": ("1", "stent model number of the reference run (paper Table 1)"),
    "stent_lumen_fraction": ("1", "share of the outlet flow passing inside the stent, integral |Q_out,lumen| dt over "
                                  "integral |Q_out,lumen| dt + integral |Q_out - Q_out,lumen| dt"),
    "wall_radial_displacement": ("m", "radial displacement of the ureter outer wall along the wall probe line "
                                      "(reference outer surface R_o(z), narrowed by a stricture, meridian y = 0)"),
    "stent_von_mises_line": ("Pa", "von Mises stress along the stent probe line (r = 0.75 mm, plane y = 0)"),
    "hole_velocity_y": ("m s-1", "velocity component along the hole axis (y, or x for a rotated pair) across the "
                                 "outlet-most side hole"),
    "z": ("m", "axial position along the ureter (0 inlet, L outlet)"),
    "probe_time": ("s", "probe time"),
    "hole_offset": ("m", "axial distance from the centre of the outlet-most hole at mid-wall radius"),
    "hole_z": ("m", "axial position of the side hole"),
    "hole_side": ("1", "side of the side hole on its axis (+1 or -1)"),
    "hole_axis": ("1", "axis of the side hole (0 = x, 1 = y)"),
    "model_fraction": ("1", "share of the full model a design point meshes (1/4 quarter, 1/2 half, 1 full or r-z), "
                            "from its mirror planes"),
    "pulse_centre": ("m", "axial position of the centre of the peristaltic pulse"),
    "step_time": ("s", "time at the end of the step"),
    "step_dt": ("s", "time step"),
    "newton_iterations": ("1", "Newton iterations of the step"),
    "newton_residual": ("1", "final Newton residual norm of the step"),
    "min_ale_jacobian": ("1", "minimum Jacobian of the ALE map over the fluid mesh"),
    "mesh_motion": ("1", "ALE map of the one-way urine solve: algebraic (radial blend) or extension (solver."
                         "one_way_mesh_motion, chosen per design point under auto)"),
    "predicted_min_jacobian": ("1", "minimum Jacobian of the algebraic ALE map over the recorded wall motion, "
                                    "evaluated before the solve (one_way_mesh_motion auto)"),
    "predicted_extension_min_jacobian": ("1", "minimum Jacobian of the extension (ALE) over the recorded wall "
                                              "motion, evaluated before the solve where the algebraic map's is below "
                                              "solver.one_way_auto_min_jacobian (one_way_mesh_motion auto)"),
    "step_wall_time": ("s", "wall-clock time of the step"),
    "model": ("1", "stent model number (paper Table 1)"),
    "model_label": ("1", "stent model label: distance between side-hole pairs (paper Table 1)"),
    "level": ("1", "mesh level (config mesh.levels)"),
    "step": ("1", "index of the time step (0: the initial state, where one is recorded)"),
    "hole": ("1", "index of the side hole, by axial position"),
    "cells": ("1", "number of cells of the mesh"),
    "dofs": ("1", "number of degrees of freedom of the monolithic system"),
    "wall_time": ("s", "wall-clock time of the run"),
    "processes": ("1", "number of MPI processes of the run"),
    "peak_outlet_flux": ("m3 s-1", "maximum over the dataset's time window (the comparison time, or the whole run) "
                                   "of the outlet volumetric flow rate"),
    "peak_stent_max_von_mises": ("Pa", "maximum up to the comparison time of the maximum von Mises stress over "
                                       "the stent"),
    "peak_outlet_hole_flux": ("m3 s-1", "maximum up to the comparison time of |volumetric flow rate| through the "
                                        "outlet-most side hole"),
    "outlet_hole_peak_velocity": ("m s-1", "maximum |velocity along the hole axis| across the outlet-most side "
                                           "hole at the comparison time"),
    "mean_outlet_flux": ("m3 s-1", "time mean of the outlet volumetric flow rate over the run"),
    "backflow_volume": ("m3", "volume flowing back in through the outlet, integral of max(-Q_out, 0) dt"),
    "peak_pelvic_pressure": ("Pa", "maximum over the run of the renal pelvis pressure (pelvic_pressure)"),
    "reflux_volume_lumen": ("m3", "volume of urine moved toward the kidney through the kidney end face inside the "
                                  "stent lumen over the run"),
    "reflux_volume_annulus": ("m3", "volume of urine moved toward the kidney through the kidney end face outside the "
                                    "stent over the run"),
    "peak_hole_flux": ("m3 s-1", "maximum over time of |volumetric flow rate| through each side hole"),
    "hole_exchange_volume": ("m3", "integral over time of |volumetric flow rate| through each side hole"),
    "hole_exchange_fraction": ("1", "volume exchanged through all side holes, sum of integral |Q_hole| dt, over "
                                    "the volume through the outlet, integral |Q_out| dt"),
    "peak_stent_von_mises": ("Pa", "maximum over time and the stent of the von Mises stress"),
    "peak_wall_displacement": ("m", "maximum over time of max_wall_displacement, |radial displacement| of the ureter "
                                    "outer wall along the wall probe line (reference outer surface R_o(z))"),
    "design": ("1", "design point id (hash of its parameter values)"),
    "point_id": ("1", "design point id (hash of its parameter values)"),
    "saltelli_point": ("1", "index along design of the point of each row of the Saltelli design (rows may repeat)"),
    "quantity": ("1", "name of the design quantity (of the sensitivity indices and the rung errors)"),
    "parameter": ("1", "name of the design parameter (in the sample's column order)"),
    "sobol_first_order": ("1", "first-order Sobol' index S1 = V[E(y | x_j)] / V(y) (SALib.analyze.sobol)"),
    "sobol_first_order_conf": ("1", "half-width of the 95 % bootstrap confidence interval of sobol_first_order"),
    "sobol_total": ("1", "total Sobol' index ST = E[V(y | x_~j)] / V(y) (SALib.analyze.sobol)"),
    "sobol_total_conf": ("1", "half-width of the 95 % bootstrap confidence interval of sobol_total"),
    "outlet_hole_z": ("m", "axial position of the outlet-most side hole (Figs. 6-9)"),
    "line_max_difference_to_finest": ("Pa", "maximum over z of |stent_von_mises_line - that of the finest level|"),
    # the stability matrix (ureterfsi.stability): per recorded state of a case
    "dt": ("s", "length of the accepted time step (0 for the initial state)"),
    "kinetic_energy": ("J", "kinetic energy of urine and wall: int_fluid 1/2 rho |v|^2 dx + int_wall 1/2 rho0 |v|^2 "
                            "dX"),
    "kinetic_energy_fluid": ("J", "kinetic energy of the urine, int 1/2 rho |v|^2 J dX (whole tube)"),
    "kinetic_energy_solid": ("J", "kinetic energy of the ureter wall, int 1/2 rho0 |v|^2 dX (whole tube)"),
    "elastic_energy": ("J", "strain energy of the ureter wall, int W(F) dX (Mooney-Rivlin, >= 0)"),
    "energy_bound": ("J", "E(0) + E_el(0) + W(t): the kinetic energy a dissipative system cannot exceed"),
    "load_power": ("W", "power of the peristaltic load on the wall, int t . v dA"),
    "open_boundary_power": ("W", "power of the prescribed normal stress on the open ends, -p_ref int v . n da"),
    "prescribed_power": ("W", "power of the prescribed (Dirichlet) motion, sum_i R_i v_i over the velocity dofs "
                         "(R: residual without boundary conditions)"),
    "external_work": ("J", "W(t) = int_0^t |load power| + |open-boundary power| + |prescribed power| dt "
                      "(rectangle rule)"),
    "volume_from_flux": ("m3", "V(0) - int_0^t (Q_out - Q_in) dt, the flux integrated with the BDF weights of each "
                              "step"),
    "volume_balance_error": ("m3", "|V(t) - V(0) + int_0^t (Q_out - Q_in) dt|"),
    "max_displacement": ("m", "largest nodal displacement component over wall and ALE mesh"),
    "max_speed": ("m s-1", "largest nodal speed |v| (a local instability shows here before it shows in the "
                  "kinetic energy)"),
    "halving_time": ("s", "end time of each failed step attempt (retried with dt/2, or the last of a failed step)"),
    # the stability matrix: per case
    "case": ("1", "name of the stability case (<axis>_<value>, or baseline)"),
    "axis": ("1", "the varied quantity (stability.axes key; baseline: none)"),
    "value_label": ("1", "value of the varied quantity, as in the configuration"),
    "outcome": ("1", "stable (ran to the end, energy bounded, volume conserved) or failed"),
    "limit": ("1", "limit that ended a failed case: none, newton, nan, ale_inversion, energy, volume, wall_time, "
                   "exception"),
    "diagnosis": ("1", "what failed, when and where (empty if stable)"),
    "failure_time": ("s", "time at which the limit was hit (NaN if stable)"),
    "failure_r": ("m", "reference radial coordinate of the place of the failure (NaN if none)"),
    "failure_z": ("m", "reference axial coordinate of the place of the failure (NaN if none)"),
    "pulse_centre_at_failure": ("m", "axial position of the pulse centre at the failure time"),
    "time_step": ("s", "nominal time step"),
    "mesh_level": ("1", "mesh level (config mesh.levels)"),
    "scene": ("1", "rz: r-z model, fully coupled; holes: 3D stented model, one-way (the urine alone)"),
    "hole_elements": ("1", "elements across a side-hole diameter, hole_diameter / mesh size (NaN: no holes)"),
    "hole_elements_measured": ("1", "hole diameter / mean edge length of the hole-wall triangles of the mesh "
                               "(NaN: no holes)"),
    "is_baseline": ("1", "1 for the baseline of the case's scene (r-z: baseline; 3D: the study's own mesh)"),
    "hole_channels_found": ("1", "side-hole channels found in the mesh (ureterfsi.mesh.quality.hole_channels)"),
    "mesh_min_quality": ("1", "smallest signed inverse condition number (gmsh minSICN) of the mesh cells"),
    "bulk_ratio": ("1", "kappa / (C10 + C01) of the ureter wall"),
    "density_ratio": ("1", "ureter wall density / urine density"),
    "peak_traction": ("Pa", "peak traction of the peristaltic pulse"),
    "wave_speed": ("m s-1", "speed of the peristaltic pulse"),
    "wave_width": ("m", "width of the peristaltic pulse (in peristalsis.width_measure)"),
    "dynamic_viscosity": ("Pa s", "dynamic viscosity of the urine"),
    "end_time": ("s", "time the case was to reach"),
    "reached_time": ("s", "last accepted time"),
    "steps": ("1", "number of accepted time steps"),
    "max_kinetic_energy": ("J", "maximum over time of the kinetic energy"),
    "max_energy_ratio": ("1", "maximum over time of kinetic energy / energy_bound (limit: stability.energy_safety)"),
    "displaced_volume": ("m3", "volume the wave displaces, max over time of |V(t) - V(0)|"),
    "volume_error": ("1", "maximum over time of the volume balance error relative to the displaced volume"),
    "min_jacobian": ("1", "minimum over time of the minimum ALE Jacobian"),
    "peak_displacement": ("m", "maximum over time of the largest nodal displacement component"),
    "peak_speed": ("m s-1", "maximum over time of the largest nodal speed"),
    "total_newton_iterations": ("1", "Newton iterations of all accepted steps"),
    "mean_newton_iterations": ("1", "mean Newton iterations per accepted step"),
    "max_newton_iterations": ("1", "largest number of Newton iterations of an accepted step"),
    "step_halvings": ("1", "number of failed step attempts retried with dt/2 (engine retries)"),
    "factorisations": ("1", "LU factorisations of the Jacobian"),
    "wall_time_per_step": ("s", "mean wall-clock time per accepted step"),
}

# the tables of the other datasets, each in its own words (a name may mean another thing elsewhere)
# XDMF field attributes and fields.json (ureterfsi.study.fields): quantity -> (units, long_name)
FIELD_VARIABLES = {
    "velocity": ("m s-1", "urine velocity (solid velocity in the ureter wall and the stent)"),
    "pressure": ("Pa", "urine pressure"),
    "displacement": ("m", "displacement: solid in the ureter wall and the stent, ALE mesh displacement in the urine"),
    "von_mises": ("Pa", "stent von Mises stress, cell mean"),
    "wall_shear_stress": ("Pa", "wall shear stress on the stent, the mean over each urine cell's stent facets, NaN on "
                                "the cells off the stent"),
    "subdomain": ("1", "cell tag of the subdomain (ureterfsi.mesh.tags: urine 1, ureter wall 2, stent 3)"),
    "time": ("s", "simulated time of the snapshot"),
}
# the one-way rung's wall-motion file (ureterfsi.study.oneway.WallHistory)
WALL_MOTION_VARIABLES = {
    "inner_radial_displacement": ("m", "radial displacement of the inner wall surface"),
    "inner_axial_displacement": ("m", "axial displacement of the inner wall surface"),
    "inner_radial_velocity": ("m s-1", "radial velocity of the inner wall surface"),
    "inner_axial_velocity": ("m s-1", "axial velocity of the inner wall surface"),
    "outer_radial_displacement": ("m", "radial displacement of the outer wall surface"),
    "time": ("s", "time"),
    "z_inner": ("m", "axial position on the inner wall surface (reference)"),
    "z_outer": ("m", "axial position on the outer wall surface (reference)"),
}
# design-study parameters (ureterfsi.designs.space.PARAMETERS), SI units
DESIGN_PARAMETERS = {
    "hole_diameter": ("m", "side-hole diameter"),
    "hole_pair_spacing": ("m", "distance between side-hole pairs (count by the Table 1 rule)"),
    "stent_outer_diameter": ("m", "stent outer diameter"),
    "stent_wall_thickness": ("m", "stent wall thickness"),
    "stent_youngs_modulus": ("Pa", "Young's modulus of the stent"),
    "wall_stiffness_scale": ("1", "common factor on the five Mooney-Rivlin coefficients of the wall"),
    "peak_traction": ("Pa", "peak traction of the peristaltic load"),
    "pulse_speed": ("m s-1", "speed of the peristaltic pulse"),
    "stricture_fraction": ("1", "fraction by which a stricture narrows the lumen radius at its centre"),
    "stricture_length": ("m", "axial length of the stricture"),
    "stricture_position": ("m", "axial position of the stricture centre"),
    "hole_pair_rotation": ("degree", "angle between the axes of successive side-hole pairs"),
    "stent_eccentricity": ("m", "offset of the stent axis from the ureter axis, along x"),
    "occlusion_position": ("m", "axial position of the complete occlusion's centre"),
    "occlusion_length": ("m", "axial length over which a complete occlusion lies on the stent (0: none)"),
}
# the rung check of a design study at the corners of its design space (ureterfsi.designs.rung_check); the corners'
# parameter coordinates come from rung_check_metadata
RUNG_CHECK_VARIABLES = {
    "corner": ("1", "id of a corner of the design space (hash of its parameter values) where the study's rung is "
                    "checked against the fully coupled model"),
    "rung_error": ("1", "relative error of the study's rung at the corner, |q_rung - q_fully_coupled| / s, s the "
                        "fully coupled run's scale: max |Q_out| for the peak and mean outlet flow, integral |Q_out| "
                        "dt for the backflow volume, |q_fully_coupled| for the others"),
    "max_rung_error": ("1", "largest relative error of the study's rung over the corners"),
    "rung_tolerance": ("1", "largest relative error of the study's rung at a corner the check accepts "
                            "(design_studies.<study>.rung_check.tolerance)"),
    "corner_within_tolerance": ("1", "1 if every quantity's rung error at the corner is within the tolerance, else 0"),
    "corner_rung_wall_time": ("s", "wall-clock time of the corner's solve on the study's rung"),
    "corner_reference_wall_time": ("s", "wall-clock time of the corner's fully coupled solve"),
    "in_rung_check_region": ("1", "1 if the design point lies in the convex hull of the checked corners, else 0"),
    "rung_trusted": ("1", "1 if the design point lies in the checked region and every corner is within the "
                          "tolerance, else 0"),
}


def reference_metadata(names) -> dict:
    """(units, long_name) of the reference runs' scalars of a design dataset (reference_<name> on the reference
    dimension), from VARIABLES."""
    return {f"reference_{k}": (VARIABLES[k][0], f"{VARIABLES[k][1]}, of the reference run") for k in names}


def rung_check_metadata(parameters) -> dict:
    """RUNG_CHECK_VARIABLES with each parameter's value at the corners (corner_<parameter>)."""
    return RUNG_CHECK_VARIABLES | {f"corner_{p}": (DESIGN_PARAMETERS[p][0], f"{DESIGN_PARAMETERS[p][1]}, at the corner")
                                   for p in parameters}


# the GCI dataset (ureterfsi.analyses.gci); the templated entries come from gci_variables
GCI_VARIABLES = {
    "cells": VARIABLES["cells"],
    "apparent_order": ("1", "apparent order p of Celik et al. 2008 (NaN: undefined, see note)"),
    "e_a21": ("1", "approximate relative error |(phi1 - phi2)/phi1| (fraction)"),
    "e_ext21": ("1", "extrapolated relative error |(phi_ext21 - phi1)/phi_ext21| (fraction)"),
    "gci_fine21": ("1", "fine-grid convergence index GCI_fine21 = Fs e_a21/(r21^p - 1) (fraction)"),
    "gci32": ("1", "coarse-pair convergence index GCI32 = Fs e_a32/(r32^p - 1) (fraction)"),
    "asymptotic_ratio": ("1", "GCI32 / (r21^p GCI_fine21), ~1 in the asymptotic range"),
    "convergence_ratio": ("1", "R = eps21/eps32 = (phi2 - phi1)/(phi3 - phi2); monotone for "
                               "0 < R < ln r21/ln r32, oscillatory for R < 0"),
    "note": ("1", "explanation of NaN or non-monotone results"),
    "probe_z": ("m", "axial position of the probe-line point (NaN for whole-run scalars)"),
    "quantity": ("1", "quantity of the GCI"),
    "level": VARIABLES["level"],
}
# the fidelity-ladder dataset (ureterfsi.analyses.ladder); the templated entries come from ladder_variables
LADDER_VARIABLES = {
    "pairwise_error": ("1", "relative max-norm error of a rung against another (e.g. the quarter model against "
                            "the full one)"),
    "wall_time": VARIABLES["wall_time"],
    "peak_memory": ("1048576 byte", "peak resident memory of the run (MiB)"),
    "cells": ("1", "cells of the mesh"),
    "dofs": ("1", "unknowns of the (fluid or coupled) Newton system"),
    "time_step": ("s", "time step"),
    "fidelity": ("1", "coupling of the rung"),
    "symmetry": ("1", "mesh symmetry of the rung"),
    "level": ("1", "mesh level of the rung"),
    "rung": ("1", "rung of the fidelity ladder"),
    "against": ("1", "rung an error is measured against"),
    "quantity": ("1", "quantity of interest"),
    "scene": ("1", "figure (scene)"),
    "tolerance": ("1", "tolerated relative error of the scene"),
    "chosen_rung": ("1", "cheapest rung within the scene's tolerance"),
    "chosen_error": ("1", "largest error of the chosen rung over the scene's quantities"),
    "recorded_error": ("1", "the scene's measured_error recorded in the configuration"),
}


def gci_variables(relative: bool, fine: str, medium: str, coarse: str, diagnoses) -> dict:
    """GCI_VARIABLES with the entries that name the levels, the measure of h and the diagnoses."""
    return GCI_VARIABLES | {
        "h": ("1" if relative else "m",
              "representative cell size (V/N)^(1/d)" + (", with V = 1 (relative)" if relative else "")),
        "r21": ("1", f"refinement ratio h2/h1 ({medium}/{fine})"),
        "r32": ("1", f"refinement ratio h3/h2 ({coarse}/{medium})"),
        "diagnosis": ("1", "convergence diagnosis: " + ", ".join(diagnoses)),
    }


def gci_quantity_variables(quantity: str, units: str, long_name: str) -> dict:
    """(units, long_name) of a GCI quantity's per-level values and its Richardson-extrapolated value."""
    return {f"value_{quantity}": (units, f"{long_name}, on each mesh level"),
            f"extrapolated_value_{quantity}": (units, f"{long_name}, Richardson-extrapolated value phi_ext21")}


def ladder_variables(reference: str, default: str | None = None) -> dict:
    """LADDER_VARIABLES with the entries that name the reference rung and the default runs' rung."""
    out = LADDER_VARIABLES | {"error": ("1", f"relative max-norm error against the reference rung '{reference}'")}
    if default is not None:
        out["default_error"] = ("1", f"largest error of the default runs' rung '{default}' over the scene's "
                                     f"quantities")
    return out


def at_time(long_name: str, time: float) -> str:
    """long_name of a snapshot of a variable at time `time` (s)."""
    return f"{long_name} at t = {time:g} s"


def at_z(long_name: str, z: float) -> str:
    """long_name of a probe-line variable at the axial position `z` (m; named in mm)."""
    return f"{long_name}, at z = {z * 1e3:g} mm"


# CF standard names (CF standard name table) of the variables that have one
STANDARD_NAMES = {"time": "time"}
