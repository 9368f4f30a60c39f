"""Named scenarios shared by every plant (common vocabulary of ``docs/architecture.md``).

- ``load_ramp_100_50``: the load-ramp test of Sagara et al., JSME International
  Journal, Series C, 1998 (``docs/references.md``, key 000): load 100 -> 50 % at
  5 %/min from minute 20 to minute 30, then held to minute 60.
- ``load_ramp_50_100``: the same ramp upward.
- ``load_cycle``: the IDAES 320 MW dynamic example (``docs/references.md``): 100 -> 50 %
  at 5 %/min, hold 30 min, back to 100 % at 5 %/min, hold 20 min.
- ``setpoint_step``: +10 K setpoint step at 5 min, rated load (field step tests are
  5-10 K).
- ``heat_imbalance_step``: +8 % heat-absorption step (over 60 s) at 5 min, rated load.
- ``load_following``: AGC-like ramps of 1-2 %/min between 50 and 100 % (a fixed
  draw, seed 2026), holds of 3-8 min, 60 min.

Every named scenario carries the disturbances of real operation
(``NAMED_DISTURBANCES``: thermocouple noise and the coloured heat-absorption
disturbance), so each seed of a named scenario is a different realization of them.
A plant's own named scenarios carry them too: the plant declares them with
:func:`declare` as its ``scenarios`` class attribute.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from types import MappingProxyType

import numpy as np

from steamtemp_gym.scenarios.model import Scenario, describe
from steamtemp_gym.scenarios.registry import check_name
from steamtemp_gym.scenarios.registry import register as _register

MIN = 60.0

#: Disturbances on in every named scenario: thermocouple noise 0.25 K (real units:
#: 0.2-0.3 K) and a coloured heat-absorption disturbance of 2 % std with a 5 min
#: correlation time (slagging, coal quality and mill changes; plausible default, unverified).
NAMED_DISTURBANCES = {
    "noise_std_C": 0.25,
    "heat_absorption_noise_std": 0.02,
    "heat_absorption_noise_tau_s": 300.0,
}


def register(scenario: Scenario, plants: Sequence[str] | None = None) -> Scenario:
    """Register a named scenario with the disturbances of real operation switched on."""
    return _register(dataclasses.replace(scenario, **NAMED_DISTURBANCES), plants)


def declare(*scenarios: Scenario) -> Mapping[str, Scenario]:
    """A plant's own named scenarios, for its ``scenarios`` class attribute: each with the
    disturbances of real operation switched on, keyed by name (read-only).

    Raises:
        ValueError: not a Scenario, a name the command lines cannot spell (as for
            :func:`~steamtemp_gym.scenarios.registry.register`) or a name given twice.
    """
    out: dict[str, Scenario] = {}
    for scenario in scenarios:
        if not isinstance(scenario, Scenario):
            raise ValueError(f"declare() needs Scenarios, got {describe(scenario)}")
        check_name(scenario.name)
        if scenario.name in out:
            raise ValueError(f"scenario {scenario.name!r} is declared twice")
        out[scenario.name] = dataclasses.replace(scenario, **NAMED_DISTURBANCES)
    return MappingProxyType(out)


def _load_following() -> Scenario:
    """The fixed AGC-like draw of ``load_following`` (seed 2026)."""
    rng = np.random.default_rng(2026)
    t, load, pts = 0.0, 0.9, [(0.0, 0.9)]
    while t < 3600.0:
        t += rng.uniform(180.0, 480.0)
        target = float(np.clip(load + rng.choice([-1, 1]) * rng.uniform(0.1, 0.3), 0.5, 1.0))
        t_end = t + abs(target - load) / (rng.uniform(0.01, 0.02) / MIN)
        pts += [(t, load), (t_end, target)]
        t, load = t_end, target
    return Scenario(
        name="load_following",
        duration_s=3600.0,
        load=tuple(pts),
        description="AGC-like ramps of 1-2 %/min within 50-100 % load",
    )


register(
    Scenario(
        name="load_ramp_100_50",
        duration_s=60 * MIN,
        load=((0.0, 1.0), (20 * MIN, 1.0), (30 * MIN, 0.5)),
        description="load 100 -> 50 % at 5 %/min, minutes 20-30 (Sagara et al. 1998, Fig. 4, 7)",
    )
)
register(
    Scenario(
        name="load_ramp_50_100",
        duration_s=60 * MIN,
        load=((0.0, 0.5), (20 * MIN, 0.5), (30 * MIN, 1.0)),
        description="load 50 -> 100 % at 5 %/min from minute 20 to 30",
    )
)
register(
    Scenario(
        name="load_cycle",
        duration_s=80 * MIN,
        load=((0.0, 1.0), (10 * MIN, 1.0), (20 * MIN, 0.5), (50 * MIN, 0.5), (60 * MIN, 1.0)),
        description="100 -> 50 % at 5 %/min, hold 30 min, back, hold 20 min (IDAES example)",
    )
)
register(
    Scenario(
        name="setpoint_step",
        duration_s=30 * MIN,
        setpoint_offset_C=((0.0, 0.0), (5 * MIN, 0.0), (5 * MIN, 10.0)),
        description="+10 K setpoint step at minute 5, rated load",
    )
)
register(
    Scenario(
        name="heat_imbalance_step",
        duration_s=40 * MIN,
        heat_absorption_bias=((0.0, 0.0), (5 * MIN, 0.0), (6 * MIN, 0.08)),
        description="+8 % superheater heat absorption (firing imbalance) at minute 5, rated load",
    )
)
register(_load_following())
