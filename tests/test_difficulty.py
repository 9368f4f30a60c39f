"""The benchmark has headroom: difficulty targets over every id (agents/difficulty.py).

Means over 3 seeds of the named scenarios (sensor noise and the coloured heat-absorption
disturbance on). Targets: the field tolerances of steam temperature control in load
changes (+-10 K once-through, +-8 K drum; docs/difficulty.md) and a benchmark with headroom
above the plain cascade.
"""

from __future__ import annotations

import pytest

import steamtemp_gym
from agents.difficulty import (
    RAMPS,
    TARGETS,
    TU_TG_MEASURED_MAX,
    TU_TG_TRUE,
    evaluate,
    ramp_band,
    spray_step_dead_time,
)
from steamtemp_gym import scenarios

IDS = steamtemp_gym.ENV_IDS
#: The plants with a steam-water circuit (``Plant.circulation``): a ramp band and a spray.
BOILERS = [i for i in IDS if ramp_band(i) is not None]


@pytest.mark.parametrize("env_id", IDS)
def test_frozen_valve_drifts_far_on_the_load_ramp(env_id):
    m = evaluate(env_id, "frozen", "load_ramp_100_50")
    assert m["max_abs_dev_K"] >= TARGETS["frozen_ramp_peak_min_K"]


@pytest.mark.parametrize("env_id", BOILERS)
def test_cascade_pi_peak_on_the_ramps_is_in_the_field_band(env_id):
    lo, hi = ramp_band(env_id)
    for sc in RAMPS:
        m = evaluate(env_id, "cascade_pi", sc)
        assert lo <= m["max_abs_dev_K"] <= hi, (sc, m["max_abs_dev_K"])


#: Plants where the identified feed-forward falls short of the 25 % margin (measured, 3 seeds).
FF_SHORT = {
    "steamtemp/BoilerTurbineMIMO-v0": "margins 33 % down-ramp (4.7 -> 3.1 K), 5 % up-ramp "
    "(4.2 -> 4.0 K); not diagnosed",
    "steamtemp/SupercriticalFSH-v0": "margins 24.5 % down-ramp (5.23 -> 3.95 K), 45 % up-ramp "
    "(6.2 -> 3.5 K): the range-commissioned PI peaks lower on the down-ramp",
}


@pytest.mark.parametrize(
    "env_id",
    [
        pytest.param(i, marks=pytest.mark.xfail(strict=True, reason=FF_SHORT[i]))
        if i in FF_SHORT
        else i
        for i in BOILERS
    ],
)
def test_load_feedforward_shows_headroom_over_cascade_pi(env_id):
    """A better-informed controller (the load demand is observed) beats plain PI clearly."""
    for sc in RAMPS:
        pi = evaluate(env_id, "cascade_pi", sc)["max_abs_dev_K"]
        ff = evaluate(env_id, "cascade_pi_ff", sc)["max_abs_dev_K"]
        assert ff <= (1.0 - TARGETS["ff_peak_reduction_min"]) * pi, (sc, pi, ff)


@pytest.mark.parametrize("env_id", IDS)
def test_cascade_pi_never_trips_on_a_named_scenario(env_id):
    for sc in scenarios.names(env_id):
        if sc != scenarios.RANDOM:
            assert evaluate(env_id, "cascade_pi", sc)["tripped"] == 0.0, sc


def test_cascade300_pi_error_std_is_of_the_papers_order():
    """004 Section 5 reports a tracking-error std of 1.7 K for its improved controller."""
    m = evaluate("steamtemp/Cascade300MW-v0", "cascade_pi", "setpoint_step_535_545")
    lo, hi = TARGETS["cascade300_pi_std_K"]
    assert lo <= m["late_error_std_K"] <= hi


@pytest.mark.parametrize("load", [1.0, 0.5])
@pytest.mark.parametrize("env_id", BOILERS)
def test_spray_step_has_the_field_dead_time(env_id, load):
    """Last-stage spray step: Tu/Tg of the true turbine-inlet temperature in the field range
    (the main-steam line; without it 0.02-0.06), the thermocouple reading a bit above."""
    true, meas = spray_step_dead_time(env_id, load)
    r_true, r_meas = true.theta_s / true.tau_s, meas.theta_s / meas.tau_s
    assert TU_TG_TRUE[0] <= r_true <= TU_TG_TRUE[1]
    assert r_true < r_meas <= TU_TG_MEASURED_MAX
