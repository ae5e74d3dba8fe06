"""Code the tests share that is not a test: cases, comparisons, synthetic datasets, Snakemake runs and the
scripts some tests launch in processes of their own (mpi_driver.py, release_driver.py)."""
