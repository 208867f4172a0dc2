"""Shared fixtures for the physics and unit tests.

* ``materials``: the materials of the Chung & Ooi benchmark set (CASES.md B0), keyed by name.
* ``hertz_pair``: effective pair quantities and the elastic Hertz closed form (CASES.md A1).
* ``run_impact``: drives a single two-body normal impact (sphere-sphere or sphere-rigid plane)
  and returns the time series of overlap, normal force and normal velocity.

Conventions follow CASES.md section 0: compression positive,
overlap delta = r_i + r_j - |x_i - x_j|,
rigid wall: E* = E/(1 - nu^2), G* = G/(2 - nu), R* = r, m* = m.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pytest

import grainscale as gs
from grainscale.parallel import launched_ranks

# tests/mpi run under mpirun (`make test` starts them on 2 and on 3 ranks); a serial run skips them.
collect_ignore = [] if launched_ranks() > 1 else ["mpi"]

# Hertz duration integral I = int_0^1 dx / sqrt(1 - x^(5/2)) (CASES.md A1):
# t_c = 2 I delta_max / v0.
HERTZ_DURATION_INTEGRAL = 1.471638

# CASES.md B0: E (Pa), nu, rho (kg/m^3).
_B0_MATERIALS = {
    "glass": (48e9, 0.20, 2800.0),  # Test 1
    "limestone": (20e9, 0.25, 2500.0),  # Test 1
    "al_alloy_t2": (70e9, 0.30, 2699.0),  # Test 2 (Al alloy with nu = 0.30)
    "mg_alloy": (40e9, 0.35, 1800.0),  # Test 2
    "al_oxide": (380e9, 0.23, 4000.0),  # Tests 3, 4
    "cast_iron": (100e9, 0.25, 7000.0),  # Test 3
    "al_alloy": (70e9, 0.33, 2700.0),  # Tests 4, 6, 7, 8
    "copper": (120e9, 0.35, 8900.0),  # Test 7
    "nylon": (2.5e9, 0.40, 1000.0),  # Tests 6, 8
    "steel": (208e9, 0.30, 7850.0),  # Test 5
    "polyethylene": (1.0e9, 0.40, 1400.0),  # Test 5
}


@pytest.fixture(scope="session")
def materials() -> dict[str, gs.Material]:
    return {
        name: gs.Material(density=rho, youngs_modulus=e, poisson_ratio=nu, name=name)
        for name, (e, nu, rho) in _B0_MATERIALS.items()
    }


def sphere_mass(material: gs.Material, radius: float) -> float:
    return material.density * 4.0 / 3.0 * math.pi * radius**3


@dataclass(frozen=True)
class HertzPair:
    """Effective quantities of a pair and the elastic Hertz closed form (CASES.md A1)."""

    youngs: float  # E*
    shear: float  # G*
    radius: float  # R*
    mass: float  # m*

    @property
    def stiffness(self) -> float:
        """K in F = K delta^(3/2), K = (4/3) E* sqrt(R*)."""
        return 4.0 / 3.0 * self.youngs * math.sqrt(self.radius)

    def force(self, overlap):
        """Elastic Hertz force (4/3) E* sqrt(R*) delta^(3/2) (0 for delta <= 0)."""
        return self.stiffness * np.clip(overlap, 0.0, None) ** 1.5

    def potential_energy(self, overlap):
        """Elastic energy (8/15) E* sqrt(R*) delta^(5/2)."""
        return 0.4 * self.stiffness * np.clip(overlap, 0.0, None) ** 2.5

    def max_overlap(self, v0: float) -> float:
        return (15.0 * self.mass * v0**2 / (16.0 * self.youngs * math.sqrt(self.radius))) ** 0.4

    def max_force(self, v0: float) -> float:
        return self.stiffness * self.max_overlap(v0) ** 1.5

    def contact_time(self, v0: float) -> float:
        return 2.0 * HERTZ_DURATION_INTEGRAL * self.max_overlap(v0) / v0


def _hertz_pair(
    material: gs.Material,
    radius: float,
    other: tuple[gs.Material, float] | None = None,
) -> HertzPair:
    """Pair quantities of a sphere with ``other`` = (material, radius) or a rigid wall (None)."""
    e1, nu1 = material.youngs_modulus, material.poisson_ratio
    m1 = sphere_mass(material, radius)
    if other is None:
        return HertzPair(
            youngs=e1 / (1.0 - nu1**2),
            shear=material.shear_modulus / (2.0 - nu1),
            radius=radius,
            mass=m1,
        )
    mat2, r2 = other
    e2, nu2 = mat2.youngs_modulus, mat2.poisson_ratio
    m2 = sphere_mass(mat2, r2)
    return HertzPair(
        youngs=1.0 / ((1.0 - nu1**2) / e1 + (1.0 - nu2**2) / e2),
        shear=1.0 / (2.0 * (2.0 - nu1) * (1.0 + nu1) / e1 + 2.0 * (2.0 - nu2) * (1.0 + nu2) / e2),
        radius=radius * r2 / (radius + r2),
        mass=m1 * m2 / (m1 + m2),
    )


@pytest.fixture(scope="session")
def hertz_pair():
    return _hertz_pair


@dataclass
class ImpactResult:
    """Time series of a two-body normal impact.

    Body 1 is the sphere that the force refers to; body 2 is the second sphere or the wall.
    ``overlap`` is computed from the positions; ``force_n`` is the normal component of the total
    force on body 1 (compression positive); ``approach_speed`` is the relative normal velocity
    (positive while approaching). Records are taken at t = 0, after every step inside the record
    windows and after every bulk run outside them.
    """

    time_step: float
    v_in: float
    t: np.ndarray
    step: np.ndarray
    overlap: np.ndarray
    force_n: np.ndarray
    approach_speed: np.ndarray
    velocity: np.ndarray  # (records, bodies, 3)
    angular_velocity: np.ndarray  # (records, bodies, 3)
    force: np.ndarray  # (records, bodies, 3) total force on each sphere
    contact_force: np.ndarray  # (records, 3) force on body 1 from sim.contacts() (0 if none)
    contact_normal: np.ndarray  # (records, 3) contact normal from sim.contacts() (0 if none)
    contact_overlap: np.ndarray  # (records,) overlap from sim.contacts() (0 if none)
    num_contacts: np.ndarray  # (records,) sim.num_contacts()
    notes: list[str] = field(default_factory=list)

    @property
    def v_out(self) -> float:
        """Separation speed at the end of the run (positive when the bodies move apart)."""
        return float(-self.approach_speed[-1])

    @property
    def restitution(self) -> float:
        return self.v_out / self.v_in

    def _crossing(self, y: np.ndarray, what: str, extrapolate: bool) -> float:
        """Time at which y first drops to <= 0 after having been > 0 (linear in time).

        The bracketing records must be one step apart, otherwise NaN is returned (crossing hidden
        in a bulk run outside the record windows). With ``extrapolate`` the value is
        extrapolated from the last two positive records (for clamped quantities that sit at 0).
        """
        positive = np.nonzero(y > 0)[0]
        if positive.size == 0:
            self.notes.append(f"{what}: never positive")
            return math.nan
        after = np.nonzero((y <= 0) & (np.arange(y.size) > positive[0]))[0]
        if after.size == 0:
            self.notes.append(f"{what}: never returned to <= 0")
            return math.nan
        k = after[0]
        if self.step[k] - self.step[k - 1] != 1:
            self.notes.append(
                f"{what}: crossing between steps {self.step[k - 1]} and {self.step[k]} "
                "lies outside the per-step record windows"
            )
            return math.nan
        dt = self.time_step
        if extrapolate and k >= 2 and self.step[k - 1] - self.step[k - 2] == 1:
            slope = y[k - 1] - y[k - 2]
            frac = y[k - 1] / -slope if slope < 0 else 0.5
            return float(self.t[k - 1] + dt * min(max(frac, 0.0), 1.0))
        return float(self.t[k - 1] + dt * y[k - 1] / (y[k - 1] - y[k]))

    def contact_end_time(self) -> float:
        """Time at which the geometric overlap returns to zero."""
        return self._crossing(self.overlap, "overlap", extrapolate=False)

    def force_end_time(self) -> float:
        """Time at which the normal force first returns to zero (no-tension contact end)."""
        return self._crossing(self.force_n, "normal force", extrapolate=True)


def _run_impact(
    law,
    material: gs.Material,
    radius: float,
    v0: float,
    *,
    time_step: float,
    duration: float,
    other: tuple[gs.Material, float] | None = None,
    angular_velocity: Sequence[Sequence[float]] | None = None,
    record_windows: Sequence[tuple[float, float]] | None = None,
    record_contacts: bool = False,
) -> ImpactResult:
    """Normal impact at approach speed v0, bodies exactly touching at t = 0, no gravity.

    other=None: sphere at (0, 0, R) moving at -v0 ez onto the rigid plane z = 0 (normal +ez).
    other=(material2, radius2): sphere 1 at (-R1, 0, 0), sphere 2 at (R2, 0, 0), velocities
    +v0 m2/(m1+m2) and -v0 m1/(m1+m2) along ex (zero total momentum).
    angular_velocity: one (3,) vector per sphere. record_windows: time intervals (s) recorded
    every step; None records every step of the run. The run lasts round(duration / time_step)
    steps.
    """
    two_spheres = other is not None
    if two_spheres:
        mat2, r2 = other
        m1, m2 = sphere_mass(material, radius), sphere_mass(mat2, r2)
        x = np.array([[-radius, 0.0, 0.0], [r2, 0.0, 0.0]])
        v = np.array([[v0 * m2 / (m1 + m2), 0.0, 0.0], [-v0 * m1 / (m1 + m2), 0.0, 0.0]])
        half = 4.0 * (radius + r2) + 2.0 * v0 * duration
    else:
        x = np.array([[0.0, 0.0, radius]])
        v = np.array([[0.0, 0.0, -v0]])
        half = 4.0 * radius + 2.0 * v0 * duration
    w = np.zeros_like(x) if angular_velocity is None else np.asarray(angular_velocity, float)
    sim = gs.Simulation(
        record_contacts=True,
        domain=gs.Box(lo=(-half, -half, -half), hi=(half, half, half)),
        contact=law,
        gravity=(0.0, 0.0, 0.0),
        time_step=time_step,
        thermo_every=10**9,
    )
    if two_spheres:
        ids = [
            int(
                sim.add_particles(
                    position=x[:1],
                    radius=radius,
                    material=material,
                    velocity=v[:1],
                    angular_velocity=w[:1],
                )[0]
            ),
            int(
                sim.add_particles(
                    position=x[1:], radius=r2, material=mat2, velocity=v[1:], angular_velocity=w[1:]
                )[0]
            ),
        ]
    else:
        ids = [
            int(
                sim.add_particles(
                    position=x, radius=radius, material=material, velocity=v, angular_velocity=w
                )[0]
            )
        ]
        sim.add_wall(gs.geometry.Plane(point=(0, 0, 0), normal=(0, 0, 1), material=None))

    rec: dict[str, list] = {
        k: []
        for k in (
            "t",
            "step",
            "overlap",
            "force_n",
            "approach",
            "vel",
            "omega",
            "force",
            "cforce",
            "cnormal",
            "coverlap",
            "ncontacts",
        )
    }

    def record(step: int) -> None:
        with sim.particles() as p:
            row = {int(k): r for r, k in enumerate(p.id)}
            rows = [row[i] for i in ids]
            pos = np.array(p.position[rows])
            vel = np.array(p.velocity[rows])
            rec["omega"].append(np.array(p.angular_velocity[rows]))
            rec["force"].append(np.array(p.force[rows]))
        if two_spheres:
            d = pos[0] - pos[1]
            dist = float(np.linalg.norm(d))
            n = d / dist
            overlap = radius + r2 - dist
            approach = -float(np.dot(vel[0] - vel[1], n))
        else:
            n = np.array([0.0, 0.0, 1.0])
            overlap = radius - float(pos[0, 2])
            approach = -float(vel[0, 2])
        rec["t"].append(step * time_step)
        rec["step"].append(step)
        rec["overlap"].append(overlap)
        rec["force_n"].append(float(np.dot(rec["force"][-1][0], n)))
        rec["approach"].append(approach)
        rec["vel"].append(vel)
        cf, cn, co = np.zeros(3), np.zeros(3), 0.0
        if record_contacts:
            c = sim.contacts()
            for k in range(len(c["id_i"])):
                i, j = int(c["id_i"][k]), int(c["id_j"][k])
                if i == ids[0] and (j == (ids[1] if two_spheres else -1)):
                    cf, cn, co = c["force"][k], c["normal"][k], float(c["overlap"][k])
                elif two_spheres and i == ids[1] and j == ids[0]:
                    cf, cn, co = -c["force"][k], -c["normal"][k], float(c["overlap"][k])
        rec["cforce"].append(np.array(cf, float))
        rec["cnormal"].append(np.array(cn, float))
        rec["coverlap"].append(co)
        rec["ncontacts"].append(sim.num_contacts())

    n_steps = int(round(duration / time_step))
    if record_windows is None:
        windows = [(0, n_steps)]
    else:
        windows = sorted(
            (max(0, int(math.floor(a / time_step))), min(n_steps, int(math.ceil(b / time_step))))
            for a, b in record_windows
        )
    record(0)
    done = 0
    while done < n_steps:
        if any(a <= done < b for a, b in windows):
            sim.run(steps=1)
            done += 1
        else:
            starts = [a for a, _ in windows if a > done]
            target = min(starts + [n_steps])
            sim.run(steps=target - done)
            done = target
        record(done)
    if sim.step != n_steps:
        raise AssertionError(f"sim.step = {sim.step}, expected {n_steps}")

    return ImpactResult(
        time_step=time_step,
        v_in=v0,
        t=np.array(rec["t"]),
        step=np.array(rec["step"]),
        overlap=np.array(rec["overlap"]),
        force_n=np.array(rec["force_n"]),
        approach_speed=np.array(rec["approach"]),
        velocity=np.array(rec["vel"]),
        angular_velocity=np.array(rec["omega"]),
        force=np.array(rec["force"]),
        contact_force=np.array(rec["cforce"]),
        contact_normal=np.array(rec["cnormal"]),
        contact_overlap=np.array(rec["coverlap"]),
        num_contacts=np.array(rec["ncontacts"]),
    )


@pytest.fixture(scope="session")
def run_impact():
    return _run_impact
