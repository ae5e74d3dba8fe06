"""Validated configuration: schema layer, consistency checks, CLI and the Snakefile's refusal."""
from __future__ import annotations

import copy
import subprocess
import sys

import pytest
import yaml

from ureterfsi.config import ConfigError, load_config, main, validate_config
from ureterfsi.data.provenance import config_hash

DELETE = object()


def _set(cfg: dict, dotted: str, value) -> None:
    *parents, last = dotted.split(".")
    node = cfg
    for p in parents:
        node = node[p]
    if value is DELETE:
        del node[last]
    else:
        node[last] = copy.deepcopy(value)


MODEL4 = {"label": "x", "stent": True, "hole_pair_spacing": 0.025, "holes": 6}

# (key to change, new value or DELETE, key the message must name, fragment of the constraint)
BAD = [
    # ---- schema: missing, type, range, unknown key, enum
    ("geometry.length", DELETE, "geometry.length", "required key is missing"),
    # ---- fidelity ladder and per-model runs
    ("study.fidelity", "two_way", "study.fidelity", "must be one of"),
    ("study.runs", {"7": {"fidelity": "one_way"}}, "study.runs.7", "must be a key of models"),
    ("study.runs", {"3": {"symmetry": "axisymmetric"}}, "study.runs.3.symmetry", "only valid for a model without stent"),
    ("ladder.reference", "exact", "ladder.reference", "must be one of ladder.rungs"),
    ("ladder.model", "9", "ladder.model", "must be one of models"),
    ("ladder.rungs.one_way.level", "ultra", "ladder.rungs.one_way.level", "must be one of mesh.levels"),
    ("ladder.rungs.one_way.dt", 1.0, "ladder.rungs.one_way.dt", "must be <= ladder.end"),
    ("ladder.rungs.one_way.symmetry", "axisymmetric", "ladder.rungs.one_way.symmetry", "needs a model without stent"),
    ("scenes.fig04_outlet_flow.quantities", ["pressure"], "scenes.fig04_outlet_flow.quantities[0]", "must be one of"),
    ("time", DELETE, "time", "required key is missing"),
    ("geometry.length", "abc", "geometry.length", "must be of type number, got str 'abc'"),
    ("models.2.stent", "yes", "models.2.stent", "must be of type boolean"),
    ("models.2.holes", 22.5, "models.2.holes", "must be an integer, got the float 22.5"),
    ("geometry.ureter_wall_thickness", -0.001, "geometry.ureter_wall_thickness", "must be > 0, got -0.001"),
    ("geometry.stent_inner_diameter", 0.0, "geometry.stent_inner_diameter", "must be > 0, got 0"),
    ("fluid.density", 0.0, "fluid.density", "must be > 0"),
    ("stent.poisson_ratio", 0.5, "stent.poisson_ratio", "must be < 0.5, got 0.5"),
    ("stent.poisson_ratio", -1.0, "stent.poisson_ratio", "must be > -1"),
    ("ureter.design_tolerance", 1.0, "ureter.design_tolerance", "must be < 1"),
    ("ureter.design_tolerance", 0.0, "ureter.design_tolerance", "must be > 0"),
    ("fluid.dynamic_viscosity", float("nan"), "fluid.dynamic_viscosity", "finite"),
    ("fluid.density", "1.0e999", "fluid.density", "finite"),
    ("geometry.lenght", 0.05, "geometry.lenght", "unknown key"),
    ("solvers", {}, "solvers", "unknown key"),
    ("models.x", MODEL4, "models.x", "unknown key"),
    ("mesh.levels.coarse.size_facter", 1.0, "mesh.levels.coarse.size_facter", "unknown key"),
    ("mesh.levels", {}, "mesh.levels", "at least 1"),
    ("time.probe_times", [], "time.probe_times", "at least 1"),
    ("peristalsis.width_measure", "FWHM", "peristalsis.width_measure", "must be one of fwhm, sigma"),
    ("stent.kinematics", "nonlinear", "stent.kinematics", "must be one of"),
    ("time.scheme", "rk4", "time.scheme", "must be one of"),
    ("mesh.symmetry", "octant", "mesh.symmetry", "must be one of"),
    ("solver.mesh_motion", "laplace", "solver.mesh_motion", "must be one of"),
    ("solver.linear_solver", "pardiso", "solver.linear_solver", "must be one of"),
    ("peristalsis.direction", "sideways", "peristalsis.direction", "must be one of"),
    ("solver.newton_max_iterations", 0, "solver.newton_max_iterations", "must be >= 1"),
    ("solver.krylov_rtol", 0.5, "solver.krylov_rtol", "must be <= 0.01"),
    ("solver.mesh_motion_direct_max_unknowns", 10, "solver.mesh_motion_direct_max_unknowns", "must be >= 1000"),
    ("study.memory_mb.one_way.fine", 50, "study.memory_mb.one_way.fine", "must be >= 100"),
    ("study.memory_mb.one_way", {}, "study.memory_mb.one_way", "at least 1"),
    ("study.memory_mb.fully_coupled", "lots", "study.memory_mb.fully_coupled", "must be of type object"),
    ("study.memory_mb.symmetry_factor.full", 0, "study.memory_mb.symmetry_factor.full", "must be > 0"),
    ("study.memory_headroom_mb", -1, "study.memory_headroom_mb", "must be >= 0"),
    ("solver.predictor", "cubic", "solver.predictor", "must be one of quadratic, linear, constant"),
    ("solver.one_way_mesh_motion", "harmonic", "solver.one_way_mesh_motion", "must be one of algebraic, extension"),
    ("scenes.fig04_outlet_flow.measured_error", -0.1, "scenes.fig04_outlet_flow.measured_error", "must be >= 0"),
    # ---- geometry
    ("geometry.ureter_wall_thickness", 0.005, "geometry.ureter_wall_thickness", "ureter outer radius"),
    ("geometry.hole_diameter", 0.0025, "geometry.hole_diameter", "stent outer diameter"),
    ("geometry.hole_diameter", 0.0012, "geometry.hole_diameter", "stent inner diameter"),
    ("geometry.stent_wall_thickness", 0.003, "geometry.stent_wall_thickness", "fluid gap"),
    ("geometry.hole_end_clearance", 0.0002, "geometry.hole_end_clearance", "wholly inside the stent"),
    ("geometry.hole_end_clearance", 0.0249, "geometry.hole_end_clearance", "clipped to [c, L - c]"),
    # ---- models (Table 1)
    ("models.6", MODEL4, "models", "without gaps"),
    ("models.1.holes", 2, "models.1.holes", "without a stent"),
    ("models.1.hole_pair_spacing", 0.005, "models.1.hole_pair_spacing", "without a stent"),
    ("models.1.stent", True, "models.1.hole_pair_spacing", "must be > 0 for a stented model"),
    ("models.2.holes", 21, "models.2.holes", "even"),
    ("models.2.holes", 20, "models.2.holes", "n pairs at spacing s span the segment end to end"),
    ("models.4.hole_pair_spacing", 0.015, "models.4.holes", "floor(L/s) + 1 = 4 pairs"),
    # 1.5 mm spacing, count consistent (34 pairs), but the clipped first pairs 1.25/1.5 mm overlap
    ("models.2", {"label": "x", "stent": True, "hole_pair_spacing": 0.0015, "holes": 68},
     "models.2.hole_pair_spacing", "overlap"),
    # ---- time
    ("time.dt", 3.0, "time.dt", "< time.end"),
    ("time.dt", 0.6, "time.dt", "smallest spacing of the probe times"),
    ("time.probe_times", [0.5, 3.5], "time.probe_times[1]", "(0, time.end = 3]"),
    ("time.probe_times", [0.0, 1.0], "time.probe_times[0]", "(0, time.end"),
    ("time.probe_times", [1.0, 0.5], "time.probe_times[1]", "strictly increasing"),
    ("peristalsis.ramp_time", 3.0, "peristalsis.ramp_time", "< time.end"),
    # ---- mesh
    ("mesh.levels.fine.size_factor", 0.8, "mesh.levels.fine.size_factor", "coarse to fine"),
    ("mesh.sizes.stent_wall", 1.0e-4, "mesh.sizes.stent_wall", ">= mesh.sizes.hole"),
    ("mesh.sizes.fluid_bulk", 4.0e-4, "mesh.sizes.fluid_bulk", ">= mesh.sizes.ureter_wall"),
    ("mesh.sizes.hole", 2.0e-4, "mesh.sizes.hole", "need >= 4"),
    ("mesh.sizes.stent_wall", 3.0e-4, "mesh.sizes.stent_wall", "need >= 2"),
    ("mesh.sizes.ureter_wall", 6.0e-4, "mesh.sizes.ureter_wall", "need >= 2"),
    ("mesh.levels.coarse.size_factor", 1.2, "mesh.sizes.hole", "level 'coarse'"),
    ("mesh.symmetry", "axisymmetric", "mesh.symmetry", "stented models: 2, 3, 4"),
    # ---- peristalsis and material
    ("peristalsis.start_position", -0.05, "peristalsis.start_position", "[-3 widths, L]"),
    ("peristalsis.start_position", 0.06, "peristalsis.start_position", "got 0.06"),
    ("ureter.bulk_modulus", 5.0e5, "ureter.bulk_modulus", "near-incompressibility"),
    ("ureter.c10", -3.0e4, "ureter.c10", "2(c10 + c01) must be > 0"),
    # ---- study and figures
    ("study.level", "finest", "study.level", "must be one of mesh.levels"),
    ("study.convergence_model", "7", "study.convergence_model", "must be one of models"),
    ("study.convergence_time", 1.25, "study.convergence_time", "time.probe_times"),
    ("figures.formats", ["jpg"], "figures.formats[0]", "jpg"),
    ("figures.dpi", 10, "figures.dpi", "10"),
    ("figures.wave_times", [0.5, 0.75], "figures.wave_times[1]", "must be one of time.probe_times"),
    ("figures.hole_velocity_times", [0.5, 1.0, 2.0, 3.0], "figures.hole_velocity_times[3]", "time.probe_times"),
    ("figures.hole_velocity_times", [0.5, 1.0, 2.0], "figures.hole_velocity_times", "at least 4"),
    ("figures.domain_model", "9", "figures.domain_model", "must be one of models"),
]


