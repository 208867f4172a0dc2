"""Coarse-grained silo discharge (CASES D1 ii): the resolved reference and the comparison.

``load_reference`` reads the resolved study (its SiloCase and Beverloo fit); ``compare`` sets
the CG runs at each (h, D0) against it and against Beverloo's predicted ratio
W_CG / W_ref = ((D0/d - k h) / (D0/d - k))^(5/2); ``fit_cg`` and ``broken_similarities``
describe the CG runs. The study is ``studies.silo_cg.silo_cg``.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from studies.silo_discharge import silo_beverloo, silo_case, silo_run

TOLERANCE = 0.05  # CASES D1 (ii): |measured - predicted ratio| on the mean over seeds
GATED_H = 2.0  # CASES D1 (ii) gates h = 2 only
GATED_RANGE = (5.0, 8.0)  # ... at D0 / (h d) in this range


# ------------------------------------------------------------------------------------------
# the resolved reference
# ------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Reference:
    """The resolved study a CG study is compared with (from its results.json)."""

    path: Path
    case: silo_case.SiloCase
    orifices: list[float]  # m
    seeds: list[int]
    rate_mean: list[float]  # kg/s per orifice
    rate_std: list[float]  # kg/s (NaN for one seed)
    bulk_density: list[float]  # kg/m^3, core of the settled bed
    particles: list[float]  # mean inventory per orifice
    wall_clock: list[float]  # mean s per run per orifice
    c: float  # Beverloo fit with n = 2.5
    k: float
    free_fit: tuple[float, float] | None  # (k, n) of the fit with n free: W_ref(D0) smoothly

    def similar_ratio(self, orifice: float, h: float) -> float:
        """W_CG / W_ref if the CG silo behaves as the resolved one at D0 / h magnified h times:
        h^2.5 W_ref(D0 / h) / W_ref(D0), W_ref from the free fit (NaN without one)."""
        if self.free_fit is None:
            return math.nan
        k, n = self.free_fit
        x = orifice / self.case.diameter
        return h ** (2.5 - n) * max(0.0, (x - k * h) / (x - k)) ** n

    def index(self, orifice: float) -> int:
        """Position of the orifice D0 (m) in the reference; ValueError if it was not run."""
        for i, d0 in enumerate(self.orifices):
            if math.isclose(d0, orifice, rel_tol=1e-9):
                return i
        raise ValueError(
            f"silo_cg: orifice {orifice * 1e3:g} mm is not in the reference {self.path} "
            f"(D0 = {', '.join(f'{v * 1e3:g}' for v in self.orifices)} mm)"
        )


def load_reference(path: str | Path) -> Reference:
    """The resolved study stored in ``path`` (results.json of silo_discharge)."""
    p = Path(path)
    data = json.loads(p.read_text())
    case = silo_case.SiloCase(**data["case"])
    if case.cg != 1:
        raise ValueError(f"silo_cg.reference must be a resolved study (cg = 1), got cg = {case.cg}")
    fit = data.get("fit_exponent_2_5")
    if fit is None:
        raise ValueError(f"silo_cg.reference {p} has no Beverloo fit (fit_exponent_2_5)")
    free = data.get("fit_free")
    orifices = [float(v) for v in data["orifices_m"]]
    runs = data["runs"]

    def mean_of(key: str, d0: float) -> float:
        return float(np.mean([r[key] for r in runs if math.isclose(r["orifice"], d0)]))

    def value(v: Any) -> float:
        return math.nan if v is None else float(v)

    return Reference(
        path=p,
        case=case,
        orifices=orifices,
        seeds=[int(s) for s in data["seeds"]],
        rate_mean=[value(v) for v in data["rate_mean_kg_s"]],
        rate_std=[value(v) for v in data["rate_std_kg_s"]],
        bulk_density=[value(v) for v in data["core_bulk_density_kg_m3"]],
        particles=[mean_of("particles", d0) for d0 in orifices],
        wall_clock=[mean_of("wall_clock", d0) for d0 in orifices],
        c=float(fit["c"]),
        k=float(fit["k"]),
        free_fit=None if free is None else (float(free["k"]), float(free["exponent"])),
    )


def predicted_ratio(d0_over_d: float, h: float, k: float, exponent: float = 2.5) -> float:
    """Beverloo's W_CG / W_ref = ((D0/d - k h) / (D0/d - k))^n (CASES.md D1 ii): k acts on the
    parcel diameter h d; 0 when the parcels cannot pass (D0 <= k h d)."""
    if not d0_over_d > k:
        raise ValueError(f"predicted_ratio.d0_over_d must exceed k = {k:g}, got {d0_over_d!r}")
    return max(0.0, (d0_over_d - k * h) / (d0_over_d - k)) ** exponent


def effective_k(d0_over_d: float, h: float, k: float, ratio: float) -> float:
    """The k' for which ((D0/d - k' h) / (D0/d - k))^2.5 equals the measured ratio: the empty
    annulus of the CG run in parcel diameters (k' = k when Beverloo's scaling holds)."""
    return (d0_over_d - (d0_over_d - k) * ratio**0.4) / h


# ------------------------------------------------------------------------------------------
# analysis
# ------------------------------------------------------------------------------------------


@dataclass
class Comparison:
    """The CG runs at one (h, D0) against the resolved ones."""

    h: float
    orifice: float  # m
    d0_over_d: float  # resolved D0 / d
    seeds: list[int]
    rates: list[float]  # kg/s per seed (NaN: clogged or window not reached)
    clogged: int  # runs without a rate (clogged, or no flow in the window)
    rate_mean: float
    rate_std: float
    reference_rate: float
    reference_std: float
    ratio: float  # mean W_CG / mean W_ref
    ratio_spread: float  # sample sd over the seeds of W_CG,i / W_ref
    ratio_error: float  # standard error of the ratio (CG and reference seeds)
    predicted: float  # Beverloo, fitted k
    predicted_k15: float  # Beverloo, k = 1.5
    similar: float  # h^2.5 W_ref(D0 / h) / W_ref(D0) from the resolved free fit
    similar_extrapolated: bool  # D0 / h below the smallest resolved orifice
    effective_k: float
    bulk_density: float  # CG core bulk density, kg/m^3
    reference_bulk_density: float
    particles: float  # mean CG inventory
    reference_particles: float
    time_step: float
    wall_clock: float  # mean s per CG run
    reference_wall_clock: float
    gated: bool
    passed: bool | None  # None when not gated

    @property
    def deviation(self) -> float:
        return self.ratio - self.predicted


def compare(reference: Reference, runs: Sequence[silo_run.DischargeResult]) -> list[Comparison]:
    """One Comparison per (h, D0) of the runs."""
    d = reference.case.diameter
    out = []
    for h, d0 in sorted({(r.cg, r.orifice) for r in runs}):
        mine = [r for r in runs if r.cg == h and r.orifice == d0]
        i = reference.index(d0)
        w_ref, s_ref = reference.rate_mean[i], reference.rate_std[i]
        # a run that clogged, or stopped flowing so that its window holds no discharge, has
        # no Beverloo rate: left out of the mean and counted
        rates = [r.rate if not r.clogged else math.nan for r in mine]
        ok = np.array([w for w in rates if math.isfinite(w)])
        n_ref = len(reference.seeds)
        mean = float(ok.mean()) if len(ok) else math.nan
        std = float(ok.std(ddof=1)) if len(ok) > 1 else math.nan
        ratio = mean / w_ref
        rel = (std / mean) ** 2 / len(ok) if len(ok) > 1 else math.nan
        if math.isfinite(s_ref):
            rel += (s_ref / w_ref) ** 2 / n_ref
        x = d0 / d
        predicted = predicted_ratio(x, h, reference.k)
        gated = h == GATED_H and GATED_RANGE[0] - 1e-9 <= x / h <= GATED_RANGE[1] + 1e-9
        out.append(
            Comparison(
                h=h,
                orifice=d0,
                d0_over_d=x,
                seeds=[r.seed for r in mine],
                rates=rates,
                clogged=sum(not math.isfinite(w) for w in rates),
                rate_mean=mean,
                rate_std=std,
                reference_rate=w_ref,
                reference_std=s_ref,
                ratio=ratio,
                ratio_spread=std / w_ref,
                ratio_error=ratio * math.sqrt(rel),
                predicted=predicted,
                predicted_k15=predicted_ratio(x, h, silo_beverloo.BEVERLOO_K),
                similar=reference.similar_ratio(d0, h),
                similar_extrapolated=d0 / h < min(reference.orifices) * (1 - 1e-9),
                effective_k=effective_k(x, h, reference.k, ratio) if ratio > 0 else math.nan,
                bulk_density=float(np.mean([r.core_bulk_density for r in mine])),
                reference_bulk_density=reference.bulk_density[i],
                particles=float(np.mean([r.particles for r in mine])),
                reference_particles=reference.particles[i],
                time_step=mine[0].time_step,
                wall_clock=float(np.mean([r.wall_clock for r in mine])),
                reference_wall_clock=reference.wall_clock[i],
                gated=gated,
                passed=(abs(ratio - predicted) <= TOLERANCE) if gated else None,
            )
        )
    return out


def fit_cg(
    reference: Reference, comparisons: Sequence[Comparison], h: float
) -> silo_beverloo.BeverlooFit | None:
    """Beverloo (n = 2.5) fitted to the CG runs of ratio h with the parcel diameter h d: C and k
    of the coarse system, from the orifices where at most 1 run in 10 clogged (intermittent
    flow is not Beverloo's); None with fewer than 2 such orifices."""
    mine = [
        c
        for c in comparisons
        if c.h == h and math.isfinite(c.rate_mean) and c.clogged <= 0.1 * len(c.seeds)
    ]
    if len(mine) < 2:
        return None
    return silo_beverloo.fit_beverloo(
        [c.orifice for c in mine],
        [c.rate_mean for c in mine],
        h * reference.case.diameter,
        [c.bulk_density for c in mine],
        exponent=2.5,
    )


def broken_similarities(reference: Reference, h: float, orifice: float) -> list[dict[str, Any]]:
    """The similarity numbers scale(..., "cg") reports broken for the silo at ratio h."""
    setup = silo_run.silo_setup(dataclasses.replace(reference.case, cg=h), orifice)
    assert setup.scaled is not None
    return [dataclasses.asdict(b) for b in setup.scaled.broken]
