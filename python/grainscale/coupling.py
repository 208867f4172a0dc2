"""The controllers of a multi-level interface (DESIGN.md 4; Queteschiner et al. 2018), one small
class each, set once per exchange interval from the cell averages of both levels.

* :class:`VelocityFeedback` (fine -> coarse): the parent's particles in the interior cells follow
  the child's Favre velocity (times the solid-fraction ratio, so that the mass fluxes match);
  each particle's push is limited by the child's velocity range in the cell, never by the
  parent's own motion, so that it sets a bed at rest in motion (a coarse bed jammed at an
  orifice it cannot pass is exactly the case the feedback exists for).
* :class:`BoundaryVelocity` (coarse -> fine): the child's boundary cells are relaxed towards the
  parent's Favre velocity (the shear and pace of the material beyond the faces).
* :class:`ShearTraction` (coarse -> fine): the tangential traction the parent's material beyond
  each face carries (its stress on the face) acts on the child's particles in the face's cell:
  the friction of the slower material beside a flowing zone, which the normal push cannot give.
* :class:`StressBoundary` (coarse -> fine): a PI controller per interface face pushes the child's
  particles in a layer at the face so that the child's normal stress in the boundary cell
  follows the parent's.
* :class:`Advance` (coarse -> fine): below a dense parent bed the child may place particles ahead
  of the flux, which the flux then repays (Exchange.advance).

Each holds its last output (re-applied after a restart) and its state for checkpoints.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from . import _core

# The stress controller's output is clipped to [0, PRESSURE_CAP x the parent's stress]: it never
# pulls, and the push, which stands for the contacts with the material beyond the face, cannot
# exceed what that material carries. A face's push totals pressure x area whatever its layer's
# packing (cpp/coupling/coupling_forces.hpp); before it did, a loose layer took less and the
# controller needed a margin (2 x), at which it sat wherever the child's material flows and set
# the rate (studies/mlcg_jam/NOTES.md).
PRESSURE_CAP = 1.0
# Without a coarse motion to follow, the push of a face stops for particles moving inwards faster
# than this fraction of the free-fall speed over a fine diameter.
REST_SPEED_FRACTION = 0.1


def _vec_rows(values: Any, n: int) -> np.ndarray:
    return np.asarray(values, float).reshape(n, 3)


class VelocityFeedback:
    """Fine -> coarse: per interior cell holding both levels, the acceleration
    a = gain (chi u_fine - u_coarse) / T of the parent's particles, with chi = phi_fine /
    phi_coarse when ``mass_flux_correction`` (else 1) and T the exchange interval; a particle's
    push is limited to the bounds chi x [v_min, v_max] of the child's velocities in the cell."""

    def __init__(self, gain: float, mass_flux_correction: bool, n_cells: int) -> None:
        self.gain = gain
        self.mass_flux_correction = mass_flux_correction
        self.acceleration = np.zeros((n_cells, 3))
        self.velocity_min = np.zeros((n_cells, 3))
        self.velocity_max = np.zeros((n_cells, 3))

    @property
    def active(self) -> bool:
        return self.gain > 0

    def update(
        self, grid: dict[str, Any], parent: dict[str, Any], child: dict[str, Any], interval: float
    ) -> None:
        inside = grid["inside"] > 0
        coupled = inside & ~(grid["boundary"] > 0) & (parent["mass"] > 0) & (child["mass"] > 0)
        chi = np.ones(len(inside))
        if self.mass_flux_correction:
            with np.errstate(divide="ignore", invalid="ignore"):
                chi = np.where(coupled, child["solid_fraction"] / parent["solid_fraction"], 1.0)
        du = self.gain * (chi[:, None] * child["velocity"] - parent["velocity"])
        du[~coupled] = 0.0
        self.acceleration = du / interval
        lo, hi = chi[:, None] * child["velocity_min"], chi[:, None] * child["velocity_max"]
        self.velocity_min = np.where(coupled[:, None], lo, 0.0)
        self.velocity_max = np.where(coupled[:, None], hi, 0.0)

    def apply(self, level: _core.Level, index: int) -> None:
        level.set_coupling_acceleration(index, self.acceleration)
        level.set_coupling_velocity_bounds(index, self.velocity_min, self.velocity_max)

    def state(self) -> dict[str, Any]:
        return {
            "acceleration": self.acceleration.tolist(),
            "velocity_min": self.velocity_min.tolist(),
            "velocity_max": self.velocity_max.tolist(),
        }

    def load(self, state: dict[str, Any]) -> None:
        n = len(self.acceleration)
        self.acceleration = _vec_rows(state["acceleration"], n)
        if "velocity_min" in state:  # written since the limiter follows the fine velocities
            self.velocity_min = _vec_rows(state["velocity_min"], n)
            self.velocity_max = _vec_rows(state["velocity_max"], n)
        else:  # an older checkpoint: no limiter until the next update
            self.velocity_min = np.full((n, 3), -np.inf)
            self.velocity_max = np.full((n, 3), np.inf)


