"""Contact laws: declarative, validated parameter sets; the C++ core evaluates them.

A law is composed of sub-models (cpp/contact/): a normal spring with its damping, the
Mindlin-type tangential spring with Coulomb limit, and an optional rolling resistance::

    law = HertzMindlin(restitution=0.5, friction=0.5, rolling=EPSD(0.1, 0.3))
    law = Linear(normal_stiffness=1e5, restitution=0.9)
    law = EEPA(unloading_ratio=3, adhesive_stiffness=50.0, pull_off_force=-1e-4)

Conventions (DESIGN.md 2.4): compression positive, overlap ``d = r_i + r_j - |x_i - x_j|``,
effective radius R*, mass m*, moduli E*, G* as in validation/CASES.md section 0; SI units.

Interaction properties per material pair — restitution, friction, rolling friction, rolling
damping and the law's own parameters — are resolved with these mixing rules, first match wins:

1. an explicit entry ``pairs={(material_a, material_b): Pair(...)}`` on the law (``None`` as a
   material means every wall without a material; a rigid wall that needs entries of its own
   gets a rigid material, ``Material(youngs_modulus=math.inf)``; ``(a, b)`` and ``(b, a)`` are
   the same entry);
2. for restitution, friction, rolling_friction and rolling_damping, the values set on the two
   materials (``Material(friction=...)``): their arithmetic mean when both set one, the one set
   otherwise (a rigid wall has no material: the particle's value is used);
3. the law's value.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any, ClassVar, Literal

from ._validate import at_least, finite, flag, in_range, is_real, non_negative, positive
from .materials import Material

# --------------------------------------------------------------------------- rolling models


@dataclass(frozen=True)
class CDT:
    """Constant directional torque: ``M = -mu_r R* F_n w_r/|w_r|`` (it oscillates at rest).

    Args:
        rolling_friction: mu_r >= 0 (dimensionless).
    """

    rolling_friction: float

    _name: ClassVar[str] = "cdt"

    def __post_init__(self) -> None:
        non_negative("CDT", "rolling_friction", self.rolling_friction)


@dataclass(frozen=True)
class EPSD:
    """Elastic–plastic spring–dashpot rolling resistance (Ai et al. 2011).

    k_r = 2.25 k_n mu_r^2 R*^2; spring torque limited to ``mu_r R* |F_n|``; damping
    eta_r 2 sqrt(I_r k_r) only while below the limit.

    Args:
        rolling_friction: mu_r >= 0.
        rolling_damping: eta_r >= 0 (0.3 is typical).
    """

    rolling_friction: float
    rolling_damping: float = 0.3

    _name: ClassVar[str] = "epsd"

    def __post_init__(self) -> None:
        non_negative("EPSD", "rolling_friction", self.rolling_friction)
        non_negative("EPSD", "rolling_damping", self.rolling_damping)


@dataclass(frozen=True)
class EPSD2:
    """EPSD with k_r = k_t R*^2 and no damping (LIGGGHTS epsd2).

    Args:
        rolling_friction: mu_r >= 0.
    """

    rolling_friction: float

    _name: ClassVar[str] = "epsd2"

    def __post_init__(self) -> None:
        non_negative("EPSD2", "rolling_friction", self.rolling_friction)


Rolling = CDT | EPSD | EPSD2

# --------------------------------------------------------------------------- per-pair entries

_SHARED = ("restitution", "friction", "rolling_friction", "rolling_damping")


@dataclass(frozen=True)
class Pair:
    """Interaction properties of one material pair; None leaves a value to the mixing rules.

    Any field of the law it is used with may be given (e.g. ``normal_stiffness`` for Linear,
    ``pull_off_force`` for EEPA).
    """

    restitution: float | None = None
    friction: float | None = None
    rolling_friction: float | None = None
    rolling_damping: float | None = None
    normal_stiffness: float | None = None
    tangential_stiffness: float | None = None
    characteristic_velocity: float | None = None
    loading_stiffness: float | None = None
    unloading_ratio: float | None = None
    adhesive_stiffness: float | None = None
    pull_off_force: float | None = None
    adhesion_exponent: float | None = None

    def __post_init__(self) -> None:
        if self.restitution is not None:
            in_range("Pair", "restitution", self.restitution, 0, 1)
        for name in ("friction", "rolling_friction", "rolling_damping", "adhesive_stiffness"):
            v = getattr(self, name)
            if v is not None:
                non_negative("Pair", name, v)
        for name in (
            "normal_stiffness",
            "tangential_stiffness",
            "characteristic_velocity",
            "loading_stiffness",
            "adhesion_exponent",
        ):
            v = getattr(self, name)
            if v is not None:
                positive("Pair", name, v)
        if self.unloading_ratio is not None:
            at_least("Pair", "unloading_ratio", self.unloading_ratio, 1, " (k2/k1)")
        if self.pull_off_force is not None:
            finite("Pair", "pull_off_force", self.pull_off_force, " (N)")


# --------------------------------------------------------------------------- laws


@dataclass(frozen=True)
class _Law:
    """Fields shared by every law (see the subclasses)."""

    restitution: float = 0.5
    friction: float = 0.5
    rolling: Rolling | None = None
    limit_force: bool = False
    tangential_damping: bool = True
    tangential_history: Literal["total", "incremental"] = "total"
    spring_rotation: Literal["rescale", "project"] = "rescale"
    pairs: Mapping[tuple[Material | None, Material | None], Pair] = field(default_factory=dict)

    _normal: ClassVar[str] = ""
    # Interaction fields of this law: python name -> C++ Interaction attribute.
    _own: ClassVar[dict[str, str]] = {}

    def __post_init__(self) -> None:
        owner = type(self).__name__
        object.__setattr__(
            self, "restitution", in_range(owner, "restitution", self.restitution, 0, 1)
        )
        object.__setattr__(self, "friction", non_negative(owner, "friction", self.friction))
        for name in ("limit_force", "tangential_damping"):
            object.__setattr__(self, name, flag(owner, name, getattr(self, name)))
        if self.rolling is not None and not isinstance(self.rolling, CDT | EPSD | EPSD2):
            raise ValueError(
                f"{owner}.rolling must be None, CDT, EPSD or EPSD2, got {self.rolling!r}"
            )
        if self.tangential_history not in ("total", "incremental"):
            raise ValueError(
                f"{owner}.tangential_history must be 'total' or 'incremental', "
                f"got {self.tangential_history!r}"
            )
        if self.spring_rotation not in ("rescale", "project"):
            raise ValueError(
                f"{owner}.spring_rotation must be 'rescale' or 'project', "
                f"got {self.spring_rotation!r}"
            )
        for key, value in dict(self.pairs).items():
            ok = (
                isinstance(key, tuple)
                and len(key) == 2
                and all(m is None or isinstance(m, Material) for m in key)
            )
            if not ok:
                raise ValueError(
                    f"{owner}.pairs keys must be (Material | None, Material | None), got {key!r}"
                )
            if not isinstance(value, Pair):
                raise ValueError(f"{owner}.pairs values must be contact.Pair, got {value!r}")
        object.__setattr__(self, "pairs", dict(self.pairs))

    # ----- what the simulation calls
    @property
    def rolling_name(self) -> str:
        return "none" if self.rolling is None else self.rolling._name

    def _apply_law(self, level: Any) -> None:
        level.set_contact_law(
            self._normal,
            self.rolling_name,
            bool(self.limit_force),
            bool(self.tangential_damping),
            self.tangential_history == "incremental",
            self.spring_rotation == "project",
        )

    def _law_values(self) -> dict[str, float]:
        values = {"restitution": self.restitution, "friction": self.friction}
        if self.rolling is not None:
            values["rolling_friction"] = self.rolling.rolling_friction
            values["rolling_damping"] = getattr(self.rolling, "rolling_damping", 0.0)
        for py_name in self._own:
            v = getattr(self, py_name)
            if v is not None:
                values[py_name] = v
        return values

    def interaction(self, a: Material | None, b: Material | None) -> dict[str, float]:
        """The resolved interaction properties of the pair (a, b) (None: rigid wall)."""
        values = self._law_values()
        for name in _SHARED:
            found = [getattr(m, name, None) for m in (a, b) if m is not None]
            own: list[float] = [v for v in found if v is not None]
            if own:
                values[name] = sum(own) / len(own)
        explicit = self.pairs.get((a, b)) or self.pairs.get((b, a))
        if explicit is not None:
            for f in fields(Pair):
                v = getattr(explicit, f.name)
                if v is not None:
                    values[f.name] = v
        return values

    def _apply_pair(self, level: Any, core: Any, i: int, j: int, values: dict[str, float]) -> None:
        inter = core.Interaction()
        for name, v in values.items():
            setattr(inter, self._own.get(name, name), float(v))
        level.set_interaction(i, j, inter)


@dataclass(frozen=True)
class HertzMindlin(_Law):
    """Hertz–Mindlin with nonlinear damping from the restitution coefficient (the default law).

    ``F_n = 4/3 E* sqrt(R* d) d + 2 sqrt(5/6) |beta| sqrt(2 E* sqrt(R* d) m*) d'``, with
    beta = ln e / sqrt(ln^2 e + pi^2); tangential spring k_t = 8 G* sqrt(R* d) with history,
    damping of the same form, Coulomb limit ``|F_t| <= friction * max(F_n, 0)``.

    Args:
        restitution: coefficient of normal restitution e in [0, 1]. With tension allowed the
            simulated restitution equals e exactly for any speed, size and stiffness.
        friction: Coulomb friction coefficient mu >= 0.
        rolling: rolling resistance (CDT, EPSD, EPSD2) or None.
        limit_force: clamp the normal force at zero (no attraction from damping).
        tangential_damping: apply the tangential dashpot while sticking.
        tangential_history: "total" (F_t = -k_t xi, LIGGGHTS "history", the default) or
            "incremental" (dF_t = -k_t dxi, recommended by Thornton et al. 2011).
        spring_rotation: how the tangential (and rolling) spring follows the contact normal each
            step: "rescale" (projected onto the new tangent plane, its length kept: a pair
            turning rigidly keeps its spring, as in LAMMPS pair granular; the default) or
            "project" (projected only, as LIGGGHTS' tangential history model: the spring
            shrinks by cos(theta) for a turn theta per step; a little faster, and the choice
            for reproducing a LIGGGHTS run).
        pairs: per-material-pair overrides (see the module docstring).
    """

    _normal: ClassVar[str] = "hertz"


@dataclass(frozen=True)
class Linear(_Law):
    """Linear spring–dashpot: F_n = k_n d + c_n d', c = 2 zeta sqrt(k m*),
    ``zeta = |ln e| / sqrt(ln^2 e + pi^2)`` (exact restitution e with tension allowed).

    Args:
        normal_stiffness: k_n (N/m). None derives it per contact from E*, R*, m* and
            ``characteristic_velocity`` (the linear spring with the Hertz maximum overlap at that
            impact speed; LIGGGHTS hooke).
        tangential_stiffness: k_t (N/m); None means k_t = 2/7 k_n.
        characteristic_velocity: v_c (m/s) for the derived k_n.
        (restitution, friction, rolling, limit_force, ...: see HertzMindlin.)
    """

    normal_stiffness: float | None = None
    tangential_stiffness: float | None = None
    characteristic_velocity: float = 1.0

    _normal: ClassVar[str] = "linear"
    _own: ClassVar[dict[str, str]] = {
        "normal_stiffness": "normal_stiffness",
        "tangential_stiffness": "tangential_stiffness",
        "characteristic_velocity": "characteristic_velocity",
    }

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.normal_stiffness is not None:
            positive("Linear", "normal_stiffness", self.normal_stiffness, " (N/m)")
        if self.tangential_stiffness is not None:
            positive("Linear", "tangential_stiffness", self.tangential_stiffness, " (N/m)")
        positive("Linear", "characteristic_velocity", self.characteristic_velocity, " (m/s)")


@dataclass(frozen=True)
class EEPA(_Law):
    """Bilinear elasto-plastic adhesive contact (Thakur et al. 2014, 2016).

    loading F = f0 + k1 d^n; unloading/reloading F = f0 + k2 (d^n - dp^n); adhesive branch
    F = f0 - k_adh d^chi; plastic overlap dp^n = (1 - k1/k2) d_max^n. Damping
    beta = sqrt(4 m* k / (1 + (pi/ln e)^2)) on the loading slope k; k_t = 2/7 of that slope.
    Pull-off: constant f0 and k_adh are given (no surface-energy derivation).

    Args:
        exponent: n, 1 (linear, as in Thakur et al. 2016) or 1.5.
        loading_stiffness: k1 (N/m^n); None derives k1 = 2 E* R* (n = 1) or 4/3 E* sqrt(R*)
            (n = 1.5), so that k1 scales with particle size.
        unloading_ratio: k2 / k1 >= 1 (plasticity ratio 1 - k1/k2).
        adhesive_stiffness: k_adh >= 0 (N/m^chi).
        pull_off_force: f0 (N), added on every branch; negative attracts.
        adhesion_exponent: chi > 0.
    """

    exponent: float = 1.0
    loading_stiffness: float | None = None
    unloading_ratio: float = 3.0
    adhesive_stiffness: float = 0.0
    pull_off_force: float = 0.0
    adhesion_exponent: float = 1.0

    _normal: ClassVar[str] = "eepa"
    _own: ClassVar[dict[str, str]] = {
        "exponent": "eepa_exponent",
        "loading_stiffness": "loading_stiffness",
        "unloading_ratio": "unloading_ratio",
        "adhesive_stiffness": "adhesive_stiffness",
        "pull_off_force": "pull_off_force",
        "adhesion_exponent": "adhesion_exponent",
    }

    def __post_init__(self) -> None:
        super().__post_init__()
        if not is_real(self.exponent) or self.exponent not in (1, 1.5):
            raise ValueError(f"EEPA.exponent must be 1 or 1.5, got {self.exponent!r}")
        if self.loading_stiffness is not None:
            positive("EEPA", "loading_stiffness", self.loading_stiffness)
        at_least("EEPA", "unloading_ratio", self.unloading_ratio, 1, " (k2/k1)")
        non_negative("EEPA", "adhesive_stiffness", self.adhesive_stiffness)
        finite("EEPA", "pull_off_force", self.pull_off_force, " (N)")
        positive("EEPA", "adhesion_exponent", self.adhesion_exponent)


ContactLaw = HertzMindlin | Linear | EEPA


def supported_laws() -> list[str]:
    """The supported combinations, as "normal+rolling" names."""
    from . import _core

    return list(_core.supported_contact_laws())
