"""The workflow end to end (Snakefile, every rule): one small run of the whole DAG, then its contracts.

Configuration: config/config.yaml + config/segment-10mm.yaml (10 mm segment) + tests/overlays/e2e.yaml (two
steps of 20 ms, one mesh level `coarse`, models "1" (no stent) and "2" (10 mm between hole pairs)). The
overlays are merged here into one file handed to Snakemake, with e2e.yaml's `models` and `mesh.levels`
replacing the inherited ones: Snakemake deep-merges --configfile overlays, so an overlay cannot drop a model
or a mesh level (see the header of tests/overlays/e2e.yaml).

One module-scoped run (`e2e`), then: the run and study datasets, figures, Table 1, logs and benchmarks;
a forced figure re-runs alone; a plotting option re-runs only the figure rules; the HTML report holds every
figure, renders in headless Chromium and its figure pages click through; the SLURM profile plans the jobs; a
killed solve resumes from its checkpoint (slow); the solve rule under MPI (2 ranks) matches the serial run (mpi).
"""
from __future__ import annotations

import base64
import io
import json
import os
import re
import shutil
import signal
import subprocess
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import xarray as xr

from helpers.browser import Browser
from helpers.snakemake_runs import REPO, SLURM_PROFILE, e2e_config, job_counts, ok, planned_jobs, snakemake

# as root, Open MPI refuses to start without these; more ranks than cores on a 2-core machine
MPI_LAUNCHER = "mpiexec --allow-run-as-root --oversubscribe"

FIGURES = ["fig02_domain", "fig03_mesh_convergence", "fig04_outlet_flow", "fig05_wall_displacement",
           "fig06_hole_velocity", "fig07_hole_velocity", "fig08_hole_velocity", "fig09_hole_velocity",
           "fig10_stent_von_mises", "fig11_hole_flux", "field_hole_flow", "field_stent_wss", "field_pressure"]
FIGURE_RULES = set(FIGURES) | {"table1", "all_figures", "all_field_figures", "all"}
HEAVY_RULES = ("mesh", "solve")
SERIES = ("outlet_flux", "inlet_flux", "outlet_mean_axial_velocity", "fluid_volume", "max_wall_displacement",
          "pulse_centre")
STENT_SERIES = ("stent_max_von_mises", "stent_max_von_mises_x", "stent_max_von_mises_y", "stent_max_von_mises_z")
STEP_VARS = ("step_time", "step_dt", "newton_iterations", "newton_residual", "min_ale_jacobian", "step_wall_time")


@pytest.fixture(scope="module")
def e2e(tmp_path_factory):
    work = tmp_path_factory.mktemp("e2e")
    cfg_path = work / "e2e-config.yaml"
    cfg = e2e_config(cfg_path)
    t0 = time.perf_counter()
    run = snakemake(work, cfg_path, "--cores", "2")
    wall = time.perf_counter() - t0
    log = ok(run)
    print(f"\ne2e workflow run: {wall:.1f} s")
    level = cfg["study"]["level"]
    models = sorted(cfg["models"], key=int)
    stented = [m for m in models if cfg["models"][m]["stent"]]
    runs = cfg["study"]["runs"]
    sym = {m: runs.get(m, {}).get("symmetry", cfg["mesh"]["symmetry"]) for m in models}
    fid = {m: runs.get(m, {}).get("fidelity", cfg["study"]["fidelity"]) for m in models}
    stem = {m: f"{fid[m]}/{sym[m]}/model{m}_{level}" for m in models}      # run, log, checkpoint paths
    run_file = lambda m: work / f"results/runs/{stem[m]}.nc"   # noqa: E731
    # the uninterrupted 1-process run of the stented model, kept aside: the solve-again tests replace it
    reference = tmp_path_factory.mktemp("e2e-reference") / "serial.nc"
    shutil.copy2(run_file(stented[0]), reference)
    return SimpleNamespace(dir=work, cfg=cfg, cfg_path=cfg_path, log=log, wall=wall, symmetry=sym, level=level,
                           stem=stem,
                           models=models, stented=stented, run_file=run_file, reference=reference)


