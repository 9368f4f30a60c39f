"""The default reward, in engineering terms, and its options.

Per control interval (all temperatures in K, e = setpoint - true outlet temperature):

    c(e) = w_abs |e|/T0 + w_sq (e/T0)^2 + w_band max(0, |e| - band_K)/T0
    r = -( c(e) + w_secondary sum_k c(e_k)
           + w_spray max(0, sum(spray flow) - design spray) / spray scale
           + w_move sum|u_k - u_{k-1}| )
        - trip_penalty  if the step terminates the episode (unit trip)

e_k are the errors of the plant's secondary controlled temperatures
(``Plant.secondary``, e.g. the reheat steam temperature of Toyoda and Wada 1999, whose
controller design scores STE and RTE together).

T0 = 20 K is the normalizing temperature of Sagara et al. 1998 (its
|Delta T_a| <= 20 K maps to [-1, 1]); band_K = 5 K is the inner band plant
engineers read (+-5 K; +-8 K during load changes of drum units). The spray term charges spray
water above the plant's design spray at the current operating point
(``Plant.design_spray``: what the boiler's schedules are designed to need; spray
beyond it bypasses heating surfaces and costs cycle efficiency), so a controller
that holds the setpoint with the design spray scores close to zero apart from the
temperature terms; the spray scale is the observation scale of the first spray
flow (about the design spray at rated load). The move term charges valve travel
(wear, reversals). u are the valve commands in [0, 1]. The reward uses the *true*
outlet temperature (the agent sees only the measured one).

The trip (``terminated``) is the outlet leaving the plant's trip band,
``Plant.trip_band_K``: by default 50 K below and 28 K above the setpoint (the
turbine's main-steam limits, steamtemp_gym/plants/base.py:TRIP_BAND_K).

Options: ``gym.make(id, reward={"w_move": 0.0, ...})``; unknown keys raise ValueError.

This module is the one place the reward is defined: :func:`row_reward` assembles the
terms of one row's transition from the plant's outputs and commands (the env core calls
it from its compiled step, steamtemp_gym/envs/core.py), :func:`reward` combines them. A
different reward is either a Gymnasium wrapper over ``info`` (every term's inputs are
there: temperatures, setpoint, spray flow, valve openings) or a change of these two
functions.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields

import numpy as np

from steamtemp_gym._jit import njit
from steamtemp_gym.checks import check_fields, key_list, ranged
from steamtemp_gym.slots import slots

#: Largest weight accepted (every weight is >= 0): with the trip band and these ranges every
#: per-step reward is finite (|e| is bounded by the steam tables' range, about 800 K).
MAX_WEIGHT = 1e4


def _weight(default: float) -> float:
    """A weight's field: ``default``, accepted in [0, :data:`MAX_WEIGHT`]."""
    return ranged(default, 0.0, MAX_WEIGHT)


@dataclass(frozen=True)
class RewardConfig:
    """Weights of the default reward (see module docstring), each in [0, MAX_WEIGHT]; the
    temperature scale, the band (K) and the trip penalty (a one-off cost) in ranges of
    their own."""

    T0_K: float = ranged(20.0, 0.1, 1000.0)
    w_abs: float = _weight(1.0)
    w_sq: float = _weight(0.0)
    band_K: float = ranged(5.0, 0.0, 500.0)
    w_band: float = _weight(1.0)
    w_spray: float = _weight(0.02)
    w_move: float = _weight(0.1)
    trip_penalty: float = ranged(100.0, 0.0, 1e6)
    w_secondary: float = _weight(1.0)

    def __post_init__(self) -> None:
        check_fields(self, "reward option {name!r}")

    @classmethod
    def from_options(cls, options: dict | RewardConfig | None) -> RewardConfig:
        """Build from a dict of overrides, rejecting unknown keys."""
        if options is None:
            return cls()
        if isinstance(options, RewardConfig):
            return options
        if not isinstance(options, dict):
            raise ValueError(f"reward options must be a dict, got {type(options).__name__}")
        valid = [f.name for f in fields(cls)]
        unknown = key_list(set(options) - set(valid))
        if unknown:
            raise ValueError(f"unknown reward option(s) {unknown}; valid options: {valid}")
        return cls(**options)

    def to_array(self) -> np.ndarray:
        """Weights in the order the kernel reads them."""
        return np.array(list(asdict(self).values()), dtype=np.float64)


#: Index of each weight in :meth:`RewardConfig.to_array` (the dataclass's field order).
W = slots("RewardWeights", *(f.name for f in fields(RewardConfig)))
N_WEIGHTS = len(W)


@njit(cache=True, error_model="numpy")
def temperature_cost(e, w):
    """c(e) of the module docstring for a temperature error e (K)."""
    a = abs(e) / w[W.T0_K]
    return (
        w[W.w_abs] * a
        + w[W.w_sq] * a * a
        + w[W.w_band] * max(0.0, abs(e) - w[W.band_K]) / w[W.T0_K]
    )


@njit(cache=True, error_model="numpy")
def reward(e, secondary_cost, spray_norm, move, terminated, w):
    """Reward of one transition (see module docstring); w = RewardConfig.to_array().

    ``secondary_cost`` is the sum of temperature_cost over the secondary errors.
    """
    r = (
        temperature_cost(e, w)
        + w[W.w_secondary] * secondary_cost
        + w[W.w_spray] * spray_norm
        + w[W.w_move] * move
    )
    if terminated:
        r += w[W.trip_penalty]
    return -r


@njit(cache=True, error_model="numpy")
def row_reward(
    b, Z, U, U_prev, e, terminated, sprays, i_design, spray_scale, secondary, secondary_sp, w
):
    """Reward of row b's transition (module docstring) from its plant outputs ``Z[b]``, its
    commands ``U[b]`` and the previous ones ``U_prev[b]`` (valve openings in [0, 1]).

    Args:
        e: Main-steam setpoint minus the true outlet temperature (K).
        sprays: Columns of Z holding spray flows (kg/s); their sum is charged above the
            design spray ``Z[b, i_design]`` (all of it if ``i_design < 0``), in units of
            ``spray_scale``.
        secondary: Columns of Z of the secondary controlled temperatures, with their
            setpoints ``secondary_sp`` (C).
        w: The weights, :meth:`RewardConfig.to_array`.
    """
    spray = 0.0
    for j in range(sprays.shape[0]):
        spray += Z[b, sprays[j]]
    if i_design >= 0:  # only spray above the design spray of this operating point
        spray = max(spray - Z[b, i_design], 0.0)
    spray /= spray_scale
    move = 0.0
    for j in range(U.shape[1]):
        move += abs(U[b, j] - U_prev[b, j])
    sec = 0.0
    for j in range(secondary.shape[0]):
        sec += temperature_cost(secondary_sp[j] - Z[b, secondary[j]], w)
    return reward(e, sec, spray, move, terminated, w)


@njit(cache=True, error_model="numpy")
def non_finite_reward(trip_below_K, w):
    """Reward of a transition that left the plant's valid region (a non-finite state or
    output): a trip at the lower edge of the trip band, no other term."""
    return reward(trip_below_K, 0.0, 0.0, 0.0, True, w)
