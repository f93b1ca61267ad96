"""Shared by every test folder (one per floor of the package): the helpers beside this file
(literal.py: the literal pseudo-inverse form of (2.14); rotations.py: rotation matrices and
quaternion rate matrices written out by hand) import by their names; ``scheduler``: a Dask
scheduler with one in-process worker, for tests that run sweeps through ``--scheduler``."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))


@pytest.fixture(scope="module")
def scheduler():
    """The address of a Dask scheduler with one in-process worker (no cluster start per sweep)."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=1, processes=False, dashboard_address=None) as cluster:
        yield cluster.scheduler_address
