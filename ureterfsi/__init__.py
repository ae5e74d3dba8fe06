"""ureterfsi: open, reproducible fluid-structure interaction of a stented ureter.

Subpackages and modules
-----------------------
config      load and validate the study configuration (JSON schema + geometric checks)
geometry    ureter/stent/hole geometry from the configuration, analytic volumes
tags        integer tags of the subdomains and boundaries of every mesh
mesh        gmsh meshes (full, half, quarter, axisymmetric) with sidecar statistics
fsi         the scene-agnostic FSI engine: physics blocks, monolithic ALE coupling, time stepping
"""

# netCDF4 must load its bundled HDF5 before dolfinx loads Debian's MPI-HDF5: the other order
# segfaults on the first netCDF write (two HDF5 libraries in one process).
import netCDF4  # noqa: F401,E402  (import order matters)

__version__ = "0.1.0"
