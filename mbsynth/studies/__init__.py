"""Many runs of one model: parameter sweeps on Dask (sweep.py)."""
