"""CASES.md E1: exact scaling (Feng & Owen 2014, Comp. Part. Mech. 1:159).

System A: 200 polydisperse spheres of two materials thrown into a closed box (side planes, a
triangulated floor, a servo-controlled lid) under gravity, with three contact laws: Hertz-Mindlin
+ EPSD, linear (derived and explicit per-pair stiffness) + CDT, EEPA (derived and explicit k1,
cohesion) + EPSD2. System B = gs.scaling.scale(A, h, "exact"). The trajectories must obey
x_B(h t) = h x_A(t), v_B = v_A, omega_B = omega_A / h, F_B = h^2 F_A, torque_B = h^3 torque_A,
wall forces x h^2: bit-identical for h = 2 (gate 1e-12 relative over 20 000 steps), to 1e-9 for
h = 3 over the first 1000 steps. Error of an array: max |B / factor - A| / max |A|.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import grainscale as gs
from grainscale.contact import CDT, EEPA, EPSD, EPSD2, HertzMindlin, Linear, Pair
from grainscale.geometry import Mesh, Plane, Servo
from grainscale.scaling import ParameterSet, Particles, build_simulation, scale

# Soft materials (as often used to speed DEM up) so that 20 000 steps cover a dense, settling flow.
GLASS = gs.Material(density=2500, youngs_modulus=1e7, poisson_ratio=0.3, name="soft glass")
STEEL = gs.Material(density=7800, youngs_modulus=4e7, poisson_ratio=0.29, name="soft steel")
L, H_BOX = 0.04, 0.08  # box edge and height (m)
DT = 4e-6  # s; >= 24 steps per loading for the stiffest (EEPA k1 = 2 E* R*, steel-wall) contacts


def _laws() -> dict[str, gs.contact.ContactLaw]:
    mixed = (GLASS, STEEL)
    return {
        "hertz_epsd": HertzMindlin(
            restitution=0.6,
            friction=0.4,
            rolling=EPSD(0.1, 0.3),
            pairs={mixed: Pair(restitution=0.5, friction=0.3)},
        ),
        "linear_cdt": Linear(
            restitution=0.7,
            friction=0.5,
            rolling=CDT(0.05),
            characteristic_velocity=1.0,  # k_n derived from E*, R*, m* ...
            pairs={mixed: Pair(normal_stiffness=3e3, tangential_stiffness=1e3)},  # ... or given
        ),
        "eepa_epsd2": EEPA(
            restitution=0.5,
            friction=0.5,
            rolling=EPSD2(0.05),
            unloading_ratio=3.0,  # k1 = 2 E* R* (derived) ...
            adhesive_stiffness=50.0,
            pull_off_force=-2e-4,
            pairs={(GLASS, GLASS): Pair(loading_stiffness=5e3, pull_off_force=-1e-4)},  # ... given
        ),
    }


def _floor() -> Mesh:
    """The floor z = 0 as four triangles around the centre (coplanar edges to resolve)."""
    v = np.array([[0, 0, 0], [L, 0, 0], [L, L, 0], [0, L, 0], [L / 2, L / 2, 0]], dtype=float)
    t = np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]])
    return Mesh(vertices=v, triangles=t, material=STEEL)


def reference(law: gs.contact.ContactLaw) -> ParameterSet:
    rng = np.random.default_rng(5)
    spacing = 4.9e-3  # largest diameter 4.8 mm: neighbours collide at once
    grid = np.array([(i, j, k) for k in range(5) for j in range(7) for i in range(7)], dtype=float)[
        :200
    ]
    position = (grid + 0.6) * spacing + rng.uniform(-2e-4, 2e-4, (200, 3))
    radius = rng.uniform(1.6e-3, 2.4e-3, 200)
    velocity = rng.normal(0.0, 0.3, (200, 3))
    spin = rng.normal(0.0, 30.0, (200, 3))
    groups = [
        Particles(position[s], radius[s], mat, velocity=velocity[s], angular_velocity=spin[s])
        for s, mat in ((slice(0, 100), GLASS), (slice(100, 200), STEEL))
    ]
    walls = [
        Plane(point=(0, 0, 0), normal=(1, 0, 0)),
        Plane(point=(L, 0, 0), normal=(-1, 0, 0), material=GLASS),
        Plane(point=(0, 0, 0), normal=(0, 1, 0)),
        Plane(point=(0, L, 0), normal=(0, -1, 0)),
        _floor(),
        Plane(point=(0, 0, 0.035), normal=(0, 0, -1), material=GLASS),
    ]
    return ParameterSet(
        domain=gs.Box(lo=(0, 0, 0), hi=(L, L, H_BOX)),
        contact=law,
        gravity=(0.0, 0.0, -9.81),
        time_step=DT,
        skin=3e-4,
        walls=walls,
        servos={5: Servo(gain=0.5, max_speed=0.2, target_force=0.3)},
        particles=groups,
    )


def _state(sim: gs.Simulation) -> dict[str, np.ndarray]:
    with sim.particles(writable=False) as p:
        order = np.argsort(p.id)
        out = {
            name: np.array(getattr(p, name)[order])
            for name in ("position", "velocity", "angular_velocity", "force", "torque")
        }
    out["wall_force"] = np.array([sim.walls[k].force for k in range(6)])
    out["time"] = np.array([sim.time])
    return out


# quantity -> exponent of h (Feng & Owen): x_B = h x_A etc.
_EXPONENT = {
    "position": 1,
    "velocity": 0,
    "angular_velocity": -1,
    "force": 2,
    "torque": 3,
    "wall_force": 2,
    "time": 1,
}


def _error(a: np.ndarray, b: np.ndarray) -> float:
    """max |b - a| / max |a|; an all-zero reference needs an all-zero b."""
    diff = float(np.max(np.abs(b - a)))
    scale = float(np.max(np.abs(a)))
    return diff / scale if scale > 0 else (0.0 if diff == 0 else np.inf)


def _errors(a: dict[str, np.ndarray], b: dict[str, np.ndarray], h: float) -> dict[str, float]:
    return {name: _error(a[name], b[name] / h**p) for name, p in _EXPONENT.items()}


def _compare_runs(
    ref: ParameterSet, scaled: ParameterSet, h: float, outputs: list[int]
) -> tuple[float, int, dict[str, float]]:
    """Runs both systems to each output step; returns the worst error, the most contacts seen
    and the errors at the worst output."""
    a = build_simulation(ref)
    b = build_simulation(scaled)
    worst, worst_errors, contacts = 0.0, {}, 0
    done = 0
    for step in outputs:
        a.run(steps=step - done, progress=False)
        b.run(steps=step - done, progress=False)
        done = step
        assert a.num_particles == b.num_particles == 200, "particles were lost"
        errors = _errors(_state(a), _state(b), h)
        contacts = max(contacts, a.num_contacts())
        if max(errors.values()) >= worst:
            worst, worst_errors = max(errors.values()), errors
    return worst, contacts, worst_errors


@pytest.mark.parametrize("law_name", ["hertz_epsd", "linear_cdt", "eepa_epsd2"])
def test_e1_exact_scaling_h2_is_bit_identical(law_name: str) -> None:
    ref = reference(_laws()[law_name])
    scaled = scale(ref, 2.0, "exact")
    assert scaled.broken == []
    worst, contacts, errors = _compare_runs(ref, scaled.params, 2.0, [1, 2000, 5000, 10000, 20000])
    assert contacts > 50, f"{law_name}: too few contacts ({contacts}) for a meaningful test"
    assert worst <= 1e-12, f"{law_name}, h = 2: relative errors {errors}"


@pytest.mark.parametrize("law_name", ["hertz_epsd", "linear_cdt", "eepa_epsd2"])
def test_e1_exact_scaling_h3_first_1000_steps(law_name: str) -> None:
    ref = reference(_laws()[law_name])
    worst, _, errors = _compare_runs(ref, scale(ref, 3.0, "exact").params, 3.0, [1, 500, 1000])
    assert worst <= 1e-9, f"{law_name}, h = 3: relative errors {errors}"


def test_e1_detects_an_unscaled_term() -> None:
    """Negative control: the same comparison with gravity left unscaled fails by O(1e-3+)."""
    ref = reference(_laws()["hertz_epsd"])
    wrong = dataclasses.replace(scale(ref, 2.0, "exact").params, gravity=ref.gravity)
    worst, _, _ = _compare_runs(ref, wrong, 2.0, [1, 1000])
    assert worst > 1e-4