class BoundaryVelocity:
    """Coarse -> fine: per boundary cell holding both levels, the acceleration
    a = gain (u_coarse - u_fine) / T of the child's particles, every component, the change per
    interval limited by the child cell's own velocity range."""

    def __init__(self, gain: float, n_cells: int) -> None:
        self.gain = gain
        self.acceleration = np.zeros((n_cells, 3))

    @property
    def active(self) -> bool:
        return self.gain > 0

    def update(
        self, grid: dict[str, Any], parent: dict[str, Any], child: dict[str, Any], interval: float
    ) -> None:
        inside, boundary = grid["inside"] > 0, grid["boundary"] > 0
        held = inside & boundary & (parent["mass"] > 0) & (child["mass"] > 0)
        du = self.gain * (parent["velocity"] - child["velocity"])
        span = np.maximum(child["velocity_max"] - child["velocity_min"], 0.0)
        du = np.clip(du, -span, span)
        du[~held] = 0.0
        self.acceleration = du / interval

    def state(self) -> dict[str, Any]:
        return {"child_acceleration": self.acceleration.tolist()}

    def load(self, state: dict[str, Any]) -> None:
        if "child_acceleration" in state:
            self.acceleration = _vec_rows(state["child_acceleration"], len(self.acceleration))


class ShearTraction:
    """Coarse -> fine: per interface face whose cell holds both levels, the tangential part of
    the parent's traction t = sigma n (sigma the parent's cell stress, compressive positive, n the
    face's inward normal) times the face's area, spread over the child's mass in the face's cell
    as an acceleration (a body force standing for a surface traction, like the boundary velocity
    condition's). ``gain`` scales it (0 switches it off)."""

    def __init__(self, gain: float, grid: dict[str, Any]) -> None:
        self.gain = gain
        self.acceleration = np.zeros((len(grid["inside"]), 3))
        self.area = np.asarray(grid["face_area"], float)

    @property
    def active(self) -> bool:
        return self.gain > 0

    def update(
        self, grid: dict[str, Any], parent: dict[str, Any], child: dict[str, Any], interval: float
    ) -> None:
        cells = grid["face_cell"].astype(int)
        normal = np.asarray(grid["face_normal"], float)
        traction = np.einsum("kij,kj->ki", np.asarray(parent["stress"])[cells], normal)
        shear = traction - np.einsum("ki,ki->k", traction, normal)[:, None] * normal
        mass = np.asarray(child["mass"], float)
        held = (np.asarray(parent["mass"])[cells] > 0) & (mass[cells] > 0)
        force = np.zeros_like(self.acceleration)
        np.add.at(force, cells[held], self.gain * shear[held] * self.area[held, None])
        with np.errstate(divide="ignore", invalid="ignore"):
            self.acceleration = np.where(mass[:, None] > 0, force / mass[:, None], 0.0)

    def state(self) -> dict[str, Any]:
        return {"shear_acceleration": self.acceleration.tolist()}

    def load(self, state: dict[str, Any]) -> None:
        if "shear_acceleration" in state:
            self.acceleration = _vec_rows(state["shear_acceleration"], len(self.acceleration))


