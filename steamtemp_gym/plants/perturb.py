"""Plant-parameter perturbations: the groups ``plant_randomization`` draws and the public
model-mismatch set.

A controller commissioned on a model meets a unit whose heat transfer, metal, firing lags
and thermowells differ from the model's by tens of per cent. The parameter fields of each
plant that carry one such physical meaning form a *group*; a perturbed
plant multiplies every field of a group by the group's factor.

- ``heat_transfer``: the heat-transfer coefficients (steam-side films, tube-bank kA,
  convective/radiant conductances); fouling and slagging lower them, a clean unit after
  sootblowing or a conservative design raises them.
- ``metal_heat_capacity``: the specific heat (or lumped heat capacity) of the tube,
  header and drum metal: the storage that slows every temperature response.
- ``firing_lag``: the lags between the fuel demand and the heat release (coal mills,
  furnace); mill wear, coal quality and the number of mills in service change them.
- ``sensor_lag``: the thermocouple and thermowell time constants of the measured
  temperatures; well design, deposits and immersion depth change them.
- ``section_gains``, ``section_time_constants`` (Cascade300MW, whose plant is transfer
  functions): the gains and time constants of its leading and inertia sections.

:data:`RANGES` holds the default factor range of each group (``plant_randomization=True``).
Each plant declares its groups (``Plant.perturbation_groups``: group -> its fields) and its
named model-mismatch variants (``Plant.mismatch_variants``: variant -> group factors within
those ranges; the boilers' are :data:`BOILER_VARIANTS`); :func:`mismatch` turns them into
the public model-mismatch set, a ``params`` dict of ``gym.make`` per variant
(docs/plant_uncertainty.md).

Draws (:func:`draw_plant`): one factor per group, log-uniform in its range (so 0.5..2 is
as likely slower as faster), from a generator seeded by the episode's noise key, so an
episode's plant is a function of its seed alone. A draw whose plant cannot be built or
cannot hold the episode's start in steady state is redrawn from the next stream of the
same key, at most :data:`MAX_DRAWS` times; then ValueError names the parameters.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from steamtemp_gym import catalog
from steamtemp_gym.checks import is_finite, is_real

#: Default factor range (lo, hi) of each group.
RANGES: dict[str, tuple[float, float]] = {
    "heat_transfer": (0.8, 1.2),
    "metal_heat_capacity": (0.75, 1.25),
    "firing_lag": (0.5, 1.5),
    "sensor_lag": (0.5, 2.0),
    "section_gains": (0.7, 1.3),
    "section_time_constants": (0.7, 1.3),
}

#: The named variants of a boiler (variant -> group -> factor), the ends of the ranges in
#: pairs a plant engineer meets: a fouled unit with heavy metal, a clean one with light
#: metal, slow and fast firing with slow and fast thermowells.
BOILER_VARIANTS: dict[str, dict[str, float]] = {
    "fouled_heavy_metal": {"heat_transfer": 0.8, "metal_heat_capacity": 1.25},
    "clean_light_metal": {"heat_transfer": 1.2, "metal_heat_capacity": 0.75},
    "slow_firing_lag_sensor": {"firing_lag": 1.5, "sensor_lag": 2.0},
    "fast_firing_lag_sensor": {"firing_lag": 0.5, "sensor_lag": 0.5},
}
#: Significant digits of a mismatch variant's parameter values: the product of a default
#: and a factor stated as its decimal value (0.8 x 12 MW/K is 9.6, not 9.600000000000001).
DIGITS = 12

#: Draws tried per episode before a draw that fails raises.
MAX_DRAWS = 8
#: Seed word that separates the plant draws from every other use of an episode's key.
_STREAM = 0x706C616E74  # "plant"


def plant_groups(plant_id: str) -> Mapping[str, tuple[str, ...]]:
    """The groups ``plant_id``'s plant declares (``Plant.perturbation_groups``); ValueError
    for an unknown id or a plant without any."""
    groups = catalog.plant_class(plant_id).perturbation_groups
    if not groups:
        have = [i for i in catalog.PLANTS if catalog.plant_class(i).perturbation_groups]
        raise ValueError(
            f"plant_randomization: no parameter groups for {plant_id!r}; plants with groups: {have}"
        )
    return groups


def variant_factors(plant_id: str) -> Mapping[str, Mapping[str, float]]:
    """The named mismatch variants ``plant_id``'s plant declares (``Plant.mismatch_variants``:
    variant -> group -> factor; empty for a plant without any); ValueError for an unknown
    id."""
    return catalog.plant_class(plant_id).mismatch_variants


def mismatch(plant_id: str) -> dict[str, dict[str, float]]:
    """The public model-mismatch set of ``plant_id``: variant -> ``params`` of ``gym.make``,
    each field of the variant's groups at its default times the group's factor (to
    :data:`DIGITS` significant digits); empty for a plant without variants."""
    out = {}
    for v, factors in variant_factors(plant_id).items():
        params = scaled(plant_id, {}, factors)
        out[v] = {k: float(f"{x:.{DIGITS}g}") for k, x in params.items()}
    return out


def parse(plant_id: str, option: Any) -> dict[str, tuple[float, float]] | None:
    """The factor range of each group to draw, from a ``plant_randomization`` option.

    ``None`` or ``False``: no randomization (None). ``True``: every group of the plant in
    its :data:`RANGES` range. A dict ``{group: (lo, hi)}``: those groups only, with
    0 < lo <= hi finite (lo == hi fixes the factor).

    Raises:
        ValueError: anything else, naming the problem (unknown group, bad range).
    """
    if option is None or option is False or (isinstance(option, np.bool_) and not option):
        return None
    groups = plant_groups(plant_id)
    if option is True or (isinstance(option, np.bool_) and option):
        return {g: RANGES[g] for g in groups}
    if not isinstance(option, Mapping):
        raise ValueError(
            f"plant_randomization must be True, False, None or a dict "
            f"{{group: (lo, hi)}}, got {type(option).__name__} "
            f"{str(option)[:60]!r}"
        )
    if not option:
        raise ValueError(
            "plant_randomization is an empty dict; give at least one group "
            f"of {list(groups)} or True"
        )
    unknown = [g for g in option if g not in groups]
    if unknown:
        raise ValueError(
            f"plant_randomization: unknown group(s) {[str(g)[:40] for g in unknown]} "
            f"for {plant_id}; valid groups: {list(groups)}"
        )
    out = {}
    for g in groups:  # the plant's order: the draw does not depend on the dict's order
        if g not in option:
            continue
        value = option[g]
        if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != 2:
            raise ValueError(
                f"plant_randomization[{g!r}] must be a pair (lo, hi) of "
                f"factors, got {str(value)[:60]!r}"
            )
        lo, hi = value
        for name, v in (("lo", lo), ("hi", hi)):
            if not is_real(v) or isinstance(v, (bool, np.bool_)) or not is_finite(v):
                raise ValueError(
                    f"plant_randomization[{g!r}]: {name} must be a finite "
                    f"number, got {str(v)[:40]!r}"
                )
            if not v > 0:
                raise ValueError(
                    f"plant_randomization[{g!r}]: {name} = {v!r} must be a positive factor"
                )
        if lo > hi:
            raise ValueError(f"plant_randomization[{g!r}]: lo = {lo!r} is above hi = {hi!r}")
        out[g] = (float(lo), float(hi))
    return out


def draw_factors(
    ranges: dict[str, tuple[float, float]], rng: np.random.Generator
) -> dict[str, float]:
    """One factor per group, log-uniform in its range (one uniform number per group, in
    the order of ``ranges``, also for a fixed range lo == hi)."""
    out = {}
    for g, (lo, hi) in ranges.items():
        u = float(rng.random())
        out[g] = lo if lo == hi else math.exp(math.log(lo) + u * (math.log(hi) - math.log(lo)))
    return out


def scaled(plant_id: str, base: Mapping[str, Any], factors: Mapping[str, float]) -> dict[str, Any]:
    """``base`` (parameter overrides of ``gym.make``'s ``params``) with every field of each
    group of ``factors`` set to its value (the override, else the default) times the
    group's factor."""
    defaults = {f.name: f.default for f in dataclasses.fields(catalog.plant_class(plant_id).Params)}
    out = dict(base)
    groups = catalog.plant_class(plant_id).perturbation_groups
    for g, k in factors.items():
        for name in groups[g]:
            out[name] = float(base.get(name, defaults[name])) * k
    return out


def corners(plant_id: str, margin: float = 0.0) -> list[dict[str, float]]:
    """Every corner of ``plant_id``'s box of group factors (its declared groups, each over
    its :data:`RANGES` range): the ends themselves for ``margin`` 0, else ``margin`` (a
    fraction of the half-width, log scale) inside each end. Groups in the plant's order,
    the low ends first; one empty corner for a plant without groups."""
    groups = list(catalog.plant_class(plant_id).perturbation_groups)
    ends = []
    for g in groups:
        lo, hi = RANGES[g]
        if margin:
            lo, hi = np.log(lo), np.log(hi)
            mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo) * (1.0 - margin)
            lo, hi = float(np.exp(mid - half)), float(np.exp(mid + half))
        ends.append((lo, hi))
    return [dict(zip(groups, c, strict=True)) for c in itertools.product(*ends)]


