"""Files and their metadata (no dolfinx).

checked     read-back contracts: every file the workflow reads is checked (BadFile)
cf          the one CF metadata registry (units, long_name) and the netCDF writer
provenance  provenance attributes, atomic writes (atomic_path), JSON
fieldfiles  reading a run's field files (XDMF + HDF5) without dolfinx, sampling them
tables      the one CSV + Markdown table writer
"""
__all__ = ["cf", "checked", "fieldfiles", "provenance", "tables"]
