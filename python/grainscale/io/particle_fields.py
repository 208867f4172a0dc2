"""The per-particle arrays an output writes: a choice among the particle view's fields and
user arrays computed at each snapshot. Shared by :class:`~grainscale.io.VTK` and
:class:`~grainscale.io.Dump`.

A user array is a callable that receives the open, read-only
:class:`~grainscale.ParticleView` of this rank's particles and returns one value (or one row
of k values) per particle, in the view's order:

    >>> import numpy as np
    >>> speed = lambda p: np.linalg.norm(p.velocity, axis=1)        # m/s
    >>> height = lambda p: p.position[:, 2] - p.radius              # m, lowest point

Close over the simulation (or a dict keyed by ``p.id``) for anything else the view does not
hold, e.g. ``lambda p: tags[p.id]`` with ``tags`` an array indexed by id.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from ..particle_view import SCALAR_FIELDS, VECTOR_FIELDS

#: every per-particle field of the particle view, by name
PARTICLE_FIELDS = VECTOR_FIELDS + SCALAR_FIELDS

Extra = Callable[[Any], Any]


def choose_fields(owner: str, fields: Sequence[str] | None, default: Sequence[str]) -> list[str]:
    """The field names to write, in order: ``default`` when ``fields`` is None, else ``fields``
    checked (names of the particle view, each once); ValueError naming ``owner`` otherwise."""
    if fields is None:
        return list(default)
    if isinstance(fields, str) or not isinstance(fields, Sequence):
        raise ValueError(
            f"{owner}.fields must be a list of particle field names {PARTICLE_FIELDS}, "
            f"got {fields!r}"
        )
    chosen: list[str] = []
    for name in fields:
        if name not in PARTICLE_FIELDS:
            raise ValueError(
                f"{owner}.fields must name particle fields {PARTICLE_FIELDS}, got {name!r}"
            )
        if name in chosen:
            raise ValueError(f"{owner}.fields names {name!r} twice")
        chosen.append(name)
    return chosen


def check_extra(
    owner: str, extra: Mapping[str, Extra] | None, taken: Sequence[str]
) -> dict[str, Extra]:
    """``extra`` checked: a mapping of new, non-empty names (not in ``taken``, not particle
    field names) to callables."""
    if extra is None:
        return {}
    if not isinstance(extra, Mapping):
        raise ValueError(
            f"{owner}.extra must be a dict of name -> callable(particle view) -> array, "
            f"got {extra!r}"
        )
    checked: dict[str, Extra] = {}
    for name, fn in extra.items():
        if not isinstance(name, str) or not name.strip() or "/" in name:
            raise ValueError(
                f"{owner}.extra names must be non-empty strings without '/', got {name!r}"
            )
        if name in taken or name in PARTICLE_FIELDS:
            raise ValueError(
                f"{owner}.extra[{name!r}] has the name of a field the output already writes "
                f"({', '.join(sorted(set(taken) | set(PARTICLE_FIELDS)))}): choose another name"
            )
        if not callable(fn):
            raise ValueError(
                f"{owner}.extra[{name!r}] must be a callable(particle view) -> array, got {fn!r}"
            )
        checked[name] = fn
    return checked


def field_arrays(
    owner: str, view: Any, fields: Sequence[str], optional: Sequence[str] = ()
) -> dict[str, np.ndarray]:
    """The chosen fields of an open particle view (the view's arrays, not copies); a name in
    ``optional`` that the view lacks is left out."""
    out: dict[str, np.ndarray] = {}
    for name in fields:
        value = getattr(view, name, None)
        if value is None:
            if name in optional:
                continue
            raise ValueError(f"{owner}: the particles have no field {name!r}")
        out[name] = value
    return out


def extra_arrays(
    owner: str, view: Any, extra: Mapping[str, Extra], n: int
) -> dict[str, np.ndarray]:
    """Calls every user array on the open view; each must give (n,) or (n, k) numbers."""
    out: dict[str, np.ndarray] = {}
    for name, fn in extra.items():
        value = np.asarray(fn(view))
        if value.dtype == np.bool_:
            value = value.astype(np.uint8)
        if value.ndim not in (1, 2) or value.shape[0] != n or value.dtype.kind not in "iuf":
            raise ValueError(
                f"{owner}.extra[{name!r}] must return one number (or one row of numbers) per "
                f"particle of this rank, shape ({n},) or ({n}, k), got shape {value.shape} of "
                f"{value.dtype}"
            )
        out[name] = value
    return out
