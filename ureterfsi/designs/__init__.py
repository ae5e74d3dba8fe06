"""Design studies: parameter spaces, sampled points, their runs and results.

space       the parameter catalogue, a point's values and configuration
expand      each study's points (grid or sample) and rung-check corners, the design rules' paths and requests
jobs        what the design rules ask of the studies: inputs, rerun triggers, each solve's rung and options
rung_check  the one-way rung checked against the fully coupled one at chosen points
results     the design dataset, sensitivities
passage     past an obstruction: the lumen's share, holes up- and downstream; the rung per point; reference runs
"""
__all__ = ["expand", "jobs", "passage", "results", "rung_check", "space"]
