"""Plant-parameter perturbations: the groups ``plant_randomization`` draws and the public
model-mismatch set.

A controller commissioned on a model meets a unit whose heat transfer, metal, firing lags
and thermowells differ from the model's by tens of per cent. The parameter fields of each
plant that carry one such physical meaning form a *group* (:data:`GROUPS`); a perturbed
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
:data:`MISMATCH` holds fixed perturbed variants of each plant, each a ``params`` dict of
``gym.make`` within those ranges (docs/robustness.md).

Draws (:func:`draw_plant`): one factor per group, log-uniform in its range (so 0.5..2 is
as likely slower as faster), from a generator seeded by the episode's noise key, so an
episode's plant is a function of its seed alone. A draw whose plant cannot be built or
cannot hold the episode's start in steady state is redrawn from the next stream of the
same key, at most :data:`MAX_DRAWS` times; then ValueError names the parameters.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from steamtemp_gym.checks import is_finite, is_real

FSH = "steamtemp/SupercriticalFSH-v0"
BENSON = "steamtemp/BensonSubcritical-v0"
BTM = "steamtemp/BoilerTurbineMIMO-v0"
DRUM = "steamtemp/DrumBoilerSH-v0"
CASCADE = "steamtemp/Cascade300MW-v0"

#: Default factor range (lo, hi) of each group.
RANGES: dict[str, tuple[float, float]] = {
    "heat_transfer": (0.8, 1.2),
    "metal_heat_capacity": (0.75, 1.25),
    "firing_lag": (0.5, 1.5),
    "sensor_lag": (0.5, 2.0),
    "section_gains": (0.7, 1.3),
    "section_time_constants": (0.7, 1.3),
}

#: plant id -> group -> the parameter fields (of the plant's Params) the group scales.
GROUPS: dict[str, dict[str, tuple[str, ...]]] = {
    FSH: {
        "heat_transfer": ("alpha_nom_W_m2K",),
        "metal_heat_capacity": ("c_metal_J_kgK",),
        "firing_lag": ("tau_mill_s", "tau_firing_s"),
        "sensor_lag": ("tau_tc1_s", "tau_tc2_s"),
    },
    BENSON: {
        "heat_transfer": (
            "kA_eco_MW_K",
            "kA_evap_MW_K",
            "kA_sh1_MW_K",
            "kA_sh2_MW_K",
            "kA_sh3_MW_K",
            "kA_sh4_MW_K",
            "kA_rh_MW_K",
        ),  # fmt: skip
        "metal_heat_capacity": ("c_metal_J_kgK",),
        "firing_lag": ("tau_furnace_s",),
        "sensor_lag": ("tau_tc1_s", "tau_tc2_s"),
    },
    BTM: {
        "heat_transfer": (
            "alpha_sh_W_m2K",
            "alpha_rh_W_m2K",
            "platen_kA_film_MW_K",
            "platen_kA_wall_MW_K",
        ),  # fmt: skip
        "metal_heat_capacity": ("c_metal_J_kgK", "platen_metal_MJ_K"),
        "firing_lag": ("tau_mill_s", "tau_firing_s"),
        "sensor_lag": ("tau_tc1_s", "tau_tc2_s"),
    },
    DRUM: {
        "heat_transfer": ("alpha_nom_W_m2K",),
        "metal_heat_capacity": ("c_metal_J_kgK", "C_p_J_kgK"),
        "firing_lag": ("tau_mill_s", "tau_firing_s"),
        "sensor_lag": ("tau_tc1_s", "tau_tc2_s"),
    },
    CASCADE: {
        "section_gains": ("lead_gain_K_s_kg", "inertia_gain"),
        "section_time_constants": ("lead_time_s", "inertia_time_s"),
    },
}

#: Factors of the named variants of the four boilers (group -> factor).
_BOILER_VARIANTS = {
    "fouled_heavy_metal": {"heat_transfer": 0.8, "metal_heat_capacity": 1.25},
    "clean_light_metal": {"heat_transfer": 1.2, "metal_heat_capacity": 0.75},
    "slow_firing_lag_sensor": {"firing_lag": 1.5, "sensor_lag": 2.0},
    "fast_firing_lag_sensor": {"firing_lag": 0.5, "sensor_lag": 0.5},
}
#: Factors of the named variants of Cascade300MW.
_CASCADE_VARIANTS = {
    "high_gain_slow": {"section_gains": 1.3, "section_time_constants": 1.3},
    "high_gain_fast": {"section_gains": 1.3, "section_time_constants": 0.7},
    "low_gain_slow": {"section_gains": 0.7, "section_time_constants": 1.3},
    "low_gain_fast": {"section_gains": 0.7, "section_time_constants": 0.7},
}
#: plant id -> variant -> group factors (what :data:`MISMATCH` is made of).
VARIANT_FACTORS: dict[str, dict[str, dict[str, float]]] = {
    FSH: _BOILER_VARIANTS, BENSON: _BOILER_VARIANTS, BTM: _BOILER_VARIANTS,
    DRUM: _BOILER_VARIANTS, CASCADE: _CASCADE_VARIANTS,
}  # fmt: skip

#: plant id -> variant -> ``params`` of ``gym.make`` (the default values times the
#: variant's factors of :data:`VARIANT_FACTORS`), the public model-mismatch set.
MISMATCH: dict[str, dict[str, dict[str, float]]] = {
    FSH: {
        "fouled_heavy_metal": {"alpha_nom_W_m2K": 2800.0, "c_metal_J_kgK": 687.5},
        "clean_light_metal": {"alpha_nom_W_m2K": 4200.0, "c_metal_J_kgK": 412.5},
        "slow_firing_lag_sensor": {"tau_mill_s": 90.0, "tau_firing_s": 135.0,
                                   "tau_tc1_s": 10.0, "tau_tc2_s": 40.0},
        "fast_firing_lag_sensor": {"tau_mill_s": 30.0, "tau_firing_s": 45.0,
                                   "tau_tc1_s": 2.5, "tau_tc2_s": 10.0},
    },
    BENSON: {
        "fouled_heavy_metal": {"kA_eco_MW_K": 9.6, "kA_evap_MW_K": 32.0, "kA_sh1_MW_K": 4.8,
                               "kA_sh2_MW_K": 4.0, "kA_sh3_MW_K": 4.0, "kA_sh4_MW_K": 4.4,
                               "kA_rh_MW_K": 4.0, "c_metal_J_kgK": 687.5},
        "clean_light_metal": {"kA_eco_MW_K": 14.4, "kA_evap_MW_K": 48.0, "kA_sh1_MW_K": 7.2,
                              "kA_sh2_MW_K": 6.0, "kA_sh3_MW_K": 6.0, "kA_sh4_MW_K": 6.6,
                              "kA_rh_MW_K": 6.0, "c_metal_J_kgK": 412.5},
        "slow_firing_lag_sensor": {"tau_furnace_s": 30.0, "tau_tc1_s": 10.0,
                                   "tau_tc2_s": 40.0},
        "fast_firing_lag_sensor": {"tau_furnace_s": 10.0, "tau_tc1_s": 2.5,
                                   "tau_tc2_s": 10.0},
    },
    BTM: {
        "fouled_heavy_metal": {"alpha_sh_W_m2K": 4800.0, "alpha_rh_W_m2K": 1200.0,
                               "platen_kA_film_MW_K": 3.52, "platen_kA_wall_MW_K": 2.2,
                               "c_metal_J_kgK": 750.0, "platen_metal_MJ_K": 151.25},
        "clean_light_metal": {"alpha_sh_W_m2K": 7200.0, "alpha_rh_W_m2K": 1800.0,
                              "platen_kA_film_MW_K": 5.28, "platen_kA_wall_MW_K": 3.3,
                              "c_metal_J_kgK": 450.0, "platen_metal_MJ_K": 90.75},
        "slow_firing_lag_sensor": {"tau_mill_s": 150.0, "tau_firing_s": 22.5,
                                   "tau_tc1_s": 10.0, "tau_tc2_s": 40.0},
        "fast_firing_lag_sensor": {"tau_mill_s": 50.0, "tau_firing_s": 7.5,
                                   "tau_tc1_s": 2.5, "tau_tc2_s": 10.0},
    },
    DRUM: {
        "fouled_heavy_metal": {"alpha_nom_W_m2K": 2800.0, "c_metal_J_kgK": 687.5,
                               "C_p_J_kgK": 687.5},
        "clean_light_metal": {"alpha_nom_W_m2K": 4200.0, "c_metal_J_kgK": 412.5,
                              "C_p_J_kgK": 412.5},
        "slow_firing_lag_sensor": {"tau_mill_s": 90.0, "tau_firing_s": 90.0,
                                   "tau_tc1_s": 10.0, "tau_tc2_s": 40.0},
        "fast_firing_lag_sensor": {"tau_mill_s": 30.0, "tau_firing_s": 30.0,
                                   "tau_tc1_s": 2.5, "tau_tc2_s": 10.0},
    },
    CASCADE: {
        "high_gain_slow": {"lead_gain_K_s_kg": 2.613, "inertia_gain": 2.717,
                           "lead_time_s": 20.8, "inertia_time_s": 28.99},
        "high_gain_fast": {"lead_gain_K_s_kg": 2.613, "inertia_gain": 2.717,
                           "lead_time_s": 11.2, "inertia_time_s": 15.61},
        "low_gain_slow": {"lead_gain_K_s_kg": 1.407, "inertia_gain": 1.463,
                          "lead_time_s": 20.8, "inertia_time_s": 28.99},
        "low_gain_fast": {"lead_gain_K_s_kg": 1.407, "inertia_gain": 1.463,
                          "lead_time_s": 11.2, "inertia_time_s": 15.61},
    },
}  # fmt: skip

#: Draws tried per episode before a draw that fails raises.
MAX_DRAWS = 8
#: Seed word that separates the plant draws from every other use of an episode's key.
_STREAM = 0x706C616E74  # "plant"


def plant_groups(plant_id: str) -> dict[str, tuple[str, ...]]:
    """The groups of ``plant_id`` (ValueError for a plant without any)."""
    try:
        return GROUPS[plant_id]
    except (KeyError, TypeError):
        raise ValueError(f"plant_randomization: no parameter groups for {plant_id!r}; "
                         f"plants with groups: {sorted(GROUPS)}") from None  # fmt: skip


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
        raise ValueError(f"plant_randomization must be True, False, None or a dict "
                         f"{{group: (lo, hi)}}, got {type(option).__name__} "
                         f"{str(option)[:60]!r}")  # fmt: skip
    if not option:
        raise ValueError("plant_randomization is an empty dict; give at least one group "
                         f"of {list(groups)} or True")  # fmt: skip
    unknown = [g for g in option if g not in groups]
    if unknown:
        raise ValueError(f"plant_randomization: unknown group(s) {[str(g)[:40] for g in unknown]} "
                         f"for {plant_id}; valid groups: {list(groups)}")  # fmt: skip
    out = {}
    for g in groups:  # the plant's order: the draw does not depend on the dict's order
        if g not in option:
            continue
        value = option[g]
        if (isinstance(value, (str, bytes)) or not hasattr(value, "__len__")
                or len(value) != 2):  # fmt: skip
            raise ValueError(f"plant_randomization[{g!r}] must be a pair (lo, hi) of "
                             f"factors, got {str(value)[:60]!r}")  # fmt: skip
        lo, hi = value
        for name, v in (("lo", lo), ("hi", hi)):
            if not is_real(v) or isinstance(v, (bool, np.bool_)) or not is_finite(v):
                raise ValueError(f"plant_randomization[{g!r}]: {name} must be a finite "
                                 f"number, got {str(v)[:40]!r}")  # fmt: skip
            if not v > 0:
                raise ValueError(f"plant_randomization[{g!r}]: {name} = {v!r} must be a "
                                 "positive factor")  # fmt: skip
        if lo > hi:
            raise ValueError(f"plant_randomization[{g!r}]: lo = {lo!r} is above hi = {hi!r}")
        out[g] = (float(lo), float(hi))
    return out


def draw_factors(ranges: dict[str, tuple[float, float]], rng: np.random.Generator
                 ) -> dict[str, float]:  # fmt: skip
    """One factor per group, log-uniform in its range (one uniform number per group, in
    the order of ``ranges``, also for a fixed range lo == hi)."""
    out = {}
    for g, (lo, hi) in ranges.items():
        u = float(rng.random())
        out[g] = lo if lo == hi else math.exp(math.log(lo) + u * (math.log(hi) - math.log(lo)))
    return out


def scaled(plant_id: str, base: Mapping[str, Any], factors: Mapping[str, float]
           ) -> dict[str, Any]:  # fmt: skip
    """``base`` (parameter overrides of ``gym.make``'s ``params``) with every field of each
    group of ``factors`` set to its value (the override, else the default) times the
    group's factor."""
    from steamtemp_gym import plants

    defaults = {f.name: f.default for f in dataclasses.fields(plants.plant_class(plant_id).Params)}
    out = dict(base)
    groups = plant_groups(plant_id)
    for g, k in factors.items():
        for name in groups[g]:
            out[name] = float(base.get(name, defaults[name])) * k
    return out


def episode_rng(key: int, attempt: int) -> np.random.Generator:
    """The generator of draw ``attempt`` of the episode with noise key ``key``."""
    return np.random.default_rng(np.random.SeedSequence([int(key), _STREAM, int(attempt)]))


def draw_plant(plant_id: str, base: Mapping[str, Any], ranges: dict[str, tuple[float, float]],
               key: int, fits: Callable[[Any], bool]) -> tuple[Any, dict[str, float]]:  # fmt: skip
    """(plant, its factors) of the episode with noise key ``key``: the first of up to
    :data:`MAX_DRAWS` draws whose plant can be built and passes ``fits`` (the start check).

    Raises:
        ValueError: no draw passed; names the groups, their factors and parameters.
    """
    from steamtemp_gym import plants

    tried = []
    for attempt in range(MAX_DRAWS):
        factors = draw_factors(ranges, episode_rng(key, attempt))
        params = scaled(plant_id, base, factors)
        try:
            plant = plants.make(plant_id, **params)
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
