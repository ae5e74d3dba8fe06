"""The verification problems: exact solutions the engine is checked against (tests/verification/test_verify_exact.py,
tests/verification/test_solid_loads.py, benchmarks/convergence.py; the calibration uses the tube's exact pressure).

exact      annular Poiseuille flow (and its wall shear stress), the inflated Mooney-Rivlin tube, a bar and a confined column under their weight
norms      error norms, observed orders of convergence, the integrals and counts they are made of
materials  the study's materials and reference pressure the scenes use
meshing    the gmsh models of the scenes: quadratic tetrahedra, the quarter annulus
flow       the flow scenes: the channel beside a wall, Poiseuille flow in a pipe and an annulus (r-z, in a solid, 3D)
tube       the inflated Mooney-Rivlin tube's scenes (2D, r-z, 3D), its inner radius, the pure-displacement contrast
weight     the solids under their weight: the hanging bar and the confined column
"""
from ureterfsi.scenes.verification.exact import (annular_poiseuille_flux, annular_poiseuille_velocity,
                                                 annular_poiseuille_wall_shear,
                                                 confined_column_top_displacement, hanging_bar_displacement,
                                                 mooney_rivlin_plane_strain_stress_difference,
                                                 mooney_rivlin_tube_inner_radius, mooney_rivlin_tube_pressure,
                                                 mooney_rivlin_uniaxial_strain_stress)
from ureterfsi.scenes.verification.flow import (Annulus, Pipe, annulus_3d_errors, annulus_3d_scene,
                                                annulus_axisymmetric_scene, annulus_in_solid_axisymmetric_scene,
                                                channel_scene, pipe_axisymmetric_scene)
from ureterfsi.scenes.verification.materials import REFERENCE_PRESSURE, STENT, URETER_WALL, URINE
from ureterfsi.scenes.verification.meshing import quarter_annulus_mesh
from ureterfsi.scenes.verification.norms import dofs_count, integrate, l2_error, mean_facet_value, observed_order
from ureterfsi.scenes.verification.tube import (Tube, pure_displacement_tube_inner_radius, quarter_tube_3d_scene,
                                                radial_dead_load, tube_axisymmetric_scene, tube_inner_radius,
                                                tube_scene)
from ureterfsi.scenes.verification.weight import confined_column_scene, hanging_bar_scene

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
