"""A catalogue of bad configurations of the kinds people make, each an overlay on config/config.yaml
refused at the edge with one line naming the key and the constraint: by ureterfsi.config (read_yaml +
validate_config), by its command line `python -m ureterfsi.config check`, and (a few, slow) by `snakemake -n`
before any job starts. Also: a target the configuration cannot make is refused by the dry run in one line; a
key given twice in a --configfile overlay is refused by the Snakefile; every shipped configuration passes."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from ureterfsi.config import (ConfigError, load_config, load_config_files, main, read_config_args,
                              unmakeable)

REPO = Path(__file__).resolve().parents[2]
DEFAULT = REPO / "config" / "config.yaml"

DS = 'design_studies:\n  s1:\n    model: "3"\n    level: coarse\n'   # a design study on model 3, coarse mesh

# (id, overlay YAML, key the message must name, substring of the constraint)
CATALOGUE = [
    # ---- wrong types
    ("length_with_unit", 'geometry: {length: "50 mm"}\n', "geometry.length", "must be of type number, got str '50 mm'"),
    ("dt_with_unit", "time:\n  dt: 10ms\n", "time.dt", "must be of type number, got str '10ms'"),
    ("model_key_as_int", "study: {convergence_model: 3}\n", "study.convergence_model",
     "must be of type string, got int 3"),
    ("models_key_unquoted", 'models: {5: {label: x, stent: true, hole_pair_spacing: 0.025, holes: 6}}\n',
     "models.5", 'keys must be strings, got int 5 (quote it: "5")'),
    ("bool_as_string", 'mesh: {optimize: "true"}\n', "mesh.optimize", "must be of type boolean, got str 'true'"),
    ("list_as_string", 'time: {probe_times: "0.5, 1.0"}\n', "time.probe_times", "must be of type array, got str"),
    ("null_value", "time: {dt: ~}\n", "time.dt", "must be of type number, got NoneType None"),
    ("not_a_number", "fluid: {density: .nan}\n", "fluid.density", "must be a finite number, got nan"),
    ("infinite", "time: {end: .inf}\n", "time.end", "must be a finite number, got inf"),
    ("empty_section", "solver:\n", "solver", "must be of type object, got NoneType None"),
    ("level_as_number", "mesh: {levels: {coarse: 1.0}}\n", "mesh.levels.coarse", "must be of type object, got float 1"),
    ("label_as_number", 'models: {"2": {label: 5}}\n', "models.2.label", "must be of type string, got int 5"),
    ("unicode_minus", "geometry: {length: \u22120.05}\n", "geometry.length", "must be of type number, got str"),
    ("file_is_a_number", "42\n", "refusal.yaml", "must be a YAML mapping of sections, got int"),
    ("top_level_list", "- time\n", "refusal.yaml", "must be a YAML mapping of sections, got list"),
    # ---- integers written as floats
    ("newton_iterations_float", "solver: {newton_max_iterations: 15.0}\n", "solver.newton_max_iterations",
     "must be an integer, got the float 15.0: write 15"),
    ("holes_float", 'models: {"2": {holes: 22.0}}\n', "models.2.holes", "must be an integer, got the float 22.0"),
    ("checkpoint_interval_float", "time: {checkpoint_interval: 10.0}\n", "time.checkpoint_interval",
     "must be an integer, got the float 10.0"),
    ("dpi_float", "figures: {dpi: 150.0}\n", "figures.dpi", "must be an integer, got the float 150.0"),
    ("leading_zero_octal", 'models: {"2": {holes: 022}}\n', "models.2.holes",
     "022 has a leading zero, which YAML 1.1 reads as an octal number"),
    # ---- negative or zero sizes
    ("mesh_size_zero", "mesh: {sizes: {hole: 0}}\n", "mesh.sizes.hole", "must be > 0, got 0"),
    ("length_negative", "geometry: {length: -0.05}\n", "geometry.length", "must be > 0, got -0.05"),
    ("size_factor_zero", "mesh: {levels: {coarse: {size_factor: 0}}}\n", "mesh.levels.coarse.size_factor",
     "must be > 0, got 0"),
    ("dt_zero", "time: {dt: 0.0}\n", "time.dt", "must be > 0, got 0"),
    ("resolution_minimum_zero", "mesh: {resolution_minima: {hole: 0}}\n", "mesh.resolution_minima.hole",
     "must be > 0, got 0"),
    # ---- implausible magnitudes (unit slips)
    ("length_in_mm", "geometry: {length: 50}\n", "geometry.length",
     "50 m is outside the plausible range [0.005, 0.5] m (a ureter segment, 5 mm up to the whole ~0.3 m ureter); "
     "in mm? that is 0.05 m"),
    ("ureter_10_m", "geometry: {ureter_outer_diameter: 10.0}\n", "geometry.ureter_outer_diameter",
     "10 m is outside the plausible range [0.001, 0.03] m"),
    ("hole_in_mm", "geometry: {hole_diameter: 0.5}\n", "geometry.hole_diameter", "in mm? that is 0.0005 m"),
    ("mesh_size_1_m", "mesh: {sizes: {fluid_bulk: 1.0}}\n", "mesh.sizes.fluid_bulk",
     "1 m is outside the plausible range [1e-06, 0.01] m"),
    ("viscosity_in_cP", "fluid: {dynamic_viscosity: 1.3}\n", "fluid.dynamic_viscosity",
     "in mPa s (cP)? that is 0.0013 Pa s"),
    ("traction_in_kPa", "peristalsis: {peak_traction: 50.0}\n", "peristalsis.peak_traction",
     "in kPa? that is 50000 Pa"),
    ("speed_in_cm_per_s", "peristalsis: {speed: 2.0}\n", "peristalsis.speed", "in cm/s? that is 0.02 m/s"),
    ("density_in_g_per_cm3", "fluid: {density: 1.05}\n", "fluid.density", "in g/cm^3? that is 1050 kg/m^3"),
    ("spacing_in_mm", 'models: {"4": {hole_pair_spacing: 25.0}}\n', "models.4.hole_pair_spacing",
     "in mm? that is 0.025 m"),
    ("mooney_rivlin_in_kPa", "ureter: {c10: 87.0, c01: 29.0}\n", "ureter.c10",
     "2(c10 + c01) = 2(87 + 29): 232 Pa is outside the plausible range"),
    ("newton_rtol_loose", "solver: {newton_rtol: 0.5}\n", "solver.newton_rtol",
     "0.5 is outside the plausible range [1e-14, 0.01]"),
    ("scene_tolerance_500_percent", "scenes: {fig04_outlet_flow: {quantities: [outlet_flux], tolerance: 5.0}}\n",
     "scenes.fig04_outlet_flow.tolerance", "5 is outside the plausible range [0, 1]"),
    ("mesh_size_wider_than_lumen", "mesh: {sizes: {fluid_bulk: 3.0e-3}}\n", "mesh.sizes.fluid_bulk",
     "the fluid gap 0.003 m (ureter inner radius - stent outer radius) / (mesh.sizes.fluid_bulk * size_factor) "
     "= 0.003 / (0.003 * 1) = 1 elements; need >= 2"),
    # ---- decimal commas
    ("decimal_comma_flow_mapping", "time: {end: 3.0, dt: 0,005}\n", "time.dt", "decimal comma in 0,005 ("),
    ("decimal_comma_model_row", 'models: {"2": {label: "5 mm", stent: true, hole_pair_spacing: 0,005, holes: 22}}\n',
     "models.2.hole_pair_spacing", "decimal comma in 0,005 ("),
    ("decimal_comma_block", "time:\n  dt: 0,005\n", "time.dt", "got str '0,005' (decimal comma? write 0.005)"),
    ("decimal_comma_list", "time: {probe_times: [0,5, 1,0, 1,5, 2,0, 2,5]}\n", "time.probe_times[0]",
     "decimal comma in 0,5 ("),
    ("decimal_comma_list_leading_zero", "time: {probe_times: [0,005, 1.0, 1.5, 2.0, 2.5]}\n", "time.probe_times[0]",
     "decimal comma in 0,005 ("),
    ("decimal_comma_list_middle", "figures: {wave_times: [0.5, 1,0, 2.0, 2.5]}\n", "figures.wave_times[1]",
     "decimal comma in 1,0 ("),
    # ---- misspelt keys and names
    ("misspelt_key", "solver: {newton_rtoll: 1.0e-8}\n", "solver.newton_rtoll",
     "unknown key (misspelt?); allowed keys:"),
    ("misspelt_section", "geometri: {length: 0.05}\n", "geometri", "unknown key (misspelt?)"),
    ("misspelt_scene", "scenes: {fig04_outflow: {quantities: [outlet_flux], tolerance: 0.05}}\n",
     "scenes.fig04_outflow", "unknown key (misspelt?); allowed keys: fig03_mesh_convergence"),
    ("misspelt_scene_quantity", "scenes: {fig04_outlet_flow: {quantities: [outlet_flow], tolerance: 0.05}}\n",
     "scenes.fig04_outlet_flow.quantities[0]", "got 'outlet_flow'"),
    ("model_name", 'study: {convergence_model: "three"}\n', "study.convergence_model",
     "must be one of models ['1', '2', '3', '4'], got 'three'"),
    ("convergence_model_without_stent", 'study: {convergence_model: "1"}\n', "study.convergence_model",
     "model '1' has no stent: the mesh-convergence study"),
    ("model_gap", 'models: {"6": {label: x, stent: true, hole_pair_spacing: 0.025, holes: 6}}\n', "models",
     'model keys must be "1".."5" without gaps'),
    ("level_name", "study: {level: ultra}\n", "study.level", "must be one of mesh.levels"),
    ("fidelity_hyphen", "study: {fidelity: one-way}\n", "study.fidelity", "must be one of fully_coupled, one_way"),
    ("symmetry_capitalised", "mesh: {symmetry: Quarter}\n", "mesh.symmetry", "got 'Quarter'"),
    ("runs_key_misspelt", 'study: {runs: {"2": {symetry: half}}}\n', "study.runs.2.symetry",
     "unknown key (misspelt?); allowed keys: symmetry, fidelity"),
    ("figure_domain_model", 'figures: {domain_model: "9"}\n', "figures.domain_model", "must be one of models"),
    ("ladder_model_as_number", "ladder: {model: 3}\n", "ladder.model", "must be of type string, got int 3"),
    ("dpi_too_high", "figures: {dpi: 6000}\n", "figures.dpi", "must be <= 600, got 6000"),
    ("scene_without_quantities", "scenes: {fig04_outlet_flow: {quantities: [], tolerance: 0.05}}\n",
     "scenes.fig04_outlet_flow.quantities", "must have at least 1 entry, got 0"),
    ("runs_of_unknown_model", 'study: {runs: {"9": {fidelity: one_way}}}\n', "study.runs.9", "must be a key of models"),
    # ---- duplicate keys
    ("duplicate_key_flow", "time: {dt: 0.01, dt: 0.02}\n", "time.dt", "key given twice ("),
    ("duplicate_key_block", "time:\n  dt: 0.01\n  dt: 0.02\n", "time.dt", "YAML keeps the second silently"),
    ("duplicate_section", "time: {dt: 0.01}\ntime: {end: 3.0}\n", "time", "key given twice ("),
    # ---- inconsistent geometry
    ("hole_wider_than_stent_lumen", "geometry: {hole_diameter: 1.5e-3}\n", "geometry.hole_diameter",
     "must be < the stent inner diameter 0.001 m (radial through-hole), got 0.0015"),
    ("stent_touches_wall", "geometry: {stent_wall_thickness: 3.5e-3}\n", "geometry.stent_wall_thickness",
     "and ureter inner radius 0.004 m is 0 m; need >= 2 hole diameters = 0.001 m"),
    ("ureter_narrower_than_stent", "geometry: {ureter_outer_diameter: 0.003}\n", "geometry.stent_wall_thickness",
     "is -0.0005 m; need >= 2 hole diameters"),
    ("wall_thicker_than_radius", "geometry: {ureter_wall_thickness: 5.0e-3}\n", "geometry.ureter_wall_thickness",
     "must be < the ureter outer radius 0.005 m"),
    ("length_too_long", "geometry: {length: 0.08}\n", "geometry.length",
     "0.08 m contradicts the hole counts of models 2, 3, 4"),
    ("length_too_short", "geometry: {length: 0.04}\n", "geometry.length",
     "which every stented model meets for L in [0.05, 0.055) m"),
    ("hole_at_the_end_face", "geometry: {hole_end_clearance: 1.0e-4}\n", "geometry.hole_end_clearance",
     "must be > the hole radius 0.00025 m"),
    ("holes_odd", 'models: {"2": {holes: 21}}\n', "models.2.holes", "must be a positive even number"),
    # the study's own runs cannot be made (was: `config check` said ok, only the dry run refused the mesh)
    ("offset_stent_on_quarter_model", "geometry: {stent_offset: 2.0e-4}\n", "mesh.symmetry",
     "geometry.stent_offset 0.0002 m breaks the x = 0 mirror plane: model 2 has no quarter model"),
    ("offset_stent_run_quarter", 'geometry: {stent_offset: 2.0e-4}\nmesh: {symmetry: half}\n'
     'study: {runs: {"3": {symmetry: quarter}}}\n', "study.runs.3.symmetry", "model 3 has no quarter model"),
    ("holes_without_stent", 'models: {"1": {holes: 2}}\n', "models.1.holes", "must be 0 for a model without a stent"),
    ("axisymmetric_stented_run", 'study: {runs: {"3": {symmetry: axisymmetric}}}\n', "study.runs.3.symmetry",
     "'axisymmetric' is only valid for a model without stent"),
    ("hole_coarser_than_minimum", "mesh: {sizes: {hole: 2.5e-4}}\n", "mesh.sizes.hole", "= 2 elements; need >= 4"),
    ("levels_not_coarse_to_fine", "mesh: {levels: {fine: {size_factor: 1.5}}}\n", "mesh.levels.fine.size_factor",
     "(levels are listed coarse to fine)"),
    ("pulse_starts_far_away", "peristalsis: {start_position: 0.5}\n", "peristalsis.start_position",
     "must lie in [-3 widths, L] = [-0.03, 0.05] m, got 0.5"),
    ("wall_compressible", "ureter: {bulk_modulus: 5.0e5}\n", "ureter.bulk_modulus", "near-incompressibility"),
    # ---- time settings
    ("end_before_last_probe", "time: {end: 2.0}\n", "time.probe_times[4]", "must lie in (0, time.end = 2] s, got 2.5"),
    ("dt_longer_than_run", "time: {dt: 5.0}\n", "time.dt", "must be < time.end = 3 s, got 5"),
    ("dt_in_ms", "time: {dt: 10.0}\n", "time.dt", "must be < time.end = 3 s, got 10"),
    ("dt_coarser_than_probes", "time: {dt: 0.6}\n", "time.dt", "smallest spacing of the probe times"),
    ("probe_after_end", "time: {probe_times: [0.5, 1.0, 1.5, 2.0, 2.5, 4.0]}\n", "time.probe_times[5]",
     "must lie in (0, time.end = 3] s, got 4"),
    ("probe_negative", "time: {probe_times: [-0.5, 1.0, 1.5, 2.0, 2.5]}\n", "time.probe_times[0]", "got -0.5"),
    ("probe_repeated", "time: {probe_times: [0.5, 0.5, 1.0, 1.5, 2.0, 2.5]}\n", "time.probe_times[1]",
     "strictly increasing"),
    ("ramp_longer_than_run", "peristalsis: {ramp_time: 5.0}\n", "peristalsis.ramp_time", "must be < time.end = 3 s"),
    ("figure_time_not_a_probe", "figures: {wave_times: [0.5, 0.7]}\n", "figures.wave_times[1]",
     "must be one of time.probe_times"),
    ("convergence_time_not_a_probe", "study: {convergence_time: 1.7}\n", "study.convergence_time",
     "must be one of time.probe_times"),
    ("ladder_window_before_first_probe", "ladder: {end: 0.2}\n", "ladder.end",
     "must be >= the first of time.probe_times, 0.5 s"),
    ("ladder_dt_longer_than_window",
     "ladder: {rungs: {one_way: {fidelity: one_way, symmetry: quarter, level: coarse, dt: 1.0}}}\n",
     "ladder.rungs.one_way.dt", "must be <= ladder.end = 0.5 s"),
    # ---- design studies
    ("design_model", DS.replace('"3"', '"9"') + "    grid: {parameters: {hole_diameter: [5.0e-4]}}\n",
     "design_studies.s1.model", "must be one of models"),
    ("design_level", DS.replace("coarse", "ultra") + "    grid: {parameters: {hole_diameter: [5.0e-4]}}\n",
     "design_studies.s1.level", "must be one of mesh.levels"),
    ("design_parameter_misspelt", DS + "    grid: {parameters: {hole_size: [5.0e-4]}}\n",
     "design_studies.s1.grid.parameters.hole_size", "unknown key (misspelt?)"),
    ("design_grid_and_sample", DS + "    grid: {parameters: {hole_diameter: [5.0e-4]}}\n"
     "    sample: {method: sobol, size: 4, seed: 1, bounds: {hole_diameter: [4.0e-4, 6.0e-4]}}\n",
     "design_studies.s1", "needs exactly one of grid"),
    ("design_sobol_not_power_of_2",
     DS + "    sample: {method: sobol, size: 6, seed: 1, bounds: {hole_diameter: [4.0e-4, 6.0e-4]}}\n",
     "design_studies.s1.sample.size", "only at a power of 2, got 6"),
    ("design_bounds_reversed",
     DS + "    sample: {method: latin_hypercube, size: 6, seed: 1, bounds: {hole_diameter: [6.0e-4, 4.0e-4]}}\n",
     "design_studies.s1.sample.bounds.hole_diameter", "low < high"),
    ("design_size_float",
     DS + "    sample: {method: latin_hypercube, size: 6.0, seed: 1, bounds: {hole_diameter: [4.0e-4, 6.0e-4]}}\n",
     "design_studies.s1.sample.size", "must be an integer, got the float 6.0"),
    ("design_hole_wider_than_lumen", DS + "    grid: {parameters: {hole_diameter: [5.0e-4, 1.2e-3]}}\n",
     "design_studies.s1.grid.parameters.hole_diameter",
     "cannot be posed: geometry.hole_diameter: must be < the stent inner diameter"),
    ("design_traction_in_kPa", DS + "    grid: {parameters: {peak_traction: [50.0]}}\n",
     "design_studies.s1.grid.parameters.peak_traction", "in kPa? that is 50000 Pa"),
    ("design_stent_too_thick", DS + "    grid: {parameters: {stent_outer_diameter: [2.0e-3, 4.0e-3]}}\n",
     "design_studies.s1.grid.parameters.stent_outer_diameter", "= 12 Fr is outside the ureteral stent sizes"),
    ("design_stent_without_lumen", DS + "    grid: {parameters: {stent_wall_thickness: [5.0e-4, 1.0e-3]}}\n",
     "design_studies.s1.grid.parameters.stent_wall_thickness", "leaves no stent lumen"),
    ("design_holes_overlap", DS + "    grid: {parameters: {hole_pair_spacing: [0.010, 0.0005]}}\n",
     "design_studies.s1.grid.parameters.hole_pair_spacing", "overlap"),
    ("design_stent_parameter_without_stent",
     DS.replace('"3"', '"1"') + "    grid: {parameters: {hole_diameter: [5.0e-4]}}\n",
     "design_studies.s1.grid.parameters.hole_diameter", "needs a stented base model"),
    ("design_rotation_not_0_or_90", DS + "    grid: {parameters: {hole_pair_rotation: [0.0, 45.0]}}\n",
     "design_studies.s1.grid.parameters.hole_pair_rotation[1]", "must be one of 0, 90; got 45"),
    ("design_reserved_name", DS.replace("s1", "meshes") + "    grid: {parameters: {hole_diameter: [5.0e-4]}}\n",
     "design_studies.meshes", "reserved"),
    ("design_without_parameters", DS + "    grid: {parameters: {}}\n", "design_studies.s1.grid.parameters",
     "must have at least 1 entry, got 0"),
    ("design_repeated_values", DS + "    grid: {parameters: {hole_diameter: [5.0e-4, 5.0e-4]}}\n",
     "design_studies.s1.grid.parameters.hole_diameter", "values must be distinct"),
    # ---- stability section
    ("stability_model_with_stent", 'stability: {model: "3"}\n', "stability.model",
     "model '3' has a stent: the r-z (axisymmetric) scene needs a stent-free model"),
    ("stability_level", "stability: {level: ultra}\n", "stability.level", "'ultra' is not one of mesh.levels"),
    ("stability_hole_model_without_holes", 'stability: {holes: {model: "1"}}\n', "stability.holes.model",
     "has no side holes"),
    ("stability_mesh_level", "stability: {axes: {mesh_level: [medium, ultra]}}\n", "stability.axes.mesh_level[1]",
     "'ultra' is not one of mesh.levels"),
    ("stability_axis_misspelt", "stability: {axes: {time_stp: [0.001]}}\n", "stability.axes.time_stp",
     "unknown key (misspelt?)"),
    ("stability_case_names_collide", "stability: {axes: {time_step: [0.001, 0.0010001]}}\n",
     "stability.axes.time_step[1]", "gives the case name 'time_step_0.001'"),
    ("stability_end_shorter_than_dt", "stability: {end: 0.005, axes: {time_step: []}}\n", "stability.end",
     "must be > time.dt = 0.01 s"),
    ("stability_speed_in_cm_per_s", "stability: {axes: {wave_speed: [2.0]}}\n", "stability.axes.wave_speed[0]",
     "in cm/s? that is 0.02 m/s"),
    ("stability_hole_model_unknown", 'stability: {holes: {model: "9"}}\n', "stability.holes.model",
     "must be one of models ['1', '2', '3', '4'], got '9'"),
    ("stability_energy_safety", "stability: {energy_safety: 0.5}\n", "stability.energy_safety", "must be >= 1"),
    # ---- fields section
    ("fields_quantity", "fields: {quantities: [velocity, vorticity]}\n", "fields.quantities[1]", "got 'vorticity'"),
    ("fields_format", "fields: {format: vtx}\n", "fields.format", "must be one of xdmf; got 'vtx'"),
    ("fields_every_negative", "fields: {every_steps: -1}\n", "fields.every_steps", "must be >= 0, got -1"),
    ("fields_repeated_quantity", "fields: {quantities: [velocity, velocity]}\n", "fields.quantities",
     "has non-unique elements"),
    ("fields_every_float", "fields: {every_steps: 2.0}\n", "fields.every_steps", "must be an integer"),
    # ---- solver options
    ("linear_solver_unknown", "solver: {linear_solver: lu}\n", "solver.linear_solver", "got 'lu'"),
    ("newton_rtol_zero", "solver: {newton_rtol: 0.0}\n", "solver.newton_rtol", "must be > 0, got 0"),
    ("newton_atol_negative", "solver: {newton_atol: -1.0e-10}\n", "solver.newton_atol", "must be > 0, got -1e-10"),
    ("krylov_rtol_zero", "solver: {krylov_rtol: 0.0}\n", "solver.krylov_rtol", "must be > 0, got 0"),
    ("reuse_contraction_one", "solver: {reuse_contraction: 1.0}\n", "solver.reuse_contraction", "must be < 1, got 1"),
    ("one_way_reuse_contraction_zero", "solver: {one_way_reuse_contraction: 0.0}\n", "solver.one_way_reuse_contraction",
     "must be > 0, got 0"),
    ("newton_iterations_huge", "solver: {newton_max_iterations: 1000}\n", "solver.newton_max_iterations",
     "outside the plausible range [1, 200]"),
    ("step_halvings_negative", "solver: {max_step_halvings: -1}\n", "solver.max_step_halvings", "must be >= 0"),
    # ---- YAML syntax
    ("unclosed_flow_mapping", "time: {dt: 0.01\n", "refusal.yaml:2:1",
     "YAML syntax error: while parsing a flow mapping"),
    ("tab_indentation", "time:\n\tdt: 0.01\n", "refusal.yaml:2:1", "found character '\\t' that cannot start any token"),
]
IDS = [c[0] for c in CATALOGUE]


def _overlay(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "refusal.yaml"
    path.write_text(text)
    return path


def _key(key: str, overlay: Path) -> str:
    """The key as the message names it (a file-level error names the overlay's full path)."""
    return str(overlay.parent / key) if key.startswith("refusal.yaml") else key


def test_catalogue_is_large_and_distinct():
    assert len(CATALOGUE) >= 40 and len(set(IDS)) == len(IDS)
    assert len({c[1] for c in CATALOGUE}) == len(CATALOGUE)     # no overlay tested twice under two names


@pytest.mark.parametrize("overlay,key,constraint", [c[1:] for c in CATALOGUE], ids=IDS)
def test_refused_by_validation(tmp_path, overlay, key, constraint):
    path = _overlay(tmp_path, overlay)
    with pytest.raises(ConfigError) as exc:
        load_config_files([DEFAULT, path])
    msg = str(exc.value)
    assert msg.startswith(f"config error: {_key(key, path)}: "), msg
    assert constraint in msg and "\n" not in msg, msg


@pytest.mark.parametrize("overlay,key,constraint", [c[1:] for c in CATALOGUE], ids=IDS)
def test_refused_by_the_command_line(tmp_path, capsys, overlay, key, constraint):
    path = _overlay(tmp_path, overlay)
    assert main(["check", str(DEFAULT), str(path)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1, err
    assert err.startswith(f"config error: {_key(key, path)}: ") and constraint in err, err


@pytest.mark.parametrize("name", ["duplicate_key_block", "decimal_comma_list", "unclosed_flow_mapping",
                                  "design_hole_wider_than_lumen"])
def test_command_line_exits_with_one_line_no_traceback(tmp_path, name):
    _, overlay, key, constraint = CATALOGUE[IDS.index(name)]
    path = _overlay(tmp_path, overlay)
    r = subprocess.run([sys.executable, "-m", "ureterfsi.config", "check", str(DEFAULT), str(path)],
                       capture_output=True, text=True, cwd=REPO, timeout=120)
    assert r.returncode == 2 and r.stdout == "", r
    assert r.stderr.count("\n") == 1 and "Traceback" not in r.stderr, r.stderr
    assert r.stderr.startswith(f"config error: {_key(key, path)}: ") and constraint in r.stderr, r.stderr


def _snakemake(workdir: Path, *args) -> subprocess.CompletedProcess:
    """`snakemake -n` in `workdir` (where the Snakefile's config/config.yaml is absent: the command line's
    --configfile alone is read)."""
    return subprocess.run([sys.executable, "-m", "snakemake", "-n", "--cores", "1", "--snakefile",
                           str(REPO / "Snakefile"), "--directory", str(workdir), *map(str, args)],
                          capture_output=True, text=True, timeout=300)


# the duplicate key: Snakemake's own loader keeps the second value; the stability section: checked before the
# graph is built (it was met first by an input function, with a traceback)
@pytest.mark.parametrize("name", ["duplicate_key_block", "ureter_10_m", "decimal_comma_model_row",
                                  "stability_model_with_stent"])
def test_refused_by_a_dry_run(tmp_path, name):
    _, overlay, key, constraint = CATALOGUE[IDS.index(name)]
    path = _overlay(tmp_path, overlay)
    r = _snakemake(tmp_path, "--configfile", DEFAULT, path)
    assert r.returncode != 0
    assert r.stderr.count("\n") == 1 and r.stderr.startswith(f"config error: {key}: "), r.stderr
    assert constraint in r.stderr, r.stderr
    assert not (tmp_path / "results").exists()


def test_errors_of_snakemakes_own_loader_are_as_the_readme_says(tmp_path):
    """Snakemake reads --configfile before the Snakefile runs (README, Troubleshooting): a YAML syntax error gets
    its message without file or line, which `config check` then names; a missing overlay its FileNotFoundError,
    whose last line names the file; a malformed --config is the workflow's own one line. Nothing is written."""
    bad = _overlay(tmp_path, "time:\n  dt: [0.01\n")
    r = _snakemake(tmp_path, "--configfile", DEFAULT, bad)
    assert r.returncode != 0 and "Config file is not valid JSON or YAML" in r.stdout + r.stderr, r
    check = subprocess.run([sys.executable, "-m", "ureterfsi.config", "check", str(DEFAULT), str(bad)],
                           capture_output=True, text=True, cwd=REPO, timeout=120)
    assert check.returncode == 2 and check.stderr.startswith(f"config error: {bad}:3:"), check.stderr
    r = _snakemake(tmp_path, "--configfile", DEFAULT, tmp_path / "missing.yaml")
    last = (r.stdout + r.stderr).strip().splitlines()[-1]
    assert r.returncode != 0 and last.startswith("FileNotFoundError") and "missing.yaml" in last, r
    r = _snakemake(tmp_path, "--configfile", DEFAULT, "--config", "time={dt")
    assert r.returncode != 0 and r.stderr.count("\n") == 1, r.stderr
    assert r.stderr.startswith("config error: --config time:1:4: YAML syntax error"), r.stderr
    assert not (tmp_path / "results").exists()


def test_config_arguments_are_read_as_yaml():
    # Snakemake's own parser gives {'solver': {'newton_max_iterations': '20'}, 'mesh': {'optimize': 'false'}}
    assert read_config_args(["solver={newton_max_iterations: 20}", "mesh='{optimize: false}'", "time={dt: 0.005}",
                             "time={end: 1.0}"]) == {"solver": {"newton_max_iterations": 20},
                                                     "mesh": {"optimize": False}, "time": {"dt": 0.005, "end": 1.0}}
    for entry, message in [("time={dt: 0,005}", "config error: time.dt: decimal comma in 0,005 (--config time:1)"),
                           ("time={dt: 0.01, dt: 0.02}", "config error: time.dt: key given twice (--config time:1"),
                           ("time={dt: 0.01", "config error: --config time:1:10: YAML syntax error")]:
        with pytest.raises(ConfigError) as exc:
            read_config_args([entry])
        assert str(exc.value).startswith(message), exc.value


def test_nested_config_argument_is_typed_in_a_dry_run(tmp_path):
    r = _snakemake(tmp_path, "--configfile", DEFAULT, "--config", "solver={newton_max_iterations: 20}",
                   "mesh={optimize: false}")
    assert r.returncode == 0 and r.stderr == "", r.stderr       # was: must be of type integer, got str '20'
    assert "rule solve:" in r.stdout


@pytest.mark.parametrize("target,line", [
    ("results/meshes/axisymmetric/model3_coarse.msh",
     "target error: results/meshes/axisymmetric/model3_coarse.msh: model 3 has a stent: the axisymmetric (r-z) "
     "section is only for the stent-free models ['1'] (side holes break rotational symmetry)"),
    ("results/runs/one_way/quarter/model7_coarse.nc",
     "target error: results/meshes/quarter/model7_coarse.msh: model '7' is not one of models ['1', '2', '3', '4']"),
    ("results/datasets/models_ultra.nc",
     "target error: results/meshes/axisymmetric/model1_ultra.msh: level 'ultra' is not one of mesh.levels "
     "['coarse', 'medium', 'fine']"),
])
def test_impossible_target_is_refused_before_any_job(tmp_path, target, line):
    r = _snakemake(tmp_path, target, "--configfile", DEFAULT)
    assert r.returncode == 2 and r.stderr == line + "\n", r.stderr
    assert not (tmp_path / "results").exists()


def test_possible_target_is_planned(tmp_path):
    r = _snakemake(tmp_path, "results/runs/fully_coupled/axisymmetric/model1_coarse.nc", "--configfile", DEFAULT)
    assert r.returncode == 0 and r.stderr == "", r.stderr
    assert "rule mesh:" in r.stdout and "rule solve:" in r.stdout


@pytest.mark.parametrize("model,level,symmetry,reason", [
    ("3", "coarse", "quarter", ""),
    ("1", "fine", "axisymmetric", ""),
    ("2", "medium", "axisymmetric", "model 2 has a stent: the axisymmetric (r-z) section is only for the stent-free "
                                    "models ['1'] (side holes break rotational symmetry)"),
    ("5", "coarse", "full", "model '5' is not one of models ['1', '2', '3', '4']"),
    ("3", "finest", "half", "level 'finest' is not one of mesh.levels ['coarse', 'medium', 'fine']"),
])
def test_unmakeable(cfg, model, level, symmetry, reason):
    assert unmakeable(cfg, model, level, symmetry) == reason


# every shipped configuration, as it is used: config files and overlays (each on the ones before it)
SHIPPED = [
    ["config/config.yaml"],
    ["config/config.yaml", "config/segment-10mm.yaml", "config/quickstart.yaml"],
    ["config/config.yaml", "config/reference.yaml"],
    ["config/config.yaml", "config/ladder-pulse.yaml"],
    ["config/config.yaml", "config/paper-meshes.yaml", "config/reference.yaml"],   # the SLURM profile
    ["config/config.yaml", "config/paper-meshes.yaml", "config/reference.yaml", "config/site-example.yaml"],  # a site
    ["config/config.yaml", "config/designs/hole_diameter_spacing.yaml"],
    ["config/config.yaml", "config/segment-10mm.yaml", "config/designs/stricture.yaml"],
    ["config/config.yaml", "config/segment-10mm.yaml", "config/designs/thin_gap.yaml"],
    ["config/config.yaml", "config/segment-10mm.yaml", "config/designs/arrangement_offset.yaml"],
    ["config/config.yaml", "config/segment-10mm.yaml", "config/designs/obstruction_sobol.yaml"],
    ["config/config.yaml", "config/segment-10mm.yaml", "tests/overlays/e2e.yaml"],
    ["config/config.yaml", "config/occlusion.yaml"],
    ["config/config.yaml", "config/segment-10mm.yaml", "config/occlusion.yaml"],
    ["config/config.yaml", "config/segment-10mm.yaml", "tests/overlays/e2e.yaml", "tests/overlays/ends-mini.yaml"],
    ["config/config.yaml", "config/segment-10mm.yaml", "tests/overlays/ladder-mini.yaml",
     "tests/overlays/ladder-mini-passage.yaml"],
    ["config/config.yaml", "config/designs/occlusion_holes.yaml"],
    ["config/config.yaml", "config/designs/stricture_holes.yaml"],
    ["config/config.yaml", "config/designs/voiding_reflux.yaml"],
    ["config/config.yaml", "config/designs/encrustation.yaml"],
    ["config/config.yaml", "config/segment-10mm.yaml", "tests/overlays/e2e.yaml",
     "tests/overlays/occlusion-holes-mini.yaml"],
]


@pytest.mark.parametrize("files", SHIPPED, ids=[" + ".join(Path(f).stem for f in c) for c in SHIPPED])
def test_shipped_configuration_passes(files):
    for i in range(1, len(files) + 1):
        load_config_files([REPO / f for f in files[:i]])
    assert main(["check", *(str(REPO / f) for f in files)]) == 0


def test_integer_list_without_blanks_is_not_a_decimal_comma(tmp_path):
    cfg = load_config_files([DEFAULT, _overlay(tmp_path, "figures: {wave_times: [1,2]}\n")])
    assert cfg["figures"]["wave_times"] == [1, 2]


def test_every_shipped_file_is_checked(tmp_path):
    shipped = {str(p.relative_to(REPO)) for d in ("config", "config/designs", "tests/overlays")
               for p in (REPO / d).glob("*.yaml")}
    assert shipped == {f for chain in SHIPPED for f in chain}
    from helpers.snakemake_runs import e2e_config    # the e2e run's own merge (models and levels replaced)

    load_config(e2e_config(tmp_path / "e2e.yaml"))
