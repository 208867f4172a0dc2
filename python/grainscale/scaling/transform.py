"""scale(): map a reference ParameterSet and a size ratio h to the set of a scaled system.

Pure functions: nothing is mutated, every input object is replaced by a scaled copy (objects a
scheme leaves unchanged are returned as they are, so per-pair keys keep matching).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from fractions import Fraction
from typing import Any, TypeVar

from .._validate import positive
from ..contact import EEPA, ContactLaw, Linear
from ..dist import (
    Discrete,
    Distribution,
    LogNormal,
    Monodisperse,
    Normal,
    Uniform,
    as_distribution,
)
from ..geometry import Box, Cylinder, Mesh, Plane, Rectangle, Servo, Wall
from ..insert import Outlet, Pack, RectangleFace, Region, Stream
from ..materials import Material
from .parameters import ParameterSet, Particles
from .table import Similarity, broken_similarities, factors

T = TypeVar("T")


@dataclass(frozen=True)
class Scaled:
    """Result of :func:`scale`.

    Attributes:
        params: the scaled parameter set.
        h: the size ratio.
        scheme, dimension: as requested.
        factors: quantity -> numeric factor h**p applied (the table of ``scheme`` plus
            ``youngs_modulus``, whose exponent depends on the contact law).
        broken: similarity numbers the scheme does not preserve, for this parameter set.
    """

    params: ParameterSet
    h: float
    scheme: str
    dimension: int
    factors: dict[str, float]
    broken: list[Similarity]


def _modulus_exponent(table: dict[str, float], law: ContactLaw) -> float:
    """Exponent of E (and G) that gives the law's forces the table's force factor.

    Hertz F ~ E R^(1/2) d^(3/2) (Hertz 1882); linear k from E, v_c ~ E^(4/5) R^(2/5) m^(1/5)
    v^(2/5) (LIGGGHTS hooke; must match normal_stiffness); EEPA k1 = 2 E R (n = 1) or
    4/3 E R^(1/2) (n = 1.5). Zero for exact and cg in 3-D; the representative-particle schemes,
    which keep the overlap while raising the force, need stiffer materials. In 2-D these 3-D
    formulas applied to discs give N where the table wants N per unit thickness, so E takes
    1/h (exact, cg): a plane-strain disc law (force per thickness ~ E* d) would keep E.
    """
    # Rational arithmetic: an exponent that should vanish must be exactly 0 (h**1e-16 != 1).
    t = {k: Fraction(v) for k, v in table.items()}
    f, r, d = t["force"], t["radius"], t["overlap"]
    if isinstance(law, Linear):
        p = Fraction(5, 4) * (
            t["normal_stiffness"]
            - Fraction(2, 5) * r
            - Fraction(1, 5) * t["mass"]
            - Fraction(2, 5) * t["characteristic_velocity"]
        )
    elif isinstance(law, EEPA) and law.exponent == 1:
        p = f - r - d
    else:
        p = f - r / 2 - Fraction(3, 2) * d
    return float(p)


def _times(x: Any, factor: float) -> Any:
    """x * factor for a number or a tuple of numbers; factor 1 returns x itself."""
    if factor == 1 or x is None:
        return x
    if isinstance(x, tuple):
        return tuple(float(v) * factor for v in x)
    return float(x) * factor


def _replace(obj: T, changes: dict[str, Any]) -> T:
    """dataclasses.replace that returns obj itself when nothing changes."""
    changed = {k: v for k, v in changes.items() if v is not getattr(obj, k)}
    return dataclasses.replace(obj, **changed) if changed else obj  # type: ignore[type-var]


class _Mapper:
    """Applies one scheme's factors h**p to every kind of parameter object."""

    def __init__(self, h: float, exponents: dict[str, float], law: ContactLaw) -> None:
        self.h = h
        self.p = exponents
        self.f = {name: h**p for name, p in exponents.items()}
        self.law = law
        self.materials: dict[Material, Material] = {}

    def material(self, m: Material | None) -> Material | None:
        if m is None:
            return None
        if m not in self.materials:
            e = _times(m.youngs_modulus, self.f["youngs_modulus"])
            self.materials[m] = _replace(m, {"youngs_modulus": e})
        return self.materials[m]

    def length(self, x: Any) -> Any:
        """A length or point of the system (points scale about the origin)."""
        return _times(x, self.f["domain_length"])

    def wall(self, w: Wall) -> Wall:
        changes: dict[str, Any] = {
            "material": self.material(w.material),
            "velocity": _times(w.velocity, self.f["velocity"]),
        }
        if isinstance(w, Cylinder | Mesh):
            changes["angular_velocity"] = _times(
                w.angular_velocity, self.f["wall_angular_velocity"]
            )
        if isinstance(w, Plane):
            changes["point"] = self.length(w.point)
        elif isinstance(w, Rectangle):
            for name in ("corner", "edge1", "edge2"):
                changes[name] = self.length(getattr(w, name))
        elif isinstance(w, Cylinder):
            for name in ("point", "radius", "length"):
                changes[name] = self.length(getattr(w, name))
        elif isinstance(w, Mesh):
            g = self.f["domain_length"]
            changes["vertices"] = w.vertices if g == 1 else w.vertices * g
            changes["origin"] = self.length(w.origin)
        return _replace(w, changes)

    def servo(self, s: Servo) -> Servo:
        f = self.f
        return _replace(
            s,
            {
                "gain": _times(s.gain, f["servo_gain"]),
                "integral_gain": _times(s.integral_gain, f["servo_integral_gain"]),
                "max_speed": _times(s.max_speed, f["velocity"]),
                "target_force": _times(s.target_force, f["wall_force"]),
                "target_stress": _times(s.target_stress, f["stress"]),
                "area": _times(s.area, f["area"]),
            },
        )

    def box(self, b: Box) -> Box:
        return _replace(b, {"lo": self.length(b.lo), "hi": self.length(b.hi)})

    def region(self, r: Region | Mesh) -> Region | Mesh:
        return self.box(r) if isinstance(r, Box) else self.wall(r)  # type: ignore[return-value]

    def insertion(self, op: Pack | Stream) -> Pack | Stream:
        f = self.f
        changes: dict[str, Any] = {
            "radius": self.distribution(op.radius),
            "material": self.material(op.material),
            "velocity": _times(op.velocity, f["velocity"]),
        }
        if isinstance(op, Pack):
            changes["region"] = self.region(op.region)
            if op.count is not None and f["particle_count"] != 1:
                count = round(op.count * f["particle_count"])
                if count < 1:
                    raise ValueError(
                        f"scale: Pack.count must stay >= 1 after scaling, got {op.count!r} x "
                        f"{f['particle_count']:.3g}; give a volume_fraction instead"
                    )
                changes["count"] = count
            return _replace(op, changes)
        face = op.face
        if isinstance(face, RectangleFace):
            moved: Any = {n: self.length(getattr(face, n)) for n in ("corner", "edge1", "edge2")}
        else:
            moved = {"centre": self.length(face.centre), "radius": self.length(face.radius)}
        changes["face"] = _replace(face, moved)
        changes["mass_rate"] = _times(op.mass_rate, f["mass_rate"])
        for name in ("start", "stop", "every"):
            changes[name] = _times(getattr(op, name), f["time"])
        return _replace(op, changes)

    def outlet(self, o: Outlet) -> Outlet:
        # `every` counts steps: it follows process time over the time step, at least 1
        steps = self.f["time"] / self.f["time_step"]
        every = o.every if steps == 1 else max(1, round(o.every * steps))
        return _replace(o, {"region": self.region(o.region), "every": every})

    def law_fields(self, values: Any, n: float) -> dict[str, Any]:
        """Scaled law-specific fields of a law or a Pair (None stays None)."""
        f, p, h = self.f, self.p, self.h
        out: dict[str, Any] = {}
        if isinstance(self.law, Linear):
            for name in ("normal_stiffness", "tangential_stiffness", "characteristic_velocity"):
                out[name] = _times(getattr(values, name), f[name])
        if isinstance(self.law, EEPA):
            # k1 in N/m^n: a contact force over overlap^n. The adhesive branch k_adh d^chi and
            # f0 are cohesion (van der Waals type, Thakur et al. 2016) forces.
            k1 = h ** (p["force"] - n * p["overlap"])
            out["loading_stiffness"] = _times(values.loading_stiffness, k1)
            out["pull_off_force"] = _times(values.pull_off_force, f["pull_off_force"])
            chi = values.adhesion_exponent
            if chi is None:  # a Pair without its own exponent uses the law's
                chi = self.law.adhesion_exponent
            k_adh = h ** (p["pull_off_force"] - chi * p["overlap"])
            out["adhesive_stiffness"] = _times(values.adhesive_stiffness, k_adh)
        return out

    def contact(self, law: ContactLaw) -> ContactLaw:
        n = getattr(law, "exponent", 1.0)
        pairs = {
            (self.material(a), self.material(b)): _replace(p, self.law_fields(p, n))
            for (a, b), p in law.pairs.items()
        }
        changes = self.law_fields(law, n)
        if pairs != law.pairs:
            changes["pairs"] = pairs
        return _replace(law, changes)

    def particles(self, p: Particles) -> Particles:
        f = self.f
        return Particles(
            position=p.position * f["domain_length"],
            radius=p.radius * f["radius"],
            material=self.material(p.material),  # type: ignore[arg-type]
            velocity=None if p.velocity is None else p.velocity * f["velocity"],
            angular_velocity=None
            if p.angular_velocity is None
            else p.angular_velocity * f["angular_velocity"],
        )

    def distribution(self, d: Distribution | float) -> Distribution:
        d = as_distribution(d, "scale", "radius")
        g = self.f["radius"]
        if g == 1:
            return d
        if isinstance(d, Monodisperse):
            return Monodisperse(d.radius * g)
        if isinstance(d, Uniform):
            return Uniform(d.min * g, d.max * g)
        if isinstance(d, Normal):
            return Normal(d.mean * g, d.std * g, _times(d.min, g), _times(d.max, g))
        if isinstance(d, LogNormal):
            return LogNormal(d.median * g, d.sigma, _times(d.min, g), _times(d.max, g))
        if isinstance(d, Discrete):
            return Discrete(tuple(r * g for r in d.radii), d.weights, d.fractions)
        raise ValueError(f"scale: unsupported size distribution {d!r}")


