"""One biaxial test of a 2-D disc specimen (validation/CASES.md E2, Zhang, Huang & Zhao 2021).

A specimen of discs (unit thickness, ``Simulation(dimension=2)``) is packed loosely in a
rectangle, compacted isotropically by four servo walls to the confining stress (frictionless
grains, so that it gets dense), then, with the grains' friction switched on, loaded at a constant
axial strain rate by the top and bottom walls while the lateral walls hold the confining stress.
Stresses are per unit thickness: wall force / (wall length x 1 m).

The coarse-grained specimen of scale h has the same size, radii x h and the cg parameters of
``cg_parameters`` below (from ``grainscale.scaling``); see biaxial.py for the study over h and
samples.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

import grainscale as gs

# Wall order in every simulation: left, right, bottom, top (inward normals).
NORMALS = ((1.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, -1.0, 0.0))


@dataclass(frozen=True)
class BiaxialCase:
    """Reference (h = 1) specimen and loading; SI units, stresses per unit thickness (Pa)."""

    width: float = 0.036  # m, final width of the consolidated specimen (approximately)
    height: float = 0.072  # m, aspect ratio 2 as in Zhang et al. (6 x 12); 9 d wide at h = 4
    mean_radius: float = 0.5e-3  # m, Gaussian radii (Zhang et al.), std / mean below
    radius_cv: float = 0.15
    density: float = 2650.0  # kg/m^3
    law: Literal["linear", "hertz"] = "linear"  # linear: PFC2D's default contact model
    normal_stiffness: float = 1e8  # N/m (linear), k_t = k_n / 2
    youngs_modulus: float = 2e12  # Pa (hertz: the sphere law on 1 m thick discs needs it huge)
    poisson_ratio: float = 0.25
    restitution: float = 0.3
    compaction_restitution: float = 0.1  # more damping while compacting: settles sooner
    friction: float = 0.5  # grains during loading; 0 during compaction; walls frictionless
    confining_stress: float = 1e5  # Pa
    strain_rate: float = 1.0  # 1/s: inertial number eps' d sqrt(rho/p) = 1.6e-4 at h = 1
    max_strain: float = 0.02
    loose_fraction: float = 0.52  # area fraction of the initial random packing
    dense_fraction: float = 0.82  # expected after compaction (sizes the loose rectangle)
    records: int = 80  # samples of the loading curve
    rest_speed: float = 2.4e-4  # m/s, mean grain speed below which a specimen is at rest


def cg_parameters(case: BiaxialCase, h: float) -> dict[str, float]:
    """The cg rule for discs of unit thickness at scale h (same specimen, radii x h), from
    ``grainscale.scaling.scale(..., "cg", dimension=2)``.

    Per unit thickness (Feng & Owen 2014; Zhang et al. 2021 eq. 35) force scales as h and
    stress as 1: a linear spring k = F/delta is invariant; the Hertz sphere law F = 4/3 E*
    sqrt(R*) delta^(3/2) on a disc gives F ~ E h^2, so the module scales E as 1/h. Restitution
    and friction are invariant (the dashpot follows from e and m*); the time step scales as h.
    """
    m1 = case.density * math.pi * case.mean_radius**2
    # Contact time of two mean discs, pi sqrt(m*/k); 1/15 of it per step.
    dt1 = math.pi * math.sqrt(0.5 * m1 / contact_stiffness(case)) / 15.0
    grain = gs.Material(
        density=case.density, youngs_modulus=case.youngs_modulus, poisson_ratio=case.poisson_ratio
    )
    law: gs.contact.ContactLaw = (
        gs.contact.Linear(normal_stiffness=case.normal_stiffness)
        if case.law == "linear"
        else gs.contact.HertzMindlin()
    )
    reference = gs.scaling.ParameterSet(
        domain=gs.Box(lo=(0.0, 0.0, -0.01), hi=(case.width, case.height, 0.01)),
        contact=law,
        gravity=(0.0, 0.0, 0.0),
        time_step=dt1,
        size=gs.dist.Monodisperse(case.mean_radius),
        materials=[grain],
    )
    scaled = gs.scaling.scale(reference, h, "cg", dimension=2).params
    size = scaled.size
    assert isinstance(size, gs.dist.Monodisperse) and scaled.time_step is not None
    return {
        "radius": size.radius,
        "normal_stiffness": getattr(scaled.contact, "normal_stiffness", case.normal_stiffness),
        "youngs_modulus": scaled.materials[0].youngs_modulus,
        "time_step": scaled.time_step,
    }


def contact_stiffness(case: BiaxialCase) -> float:
    """Normal contact stiffness (N/m) of the reference: k_n (linear), or the Hertz stiffness
    dF/d(delta) = 3/2 F/delta at the typical contact force sigma d (invariant under the cg rule:
    F and delta both scale as h)."""
    if case.law == "linear":
        return case.normal_stiffness
    f0 = case.confining_stress * 2 * case.mean_radius
    e_star = case.youngs_modulus / (2 * (1 - case.poisson_ratio**2))
    delta = (f0 / (4.0 / 3.0 * e_star * math.sqrt(0.5 * case.mean_radius))) ** (2.0 / 3.0)
    return 1.5 * f0 / delta


def contact_law(
    case: BiaxialCase, friction: float, restitution: float, grain: gs.Material
) -> gs.contact.ContactLaw:
    """The law, with frictionless walls for grains of material ``grain``."""
    pairs = {(grain, None): gs.contact.Pair(friction=0.0)}
    if case.law == "linear":
        k = case.normal_stiffness
        return gs.contact.Linear(
            normal_stiffness=k,
            tangential_stiffness=0.5 * k,
            restitution=restitution,
            friction=friction,
            pairs=pairs,
        )
    return gs.contact.HertzMindlin(restitution=restitution, friction=friction, pairs=pairs)


@dataclass
class Specimen:
    """Particles and wall positions of a consolidated specimen."""

    position: np.ndarray
    radius: np.ndarray
    walls: np.ndarray  # x_left, x_right, y_bottom, y_top (m)


def _simulation(
    case: BiaxialCase, h: float, friction: float, restitution: float, walls: np.ndarray
) -> tuple[gs.Simulation, gs.Material]:
    p = cg_parameters(case, h)
    grain = gs.Material(
        density=case.density,
        youngs_modulus=p["youngs_modulus"],
        poisson_ratio=case.poisson_ratio,
    )
    margin = 0.25 * max(walls[1] - walls[0], walls[3] - walls[2])
    domain = gs.Box(
        lo=(walls[0] - margin, walls[2] - margin, -0.01),
        hi=(walls[1] + margin, walls[3] + margin, 0.01),
    )
    law = contact_law(case, friction, restitution, grain)
    sim = gs.Simulation(
        domain=domain,
        contact=law,
        gravity=(0.0, 0.0, 0.0),
        time_step=p["time_step"],
        force_time_step=True,  # the step comes from the contact time, not the Rayleigh time
        dimension=2,
        quiet=True,
        record_contacts=True,
    )
    for k, n in enumerate(NORMALS):
        point = (walls[k], 0.0, 0.0) if k < 2 else (0.0, walls[k], 0.0)
        sim.add_wall(gs.Plane(point=point, normal=n))
    return sim, grain


def wall_positions(sim: gs.Simulation) -> np.ndarray:
    return np.array([sim.walls[k].position[0 if k < 2 else 1] for k in range(4)])


def wall_stresses(sim: gs.Simulation) -> np.ndarray:
    """Normal stress (Pa, per unit thickness) on left, right, bottom, top."""
    w = wall_positions(sim)
    width, height = w[1] - w[0], w[3] - w[2]
    loads = np.array([-np.dot(sim.walls[k].force, NORMALS[k]) for k in range(4)])
    return loads / np.array([height, height, width, width])


def _servo_gain(case: BiaxialCase, h: float, restitution: float) -> float:
    """Gain ((m/s)/N) of an explicit servo that is stable: the load responds within one step
    to the wall's displacement through ~L/d contact springs in parallel (stiffness n k) and to
    its velocity through their dashpots (n c, c = 2 zeta sqrt(k m), zeta from e). A tenth of
    the spring limit and a third of the dashpot limit keep the wall from chattering."""
    p = cg_parameters(case, h)
    n = 1.2 * max(case.width, case.height) / (2 * p["radius"])
    k = contact_stiffness(case)
    mass = case.density * math.pi * p["radius"] ** 2
    zeta = -math.log(restitution) / math.sqrt(math.log(restitution) ** 2 + math.pi**2)
    c = 2 * zeta * math.sqrt(k * mass)
    return min(0.1 / (n * k * p["time_step"]), 0.3 / (n * c))


class Confinement:
    """Servo walls at the confining stress x current wall length (x 1 m).

    A proportional servo lags by v / gain at a steady wall speed v, which at a stable gain is
    tens of per cent. This study adds an integral term between chunks: the commanded force is
    corrected by the measured stress error, so the mean error goes to zero. (The core now has a
    PI servo, ``Servo.integral_gain``; the study keeps its chunked integral so that its
    committed results reproduce.)
    """

    def __init__(self, case: BiaxialCase, h: float, restitution: float, walls: range) -> None:
        self.stress = case.confining_stress
        self.gain = _servo_gain(case, h, restitution)
        self.walls = walls
        self.correction = np.zeros(4)  # Pa, added to the target stress

    def update(self, sim: gs.Simulation, integrate: bool = True, approach: bool = False) -> None:
        """integrate: add the integral correction; approach: a wall carrying less than 10 % of
        the target moves at its full speed (the stable gain alone would crawl)."""
        w = wall_positions(sim)
        lengths = (w[3] - w[2], w[3] - w[2], w[1] - w[0], w[1] - w[0])
        stress = wall_stresses(sim)
        if integrate:
            error = self.stress - stress
            self.correction = np.clip(self.correction + 0.5 * error, -self.stress, self.stress)
        for k in self.walls:
            # the axial walls travel twice as far while compacting: keeps the aspect
            max_speed = 0.25 if k < 2 else 0.5
            target = (self.stress + self.correction[k]) * lengths[k]
            if approach and stress[k] < 0.1 * self.stress:
                target = max(target, max_speed / self.gain)
            sim.walls[k].servo = gs.geometry.Servo(
                target_force=target, gain=self.gain, max_speed=max_speed
            )


def prepare(case: BiaxialCase, h: float, seed: int) -> Specimen:
    """Random loose packing compacted by four servo walls to the confining stress."""
    p = cg_parameters(case, h)
    shrink = math.sqrt(case.dense_fraction / case.loose_fraction)
    walls = np.array([0.0, case.width * shrink, 0.0, case.height * shrink])
    sim, grain = _simulation(case, h, 0.0, case.compaction_restitution, walls)
    r = p["radius"]
    dist = gs.dist.Normal(mean=r, std=case.radius_cv * r)
    region = gs.Box(lo=(walls[0], walls[2], -0.005), hi=(walls[1], walls[3], 0.005))
    sim.insert(
        gs.insert.Pack(
            region, radius=dist, material=grain, volume_fraction=case.loose_fraction, seed=seed
        )
    )
    servo = Confinement(case, h, case.compaction_restitution, range(4))
    chunk = max(1, int(round(1e-4 / p["time_step"])))
    for _ in range(8000):
        servo.update(sim, integrate=False, approach=True)  # at rest a P servo has no lag
        sim.run(steps=chunk, progress=False)
        s = wall_stresses(sim)
        with sim.particles(writable=False) as view:
            v_mean = float(np.mean(np.linalg.norm(view.velocity, axis=1)))
        # Converged: every wall within 1 % and the grains at rest on average (a few rattlers
        # in their cages may still move); the default rest speed is 1 % of the axial walls'
        # loading speed.
        if np.all(np.abs(s / case.confining_stress - 1) < 0.01) and v_mean < case.rest_speed:
            break
    else:
        raise RuntimeError(f"biaxial specimen h={h} seed={seed} did not consolidate")
    with sim.particles(writable=False) as view:
        return Specimen(view.position.copy(), view.radius.copy(), wall_positions(sim))


def load(case: BiaxialCase, h: float, specimen: Specimen) -> dict[str, Any]:
    """Strain-controlled axial loading at constant lateral stress; returns the curves."""
    p = cg_parameters(case, h)
    sim, grain = _simulation(case, h, case.friction, case.restitution, specimen.walls)
    sim.add_particles(position=specimen.position, radius=specimen.radius, material=grain)
    w0 = specimen.walls
    h0 = w0[3] - w0[2]
    speed = case.strain_rate * h0  # closing speed of the two axial walls together
    sim.walls[2].set_motion(velocity=(0.0, 0.5 * speed, 0.0))
    sim.walls[3].set_motion(velocity=(0.0, -0.5 * speed, 0.0))
    servo = Confinement(case, h, case.restitution, range(2))
    total = int(round(case.max_strain / case.strain_rate / p["time_step"]))
    # Servo targets follow the height every few steps (the height shrinks by 5e-5 meanwhile).
    chunk = max(1, int(round(5e-5 / case.strain_rate / p["time_step"])))
    record_every = chunk * max(1, total // (case.records * chunk))
    out: dict[str, list[float]] = {
        k: [] for k in ("strain", "deviator", "lateral", "volumetric", "mean_force", "contacts")
    }
    step = 0
    while step < total:
        n = min(chunk, total - step)
        servo.update(sim, integrate=step > 0)
        sim.run(steps=n, progress=False)
        step += n
        if step % record_every and step != total:
            continue
        w = wall_positions(sim)
        s = wall_stresses(sim)
        c = sim.contacts()
        pairs = c["id_j"] >= 0
        fn = np.abs(np.einsum("ij,ij->i", c["force"][pairs], c["normal"][pairs]))
        area0 = (w0[1] - w0[0]) * h0
        out["strain"].append(1.0 - (w[3] - w[2]) / h0)
        out["deviator"].append(0.5 * (s[2] + s[3]) - 0.5 * (s[0] + s[1]))
        out["lateral"].append(0.5 * (s[0] + s[1]))
        out["volumetric"].append(1.0 - (w[1] - w[0]) * (w[3] - w[2]) / area0)
        out["mean_force"].append(float(fn.mean()) if fn.size else 0.0)
        out["contacts"].append(int(pairs.sum()))
    return {
        "particles": int(specimen.radius.size),
        "width": float(w0[1] - w0[0]),
        "height": float(h0),
        "area_fraction": float(np.sum(math.pi * specimen.radius**2) / ((w0[1] - w0[0]) * h0)),
        "time_step": p["time_step"],
        **{k: np.asarray(v).tolist() for k, v in out.items()},
    }


def run_sample(case: BiaxialCase, h: float, seed: int) -> dict[str, Any]:
    """Prepare and load one specimen of scale h (seed: its random packing)."""
    result = load(case, h, prepare(case, h, seed))
    return {"h": h, "seed": seed, "case": dataclasses.asdict(case), **result}
