"""What the Snakemake workflow needs of the package.

cluster     a rule's resource capped at what a compute node allows (cluster runs)
launch      the one command line of every solve job (rules solve, ladder_run, design_solve, design_corner_solve)
log         the body of every workflow script: logging into the rule's log, one-line errors
machine     the machine's physical memory (the local memory budget)
memory_plan the ranks' measured peaks of finished runs against their reservations; the study.memory_mb that covers them
paths       every results/ path of the workflow (the rules and the package read them here)
resources   memory budget and reservations, out-of-core factorisation, priorities, the MPI launcher of a solve
"""
__all__ = ["cluster", "launch", "log", "machine", "memory_plan", "paths", "resources"]
