"""A toy plant for the registry-wide tests: a spray valve and a few equal first-order lags.

The spray (a first-order valve, flow proportional to its opening; the spray water's
temperature is not modelled) cools the steam at the attemperator; heat absorption raises
it again across the section, whose response is ``n_lags`` equal lags of a time constant
that grows as the steam flow (the load) falls; a thermowell lag on each measured
temperature. Registered for the test session only (tests/conftest.py), with no more than
its module and that one line: the registry-wide suite runs on it and skips what a plant
without stored data cannot have.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from steamtemp_gym._jit import njit, read_only
from steamtemp_gym.checks import ranged
from steamtemp_gym.plants.base import (
    D_FOULING,
    D_HEAT_BIAS,
    D_LOAD,
    Plant,
    Signal,
    design_spray_signal,
)
from steamtemp_gym.plants.param_ranges import validate_params
from steamtemp_gym.slots import slots

PLANT_ID = "test/ToyLags-v0"
MAX_LAGS = 8


@dataclass(frozen=True)
class ToyParams:
    """The toy's parameters (units in the names)."""

    T_out_C: float = ranged(540.0, 400.0, 620.0)  # main-steam setpoint
    T_in_C: float = ranged(470.0, 350.0, 560.0)  # attemperator inlet at the design spray
    rise_K: float = ranged(80.0, 10.0, 200.0)  # heat-absorption rise across the section
    spray_max_kg_s: float = ranged(20.0, 1.0, 100.0)
    spray_design_kg_s: float = ranged(10.0, 0.0, 50.0)  # at rated load, falls with load
    cooling_K_s_kg: float = ranged(5.0, 0.5, 20.0)  # attemperator cooling per kg/s of spray
    n_lags: int = ranged(3, 1, MAX_LAGS)
    tau_lag_s: float = ranged(25.0, 1.0, 600.0)  # each lag's time constant at rated load
    tau_valve_s: float = ranged(3.0, 0.1, 60.0)
    tau_tc_s: float = ranged(8.0, 0.1, 120.0)  # thermowell
    dt_s: float = ranged(2.0, 0.01, 60.0)
    n_substeps: int = ranged(1, 1, 50)

    def __post_init__(self) -> None:
        validate_params(self, positive=("tau_lag_s", "tau_valve_s", "tau_tc_s", "dt_s"))
        if self.spray_design_kg_s >= self.spray_max_kg_s:
            raise ValueError("ToyParams.spray_design_kg_s must be below spray_max_kg_s")


OUTPUTS = (
    Signal("outlet_temp_C", "C", 540.0, 20.0, observed=False, description="true outlet"),
    Signal("outlet_temp_meas_C", "C", 540.0, 20.0, noisy=True, description="outlet reading"),
    Signal(
        "attemp_out_temp_meas_C",
        "C",
        460.0,
        30.0,
        noisy=True,
        description="attemperator outlet reading (inner loop)",
    ),
    Signal("spray_valve", "1", 0.5, 0.5, description="valve position feedback"),
    Signal("spray_flow_kg_s", "kg/s", 10.0, 10.0),
    design_spray_signal(10.0, 10.0, "the spray the design inlet temperature needs at this load"),
)
IZ = slots("ToyOutputs", *(s.name for s in OUTPUTS))
IP = slots(
    "ToyPacked", "TOUT", "TIN", "RISE", "WMAX", "WDES", "COOL", "NL", "TAUL", "TAUV", "TAUTC"
)
#: states: the valve, the two thermowells (attemperator, outlet), then the lags
IX = slots("ToyStates", "V", "TCA", "TCO", "LAG")


@njit(cache=True)
def _load(d):
    """The row's load, within the 20-120 % the toy's schedules cover."""
    return min(max(d[D_LOAD], 0.2), 1.2)


@njit(cache=True)
def _inputs(v, d, P):
    """(attemperator outlet temperature C, the heat rise K, spray kg/s) at opening v."""
    load = _load(d)
    w = v * P[IP.WMAX]
    t_a = P[IP.TIN] - P[IP.COOL] * (w - P[IP.WDES] * load)
    rise = P[IP.RISE] * d[D_FOULING] * (1.0 + d[D_HEAT_BIAS])
    return t_a, rise, w