def test_every_rule_ran(e2e):
    counts = job_counts(e2e.log)
    n = len(e2e.models)
    assert counts.get("mesh") == n and counts.get("solve") == n, counts
    assert {"aggregate_models", "aggregate_convergence", "table1", *FIGURES} <= set(counts), counts


def test_run_datasets(e2e):
    import netCDF4 as nc4   # noqa: F401
    from ureterfsi.data.cf import VARIABLES as CF

    cfg = e2e.cfg
    for m in e2e.models:
        with xr.open_dataset(e2e.run_file(m), decode_times=False) as ds:
            ds.load()
        stented = cfg["models"][m]["stent"]
        assert ds.attrs["model"] == m and ds.attrs["mesh_level"] == e2e.level and ds.attrs["symmetry"] == e2e.symmetry[m]
        assert ds.attrs["Conventions"] == "CF-1.8"
        np.testing.assert_allclose(ds["time"], [0.0, 0.02, 0.04], atol=1e-12)
        np.testing.assert_allclose(ds["probe_time"], cfg["time"]["probe_times"], atol=1e-12)
        for v in SERIES + (STENT_SERIES if stented else ()):
            assert ds[v].dims == ("time",), v
            assert np.isfinite(ds[v]).all(), v
        for v in STEP_VARS:
            assert ds[v].dims == ("step",) and ds.sizes["step"] == 2, v
        assert ds["wall_radial_displacement"].dims == ("probe_time", "z")
        if stented:
            assert ds["stent_von_mises_line"].dims == ("probe_time", "z")
            assert ds["hole_velocity_y"].dims == ("probe_time", "hole_offset")
            assert ds["hole_flux"].dims == ("hole", "time")       # CF §2.4: time right of the other dimensions
            assert ds.sizes["hole"] == cfg["models"][m]["holes"] // 2     # quarter model: one side of each pair
            assert (ds["stent_max_von_mises"].values[1:] > 0).all()
        else:
            assert not {"stent_max_von_mises", "hole_flux", "hole_velocity_y"} & set(ds.variables)
        for name, var in ds.variables.items():
            assert var.attrs.get("units") == CF[name][0], (name, var.attrs)
            assert var.attrs.get("long_name"), name
        assert np.abs(ds["outlet_flux"]).max() > 0 and ds["max_wall_displacement"].values[-1] > 0


def test_field_file_of_the_coupled_run(e2e):
    """The fully coupled run's field file (part `domain`, the whole mesh): the pressure is finite on every
    urine vertex, the interface included, and the velocity the hole-flow figure samples on the run's probe
    line across the outlet-most hole agrees with the run's hole_velocity_y to the P1 output's interpolation
    error (< 10 % of the peak)."""
    from ureterfsi.mesh.geometry import UreterGeometry
    from ureterfsi.data.fieldfiles import hole_flow_section, urine_cells, urine_fields

    m = e2e.stented[0]
    with xr.open_dataset(e2e.run_file(m), decode_times=False) as ds:
        ds.load()
    fs = urine_fields(e2e.run_file(m).parent / ds.attrs["fields_path"])
    assert fs.directory.name == f"model{m}_{e2e.level}" and (fs.directory / "domain.xdmf").exists()
    urine = np.unique(fs.cells[urine_cells(fs)])
    for t in fs.times:
        assert np.isfinite(fs.values("pressure", t)[urine]).all()
    g = UreterGeometry.from_config(e2e.cfg)
    zh, s = float(ds["hole_z"].max()), ds["hole_offset"].values
    sec = hole_flow_section(fs, [float(t) for t in ds["probe_time"].values], zh, g, y=[g.probe_radius], z=zh + s)
    field, probe = np.array([v[0, :, 1] for v in sec.values]), ds["hole_velocity_y"].values
    both = np.isfinite(field) & np.isfinite(probe)
    assert both.sum() >= 0.8 * probe.size
    assert np.abs(field - probe)[both].max() < 0.1 * np.abs(probe[both]).max()


