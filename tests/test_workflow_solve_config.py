"""Rule solve's configuration file (ureterfsi.config.run_sections as JSON, read back by run_config for
`python -m ureterfsi.study --run-config`): the round trip keeps every section a solve reads, and a file that
does not hold exactly those sections is refused in one line naming the constraint."""
import json

import pytest

from ureterfsi.config import RUN_SECTIONS, ConfigError, load_config, run_config, run_sections


def test_run_config_round_trip():
    cfg = load_config()
    model = sorted(cfg["models"])[1]
    sections = json.loads(json.dumps(run_sections(cfg, model)))      # as rule solve_config writes it
    back = run_config(sections, model)
    assert set(back) == set(RUN_SECTIONS) | {"models"} and back["models"] == {model: cfg["models"][model]}
    assert all(back[k] == cfg[k] for k in RUN_SECTIONS)
    assert run_sections(back, model) == sections


def test_run_config_refuses_other_sections():
    cfg = load_config()
    model = sorted(cfg["models"])[0]
    sections = run_sections(cfg, model)
    with pytest.raises(ConfigError, match=r"<run config>: must hold exactly the sections .*got"):
        run_config({k: v for k, v in sections.items() if k != "fields"}, model)
    with pytest.raises(ConfigError, match="must hold exactly"):
        run_config(sections | {"figures": cfg["figures"]}, model)
