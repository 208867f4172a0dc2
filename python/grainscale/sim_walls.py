"""Simulation's wall set: ``add_wall`` returns a :class:`WallHandle`, which reads what the
particles exert on the wall and sets its prescribed motion and servo control.

``WallMethods`` is a mixin of :class:`grainscale.simulation.Simulation`, which holds the state
(``_level``, ``_walls``, ``_wall_spin``). The index methods of earlier releases
(``sim.wall_force(k)``, ``sim.set_wall_motion(k, ...)``, ...) still work for this release and
warn (DeprecationWarning); a handle also passes where an index was expected.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from . import _core, parallel
from ._validate import flag, span, vector3
from .geometry import Cylinder, Mesh, Plane, Rectangle, Servo
from .placement import check_particles

if TYPE_CHECKING:
    from .materials import Material

WallGeometry = Plane | Rectangle | Cylinder | Mesh


class WallMotion(NamedTuple):
    """A wall's prescribed motion: translation velocity (m/s) and rotation (rad/s) about
    ``origin`` (m; also the torque reference)."""

    velocity: np.ndarray
    angular_velocity: np.ndarray
    origin: np.ndarray


class WallHandle:
    """A wall of a simulation, as returned by ``Simulation.add_wall``.

    Example:
        >>> import grainscale as gs
        >>> sim = gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01)))
        >>> floor = sim.add_wall(gs.Plane(point=(0, 0, 0), normal=(0, 0, 1)))
        >>> floor.set_motion(velocity=(0, 0, 0.01))
        >>> floor.motion.velocity.tolist()
        [0.0, 0.0, 0.01]
        >>> floor.force.tolist()  # N, from the particles at the last step
        [0.0, 0.0, 0.0]
    """

    def __init__(self, sim: WallMethods, index: int, geometry: WallGeometry) -> None:
        self._sim = sim
        self.index = index
        self.geometry = geometry

    def __index__(self) -> int:
        return self.index

    @property
    def force(self) -> np.ndarray:
        """Force (N) exerted by the particles on the wall at the last step."""
        return np.array(self._sim._level.wall_force(self.index))

    @property
    def torque(self) -> np.ndarray:
        """Torque (N m) exerted by the particles about the wall's origin (plane point,
        rectangle corner, cylinder axis point, mesh origin, or the origin of ``set_motion``)."""
        return np.array(self._sim._level.wall_torque(self.index))

    @property
    def position(self) -> np.ndarray:
        """Current reference point (m) — the plane point, rectangle corner, point on a cylinder's
        axis, mesh origin (moves with the wall)."""
        return np.array(self._sim._level.wall_point(self.index))

    @property
    def velocity(self) -> np.ndarray:
        """Current translation velocity (m/s); a servo changes it every step."""
        return np.array(self._sim._level.wall_velocity(self.index))

    @property
    def motion(self) -> WallMotion:
        """The prescribed motion now (see :meth:`set_motion`)."""
        lv, k = self._sim._level, self.index
        spin = self._sim._wall_spin.get(k, (0.0, 0.0, 0.0))
        return WallMotion(
            np.array(lv.wall_velocity(k)), np.array(spin, float), np.array(lv.wall_origin(k))
        )

    def set_motion(
        self,
        velocity: Sequence[float] | None = None,
        angular_velocity: Sequence[float] | None = None,
        origin: Sequence[float] | None = None,
    ) -> None:
        """Change the prescribed motion: translation velocity (m/s), rotation (rad/s) about
        ``origin`` (m; also the torque reference). None keeps a value."""
        parallel.same_arguments(
            self._sim.comm,
            "WallHandle.set_motion",
            wall=self.index,
            velocity=velocity,
            angular_velocity=angular_velocity,
            origin=origin,
        )
        lv, k = self._sim._level, self.index
        now = self.motion
        owner = "WallHandle.set_motion"
        v = vector3(owner, "velocity", now.velocity if velocity is None else velocity)
        spin = vector3(
            owner,
            "angular_velocity",
            now.angular_velocity if angular_velocity is None else angular_velocity,
        )
        o = vector3(owner, "origin", now.origin if origin is None else origin)
        lv.set_wall_motion(k, v, spin, o)
        if angular_velocity is not None:
            self._sim._wall_spin[k] = spin

    @property
    def servo(self) -> Servo | None:
        """The servo control of the wall's translation, or None for prescribed motion only. Setting
        it validates it against the wall; None switches it off."""
        return self._sim._wall_servos.get(self.index)

    @servo.setter
    def servo(self, servo: Servo | None) -> None:
        k = self.index
        parallel.same_arguments(self._sim.comm, "WallHandle.servo", wall=k, servo=servo)
        if servo is None:
            self._sim._level.set_wall_servo(k, False, (0.0, 0.0, 1.0), 0.0, 0.0, 0.0)
            self._sim._wall_servos.pop(k, None)
            return
        if not isinstance(servo, Servo):
            raise ValueError(f"WallHandle.servo must be a gs.Servo or None, got {servo!r}")
        self._sim._level.set_wall_servo(
            k,
            True,
            servo.direction_for(self.geometry),
            servo.force_for(self.geometry),
            servo.gain,
            servo.max_speed,
            servo.integral_gain,
        )
        self._sim._wall_servos[k] = servo

    @property
    def servo_integral(self) -> float:
        """The integrated force error (N s) of the wall's PI servo (0 without one)."""
        return float(self._sim._level.wall_servo_integral(self.index))

    def __repr__(self) -> str:
        return f"WallHandle(index={self.index}, {type(self.geometry).__name__})"


