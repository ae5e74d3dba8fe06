"""The study layer: one run of one stent model on one mesh, on a rung of the fidelity ladder -> probe dataset.

The arrows run cli -> rungs (coupled, oneway) -> pipeline -> probes, options -> engine (ureterfsi.fsi):

options   RunSpec, the fidelities, the configuration as solver options and time settings, the run identity
probes    the ureter probes (fluxes, hole flows, wall displacement, stent stress) and the probe dataset
pipeline  the run sequence every rung shares (mesh, counts, checkpoints, integration, provenance, write)
coupled   the fully coupled rung (monolithic ALE FSI)
oneway    the one-way rung: r-z wall -> urine alone -> quasi-static stent (oneway/{wall, urine, stent, rung})
fields    the run's field files for ParaView (XDMF + HDF5 at the probe times)
run       solve: one run on a rung (the rung dispatch)
cli       `python -m ureterfsi.study`: its arguments, then run.solve
calibration  the wall's peak traction against the paper's wall displacement (`python -m ureterfsi.study.calibration`)
"""

__all__ = ["calibration", "cli", "coupled", "fields", "oneway", "options", "pipeline", "probes", "run"]
