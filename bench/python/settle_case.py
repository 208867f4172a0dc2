"""Definition of the 'settle' benchmark case, shared by the driver and the grainscale worker.

N monodisperse glass-like spheres (d = 2 mm, rho = 2500 kg/m^3) start on a simple-cubic lattice
(spacing 2.2 mm) in a closed box of six plane walls and settle under gravity. The square
cross-section has n_side = ceil((N/2)^(1/3)) sites per edge; layers are filled bottom-up, row by
row, and the last layer may be partial. Lattice sites get a seeded uniform jitter of +-0.05 mm in
x and y and a seeded uniform initial velocity of +-0.05 m/s per component (no spin). The box is
n_side * 2.2 mm wide and n_layers * 2.2 mm + 2.2 mm high; the first layer's centres are 1.1 mm
above the floor. Contact law: Hertz-Mindlin with tangential history, E = 1e7 Pa, nu = 0.3,
e = 0.5, mu = 0.5 for particle pairs and particle-wall contacts (walls of the particle material).
dt = 1e-5 s, neighbour skin 0.2 mm, gravity 9.81 m/s^2 along -z.

This module only uses numpy so that it can be imported without grainscale being built.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class SettleCase:
    """Parameters of one 'settle' run (SI units)."""

    n_particles: int
    steps: int = 4000
    seed: int = 12345
    diameter: float = 2.0e-3
    density: float = 2500.0
    spacing: float = 2.2e-3
    jitter: float = 0.05e-3
    initial_speed: float = 0.05
    youngs_modulus: float = 1.0e7
    poisson_ratio: float = 0.3
    restitution: float = 0.5
    friction: float = 0.5
    time_step: float = 1.0e-5
    skin: float = 0.2e-3
    gravity: float = 9.81
    # grainscale's spring rotation: "project" is LIGGGHTS' tangential history model (the spring
    # projected onto the new tangent plane), "rescale" grainscale's default (length kept)
    spring_rotation: str = "project"

    @property
    def n_side(self) -> int:
        """Lattice sites per edge of the square cross-section: ceil((N/2)^(1/3)), exact."""
        n = max(1, math.ceil((self.n_particles / 2.0) ** (1.0 / 3.0)))
        while n > 1 and 2 * (n - 1) ** 3 >= self.n_particles:  # guard against round-off
            n -= 1
        while 2 * n**3 < self.n_particles:
            n += 1
        return n

    @property
    def n_layers(self) -> int:
        per_layer = self.n_side**2
        return -(-self.n_particles // per_layer)

    @property
    def box_hi(self) -> tuple[float, float, float]:
        """Upper corner of the box; the lower corner is the origin."""
        side = self.n_side * self.spacing
        return (side, side, self.n_layers * self.spacing + self.spacing)

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d.update(n_side=self.n_side, n_layers=self.n_layers, box_hi=list(self.box_hi))
        return d


def initial_state(case: SettleCase) -> tuple[FloatArray, FloatArray]:
    """Return (positions, velocities), both (N, 3) float64, for the seeded lattice."""
    n = case.n_particles
    ns = case.n_side
    site = np.arange(n, dtype=np.int64)
    layer, in_layer = np.divmod(site, ns * ns)
    row, col = np.divmod(in_layer, ns)
    half = 0.5 * case.spacing
    pos = np.empty((n, 3), dtype=np.float64)
    pos[:, 0] = col * case.spacing + half
    pos[:, 1] = row * case.spacing + half
    pos[:, 2] = layer * case.spacing + half
    rng = np.random.default_rng(case.seed)
    pos[:, :2] += rng.uniform(-case.jitter, case.jitter, size=(n, 2))
    vel = rng.uniform(-case.initial_speed, case.initial_speed, size=(n, 3))
    return pos, vel


def write_liggghts_data(path: Path, case: SettleCase, pos: FloatArray, vel: FloatArray) -> None:
    """Write a LIGGGHTS data file (atom_style granular) with Atoms and Velocities sections."""
    n = case.n_particles
    hx, hy, hz = case.box_hi
    ids = np.arange(1, n + 1, dtype=np.float64)
    atoms = np.column_stack(
        [ids, np.ones(n), np.full(n, case.diameter), np.full(n, case.density), pos]
    )
    vels = np.column_stack([ids, vel, np.zeros((n, 3))])
    with path.open("w") as f:
        f.write(f"LIGGGHTS data file, grainscale settle benchmark, N = {n}, seed = {case.seed}\n\n")
        f.write(f"{n} atoms\n1 atom types\n\n")
        f.write(f"0.0 {hx!r} xlo xhi\n0.0 {hy!r} ylo yhi\n0.0 {hz!r} zlo zhi\n\n")
        f.write("Atoms\n\n")
        np.savetxt(f, atoms, fmt=["%d", "%d", "%.17g", "%.17g", "%.17g", "%.17g", "%.17g"])
        f.write("\nVelocities\n\n")
        np.savetxt(f, vels, fmt=["%d"] + ["%.17g"] * 6)


def liggghts_input(
    case: SettleCase, data_file: str, thermo_every: int = 1000, runs: str | None = None
) -> str:
    """LIGGGHTS 3.8 input script for the case (one wall/gran fix per plane wall); ``runs``
    replaces the final ``run`` command (see liggghts_script)."""
    hx, hy, hz = case.box_hi
    walls = [("xlo", "xplane", 0.0), ("xhi", "xplane", hx), ("ylo", "yplane", 0.0),
             ("yhi", "yplane", hy), ("zlo", "zplane", 0.0), ("zhi", "zplane", hz)]  # fmt: skip
    wall_lines = "\n".join(
        f"fix wall_{name} all wall/gran model hertz tangential history "
        f"primitive type 1 {style} {value!r}"
        for name, style, value in walls
    )
    return liggghts_script(
        "settle", case, data_file, wall_lines, thermo_every, lost="error", runs=runs
    )


def liggghts_preamble(title: str, data_file: str, skin: float) -> str:
    """The first lines of every LIGGGHTS input here: SI units, granular atoms, closed box,
    ``newton off`` and ghost velocities (both required by LIGGGHTS), the data file, the skin."""
    return f"""\