def _check_in_domain(owner: str, wall: Rectangle | Mesh, domain: Any) -> None:
    """ValueError unless the wall's bounding box meets the domain box (touching counts):
    particles live inside the domain, so a wall wholly outside it could never be touched (a
    mesh in mm read as m lies 1000 x too far from the origin)."""
    if isinstance(wall, Rectangle):
        c, e1, e2 = (np.asarray(v, float) for v in (wall.corner, wall.edge1, wall.edge2))
        points = np.array([c, c + e1, c + e2, c + e1 + e2])
    else:
        points = np.asarray(wall.vertices, float)
    lo, hi = points.min(axis=0), points.max(axis=0)
    if np.all(hi >= domain.lo) and np.all(lo <= domain.hi):
        return
    hint = (
        "; for an STL file in mm read it with Mesh.from_stl(path, scale=1e-3)"
        if isinstance(wall, Mesh)
        else ""
    )
    raise ValueError(
        f"{owner}.wall must reach into the domain {span(domain.lo, domain.hi)}, got a "
        f"{type(wall).__name__} with bounds {span(lo, hi)}, entirely outside the domain where "
        f"no particle can touch it{hint}; pass check_placement=False to accept it"
    )


def _deprecated(old: str, new: str) -> None:
    warnings.warn(
        f"Simulation.{old} is deprecated and will be removed in the next release; use the "
        f"handle that add_wall returns: {new}",
        DeprecationWarning,
        stacklevel=3,
    )


