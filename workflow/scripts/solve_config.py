"""Snakemake script of rule `solve_config`: the configuration one solve of a model reads on a fidelity rung
(ureterfsi.config.run_sections, the rule's params) as the JSON file that `python -m ureterfsi.study
--run-config` reads."""
from ureterfsi.data.provenance import write_json
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821
run_script(smk, lambda: write_json(smk.output[0], dict(smk.params.sections)))