@njit(cache=True, nogil=True)
def step(X, U, D, P, jrow, jcol, dt, n_sub, Z):  # noqa: N803
    """Advance every row by dt (exact for each lag with its input held); dt = 0: outputs."""
    n = int(P[IP.NL])
    for b in range(X.shape[0]):
        x, d = X[b], D[b]
        load = _load(d)
        h = dt / n_sub
        for _ in range(n_sub if dt > 0.0 else 0):
            x[IX.V] += (min(max(U[b, 0], 0.0), 1.0) - x[IX.V]) * (1.0 - math.exp(-h / P[IP.TAUV]))
            t_a, rise, _ = _inputs(x[IX.V], d, P)
            a = 1.0 - math.exp(-h * load / P[IP.TAUL])
            u = t_a + rise
            for i in range(n):
                x[IX.LAG + i] += (u - x[IX.LAG + i]) * a
                u = x[IX.LAG + i]
            c = 1.0 - math.exp(-h / P[IP.TAUTC])
            x[IX.TCA] += (t_a - x[IX.TCA]) * c
            x[IX.TCO] += (x[IX.LAG + n - 1] - x[IX.TCO]) * c
        t_a, _, w = _inputs(x[IX.V], d, P)
        z = Z[b]
        z[IZ.outlet_temp_C] = x[IX.LAG + n - 1]
        z[IZ.outlet_temp_meas_C] = x[IX.TCO]
        z[IZ.attemp_out_temp_meas_C] = x[IX.TCA]
        z[IZ.spray_valve] = x[IX.V]
        z[IZ.spray_flow_kg_s] = w
        z[IZ.design_spray_kg_s] = P[IP.WDES] * load


@njit(cache=True)
def steady(D, sp_C, P, X):
    """Each row at rest holding sp_C (the valve clipped to [0, 1])."""
    n = int(P[IP.NL])
    for b in range(X.shape[0]):
        x, d = X[b], D[b]
        t_a0, rise, _ = _inputs(0.0, d, P)
        v = min(max((t_a0 + rise - sp_C[b]) / (P[IP.COOL] * P[IP.WMAX]), 0.0), 1.0)
        x[IX.V] = v
        t_a, rise, _ = _inputs(v, d, P)
        for i in range(n):
            x[IX.LAG + i] = t_a + rise
        x[IX.TCA] = t_a
        x[IX.TCO] = t_a + rise


@functools.lru_cache(maxsize=8)
def _pack(params: ToyParams) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    P = np.array(
        [
            params.T_out_C,
            params.T_in_C,
            params.rise_K,
            params.spray_max_kg_s,
            params.spray_design_kg_s,
            params.cooling_K_s_kg,
            params.n_lags,
            params.tau_lag_s,
            params.tau_valve_s,
            params.tau_tc_s,
        ]
    )
    empty = np.zeros(0, dtype=np.int64)
    return read_only(P), empty, empty, IX.LAG + params.n_lags


class ToyLags(Plant):
    """The toy plant (module docstring)."""

    id = PLANT_ID
    source = "a test fixture of steamtemp_gym: a spray valve and equal first-order lags"
    Params = ToyParams
    actions = (Signal("spray_valve_cmd", "1", 0.5, 0.5, description="spray valve command"),)
    outputs = OUTPUTS
    setpoint_C = 540.0
    setpoint_param = "T_out_C"
    design_spray = "design_spray_kg_s"
    default_duration_s = 1800.0
    perturbation_groups = {"section_time_constants": ("tau_lag_s",), "sensor_lag": ("tau_tc_s",)}
    #: LQI's error bound chosen as the package's plants choose theirs (baselines/lqi.py): at
    #: the default 1 K its valve travels 13x cascade_pi_ff's on load_ramp_100_50, at 3 K 2.3x
    commissioning = {"lqi": {"e_max_K": 3.0}}

    pack = staticmethod(_pack)

    def kernel(self):
        return step

    def steady_state(self, D: np.ndarray, setpoint_C: np.ndarray, X: np.ndarray) -> None:
        steady(D, np.asarray(setpoint_C, dtype=np.float64).copy(), self.P, X)