def _has_cohesion(law: ContactLaw) -> bool:
    if not isinstance(law, EEPA):
        return False
    entries: list[Any] = [law, *law.pairs.values()]
    return any((e.pull_off_force or 0) != 0 or (e.adhesive_stiffness or 0) != 0 for e in entries)


def scale(params: ParameterSet, h: float, scheme: str = "exact", dimension: int = 3) -> Scaled:
    """Map the reference set ``params`` to the system whose particles are h times larger.

    Args:
        params: the reference (fine) parameter set.
        h: size ratio in [0.001, 1000] (h > 1 coarsens).
        scheme: "exact" (Feng & Owen 2014), "cg" (energy-density consistent coarse graining),
            "sakai" or "spa" (representative-particle schemes, for comparison studies); see
            :mod:`grainscale.scaling.table` for the factors and their sources.
        dimension: 3, or 2 for discs per unit thickness.

    Returns:
        :class:`Scaled` with the new set, the factors and the broken similarity numbers.

    Example:
        >>> import grainscale as gs
        >>> ref = gs.scaling.ParameterSet(domain=gs.Box((0, 0, 0), (0.1, 0.1, 0.1)),
        ...                               time_step=1e-6, skin=2e-4)
        >>> s = gs.scaling.scale(ref, 2.0)
        >>> s.params.time_step, s.params.gravity[2], s.broken
        (2e-06, -4.905, [])
        >>> [b.name for b in gs.scaling.scale(ref, 2.0, "cg").broken]
        ['froude', 'size_ratio', 'inertial_number', 'time_ratio']
    """
    if not isinstance(params, ParameterSet):
        raise ValueError(f"scale.params must be a scaling.ParameterSet, got {params!r}")
    hv = positive("scale", "h", h)
    if not 1e-3 <= hv <= 1e3:  # beyond, the factors (up to h**5) leave the useful float range
        raise ValueError(f"scale.h must be in [0.001, 1000] (a size ratio), got {h!r}")
    table = factors(scheme, dimension)  # validates scheme and dimension
    law = params.contact  # one of the laws with rules here (ParameterSet checks it)
    if params.particles and table["domain_length"] != table["radius"]:
        raise ValueError(
            f"scale.params.particles must be empty for scheme {scheme!r}: only an exact scaling "
            "maps individual particles (a coarse system holds other particles); give a size "
            "distribution (ParameterSet.size) and insert instead"
        )
    m = _Mapper(hv, dict(table, youngs_modulus=_modulus_exponent(table, law)), law)
    f = m.f
    out = ParameterSet(
        domain=m.box(params.domain),
        contact=m.contact(law),
        gravity=_times(params.gravity, f["gravity"]),
        time_step=_times(params.time_step, f["time_step"]),
        skin=_times(params.skin, f["skin"]),
        walls=tuple(m.wall(w) for w in params.walls),
        servos={k: m.servo(s) for k, s in params.servos.items()},
        particles=tuple(m.particles(p) for p in params.particles),
        size=None if params.size is None else m.distribution(params.size),
        insertions=tuple(m.insertion(op) for op in params.insertions),
        outlets=tuple(m.outlet(o) for o in params.outlets),
        materials=tuple(m.material(x) for x in params.materials),  # type: ignore[misc]
    )
    broken = broken_similarities(
        scheme,
        hv,
        dimension,
        gravity=any(g != 0 for g in params.gravity),
        cohesion=_has_cohesion(law),
    )
    return Scaled(out, hv, scheme, dimension, f, broken)
