"""Contact laws (declarative parameter sets; the C++ core evaluates them).

Conventions (DESIGN.md 2.4): compression positive, overlap delta = r_i + r_j - |x_i - x_j|,
effective radius R*, mass m*, moduli E*, G* as in validation/CASES.md section 0.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from ._validate import in_range, non_negative


@dataclass(frozen=True)
class HertzMindlin:
    """Hertz–Mindlin with nonlinear damping from the restitution coefficient (the default law).

    F_n = 4/3 E* sqrt(R* d) d + 2 sqrt(5/6) |beta| sqrt(2 E* sqrt(R* d) m*) d', with
    beta = ln e / sqrt(ln^2 e + pi^2); tangential spring k_t = 8 G* sqrt(R* d) with history,
    damping of the same form, Coulomb limit |F_t| <= friction * max(F_n, 0).

    Args:
        restitution: coefficient of normal restitution e in [0, 1]. With tension allowed the
            simulated restitution equals e exactly for any speed, size and stiffness.
        friction: Coulomb friction coefficient mu >= 0.
        limit_force: clamp the normal force at zero (no attraction from damping).
        tangential_damping: apply the tangential dashpot while sticking.
        tangential_history: "total" (F_t = -k_t xi, LIGGGHTS "history", the default) or
            "incremental" (dF_t = -k_t dxi, recommended by Thornton et al. 2011).
    """

    restitution: float = 0.5
    friction: float = 0.5
    limit_force: bool = False
    tangential_damping: bool = True
    tangential_history: Literal["total", "incremental"] = "total"

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "restitution", in_range("HertzMindlin", "restitution", self.restitution, 0, 1)
        )
        object.__setattr__(
            self, "friction", non_negative("HertzMindlin", "friction", self.friction)
        )
        if self.tangential_history not in ("total", "incremental"):
            raise ValueError(
                "HertzMindlin.tangential_history must be 'total' or 'incremental', "
                f"got {self.tangential_history!r}"
            )

    def _apply(self, level: object) -> None:
        level.set_hertz_mindlin(  # type: ignore[attr-defined]
            self.restitution,
            self.friction,
            bool(self.limit_force),
            bool(self.tangential_damping),
            self.tangential_history == "incremental",
        )


ContactLaw = HertzMindlin