class WallMethods:
    """The wall methods of a Simulation (see the module docstring)."""

    _level: _core.Level
    _walls: list[WallHandle]
    _wall_spin: dict[int, tuple[float, float, float]]
    _wall_servos: dict[int, Servo]

    domain: Any

    if TYPE_CHECKING:

        @property
        def comm(self) -> Any: ...  # Simulation's property

        def material_index(self, material: Material) -> int: ...

        def particles(self, writable: bool = True) -> Any: ...

    @property
    def walls(self) -> list[WallHandle]:
        """The walls, in the order they were added."""
        return list(self._walls)

    def add_wall(
        self, wall: WallGeometry, servo: Servo | None = None, check_placement: bool = True
    ) -> WallHandle:
        """Add a wall; returns its handle (force, torque, position, motion, servo).

        Args:
            wall: Plane, Rectangle, Cylinder or Mesh.
            servo: optional force/stress control of the wall's translation.
            check_placement: refuse a wall that the particles present overlap by more than
                10 % of their radius or lie behind (a mesh: overlaps only, an open mesh has no
                behind; grainscale.placement), and a rectangle or mesh whose bounding box lies
                entirely outside the domain (no particle can reach it: e.g. an STL file in mm
                read without ``scale=1e-3``); False accepts them.
        """
        parallel.same_arguments(
            self.comm,
            "Simulation.add_wall",
            wall=wall,
            servo=servo,
            check_placement=check_placement,
        )
        owner = "Simulation.add_wall"
        if not isinstance(wall, WallGeometry):
            raise ValueError(
                f"{owner}.wall must be a Plane, Rectangle, Cylinder or Mesh (grainscale.geometry), "
                f"got {wall!r}"
            )
        if servo is not None and not isinstance(servo, Servo):
            raise ValueError(
                f"{owner}.servo must be a grainscale.geometry.Servo or None, got {servo!r}"
            )
        if flag(owner, "check_placement", check_placement):
            if isinstance(wall, Rectangle | Mesh):
                _check_in_domain(owner, wall, self.domain)
            self._check_new_wall(wall)
        mat = -1 if wall.material is None else self.material_index(wall.material)
        lv = self._level
        if servo is not None:  # validate before the wall exists
            servo.force_for(wall)
            servo.direction_for(wall)
        spin_origin = None
        spin = (0.0, 0.0, 0.0)  # planes and rectangles do not rotate
        if isinstance(wall, Plane):
            k = lv.add_plane_wall(wall.point, wall.normal, wall.velocity, mat)
        elif isinstance(wall, Rectangle):
            k = lv.add_rectangle_wall(wall.corner, wall.edge1, wall.edge2, wall.velocity, mat)
        elif isinstance(wall, Cylinder):
            length = 0.0 if wall.length is None else wall.length
            k = lv.add_cylinder_wall(
                wall.point, wall.axis, wall.radius, length, wall.inside, wall.velocity, mat
            )
            spin_origin, spin = wall.point, wall.angular_velocity
        else:
            # Mesh.__post_init__ replaces a None origin by the centroid
            origin: tuple[float, float, float] = wall.origin  # type: ignore[assignment]
            k = lv.add_mesh_wall(wall.vertices, wall.triangles, origin, wall.velocity, mat)
            spin_origin, spin = origin, wall.angular_velocity
        handle = WallHandle(self, int(k), wall)
        if spin_origin is not None and any(spin):
            lv.set_wall_motion(k, wall.velocity, spin, spin_origin)
            self._wall_spin[int(k)] = spin
        self._walls.append(handle)
        if servo is not None:
            handle.servo = servo
        return handle

    def _check_new_wall(self, wall: WallGeometry) -> None:
        """Collective: ValueError on every rank if particles present overlap the new wall."""
        if isinstance(wall, Mesh):
            reference: Any = wall.vertices
        else:
            reference = wall.corner if isinstance(wall, Rectangle) else wall.point
        error = None
        with self.particles(writable=False) as p:
            try:
                check_particles(
                    "Simulation.add_wall",
                    self.domain,
                    np.array(p.position),
                    np.array(p.radius),
                    [(wall, reference, "the new wall")],
                    labels=np.array(p.id),
                    axes=3,
                )
            except ValueError as err:
                error = err
        parallel.agree(self.comm, error)

    def mesh_walls(self) -> list[dict[str, Any]]:
        """Current geometry of the mesh walls: index, vertices, triangles, moving (for output)."""
        out = []
        for w in self._walls:
            if isinstance(w.geometry, Mesh):
                k = w.index
                moving = bool(
                    np.any(self._level.wall_velocity(k))
                    or any(self._wall_spin.get(k, w.geometry.angular_velocity))
                )
                out.append(
                    {
                        "index": k,
                        "vertices": np.asarray(self._level.wall_vertices(k)),
                        "triangles": w.geometry.triangles,
                        "moving": moving,
                    }
                )
        return out

    # --------------------------------------------- deprecated index methods (one release)
    def set_wall_motion(
        self,
        index: int | WallHandle,
        velocity: Sequence[float] | None = None,
        angular_velocity: Sequence[float] | None = None,
        origin: Sequence[float] | None = None,
    ) -> None:
        """Deprecated: ``wall.set_motion(velocity, angular_velocity, origin)``."""
        _deprecated("set_wall_motion(index, ...)", "wall.set_motion(...)")
        self._wall(index).set_motion(velocity, angular_velocity, origin)

    def set_wall_servo(self, index: int | WallHandle, servo: Servo | None) -> None:
        """Deprecated: ``wall.servo = servo``."""
        _deprecated("set_wall_servo(index, servo)", "wall.servo = servo")
        self._wall(index).servo = servo

    def _wall(self, index: int | WallHandle) -> WallHandle:
        k = int(index.index if isinstance(index, WallHandle) else index)
        if not 0 <= k < len(self._walls):
            raise ValueError(f"wall index must be in [0, {len(self._walls)}), got {index}")
        return self._walls[k]


def _deprecated_reader(attribute: str, unit: str) -> Any:
    """Simulation.wall_<attribute>(index) of earlier releases: warns, reads the handle."""

    def read(self: WallMethods, index: int | WallHandle) -> Any:
        _deprecated(f"wall_{attribute}(index)", f"wall.{attribute}")
        return getattr(self._wall(index), attribute)

    read.__name__ = f"wall_{attribute}"
    read.__doc__ = f"Deprecated: ``wall.{attribute}`` ({unit})."
    return read


for _attribute, _unit in (
    ("force", "N"),
    ("torque", "N m"),
    ("position", "m"),
    ("velocity", "m/s"),
    ("servo_integral", "N s"),
):
    setattr(WallMethods, f"wall_{_attribute}", _deprecated_reader(_attribute, _unit))
