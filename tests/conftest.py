"""Shared by every test folder (one per floor of the package): ``scheduler``, a Dask
scheduler with one in-process worker, for tests that run sweeps through ``--scheduler``.
Helpers that tests import live in the package tests/helpers (``from tests.helpers.rotations
import ...``: pyproject's ``pythonpath`` puts the repository root on the path)."""

import pytest


@pytest.fixture(scope="module")
def scheduler():
    """The address of a Dask scheduler with one in-process worker (no cluster start per sweep)."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=1, processes=False, dashboard_address=None) as cluster:
        yield cluster.scheduler_address
