"""Design studies: parameter spaces, sampled points, their runs and results.

space       the parameter catalogue, sampling and expansion into runs
rung_check  the one-way rung checked against the fully coupled one at chosen points
results     the design dataset, sensitivities
"""
__all__ = ["results", "rung_check", "space"]
