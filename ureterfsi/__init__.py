"""ureterfsi: open, reproducible fluid-structure interaction of a stented ureter.

Sub-packages (each lists its modules)
-------------------------------------
config      load and validate the study configuration (schema, plausible ranges, cross-key checks, rerun sections)
mesh        geometry of ureter, stent and holes; tags; gmsh meshes (full, half, quarter, axisymmetric) and .msh I/O
fsi         the scene-agnostic FSI engine: physics blocks, monolithic ALE coupling, time stepping, probes
scenes      scenes for the engine: the ureter, its r-z wall, Turek-Hron, the verification problems
study       the study's runs: options, pipeline, probes, field files, fully coupled and one-way rungs, calibration
stability   the stability matrix: cases, limits, observer, dataset
designs     design studies: parameter space and expansion, rung check, results
analyses    post-processing of finished runs: figure data, grid convergence index, the model ladder (no dolfinx)
plotting    figures: house style and atomic save, the paper's figures, fields, ladder, designs, stability map
data        files and metadata: read-back checks, the CF registry, provenance, field-file reading, tables (no dolfinx)
workflow    what the Snakemake workflow needs: script logging, the machine's memory, every results/ path, resources
"""

# netCDF4 must load its bundled HDF5 before dolfinx loads Debian's MPI-HDF5: the other order
# segfaults on the first netCDF write (two HDF5 libraries in one process).
import netCDF4  # noqa: F401,E402  (import order matters)

from pathlib import Path  # noqa: E402

__version__ = "0.1.0"
REPO_ROOT = Path(__file__).resolve().parent.parent   # the repository (workflow/schemas, config, .git)