class StressBoundary:
    """Coarse -> fine: per interface face a PI controller (anti-windup by conditional
    integration, never pulling, at most PRESSURE_CAP x the parent's stress) whose pressure pushes
    the child's particles in a layer at the face (in total pressure x the face's area) so that
    the child's normal stress in the face's cell, counting the push's virial, follows the
    parent's; faces whose parent cell holds less than ``skip_ratio`` x the child's solid fraction
    are not controlled. A particle already moving inwards faster than the parent's fastest inward
    motion at the face (or, for a parent at rest, REST_SPEED_FRACTION x the free-fall speed over
    a fine diameter) is not pushed."""

    def __init__(
        self,
        gain: float,
        integral_gain: float,
        skip_ratio: float,
        rest_speed: float,
        grid: dict[str, Any],
    ) -> None:
        self.gain = gain
        self.integral_gain = integral_gain
        self.skip_ratio = skip_ratio
        self.rest_speed = rest_speed
        n = len(grid["face_cell"])
        self.integral = np.zeros(n)
        self.pressure = np.zeros(n)
        self.max_inward = np.zeros(n)
        # The pushed layer's virial per face (N m), summed over the interval's child samples.
        self.push_moment = np.zeros(n)
        self.push_samples = 0

    @property
    def active(self) -> bool:
        return self.gain > 0 or self.integral_gain > 0

    def sample(self, level: _core.Level, index: int) -> None:
        self.push_moment += level.coupling_push_moment(index)
        self.push_samples += 1

    def update(
        self, grid: dict[str, Any], parent: dict[str, Any], child: dict[str, Any], interval: float
    ) -> None:
        cells = grid["face_cell"].astype(int)
        axes = grid["face_axis"].astype(int)
        normal = grid["face_normal"]
        sc = parent["stress"][cells, axes, axes]
        # The child's stress counts the push as the contacts with the material beyond the face it
        # stands for (their virial, push force x distance from the face).
        volume = float(np.prod(grid["edge"]))
        key = cells * 3 + axes  # faces of one cell along one axis share its sigma_aa
        moment = np.zeros(3 * len(grid["inside"]))
        np.add.at(moment, key, self.push_moment)
        pushed = moment[key] / (max(self.push_samples, 1) * volume)
        self.push_moment[:] = 0.0
        self.push_samples = 0
        sf = child["stress"][cells, axes, axes] + pushed
        phi_c, phi_f = parent["solid_fraction"][cells], child["solid_fraction"][cells]
        active = (parent["mass"][cells] > 0) & (phi_c >= self.skip_ratio * phi_f)
        error = np.where(active, sc - sf, 0.0)
        trial = self.integral + error * interval
        p = self.gain * error + self.integral_gain * trial
        p_max = PRESSURE_CAP * np.maximum(sc, 0.0)
        saturated = ((p < 0) & (error < 0)) | ((p > p_max) & (error > 0)) | ~active
        self.integral = np.where(saturated, self.integral, trial)
        self.pressure = np.where(active, np.clip(p, 0.0, p_max), 0.0)
        extreme = np.where(normal > 0, parent["velocity_max"][cells], parent["velocity_min"][cells])
        coarse_in = np.einsum("ij,ij->i", extreme, normal)
        self.max_inward = np.maximum(coarse_in, self.rest_speed)

    def apply(self, level: _core.Level, index: int) -> None:
        level.set_coupling_pressure(index, self.pressure, self.max_inward)

    def state(self) -> dict[str, Any]:
        return {
            "integral": self.integral.tolist(),
            "pressure": self.pressure.tolist(),
            "max_inward": self.max_inward.tolist(),
        }

    def load(self, state: dict[str, Any]) -> None:
        self.integral = np.asarray(state["integral"], float)
        self.pressure = np.asarray(state["pressure"], float)
        self.max_inward = np.asarray(state["max_inward"], float)


def rest_speed(gravity: float, fine_diameter: float) -> float:
    """The stress push's speed limit (m/s) where the parent is at rest."""
    return REST_SPEED_FRACTION * math.sqrt(gravity * fine_diameter)