def test_study_datasets(e2e):
    with xr.open_dataset(e2e.dir / f"results/datasets/models_{e2e.level}.nc", decode_times=False) as ds:
        assert "model" in ds.dims and list(ds["model"].values.astype(str)) == e2e.models
        assert list(ds["model_label"].values.astype(str)) == [e2e.cfg["models"][m]["label"] for m in e2e.models]
        assert ds["outlet_flux"].dims[0] == "model" and "time" in ds["outlet_flux"].dims
    with xr.open_dataset(e2e.dir / "results/datasets/mesh_convergence.nc", decode_times=False) as ds:
        assert "level" in ds.dims and list(ds["level"].values.astype(str)) == [e2e.level]
        assert "stent_von_mises_line" in ds and "level" in ds["stent_von_mises_line"].dims


def test_figures_and_table(e2e):
    for stem in FIGURES:
        for ext in e2e.cfg["figures"]["formats"]:
            p = e2e.dir / f"results/figures/{stem}.{ext}"
            assert p.exists() and p.stat().st_size > 0, p
    for ext in ("csv", "md"):
        p = e2e.dir / f"results/figures/table1.{ext}"
        assert p.exists() and p.stat().st_size > 0
    assert "10 mm" in (e2e.dir / "results/figures/table1.md").read_text()


def test_logs_and_benchmarks(e2e):
    for rule in HEAVY_RULES:
        for m in e2e.models:
            stem = e2e.stem[m] if rule == "solve" else f"{e2e.symmetry[m]}/model{m}_{e2e.level}"
            log = e2e.dir / f"results/logs/{rule}/{stem}.log"
            bench = e2e.dir / f"results/benchmarks/{rule}/{stem}.tsv"
            assert log.stat().st_size > 0, log
            header = bench.read_text().splitlines()[0].split("\t")
            assert header[:2] == ["s", "h:m:s"] and "max_rss" in header, bench
    solve_log = (e2e.dir / f"results/logs/solve/{e2e.stem['2']}.log").read_text()
    assert "done in" in solve_log and "checkpoint: step 1" in solve_log
    for stem in FIGURES + ["table1"]:
        assert (e2e.dir / f"results/logs/figures/{stem}.log").exists(), stem
    for name in ("models_coarse", "mesh_convergence"):
        assert (e2e.dir / f"results/logs/aggregate/{name}.log").exists()
    if (REPO / "workflow/rules/calibration.smk").exists():
        assert (e2e.dir / "results/logs/calibration/wall_calibration.log").exists()
        assert (e2e.dir / "results/benchmarks/calibration/wall_calibration.tsv").exists()
    assert not list((e2e.dir / "results").rglob("*.npz")), "checkpoints are removed after a finished run"


def _mtimes(root: Path) -> dict[str, int]:
    return {str(p.relative_to(root)): p.stat().st_mtime_ns for p in (root / "results").rglob("*") if p.is_file()}


def test_forcerun_regenerates_only_that_figure(e2e):
    dry = ok(snakemake(e2e.dir, e2e.cfg_path, "--cores", "2", "-n", "--forcerun", "fig04_outlet_flow"))
    assert set(job_counts(dry)) <= {"fig04_outlet_flow", "all"} and job_counts(dry)["fig04_outlet_flow"] == 1, dry
    before = _mtimes(e2e.dir)
    time.sleep(0.05)
    ok(snakemake(e2e.dir, e2e.cfg_path, "--cores", "2", "--forcerun", "fig04_outlet_flow"))
    after = _mtimes(e2e.dir)
    changed = {p for p in after if after[p] != before.get(p)}
    assert changed == {"results/figures/fig04_outlet_flow.png", "results/figures/fig04_outlet_flow.pdf",
                       "results/logs/figures/fig04_outlet_flow.log"}, changed


def test_nothing_to_do_after_a_complete_run(e2e):
    dry = ok(snakemake(e2e.dir, e2e.cfg_path, "--cores", "2", "-n"))
    assert job_counts(dry) == {}, dry


