"""Report captions (workflow/report/*.rst) rendered with Snakemake's Jinja2 and a configuration: they describe
the runs that were made."""
from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import jinja2
import pytest

REPORT = Path(__file__).resolve().parents[2] / "workflow" / "report"


def _render(name: str, cfg: dict) -> str:
    return jinja2.Template((REPORT / name).read_text()).render(snakemake=SimpleNamespace(config=cfg))


@pytest.mark.parametrize("models, says", [(["1", "2", "3", "4"], "of the four models of Table 1"),
                                          (["1", "3"], "of 2 of the four models of Table 1 (models 1, 3)")])
def test_fig04_caption_names_the_models_that_ran(cfg, models, says):
    cfg["models"] = {m: cfg["models"][m] for m in models}
    assert says in _render("fig04_outlet_flow.rst", cfg).splitlines()[0]
