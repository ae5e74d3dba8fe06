"""Snakemake script of rule `aggregate_models`: the runs of every stent model on one mesh level -> one
dataset with dim `model` (ureterfsi.analyses.aggregate.combine_models)."""
import logging

from ureterfsi.analyses.aggregate import combine_models, write_dataset
from ureterfsi.workflow.log import run_script

smk = snakemake  # noqa: F821


def main():
    ds = combine_models(list(smk.input.runs), smk.config, time_grid=smk.params.time_grid, expect=smk.params.expect)
    write_dataset(ds, smk.output[0])
    logging.info("models %s, %d times (%s), %d probe times -> %s", list(ds["model"].values), ds.sizes["time"],
                 ds.attrs["time_grid"], ds.sizes["probe_time"], smk.output[0])


run_script(smk, main)
