"""What the Snakemake workflow needs of the package.

log         the body of every workflow script: logging into the rule's log, one-line errors
machine     the machine's physical memory (the local memory budget)
paths       every results/ path of the workflow (the rules and the package read them here)
"""
__all__ = ["log", "machine", "paths"]