class Advance:
    """Exchange.advance: per face gravity points through into the region, below a dense parent
    bed (its cell's solid fraction at least ``min_fraction``), the child may place up to
    advance x (phi - phi_child) rho V per interval ahead of the flux, phi the smaller of the
    parent's solid fraction there and the child's one cell further in (its own packing away
    from the face)."""

    def __init__(self, fraction: float, min_fraction: float, grid: dict[str, Any]) -> None:
        self.fraction = fraction
        self.min_fraction = min_fraction
        n = len(grid["face_cell"])
        self.budget = np.zeros(n)  # kg per face, for the next insertion
        self.downward = np.zeros(n, bool)  # set by the hierarchy from gravity
        self.density = 0.0  # kg/m^3, set by the hierarchy
        # Per face, the cell next to its cell along the inward normal (its own cell at the
        # grid's edge).
        dims = np.asarray(grid["dims"])
        cell = grid["face_cell"].astype(int)
        ijk = np.stack([cell % dims[0], (cell // dims[0]) % dims[1], cell // (dims[0] * dims[1])])
        step = np.rint(grid["face_normal"]).astype(int).T
        ijk = np.clip(ijk + step, 0, (dims - 1)[:, None])
        self.inner_cells = ijk[0] + dims[0] * (ijk[1] + dims[1] * ijk[2])

    @property
    def active(self) -> bool:
        return self.fraction > 0

    def update(
        self, grid: dict[str, Any], parent: dict[str, Any], child: dict[str, Any], interval: float
    ) -> None:
        cells = grid["face_cell"].astype(int)
        phi_p, phi_c = parent["solid_fraction"][cells], child["solid_fraction"][cells]
        target = np.minimum(phi_p, child["solid_fraction"][self.inner_cells])
        dense = self.downward & (phi_p >= self.min_fraction)
        volume = float(np.prod(grid["edge"]))
        room = self.fraction * np.maximum(target - phi_c, 0.0) * self.density * volume
        self.budget = np.where(dense, room, 0.0)

    def state(self) -> dict[str, Any]:
        return {"advance": self.budget.tolist()}

    def load(self, state: dict[str, Any]) -> None:
        if "advance" in state:
            self.budget = np.asarray(state["advance"], float)


class Coupling:
    """One parent-child pair of a hierarchy: the C++ interface, its controllers and its books.

    The books (kg, cumulative): ``parent_discharged`` and ``parent_lost`` the parent's particles
    removed from the region by its outlets and through closed sides (seen by the flux meter),
    ``child_removed`` everything the child lost other than across the interface (its outlets,
    closed sides and the shadow it paid for its own children), ``paid`` the parent's particles
    removed to pay the child's discharge; ``debt = child_removed - parent_discharged -
    parent_lost - paid`` is what the parent's material in the region still owes (negative: it
    discharged ahead of the child)."""

    def __init__(self, parent: int, child: int, interface: _core.Interface, exchange: Any) -> None:
        self.parent = parent
        self.child = child
        self.interface = interface
        self.exchange = exchange
        self.grid = interface.grid()
        n_cells = len(self.grid["inside"])
        self.feedback = VelocityFeedback(
            exchange.velocity_gain, exchange.mass_flux_correction, n_cells
        )
        self.boundary_velocity = BoundaryVelocity(exchange.boundary_velocity_gain, n_cells)
        self.shear = ShearTraction(exchange.shear_traction, self.grid)
        self.stress: StressBoundary | None = None
        self.advance = Advance(exchange.advance, exchange.advance_min_fraction, self.grid)
        self.parent_coupling = -1
        self.child_coupling = -1
        self.region_outlet = -1
        self.flux: dict[str, Any] | None = None
        # Per face, the parent's Favre velocity in the face's cell over the last interval: given
        # to what is placed at the face (the bulk's velocity, not the crossings', Interface::book).
        self.beyond = np.zeros((len(self.grid["face_cell"]), 3))
        self.parent_fields: dict[str, Any] | None = None
        self.child_fields: dict[str, Any] | None = None
        self.parent_discharged = 0.0
        self.parent_lost = 0.0
        self.child_removed = 0.0
        self.paid = 0.0
        self.left_booked = np.zeros(len(self.grid["face_cell"]))
        # The child's discharge so far (kg m, kg) and where it discharged last (m; at first the
        # region's centre): the parent pays its debt nearest to it.
        self.discharge_moment = np.zeros(3)
        self.discharge_mass = 0.0
        g = self.grid
        self.discharge_point = np.asarray(g["origin"]) + 0.5 * np.asarray(g["dims"]) * np.asarray(
            g["edge"]
        )

    @property
    def debt(self) -> float:
        return self.child_removed - self.parent_discharged - self.parent_lost - self.paid

    def controllers(self) -> list[Any]:
        return [
            c
            for c in (self.feedback, self.boundary_velocity, self.shear, self.stress, self.advance)
            if c is not None
        ]

    def apply_controls(self, parent: _core.Level, child: _core.Level) -> None:
        if self.feedback.active:
            self.feedback.apply(parent, self.parent_coupling)
        # Both coarse -> fine body forces act on the child's boundary cells: one acceleration.
        held = [c.acceleration for c in (self.boundary_velocity, self.shear) if c.active]
        if held:
            child.set_coupling_acceleration(self.child_coupling, np.sum(held, axis=0))
        if self.stress is not None and self.stress.active:
            self.stress.apply(child, self.child_coupling)

    def update_controls(self, interval: float) -> None:
        pf, cf = self.parent_fields, self.child_fields
        assert pf is not None and cf is not None
        for controller in self.controllers():
            if controller.active:
                controller.update(self.grid, pf, cf, interval)
        self.beyond = np.asarray(pf["velocity"])[self.grid["face_cell"].astype(int)]

    def mass_excess(self) -> np.ndarray:
        """Per grid cell, how much more mass (kg) the parent held than the child over the last
        interval, in the interior cells (zero elsewhere: the boundary cells carry the parent's
        conditions to the child)."""
        if self.parent_fields is None or self.child_fields is None:
            return np.zeros(len(self.grid["inside"]))
        excess = np.asarray(self.parent_fields["mass"]) - np.asarray(self.child_fields["mass"])
        interior = (self.grid["inside"] > 0) & ~(self.grid["boundary"] > 0)
        return np.where(interior, excess, 0.0)

    def book_parent_interval(self, flux: dict[str, Any]) -> None:
        """The parent's removals in the region during the interval the meter just closed."""
        self.flux = flux
        self.parent_lost += float(flux["vanished_lost_mass"])
        self.parent_discharged += float(flux["vanished_mass"]) - float(flux["vanished_lost_mass"])

    def credit_leavers(self, child: _core.Level) -> None:
        """Owes back to the child what left its region through each face since the last call."""
        left = np.asarray(child.outlet_status(self.region_outlet)["removed_face_mass"], float)
        self.interface.credit(left - self.left_booked)
        self.left_booked = left

    def state(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for controller in self.controllers():
            out.update(controller.state())
        out.update(
            inserters=list(self.interface.inserter_states()),
            ledger=[
                self.parent_discharged,
                self.parent_lost,
                self.child_removed,
                self.paid,
                *self.discharge_moment,
                self.discharge_mass,
                *self.discharge_point,
            ],
            left_booked=self.left_booked.tolist(),
            beyond=self.beyond.tolist(),
        )
        return out

    def load(self, state: dict[str, Any]) -> None:
        for controller in self.controllers():
            controller.load(state)
        self.interface.load_inserter_states(state["inserters"])
        if state.get("flux") is not None:
            # Written before the ledger: the parent's last interval was fed to the child at the
            # start of the next one. Book it now (its inflow; outflow was not measured then).
            old = {k: np.asarray(v, float) for k, v in state["flux"].items()}
            none = {k: np.zeros_like(v) for k, v in old.items()}
            self.interface.book({"inward": old, "outward": none}, self.beyond)
        if "ledger" in state:  # written since the hierarchy keeps its books exactly
            ledger = [float(v) for v in state["ledger"]]
            self.parent_discharged, self.parent_lost, self.child_removed, self.paid = ledger[:4]
            self.discharge_moment = np.asarray(ledger[4:7])
            self.discharge_mass = ledger[7]
            self.discharge_point = np.asarray(ledger[8:11])
            self.left_booked = np.asarray(state["left_booked"], float)
            self.beyond = np.asarray(state["beyond"], float).reshape(-1, 3)