def test_plotting_option_reruns_only_figure_rules(e2e, tmp_path):
    dpi_cfg = tmp_path / "dpi.yaml"
    e2e_config(dpi_cfg, dpi=e2e.cfg["figures"]["dpi"] + 1)
    dry = ok(snakemake(e2e.dir, dpi_cfg, "--cores", "2", "-n"))
    counts = job_counts(dry)
    assert set(counts) <= FIGURE_RULES, counts
    assert set(FIGURES) <= set(counts), counts          # every figure carries the plotting options
    assert not {"mesh", "solve", "aggregate_models", "aggregate_convergence"} & set(counts)
    assert "params" in dry.lower()
    summary = ok(snakemake(e2e.dir, dpi_cfg, "--cores", "2", "--summary"))
    for line in summary.splitlines():
        if "/runs/" in line or "/meshes/" in line:
            assert "update pending" not in line and "params changed" not in line.lower(), line


@pytest.fixture(scope="module")
def report(e2e) -> Path:
    """The HTML report of the e2e run (snakemake --report)."""
    path = e2e.dir / "report.html"
    ok(snakemake(e2e.dir, e2e.cfg_path, "--report", str(path)))
    return path


def test_report_holds_every_figure(report):
    html = report.read_text(errors="replace")
    assert html.lstrip().lower().startswith("<!doctype html") or "<html" in html[:2000].lower()
    for stem in FIGURES:
        assert f"{stem}.png" in html, stem
    assert "table1.md" in html
    # captions are Jinja-rendered with the figure instants of the configuration
    assert "t = 0.04 s" in html and "snakemake.params" not in html
    # the landing text (workflow/report/workflow.rst), rendered with the configuration
    assert "fluid-structure interaction of a stented ureter" in html and "snakemake.config" not in html


# Debian's chromium, headless, with nothing that reaches the network (.ci/run installs it)
CHROMIUM_FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync")
REPORT_HEADING = "ureterfsi: fluid-structure interaction of a stented ureter"    # workflow/report/workflow.rst
REPORT_CATEGORIES = ("Paper figures", "Fields")     # of the e2e run's report() outputs (one mesh level: no GCI)


def chromium_exe() -> str:
    """Debian's chromium; missing, the test fails under CI and is skipped elsewhere."""
    exe = shutil.which("chromium")
    if exe is None:
        if os.environ.get("CI"):
            pytest.fail("chromium is not installed: .ci/run installs Debian's chromium for this test")
        pytest.skip("no chromium to render the report in (Debian: apt-get install chromium)")
    return exe


