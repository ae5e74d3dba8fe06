"""Rule solve's configuration file (ureterfsi.config.run_sections as JSON, read back by run_config for
`python -m ureterfsi.study --run-config`): the round trip keeps every section a solve reads, and a file that
does not hold exactly those sections is refused in one line naming the constraint."""
import json

import pytest

from ureterfsi.config import DEFAULTED_RUN_SECTIONS, RUN_SECTIONS, ConfigError, load_config, read_run_config, run_config, run_sections
from ureterfsi.config.schema import load_schema
from ureterfsi.config.sections import RUNG_KEYS
from ureterfsi.data.provenance import write_json


def test_run_config_round_trip(tmp_path):
    """Written as rule solve_config writes it (provenance.write_json: keys sorted, so the mesh levels come out
    coarse, fine, medium) and read as the solve reads it: the same sections, the levels coarse to fine again."""
    cfg = load_config()
    model = sorted(cfg["models"])[1]
    write_json(tmp_path / "run.json", run_sections(cfg, model, "fully_coupled"))
    back = read_run_config(tmp_path / "run.json", model)
    assert set(back) == set(RUN_SECTIONS + DEFAULTED_RUN_SECTIONS) | {"models"}
    assert back["models"] == {model: cfg["models"][model]}
    assert all(back[k] == cfg[k] for k in RUN_SECTIONS + DEFAULTED_RUN_SECTIONS)
    assert list(back["mesh"]["levels"]) == list(cfg["mesh"]["levels"]) == ["coarse", "medium", "fine"]
    assert run_sections(back, model, "fully_coupled") == json.loads(json.dumps(run_sections(cfg, model, "fully_coupled")))


def test_defaulted_section_enters_only_off_its_defaults(tmp_path):
    """`ends` at the schema's defaults (the paper's open ends) stays out of a run's configuration, so adding the
    section re-ran no solve; set off them it enters and reads back."""
    cfg = load_config()
    model = sorted(cfg["models"])[0]
    assert "ends" not in run_sections(cfg, model, "fully_coupled")
    cfg["ends"]["kidney"]["condition"] = "pelvis"
    write_json(tmp_path / "run.json", run_sections(cfg, model, "fully_coupled"))
    assert read_run_config(tmp_path / "run.json", model)["ends"] == cfg["ends"]


def test_run_config_refuses_other_sections():
    cfg = load_config()
    model = sorted(cfg["models"])[0]
    sections = run_sections(cfg, model, "fully_coupled")
    with pytest.raises(ConfigError, match=r"<run config>: must hold the sections .*got"):
        run_config({k: v for k, v in sections.items() if k != "fields"}, model)
    with pytest.raises(ConfigError, match="must hold the sections"):
        run_config(sections | {"figures": cfg["figures"]}, model)


def test_run_config_file_of_another_version_or_corrupt_is_named(tmp_path):
    """A run configuration missing a key the schema now defaults (written by an older version), a truncated
    file and one that is not an object: one line naming the file and what is wrong."""
    from ureterfsi.config import read_run_config

    cfg = load_config()
    model = sorted(cfg["models"])[1]
    sections = run_sections(cfg, model, "fully_coupled")
    good = tmp_path / "good.json"
    good.write_text(json.dumps(sections))
    assert read_run_config(good, model) == run_config(json.loads(good.read_text()), model)
    old = dict(sections, solver={k: v for k, v in sections["solver"].items() if k != "krylov_forcing"})
    (tmp_path / "old.json").write_text(json.dumps(old))
    with pytest.raises(ConfigError, match=r"old\.json: solver\.krylov_forcing: missing: the file was written by "
                                          r"another version"):
        read_run_config(tmp_path / "old.json", model)
    (tmp_path / "cut.json").write_text(good.read_text()[:100])
    with pytest.raises(ConfigError, match=r"cut\.json: unreadable"):
        read_run_config(tmp_path / "cut.json", model)
    (tmp_path / "list.json").write_text("[1, 2]")
    with pytest.raises(ConfigError, match=r"list\.json: must be a JSON object"):
        read_run_config(tmp_path / "list.json", model)


@pytest.mark.parametrize("section,key,value,message", [
    ("time", "dt", -1.0, "time.dt: must be > 0, got -1"),                        # ran backwards for ever
    ("solver", "newton_max_iterations", 15.0, "solver.newton_max_iterations: must be an integer, got the float 15.0"),
    ("peristalsis", "peak_traction", 50.0, "peristalsis.peak_traction: 50 Pa is outside the plausible range"),
    ("time", "probe_times", [0.5, 9.0], "time.probe_times[1]: must lie in (0, time.end = 3] s, got 9"),
])
def test_hand_edited_run_config_file_is_validated(tmp_path, section, key, value, message):
    """The run configuration file is validated like a configuration file (the schema of its sections
    and the checks that read only them), not trusted: time.dt = -1 in it used to start a solve that stepped
    backwards without end."""
    from ureterfsi.config import read_run_config

    cfg = load_config()
    sections = json.loads(json.dumps(run_sections(cfg, "3", "one_way")))
    sections[section][key] = value
    path = tmp_path / "model3.json"
    path.write_text(json.dumps(sections))
    with pytest.raises(ConfigError) as err:
        read_run_config(path, "3")
    assert str(err.value).startswith(f"config error: <run config> {path}: {message}"), err.value


def _changed(value):
    """A value other than `value` of the same kind (a key's default)."""
    if isinstance(value, bool):
        return not value
    if isinstance(value, (int, float)):
        return value * 0.5 if isinstance(value, float) else value + 1
    return None if value is not None else 3


@pytest.mark.parametrize("rung", sorted(RUNG_KEYS))
def test_a_key_one_rung_reads_re_runs_no_solve_of_the_other(rung):
    """Each key of RUNG_KEYS[rung] changed: the rung's own solve configuration (its rerun trigger, its checkpoint
    identity) changes, the other rung's does not (it holds the key at its default). A new schema key named
    one_way_* or fully_coupled_* that is not listed fails here."""
    cfg = load_config()
    other = next(r for r in RUNG_KEYS if r != rung)
    for dotted in RUNG_KEYS[rung]:
        section, key = dotted.split(".")
        changed = dict(cfg, **{section: dict(cfg[section], **{key: _changed(cfg[section][key])})})
        assert run_sections(changed, "3", rung) != run_sections(cfg, "3", rung), dotted
        assert run_sections(changed, "3", other) == run_sections(cfg, "3", other), dotted
    for section in ("solver", "ends"):
        for key in load_schema()["properties"][section]["properties"]:
            named = next((r for r in RUNG_KEYS if key.startswith(r + "_")), None)
            assert named is None or f"{section}.{key}" in RUNG_KEYS[named], f"{section}.{key} is not in RUNG_KEYS"
    # a key both rungs read changes both
    changed = dict(cfg, solver=dict(cfg["solver"], newton_rtol=cfg["solver"]["newton_rtol"] * 0.5))
    assert all(run_sections(changed, "3", r) != run_sections(cfg, "3", r) for r in RUNG_KEYS)
    with pytest.raises(ValueError, match="fidelity must be one of"):
        run_sections(cfg, "3", "two_way")
