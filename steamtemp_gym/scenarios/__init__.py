"""Scenarios: the world outside the plant.

A :class:`Scenario` is a set of piecewise-linear schedules over time (breakpoint
lists ``[[t_s, value], ...]``, linear interpolation, held constant after the
last breakpoint; two breakpoints at the same time are a step) in the common
vocabulary of the suite (``docs/architecture.md``):

========================== ========= ==========================================
channel                    unit      meaning
========================== ========= ==========================================
``load``                   fraction  unit load demand, fraction of rated
``setpoint_offset_C``      K         offset added to the plant's nominal setpoint
``heat_absorption_bias``   fraction  relative error of the superheater heat
                                     absorption (coal quality, mills, soot)
``fouling``                factor    gas-side heat-transfer multiplier (1 clean)
``spray_water_temp_offset_C`` K      spray-water temperature offset
========================== ========= ==========================================

plus three scalars:

- ``noise_std_C`` (K): standard deviation of the white noise on the measured
  temperatures (thermocouples of real units: 0.2-0.3 K);
- ``heat_absorption_noise_std`` (fraction) and ``heat_absorption_noise_tau_s`` (s):
  a coloured heat-absorption disturbance (slagging, coal quality, soot blowing,
  mill changes), an Ornstein-Uhlenbeck process with that stationary standard
  deviation and correlation time, added by the env to ``heat_absorption_bias``
  (exact discretization at the control interval, counter-based random numbers,
  started from its stationary distribution so that a reset is a steady state).

A field left out of a scenario means none of that disturbance (a file without
``noise_std_C`` is noise-free, so deterministic step tests stay possible). The
named scenarios have sensor noise and the coloured heat-absorption disturbance on
(:data:`NAMED_DISTURBANCES`). Every plant maps this vocabulary onto its own inputs.

Scenarios are deterministic; ``"random"`` is the seeded training distribution
drawn afresh at every reset (:func:`random_scenario`). The load-ramp test
``load_ramp_100_50`` (100 -> 50 % at 5 %/min from minute 20 to 30) is the test of
Sagara et al., JSME International Journal, Series C, 1998 (``docs/references.md``,
key 000).

Modules: ``model`` (the Scenario dataclass, its limits and validation), ``yaml_loader``
(scenario files), ``registry`` (names: :func:`register`, :func:`names`, :func:`get`,
:func:`resolve`), ``library`` (the named scenarios shared by every plant, and
:func:`declare` for a plant's own), ``distribution`` (``random``), ``tables`` (packing
into the kernels' breakpoint tables), ``heldout`` (the held-out set), ``stress``
(corner-biased scenarios).
"""

from steamtemp_gym.scenarios.distribution import (
    RANDOM_DISTRIBUTION,
    ScenarioFactory,
    random_scenario,
)
from steamtemp_gym.scenarios.library import NAMED_DISTURBANCES, declare
from steamtemp_gym.scenarios.model import (
    CHANNELS,
    DURATION_LIMITS_S,
    LIMITS,
    MAX_BREAKPOINTS_PER_CHANNEL,
    MAX_DESCRIPTION_CHARS,
    MAX_NAME_CHARS,
    Scenario,
    Schedule,
)
from steamtemp_gym.scenarios.registry import (
    HELDOUT_PREFIX,
    RANDOM,
    forms,
    get,
    names,
    register,
    resolve,
)
from steamtemp_gym.scenarios.tables import max_breakpoints, pack
from steamtemp_gym.scenarios.yaml_loader import MAX_FILE_BYTES, load_yaml

__all__ = [
    "CHANNELS",
    "Scenario",
    "declare",
    "forms",
    "get",
    "names",
    "register",
    "resolve",
    "load_yaml",
    "random_scenario",
    "pack",
    "RANDOM",
    "HELDOUT_PREFIX",
    "NAMED_DISTURBANCES",
    "MAX_FILE_BYTES",
    "MAX_BREAKPOINTS_PER_CHANNEL",
    "MAX_NAME_CHARS",
    "MAX_DESCRIPTION_CHARS",
    "DURATION_LIMITS_S",
    "LIMITS",
    "RANDOM_DISTRIBUTION",
    "ScenarioFactory",
    "Schedule",
    "max_breakpoints",
]
