"""The plant class of ``steamtemp/DrumBoilerSH-v0``."""

from __future__ import annotations

import numpy as np

from steamtemp_gym.plants.base import Plant, Signal
from steamtemp_gym.plants.drum_boiler.calibration import _pack
from steamtemp_gym.plants.drum_boiler.kernel import KERNELS
from steamtemp_gym.plants.drum_boiler.layout import I_RATEV, I_TAUV, S_V
from steamtemp_gym.plants.drum_boiler.params import K0, DrumBoilerParams
from steamtemp_gym.plants.drum_boiler.steady_state import steady


class DrumBoilerSH(Plant):
    """Plant of ``steamtemp/DrumBoilerSH-v0`` (Kim (Inha Univ.) with Astrom-Bell 2000)."""

    id = "steamtemp/DrumBoilerSH-v0"
    source = "Kim, M.Eng. thesis, Inha Univ.; Astrom and Bell, Automatica 2000"
    Params = DrumBoilerParams
    actions = (Signal("spray_valve_cmd", "1", 0.5, 0.5, description="spray valve command"),)
    outputs = (
        Signal("outlet_temp_C", "C", 505.0, 20.0, observed=False, description="true main steam"),
        Signal("outlet_temp_meas_C", "C", 505.0, 20.0, noisy=True, description="thermocouple"),
        Signal("attemp_out_temp_C", "C", 390.0, 30.0, observed=False),
        Signal("attemp_out_temp_meas_C", "C", 390.0, 30.0, noisy=True),
        Signal("attemp_in_temp_C", "C", 440.0, 30.0, noisy=True, description="primary SH outlet"),
        Signal("steam_flow_kg_s", "kg/s", 39.0, 13.0, description="main steam flow"),
        Signal("drum_pressure_MPa", "MPa", 8.5, 0.5),
        Signal("drum_level_m", "m", 0.0, 0.2, description="above the normal water level"),
        Signal("feedwater_flow_kg_s", "kg/s", 37.5, 12.5),
        Signal("firing_rate", "1", 0.75, 0.3, description="firing, fraction of rated"),
        Signal("spray_valve", "1", 0.5, 0.5, description="valve position feedback"),
        Signal("spray_flow_kg_s", "kg/s", 2.5, 2.5),
        Signal("main_steam_pressure_MPa", "MPa", 8.2, 0.5),
        Signal("drum_steam_flow_kg_s", "kg/s", 37.5, 12.5, observed=False),
        Signal("heat_absorption_MW", "MW", 30.0, 10.0, observed=False, description="hidden, SH"),
        Signal("evaporator_heat_MW", "MW", 65.0, 21.0, observed=False),
        Signal("metal_temp_max_C", "C", 540.0, 40.0, observed=False),
        Signal("riser_exit_quality", "1", 0.05, 0.02, observed=False),
        Signal("downcomer_flow_kg_s", "kg/s", 1150.0, 100.0, observed=False),
        Signal(
            "design_spray_kg_s",
            "kg/s",
            2.0,
            2.0,
            observed=False,
            description="scheduled design spray (function generator over load)",
        ),
        Signal(
            "sh2_outlet_temp_C",
            "C",
            505.0,
            20.0,
            observed=False,
            description="final SH outlet, ahead of the outlet header and main-steam line",
        ),
        Signal("mill_output", "1", 0.75, 0.3, observed=False, description="coal to burners"),
    )
    design_spray = "design_spray_kg_s"
    setpoint_C = 505.0
    extra_info = (
        "attemp_out_temp_C", "heat_absorption_MW", "drum_pressure_MPa", "drum_level_m",
        "steam_flow_kg_s", "feedwater_flow_kg_s", "firing_rate",
    )  # fmt: skip

    pack = staticmethod(_pack)
    kernels = KERNELS
    actuators = ((S_V, I_TAUV, I_RATEV),)
    setpoint_param = "T_out_C"

    def steady_state(self, D: np.ndarray, setpoint_C: np.ndarray, X: np.ndarray) -> None:
        steady(D, setpoint_C + K0, self.P, X)
