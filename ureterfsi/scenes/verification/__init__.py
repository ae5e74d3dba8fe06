"""The verification problems: exact solutions the engine is checked against (tests/test_verify_exact.py,
tests/test_solid_loads.py, benchmarks/convergence.py; the calibration uses the tube's exact pressure).

exact      annular Poiseuille flow (and its wall shear stress), the inflated Mooney-Rivlin tube, a bar and a confined column under their weight
norms      error norms, observed orders of convergence
problems   the small scenes the problems are solved on, with the study's materials
"""
from ureterfsi.scenes.verification.exact import (annular_poiseuille_flux, annular_poiseuille_velocity,
                                                 annular_poiseuille_wall_shear,
                                                 confined_column_top_displacement, hanging_bar_displacement,
                                                 mooney_rivlin_plane_strain_stress_difference,
                                                 mooney_rivlin_tube_inner_radius, mooney_rivlin_tube_pressure,
                                                 mooney_rivlin_uniaxial_strain_stress)
from ureterfsi.scenes.verification.norms import integrate, l2_error, observed_order
from ureterfsi.scenes.verification.problems import (Annulus, Pipe, REFERENCE_PRESSURE, STENT, Tube, URETER_WALL, URINE,
                                                    annulus_3d_errors, annulus_3d_scene, annulus_axisymmetric_scene,
                                                    annulus_in_solid_axisymmetric_scene, pipe_axisymmetric_scene,
                                                    channel_scene, confined_column_scene, dofs_count,
                                                    hanging_bar_scene, mean_facet_value,
                                                    pure_displacement_tube_inner_radius, quarter_annulus_mesh,
                                                    quarter_tube_3d_scene, radial_dead_load, tube_axisymmetric_scene,
                                                    tube_inner_radius, tube_scene)

__all__ = [
    "Annulus", "Pipe", "REFERENCE_PRESSURE", "STENT", "Tube", "URETER_WALL", "URINE", "annular_poiseuille_flux",
    "annular_poiseuille_velocity", "annular_poiseuille_wall_shear", "annulus_3d_errors", "annulus_3d_scene",
    "annulus_axisymmetric_scene", "annulus_in_solid_axisymmetric_scene", "pipe_axisymmetric_scene",
    "channel_scene", "confined_column_scene", "confined_column_top_displacement", "dofs_count",
    "hanging_bar_displacement", "hanging_bar_scene", "integrate", "l2_error", "mean_facet_value",
    "mooney_rivlin_plane_strain_stress_difference", "mooney_rivlin_tube_inner_radius", "mooney_rivlin_tube_pressure",
    "mooney_rivlin_uniaxial_strain_stress", "observed_order", "pure_displacement_tube_inner_radius",
    "quarter_annulus_mesh", "quarter_tube_3d_scene", "radial_dead_load", "tube_axisymmetric_scene",
    "tube_inner_radius", "tube_scene"
]
