"""A rule's resource capped at what a compute node (or the partition) allows (config `cluster`): applied to every
rule by workflow/rules/cluster.smk, so that no job of a cluster run waits for a node that cannot exist."""
from __future__ import annotations


def capped(resource, limit: int):
    """A Snakemake Resource: `resource` (a rule's value, callable or profile expression) evaluated for the job,
    then at most `limit` (a value that is not an integer, e.g. a profile's string, unchanged)."""
    from snakemake.resources import Resource

    def value(wildcards, input, attempt, threads, rulename, async_run):
        v = resource.evaluate(wildcards, input=input, attempt=attempt, threads=threads, rulename=rulename,
                              async_run=async_run).value
        return min(v, limit) if isinstance(v, int) else v

    return Resource(resource.name, value)