def chromium(page: Path, profile: Path, *args: str) -> str:
    """Headless Chromium on the file `page` with a new empty profile directory, its scripts given 30 s of
    virtual time; its standard output."""
    run = subprocess.run([chromium_exe(), *CHROMIUM_FLAGS, "--virtual-time-budget=30000",
                          f"--user-data-dir={profile}", *args, page.resolve().as_uri()],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    return run.stdout


def visible_text(dom: str) -> str:
    """The text of a DOM dump without its scripts and styles (the report embeds its data in scripts)."""
    dom = re.sub(r"<(script|style)\b.*?</\1>", " ", dom, flags=re.S | re.I)
    return re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", dom))


def test_report_renders_in_a_browser(report, tmp_path):
    """The report as a browser shows it: the landing page holds the workflow text (its title) and the menu
    the result categories, and its picture is not blank (the content right of the menu has contrast)."""
    from matplotlib.image import imread

    text = visible_text(chromium(report, tmp_path / "dom-profile", "--dump-dom"))
    assert REPORT_HEADING in text and "How to read it" in text, text[:3000]
    for category in REPORT_CATEGORIES:
        assert category in text, (category, text[:3000])
    png = tmp_path / "landing.png"
    chromium(report, tmp_path / "png-profile", f"--screenshot={png}", "--window-size=1400,2000")
    grey = imread(png)[..., :3].mean(axis=2)
    content = grey[:, 400:]                         # right of the navigation bar
    assert grey.shape == (2000, 1400) and content.std() > 0.05 and (content < 0.5).mean() > 0.002, (
        content.std(), (content < 0.5).mean())


def caption_opening(entry: str) -> str:
    """The opening words of the caption of the report entry `entry` (results/figures/<stem>.<ext>, caption
    workflow/report/<stem>.rst): its first line up to the first Jinja expression, without the rst emphasis."""
    first_line = (REPO / "workflow" / "report" / f"{Path(entry).stem}.rst").read_text().splitlines()[0]
    return re.split(r"\{[{%]", first_line)[0].replace("**", "").strip()


def js(value) -> str:
    """`value` as a JavaScript literal."""
    return json.dumps(value)


def nav_link(text: str) -> str:
    """JavaScript finding the link of the report's navigation bar (menu or breadcrumbs) showing `text`."""
    return f"[...document.querySelectorAll('nav a')].find(a => a.textContent.trim() === {js(text)})"


def entry_button(entry: str, index: int) -> str:
    """JavaScript finding a button of the row of `entry` in a category's table: 0 view (eye), 1 information."""
    return (f"[...document.querySelectorAll('nav tbody tr')].find(tr => tr.cells[0].textContent === {js(entry)})"
            f"?.cells[1].querySelectorAll('a')[{index}]")


# the picture of the content pane showing `entry`: its decoded size and its region within the viewport
SHOWN_IMAGE = """(() => {{
  const img = [...document.querySelectorAll('img')].find(i => !i.closest('nav') && i.src === results[{0}].data_uri);
  if (!img || !img.complete || !img.naturalWidth) return null;
  const r = img.getBoundingClientRect(), x = Math.max(r.x, 0), y = Math.max(r.y, 0);
  return {{size: [img.naturalWidth, img.naturalHeight], clip: {{x, y,
           width: Math.min(r.right, innerWidth) - x, height: Math.min(r.bottom, innerHeight) - y}}}};
}})()"""
# the caption of the information page of an entry (its "Description")
SHOWN_CAPTION = """(() => {
  const heading = [...document.querySelectorAll('nav li')].find(li => li.textContent === 'Description');
  return heading && heading.nextElementSibling.innerText;
})()"""


def test_report_figure_pages_in_a_browser(report, tmp_path):
    """Every result category and every entry of the report, clicked through in headless Chromium (DevTools
    protocol, tests/helpers/browser.py) as a reader would: the category in the menu, then for each entry of its table
    the eye button (a figure shows in the content pane: the PNG decoded at its own size and its picture not
    blank; a table is a download link holding the file), the information button (the entry's caption), and
    back to the category by the breadcrumb. Every figure and Table 1 are among the entries visited."""
    from matplotlib.image import imread
    from PIL import Image

    visited = {}
    with Browser(chromium_exe(), CHROMIUM_FLAGS, tmp_path / "profile") as browser:
        browser.open(report.resolve().as_uri(), nav_link("Workflow"))
        categories = browser.evaluate(
            "Object.fromEntries(Object.entries(categories).map(([c, s]) => [c, Object.keys(s)]))")
        assert set(categories) == set(REPORT_CATEGORIES), categories
        for category, subcategories in sorted(categories.items()):
            assert len(subcategories) == 1, (category, subcategories)   # the menu opens its only table
            browser.click(nav_link(category), f"category {category!r} in the menu")
            entries = browser.evaluate(f"categories[{js(category)}][{js(subcategories[0])}]")
            visited[category] = entries
            for entry in sorted(entries):
                where = f"{category} -> {entry}"
                kind = browser.evaluate(f"getResultMimeType({js(entry)})")
                if kind == "image/png":
                    browser.click(entry_button(entry, 0), f"the view button of {where}")
                    shown = browser.wait_for(SHOWN_IMAGE.format(js(entry)), f"the figure of {where}")
                    assert shown["size"] == list(Image.open(report.parent / entry).size), where
                    grey = imread(io.BytesIO(browser.screenshot(shown["clip"])))[..., :3].mean(axis=2)
                    assert grey.size > 10_000 and grey.std() > 0.05 and (grey < 0.5).mean() > 0.002, where
                else:
                    link = browser.evaluate(f"{entry_button(entry, 0)}.href")
                    header, payload = link.split(",", 1)
                    assert header.startswith("data:") and header.endswith(";base64"), where
                    assert base64.b64decode(payload) == (report.parent / entry).read_bytes(), where
                browser.click(entry_button(entry, 1), f"the information button of {where}")
                caption = browser.wait_for(SHOWN_CAPTION, f"the caption of {where}")
                assert caption_opening(entry) in " ".join(caption.split()), (where, caption[:300])
                browser.click(nav_link(category), f"the breadcrumb back to {category!r} from {entry}")
            browser.click(nav_link("Results"), f"the breadcrumb back to the menu from {category!r}")
    print("report pages visited:", visited)
    seen = {entry for entries in visited.values() for entry in entries}
    assert {f"results/figures/{stem}.png" for stem in FIGURES} | {"results/figures/table1.md"} <= seen, seen


def test_slurm_profile_plans_the_jobs(tmp_path):
    """Dry run with the SLURM workflow profile (executor slurm): the plugin does not call sbatch/sinfo in a
    dry run. The profile's configfiles (config/config.yaml + overlays, relative to the working directory) are
    replaced by the command line's --configfile. A fully coupled 3D solve is an MPI job (tasks > 1, mpi=srun,
    its command launching the ranks with srun); the r-z solve of model 1 is serial (one task, no mpi resource);
    memory is mem_mb only, and the solve's command shows in the plan."""
    cfg_path = tmp_path / "e2e-config.yaml"
    cfg = e2e_config(cfg_path)
    work = tmp_path / "slurm"
    work.mkdir()
    out = ok(snakemake(work, cfg_path, "-n", "--forceall", profile=SLURM_PROFILE))
    counts = job_counts(out)
    n = len(cfg["models"])
    assert counts.get("mesh") == n and counts.get("solve") == n and set(FIGURES) <= set(counts), out
    jobs = planned_jobs(out)
    solves = {Path(j["output"]).stem: j for j in jobs if j["rule"] == "solve"}
    level = cfg["study"]["level"]
    mpi, serial = solves[f"model2_{level}"], solves[f"model1_{level}"]
    assert "/fully_coupled/quarter/" in mpi["output"] and "/axisymmetric/" in serial["output"]
    tasks = int(mpi["resources"]["tasks"])
    assert tasks > 1 and mpi["resources"]["mpi"] == "srun", mpi
    assert re.search(rf"^srun -n {tasks} \S*python\S* -m ureterfsi\.study ", mpi["shell"]), mpi
    assert serial["resources"]["tasks"] == "1" and "mpi" not in serial["resources"], serial
    assert "srun" not in serial["shell"] and " -m ureterfsi.study " in serial["shell"], serial
    for name, j in ((f"model2_{level}", mpi), (f"model1_{level}", serial)):
        fidelity = Path(j["output"]).parts[-3]
        assert f"--run-config results/configs/{fidelity}/{name.split('_')[0]}.json" in j["shell"], j
    assert [j["rule"] for j in jobs if "mpi" in j["resources"]] == ["solve"], "only the 3D fully coupled solve"
    assert all("mem_mb_per_cpu" not in j["resources"] for j in jobs)
    assert all("mem_mb" in j["resources"] for j in jobs if j["rule"] in ("solve", "mesh", "wall_motion"))


def _solve_again(e2e, model, *args, **popen):
    target = f"results/runs/{e2e.stem[model]}.nc"
    # the target first: --forcerun and --set-resources take several values and would swallow it
    return snakemake(e2e.dir, e2e.cfg_path, target, "--cores", "2", "--forcerun", "solve", *args, **popen)


@pytest.mark.slow
def test_killed_solve_resumes_from_checkpoint(e2e):
    m = e2e.stented[0]
    run_file = e2e.run_file(m)
    reference = xr.load_dataset(e2e.reference, decode_times=False)     # the uninterrupted run of the module fixture
    ckpt_dir = (e2e.dir / f"results/checkpoints/{e2e.stem[m]}").parent
    proc = _solve_again(e2e, m, start_new_session=True)
    t0 = time.perf_counter()
    try:
        while not (ckpt_dir.exists() and list(ckpt_dir.glob(f"model{m}_{e2e.level}*.npz"))):
            assert proc.poll() is None, f"snakemake ended before the first checkpoint:\n{proc.stdout.read()[-3000:]}"
            assert time.perf_counter() - t0 < 600
            time.sleep(0.1)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)        # snakemake, the job shell and the solver
        proc.wait()
    assert not run_file.exists()
    log_path = e2e.dir / f"results/logs/solve/{e2e.stem[m]}.log"
    first_log = log_path.read_text()
    assert "checkpoint: step 1" in first_log and "done in" not in first_log

    # a SIGKILLed Snakemake leaves its lock behind (and the output marked incomplete): unlock, then run again
    ok(snakemake(e2e.dir, e2e.cfg_path, "--unlock"))
    ok(snakemake(e2e.dir, e2e.cfg_path, "--cores", "2", "--rerun-incomplete",
                 f"results/runs/{e2e.stem[m]}.nc"))
    log = log_path.read_text()
    assert "resumed from checkpoint: step 1" in log and "done in" in log, log[-2000:]
    assert "initial state" not in log          # no fresh start
    resumed = xr.load_dataset(run_file, decode_times=False)
    # The integrator drops the cached factorisation at every checkpoint, so the resumed run repeats the
    # uninterrupted run's arithmetic: identical results (wall times aside).
    for name, var in reference.data_vars.items():
        if name == "step_wall_time":
            continue
        np.testing.assert_allclose(resumed[name].values, var.values, rtol=1e-12, atol=0, err_msg=name)
    assert not list(ckpt_dir.glob("*.npz"))


