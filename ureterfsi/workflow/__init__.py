"""What the Snakemake workflow needs of the package.

log         the body of every workflow script: logging into the rule's log, one-line errors
machine     the machine's physical memory (the local memory budget)
paths       every results/ path of the workflow (the rules and the package read them here)
resources   memory budget and reservations, out-of-core factorisation, priorities, the MPI launcher of a solve
"""
__all__ = ["log", "machine", "paths", "resources"]
