"""Simulation's wall set: adding walls, their prescribed motion and servo control, and what the
particles exert on them, by wall index. A mixin of :class:`grainscale.simulation.Simulation`,
which holds the state (``_level``, ``_walls``, ``_wall_spin``)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from . import _core
from ._validate import vector3
from .geometry import Cylinder, Mesh, Plane, Rectangle, Servo

if TYPE_CHECKING:
    from .materials import Material


class WallMethods:
    """The wall methods of a Simulation (see the module docstring)."""

    _level: _core.Level
    _walls: list[Plane | Rectangle | Cylinder | Mesh]
    _wall_spin: dict[int, tuple[float, float, float]]

    if TYPE_CHECKING:

        def material_index(self, material: Material) -> int: ...

    def add_wall(
        self, wall: Plane | Rectangle | Cylinder | Mesh, servo: Servo | None = None
    ) -> int:
        """Add a wall; returns its index (for wall_force, wall_torque, set_wall_motion).

        Args:
            wall: Plane, Rectangle, Cylinder or Mesh.
            servo: optional force/stress control of the wall's translation.
        """
        mat = -1 if wall.material is None else self.material_index(wall.material)
        lv = self._level
        if servo is not None:  # validate before the wall exists
            servo.force_for(wall)
            servo.direction_for(wall)
        if isinstance(wall, Plane):
            k = lv.add_plane_wall(wall.point, wall.normal, wall.velocity, mat)
        elif isinstance(wall, Rectangle):
            k = lv.add_rectangle_wall(wall.corner, wall.edge1, wall.edge2, wall.velocity, mat)
        elif isinstance(wall, Cylinder):
            length = 0.0 if wall.length is None else wall.length
            k = lv.add_cylinder_wall(
                wall.point, wall.axis, wall.radius, length, wall.inside, wall.velocity, mat
            )
            if any(wall.angular_velocity):
                lv.set_wall_motion(k, wall.velocity, wall.angular_velocity, wall.point)
                self._wall_spin[int(k)] = wall.angular_velocity
        elif isinstance(wall, Mesh):
            k = lv.add_mesh_wall(wall.vertices, wall.triangles, wall.origin, wall.velocity, mat)
            if any(wall.angular_velocity):
                lv.set_wall_motion(k, wall.velocity, wall.angular_velocity, wall.origin)
                self._wall_spin[int(k)] = wall.angular_velocity
        else:
            raise ValueError(
                f"add_wall.wall must be a Plane, Rectangle, Cylinder or Mesh, got {wall!r}"
            )
        self._walls.append(wall)
        if servo is not None:
            self.set_wall_servo(int(k), servo)
        return int(k)

    def set_wall_motion(
        self,
        index: int,
        velocity: Sequence[float] | None = None,
        angular_velocity: Sequence[float] | None = None,
        origin: Sequence[float] | None = None,
    ) -> None:
        """Change a wall's prescribed motion: translation velocity (m/s) and rotation
        (rad/s) about ``origin`` (m; also the torque reference). None keeps a value."""
        lv, k = self._level, self._wall_index(index)
        lv.set_wall_motion(
            k,
            vector3(
                "set_wall_motion", "velocity", lv.wall_velocity(k) if velocity is None else velocity
            ),
            vector3(
                "set_wall_motion",
                "angular_velocity",
                self._wall_spin.get(k, (0.0, 0.0, 0.0))
                if angular_velocity is None
                else angular_velocity,
            ),
            vector3("set_wall_motion", "origin", lv.wall_origin(k) if origin is None else origin),
        )
        if angular_velocity is not None:
            self._wall_spin[k] = vector3("set_wall_motion", "angular_velocity", angular_velocity)

    def set_wall_servo(self, index: int, servo: Servo | None) -> None:
        """Put a wall under servo control (None switches it off)."""
        k = self._wall_index(index)
        if servo is None:
            self._level.set_wall_servo(k, False, (0.0, 0.0, 1.0), 0.0, 0.0, 0.0)
            return
        wall = self._walls[k]
        self._level.set_wall_servo(
            k,
            True,
            servo.direction_for(wall),
            servo.force_for(wall),
            servo.gain,
            servo.max_speed,
            servo.integral_gain,
        )

    def wall_servo_integral(self, index: int) -> float:
        """The integrated force error (N s) of wall ``index``'s PI servo (0 without one)."""
        return float(self._level.wall_servo_integral(self._wall_index(index)))

    def wall_velocity(self, index: int) -> np.ndarray:
        """Current translation velocity (m/s) of wall ``index`` (servo walls change it)."""
        return np.array(self._level.wall_velocity(self._wall_index(index)))

    def mesh_walls(self) -> list[dict[str, Any]]:
        """Current geometry of the mesh walls: index, vertices, triangles, moving (for output)."""
        out = []
        for k, wall in enumerate(self._walls):
            if isinstance(wall, Mesh):
                moving = bool(
                    np.any(self._level.wall_velocity(k))
                    or any(self._wall_spin.get(k, wall.angular_velocity))
                )
                out.append(
                    {
                        "index": k,
                        "vertices": np.asarray(self._level.wall_vertices(k)),
                        "triangles": wall.triangles,
                        "moving": moving,
                    }
                )
        return out

    def wall_force(self, index: int) -> np.ndarray:
        """Force (N) exerted by the particles on wall ``index`` at the last step."""
        return np.array(self._level.wall_force(self._wall_index(index)))

    def wall_torque(self, index: int) -> np.ndarray:
        """Torque (N m) exerted by the particles on wall ``index`` about its origin (plane point,
        rectangle corner, cylinder axis point, mesh origin, or the origin set by
        set_wall_motion)."""
        return np.array(self._level.wall_torque(self._wall_index(index)))

    def wall_position(self, index: int) -> np.ndarray:
        """Current reference point (m) of wall ``index``: plane point, rectangle corner, point on
        a cylinder's axis (moves with the wall)."""
        return np.array(self._level.wall_point(self._wall_index(index)))

    def _wall_index(self, index: int) -> int:
        if not 0 <= index < len(self._walls):
            raise ValueError(f"wall index must be in [0, {len(self._walls)}), got {index}")
        return index
