"""The paper's named scenarios of the 300 MW cascade plant (the class's ``scenarios``)."""

from __future__ import annotations

from steamtemp_gym import scenarios as sc
from steamtemp_gym.scenarios.library import declare

MIN = 60.0
_RAMP = 0.5 / (2.0 / 100.0 / MIN)  # 100 -> 50 % at 2 %/min: 1500 s
#: name -> Scenario, with the disturbances of real operation switched on (``declare``).
SCENARIOS = declare(
    sc.Scenario(
        name="setpoint_step_535_545",
        duration_s=2000.0,
        setpoint_offset_C=((0.0, 0.0), (500.0, 0.0), (500.0, 10.0)),
        description="setpoint 535 C, step to 545 C at 500 s, rated load (Zhang et al. 2012)",
    ),
    sc.Scenario(
        name="load_ramp_100_50_100_2pct",
        duration_s=500.0 + 2 * _RAMP + 20 * MIN + 15 * MIN,
        load=(
            (0.0, 1.0),
            (500.0, 1.0),
            (500.0 + _RAMP, 0.5),
            (500.0 + _RAMP + 20 * MIN, 0.5),
            (500.0 + 2 * _RAMP + 20 * MIN, 1.0),
        ),
        description="100 -> 50 % at 2 %/min after 500 s, hold 20 min, back at 2 %/min, "
        "hold 15 min (an AGC-rate ramp: 1-2 %/min; load-dependent dynamics)",
    ),
)
