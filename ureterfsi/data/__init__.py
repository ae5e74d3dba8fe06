"""Files and their metadata (no dolfinx).

checked     read-back contracts: every file the workflow reads is checked (BadFile)
cf          the one CF metadata registry (units, long_name) and the netCDF writer
cf_tables   the registry's tables (re-exported by cf, their one path)
provenance  provenance attributes, atomic writes (atomic_path), JSON
fieldfiles  reading a run's field files (XDMF + HDF5) without dolfinx, sampling them
tables      the one CSV + Markdown table writer
"""
__all__ = ["cf", "cf_tables", "checked", "fieldfiles", "provenance", "tables"]
