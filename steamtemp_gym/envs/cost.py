"""The constraint cost of a control interval and its default budget per episode, for safe
RL (the conventions of Safety-Gymnasium and OmniSafe: a non-negative cost per step, a
limit on its sum over an episode).

The cost of the interval from the previous info to this step's is the fraction of it during
which the true main-steam temperature lies outside ``setpoint +- 5 K``
(:data:`COST_BAND_K`), reading the error ``outlet_temp_C - setpoint_C`` as the straight
line between its two samples: in [0, 1], 0 inside the band, 1 for an interval spent
wholly outside it. It is the integrand of the metric ``time_outside_5K_s``
(:func:`steamtemp_gym.metrics.calculus.frac_outside`, one function for both), so over an
episode ``sum(cost_band * dt) == time_outside_5K_s`` bit for bit (summed as numpy sums).
A step whose plant left its valid region (a non-finite output, ``trip_reason``
``non_finite_state``) costs 1.

``info["cost"]`` is the sum of the components, each also in info: ``cost_band`` (the
above). No plant exposes the attemperator outlet's margin above saturation (the
SupercriticalFSH and DrumBoilerSH interlocks compute it inside their kernels to cap the
spray, and output neither it nor the saturation temperature), so there is no saturation
component. A reset's info carries cost 0 (no interval yet).

:func:`cost_limit` is the default budget of an episode's summed cost: a share of the
episode's control intervals (:data:`COST_LIMIT_SHARE` by scenario name,
:data:`DEFAULT_COST_LIMIT_SHARE` for any other), from what the industrial reference
``cascade_pi_ff`` incurs (docs/safe_rl.md gives the measurement).
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np

from steamtemp_gym import catalog, scenarios
from steamtemp_gym._jit import njit
from steamtemp_gym.metrics.calculus import frac_outside
from steamtemp_gym.metrics.names import METRIC_NAMES, band_key
from steamtemp_gym.scenarios import Scenario

#: Half-width (K) of the band around the setpoint whose excursions cost: the band of the
#: metric :data:`COST_METRIC`.
COST_BAND_K: float = 5.0
#: The metric whose per-interval integrand the band cost is.
COST_METRIC: str = band_key(COST_BAND_K)
assert COST_METRIC in METRIC_NAMES
#: The info keys of the cost: the total, then its components.
COST_KEYS: tuple[str, ...] = ("cost", "cost_band")
#: Unit and meaning of each of :data:`COST_KEYS` (the reference pages' info tables).
COST_DOC: dict[str, tuple[str, str]] = {
    "cost": (
        "1",
        "constraint cost of the control interval for safe RL: the sum of its "
        "components (docs/safe_rl.md)",
    ),
    "cost_band": (
        "1",
        f"fraction of the interval with the true main steam more than "
        f"{COST_BAND_K:g} K from the setpoint (times dt: the interval's part of "
        f"{COST_METRIC})",
    ),
}

#: Default budget of each named scenario: the share of the episode's control intervals
#: its summed cost may reach. cascade_pi_ff's share (mean of seeds 0-2, the larger of
#: SupercriticalFSH and Cascade300MW; docs/safe_rl.md) rounded up to a multiple of 0.05.
COST_LIMIT_SHARE: dict[str, float] = {
    "load_ramp_100_50": 0.05,
    "load_ramp_50_100": 0.05,
    "load_cycle": 0.05,
    "load_following": 0.05,
    "heat_imbalance_step": 0.05,
    "setpoint_step": 0.10,
    "setpoint_step_535_545": 0.10,
    "load_ramp_100_50_100_2pct": 0.05,
    "random": 0.10,
    "deep_fast_ramp": 0.15,
    "high_noise": 0.05,
    "hp_heater_out": 0.05,
    "mill_trip": 0.45,
    "setpoint_ramp_during_load_ramp": 0.10,
    "sootblowing": 0.15,
}
#: The share of a scenario not in :data:`COST_LIMIT_SHARE` (a YAML file, a Scenario).
DEFAULT_COST_LIMIT_SHARE: float = 0.10


@njit(cache=True, error_model="numpy")
def interval_cost(e0: float, e1: float) -> float:
    """Band cost of the interval from error ``e0`` to ``e1`` (K, outlet minus setpoint):
    the fraction of it outside +-:data:`COST_BAND_K`; 1 if either is not finite."""
    if not (np.isfinite(e0) and np.isfinite(e1)):
        return 1.0
    return frac_outside(e0, e1, COST_BAND_K)


def cost_limit(scenario: Any, dt_s: float) -> float:
    """The default limit of an episode's summed cost on ``scenario`` at control interval
    ``dt_s`` (s): its share (:data:`COST_LIMIT_SHARE` for the package's scenario of that
    name, else :data:`DEFAULT_COST_LIMIT_SHARE`: a YAML file or Scenario of one's own, even
    under a shipped scenario's name) of the episode's ``duration_s / dt_s`` intervals.

    Raises:
        ValueError: ``scenario`` is not a Scenario, or ``dt_s`` is not a positive finite
            number or so small that the limit is not finite.
    """
    if not isinstance(scenario, Scenario):
        raise ValueError(f"cost_limit needs a Scenario, got {type(scenario).__name__}")
    if (
        isinstance(dt_s, bool)
        or not isinstance(dt_s, (int, float, np.integer, np.floating))
        or (not (math.isfinite(dt_s) and dt_s > 0))
    ):
        raise ValueError(f"dt_s must be a positive finite number of seconds, got {dt_s!r}")
    share = COST_LIMIT_SHARE.get(scenario.name, DEFAULT_COST_LIMIT_SHARE)
    if share != DEFAULT_COST_LIMIT_SHARE and not _shipped(scenario):
        share = DEFAULT_COST_LIMIT_SHARE  # a scenario of its own under a shipped one's name
    limit = share * scenario.duration_s / float(dt_s)
    if not math.isfinite(limit):
        raise ValueError(
            f"dt_s {dt_s!r} is too small: the limit of a {scenario.duration_s:g} s "
            "episode would not be finite"
        )
    return limit


@functools.lru_cache(maxsize=256)
def _shipped(scenario: Scenario) -> bool:
    """Whether ``scenario`` is the package's scenario of its name (named or held-out, for
    some plant or none), not a scenario of one's own that bears the name."""
    for spec in (scenario.name, scenarios.HELDOUT_PREFIX + scenario.name):
        for plant_id in (None, *catalog.PLANTS):
            try:
                if scenarios.resolve(spec, plant_id) == scenario:
                    return True
            except ValueError:
                continue
    return False
