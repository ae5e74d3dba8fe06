"""ureterfsi: open, reproducible fluid-structure interaction of a stented ureter.

Subpackages and modules
-----------------------
config      load and validate the study configuration (JSON schema + geometric checks)
geometry    ureter/stent/hole geometry from the configuration, analytic volumes
tags        integer tags of the subdomains and boundaries of every mesh
mesh        gmsh meshes (full, half, quarter, axisymmetric) with sidecar statistics
fsi         the scene-agnostic FSI engine: physics blocks, monolithic ALE coupling, time stepping
"""

__version__ = "0.1.0"