def test_default_config_validates(cfg, repo_root):
    validate_config(cfg)
    raw = yaml.safe_load((repo_root / "config" / "config.yaml").read_text())
    validate_config(raw)  # as Snakemake hands it over (PyYAML: '5.0e4' is a string)
    assert raw == cfg
    assert isinstance(cfg["peristalsis"]["peak_traction"], float) and cfg["peristalsis"]["peak_traction"] == 5.0e4
    assert cfg["ureter"]["bulk_modulus"] == 1.0e9


@pytest.mark.parametrize("dotted,value,key,fragment", BAD, ids=[f"{b[0]}={b[1]!r}"[:60] for b in BAD])
def test_bad_config_is_refused(cfg, dotted, value, key, fragment):
    _set(cfg, dotted, value)
    with pytest.raises(ConfigError) as exc:
        validate_config(cfg)
    msg = str(exc.value)
    assert msg.startswith(f"config error: {key}: "), msg
    assert fragment in msg, msg
    assert "\n" not in msg


def test_non_string_key_is_refused(cfg):
    cfg["models"][5] = MODEL4
    with pytest.raises(ConfigError, match=r"^config error: models\.5: keys must be strings"):
        validate_config(cfg)


def test_first_error_is_deterministic(cfg):
    _set(cfg, "time.dt", "x")
    _set(cfg, "fluid.density", -1.0)
    _set(cfg, "geometry.zzz", 1.0)
    with pytest.raises(ConfigError, match=r"^config error: fluid\.density: must be > 0"):
        validate_config(cfg)


