"""Shared by every test folder (one per floor of the package): ``scheduler``, a Dask
scheduler with one in-process worker, for tests that run sweeps through ``--scheduler``.
Helpers that tests import live in the package tests/helpers (``from tests.helpers.rotations
import ...``: pyproject's ``pythonpath`` puts the repository root on the path)."""

import pytest

from mbsynth.core import collection

# the model layer imported first, as ``mb.load`` imports it (its objects frozen: core/collection.py), before any
# test makes objects of its own: those are then collected as in a user's process
collection.imported("mbsynth.io")


@pytest.fixture(scope="module")
def scheduler():
    """The address of a Dask scheduler with one in-process worker (no cluster start per sweep)."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=1, processes=False, dashboard_address=None) as cluster:
        yield cluster.scheduler_address
