"""Fixtures of the MPI tests (helpers: mpi_cases.py). They run under ``mpirun -np 2`` (and 3)."""

from __future__ import annotations

import pytest
from mpi4py import MPI


@pytest.fixture
def world() -> MPI.Intracomm:
    return MPI.COMM_WORLD


@pytest.fixture
def shared_tmp(tmp_path, world):
    """A directory every rank sees (rank 0's tmp_path)."""
    return world.bcast(tmp_path, root=0)