def test_stent_free_study_refused_at_convergence_model(cfg):
    """A study of stent-free models only (study-wide r-z) cannot draw Fig. 3 (the stent's stress): refused before
    any solve, naming the key, not after the solves in the figure rule."""
    stented = cfg["models"]["2"]
    cfg["models"] = {"1": cfg["models"]["1"]}
    cfg["mesh"]["symmetry"] = "axisymmetric"
    cfg["study"]["convergence_model"] = "1"
    cfg["ladder"]["model"] = "1"
    for rung in cfg["ladder"]["rungs"].values():
        rung["symmetry"] = "axisymmetric"
    del cfg["stability"]["axes"]["hole_elements"]
    with pytest.raises(ConfigError, match=r"^config error: study\.convergence_model: model '1' has no stent: "):
        validate_config(copy.deepcopy(cfg))
    cfg["models"]["2"] = stented
    cfg["study"]["convergence_model"] = "2"
    with pytest.raises(ConfigError, match=r"^config error: mesh\.symmetry: 'axisymmetric' is study-wide"):
        validate_config(copy.deepcopy(cfg))    # the stented model needs a 3D section
    cfg["mesh"]["symmetry"] = "quarter"
    cfg["study"]["runs"] = {"1": {"symmetry": "axisymmetric", "fidelity": "fully_coupled"}}
    validate_config(cfg)