@pytest.mark.mpi
@pytest.mark.slow          # a third solve of the stented model (~1-2 min on a loaded 2-core machine)
def test_solve_rule_under_mpi_matches_serial(e2e):
    assert shutil.which("mpiexec"), "mpiexec missing: workflow/setup.sh installs mpi-default-bin"
    m = e2e.stented[0]
    run_file = e2e.run_file(m)
    serial = xr.load_dataset(e2e.reference, decode_times=False)
    # --set-resources, not --default-resources: the solve rule sets resources.mpi itself, and a rule's own
    # resources take precedence over the defaults
    ok(_solve_again(e2e, m, "--set-resources", "solve:tasks=2", f"solve:mpi='{MPI_LAUNCHER}'"))
    par = xr.load_dataset(run_file, decode_times=False)
    assert par.attrs["processes"] == 2 and serial.attrs["processes"] == 1
    for name in ("outlet_flux", "stent_max_von_mises", "inlet_flux", "max_wall_displacement"):
        a, b = par[name].values[1:], serial[name].values[1:]
        rel = np.abs(a - b).max() / np.abs(b).max()
        print(f"MPI 2 vs 1 process, {name}: max relative difference {rel:.2e}")
        assert rel < 1e-8, (name, rel)


def test_ladder_target(e2e):
    """`snakemake ladder`: the reference and the one-way rung of the stented model through the workflow
    (one_way: r-z wall -> urine alone -> stent), compared in the ladder dataset, table and figure."""
    out = ok(snakemake(e2e.dir, e2e.cfg_path, "--cores", "2", "ladder"))
    counts = job_counts(out)
    assert counts.get("ladder_run") == 2 and counts.get("ladder") == 1, counts
    with xr.open_dataset(e2e.dir / "results/datasets/ladder.nc", decode_times=False) as ds:
        ds.load()
    assert list(ds["rung"].values) == ["fully_coupled", "one_way"]
    err = ds["error"].sel(rung="one_way")
    print("one-way vs fully coupled (2 steps):", {str(q): f"{float(e):.2e}" for q, e in zip(ds["quantity"].values, err)})
    assert float(ds["error"].sel(rung="fully_coupled").max()) == 0.0
    # the one-way rung follows the fully coupled model closely (< 2 % on every figure quantity)
    assert 0.0 < float(err.max()) < 0.02, err.values
    assert set(ds["chosen_rung"].values) == {"one_way"}
    with xr.open_dataset(e2e.dir / "results/ladder/one_way.nc", decode_times=False) as run:
        assert run.attrs["fidelity"] == "one_way"
        assert run.attrs["one_way_max_wall_pressure_deviation"] < 1e-2 * run.attrs["one_way_peristaltic_peak_traction"]
        assert run.attrs["one_way_max_stent_displacement"] < 1e-2 * run.attrs["one_way_hole_diameter"]
    for p in ("results/figures/table_ladder.md", "results/figures/ladder_pareto.png", "results/figures/ladder_overlay.png",
              "results/logs/ladder/one_way.log", "results/benchmarks/ladder/one_way.tsv"):
        assert (e2e.dir / p).stat().st_size > 0, p
