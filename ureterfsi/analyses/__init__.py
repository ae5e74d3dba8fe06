"""Post-processing of finished runs into datasets and tables (no dolfinx).

aggregate   the paper's figure data from the run files
gci         grid convergence index (Roache/Celik) of the mesh study
ladder      the model ladder: fully coupled against one-way probes
"""
__all__ = ["aggregate", "gci", "ladder"]