def test_defaults_filled_and_overrides_merged(cfg):
    del cfg["solver"]["linear_solver"], cfg["mesh"]["optimize"]
    out = load_config(cfg, overrides={"time": {"dt": 0.005}, "models": {"4": {"label": "25"}}})
    assert out["solver"]["linear_solver"] == "mumps" and out["mesh"]["optimize"] is True
    assert out["time"]["dt"] == 0.005 and out["time"]["end"] == 3.0
    assert out["models"]["4"] == {**cfg["models"]["4"], "label": "25"}
    assert "linear_solver" not in cfg["solver"]  # the input dict is not modified
    with pytest.raises(ConfigError, match=r"^config error: time\.dt: "):
        load_config(cfg, overrides={"time": {"dt": -1.0}})


def test_cli(tmp_path, repo_root, capsys):
    assert main(["check", str(repo_root / "config" / "config.yaml")]) == 0
    assert capsys.readouterr().out.strip() == f"config ok: {config_hash(load_config())}"
    overlay = tmp_path / "overlay.yaml"
    overlay.write_text("geometry: {hole_diameter: 2.5e-3}\n")
    r = subprocess.run([sys.executable, "-m", "ureterfsi.config", "check",
                        str(repo_root / "config" / "config.yaml"), str(overlay)],
                       capture_output=True, text=True, cwd=repo_root)
    assert r.returncode == 2 and r.stdout == ""
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("config error: geometry.hole_diameter: "), r.stderr
    assert main(["check", str(tmp_path / "missing.yaml")]) == 2


def test_snakemake_refuses_bad_config(tmp_path, repo_root, cfg):
    # With --directory the Snakefile's `configfile: "config/config.yaml"` resolves inside tmp_path, where it
    # does not exist; Snakemake then uses the --configfile alone (a complete config with one bad value).
    cfg["geometry"]["hole_diameter"] = 0.0025
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(cfg))
    r = subprocess.run([sys.executable, "-m", "snakemake", "-n", "--cores", "1",
                        "--snakefile", str(repo_root / "Snakefile"), "--directory", str(tmp_path),
                        "--configfile", str(bad)], capture_output=True, text=True, timeout=120)
    assert r.returncode != 0
    assert "config error: geometry.hole_diameter:" in r.stderr, r.stderr
    assert not (tmp_path / "results").exists()


def test_paper_mesh_overlay_validates_with_explicit_minima(repo_root):
    from ureterfsi.config import load_config_files

    cfg = load_config_files([repo_root / "config/config.yaml", repo_root / "config/paper-meshes.yaml"])
    assert cfg["mesh"]["symmetry"] == "full"
    assert cfg["mesh"]["resolution_minima"]["hole"] < 4
