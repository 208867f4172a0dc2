"""The fingerprints ranks compare before a collective call (grainscale.parallel.same_arguments):
equal arguments give equal texts on every rank, different ones differ, whatever a repr would
abbreviate or however an object prints its address."""

from __future__ import annotations

import numpy as np

import grainscale as gs
from grainscale.parallel import _fingerprint


def test_arrays_compare_by_content_not_by_their_abbreviated_repr() -> None:
    a = np.zeros((5000, 3))
    b = a.copy()
    b[2500, 1] = 1e-300  # repr of both is the same "[[0. 0. 0.] ... ]"
    assert repr(a) == repr(b)
    assert _fingerprint(a) != _fingerprint(b)
    assert _fingerprint(a) == _fingerprint(a.copy())
    assert _fingerprint(a).startswith("array(5000, 3):")


def test_walls_and_meshes_compare_field_by_field() -> None:
    v = np.random.default_rng(1).uniform(size=(2000, 3))
    t = np.arange(1998)[:, None] + np.arange(3)
    mesh = gs.geometry.Mesh(vertices=v, triangles=t)
    moved = v.copy()
    moved[1000, 2] += 1e-9
    assert _fingerprint(mesh) == _fingerprint(gs.geometry.Mesh(vertices=v.copy(), triangles=t))
    assert _fingerprint(mesh) != _fingerprint(gs.geometry.Mesh(vertices=moved, triangles=t))
    glass = gs.Material(density=2500, youngs_modulus=1e7, poisson_ratio=0.3)
    floor = gs.Plane(point=(0, 0, 0), normal=(0, 0, 1), material=glass)
    assert _fingerprint(floor) == _fingerprint(
        gs.Plane(point=(0, 0, 0), normal=(0, 0, 1), material=glass)
    )
    assert _fingerprint(floor) != _fingerprint(
        gs.Plane(point=(0, 0, 1e-12), normal=(0, 0, 1), material=glass)
    )


class Opaque:
    """An object whose repr holds its address (differs from rank to rank)."""

    def __init__(self, value: float) -> None:
        self.value = value


def test_objects_printed_with_their_address_compare_by_their_attributes() -> None:
    assert " at 0x" in repr(Opaque(1.0))
    assert _fingerprint(Opaque(1.0)) == _fingerprint(Opaque(1.0))
    assert _fingerprint(Opaque(1.0)) != _fingerprint(Opaque(2.0))
    assert _fingerprint(1e-6) == "1e-06" and _fingerprint(None) == "None"