# {title}
units           si
atom_style      granular
atom_modify     map array
boundary        f f f
newton          off
communicate     single vel yes
read_data       {data_file}
neighbor        {skin!r} bin
neigh_modify    delay 0
"""


def liggghts_script(
    name: str,
    case: Any,
    data_file: str,
    wall_lines: str,
    thermo_every: int,
    lost: str,
    runs: str | None = None,
) -> str:
    """The LIGGGHTS 3.8 input shared by the benchmarks: one particle type, Hertz with tangential
    history, gravity along -z, the given wall fixes, nve/sphere, thermo of atoms, KE, rotational
    KE and mean z. ``case`` has the fields of SettleCase's physics (n_particles, skin, moduli,
    restitution, friction, time_step, gravity, steps); ``lost``: LIGGGHTS' thermo_modify lost;
    ``runs``: the commands that end the script (default ``run <case.steps>``)."""
    runs = f"run             {case.steps}" if runs is None else runs.rstrip("\n")
    preamble = liggghts_preamble(f"grainscale '{name}' benchmark, N = {case.n_particles}",
                                 data_file, case.skin)  # fmt: skip
    return f"""\
{preamble}
fix m1 all property/global youngsModulus peratomtype {case.youngs_modulus!r}
fix m2 all property/global poissonsRatio peratomtype {case.poisson_ratio!r}
fix m3 all property/global coefficientRestitution peratomtypepair 1 {case.restitution!r}
fix m4 all property/global coefficientFriction peratomtypepair 1 {case.friction!r}

pair_style      gran model hertz tangential history
pair_coeff      * *
timestep        {case.time_step!r}

fix gravi all gravity {case.gravity!r} vector 0.0 0.0 -1.0
{wall_lines}
fix integr all nve/sphere

compute         rke all erotate/sphere
variable        zmean equal xcm(all,z)
thermo_style    custom step atoms ke c_rke v_zmean
thermo_modify   lost {lost} norm no
thermo          {thermo_every}
{runs}
"""