def episode_rng(key: int, attempt: int) -> np.random.Generator:
    """The generator of draw ``attempt`` of the episode with noise key ``key``."""
    return np.random.default_rng(np.random.SeedSequence([int(key), _STREAM, int(attempt)]))


def draw_plant(
    plant_id: str,
    base: Mapping[str, Any],
    ranges: dict[str, tuple[float, float]],
    key: int,
    fits: Callable[[Any], bool],
) -> tuple[Any, dict[str, float]]:
    """(plant, its factors) of the episode with noise key ``key``: the first of up to
    :data:`MAX_DRAWS` draws whose plant can be built and passes ``fits`` (the start check).

    Raises:
        ValueError: no draw passed; names the groups, their factors and parameters.
    """
    tried = []
    for attempt in range(MAX_DRAWS):
        factors = draw_factors(ranges, episode_rng(key, attempt))
        params = scaled(plant_id, base, factors)
        try:
            plant = catalog.plant_class(plant_id)(**params)
        except ValueError as exc:
            tried.append(f"{_factor_text(factors)}: {str(exc)[:120]}")
            continue
        if fits(plant):
            return plant, factors
        tried.append(f"{_factor_text(factors)}: cannot hold the episode's start")
    fields = sorted({n for g in ranges for n in plant_groups(plant_id)[g]})
    raise ValueError(
        f"plant_randomization: none of {MAX_DRAWS} draws of {plant_id} (parameters "
        f"{fields}) gives a plant that holds the episode's start; narrow the ranges "
        f"{ranges}. Draws: " + "; ".join(tried)
    )


def _factor_text(factors: Mapping[str, float]) -> str:
    return ", ".join(f"{g} x{k:.3f}" for g, k in factors.items())
