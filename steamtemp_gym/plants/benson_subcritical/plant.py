"""The plant class of ``steamtemp/BensonSubcritical-v0``."""

from __future__ import annotations

import numpy as np

from steamtemp_gym.plants.base import MAIN, SCHEDULED, Plant, Signal
from steamtemp_gym.plants.benson_subcritical.calibration import _pack
from steamtemp_gym.plants.benson_subcritical.kernel import step
from steamtemp_gym.plants.benson_subcritical.params import K0, BensonParams
from steamtemp_gym.plants.benson_subcritical.steady_state import steady


def _temp(name: str, center: float, scale: float, what: str) -> Signal:
    return Signal(name, "C", center, scale, noisy=True, description=what)


class BensonSubcritical(Plant):
    """Plant of ``steamtemp/BensonSubcritical-v0`` (Ghaffari et al.)."""

    id = "steamtemp/BensonSubcritical-v0"
    source = "Ghaffari, Moosavian and Chaibakhsh, K. N. Toosi Univ. of Technology"
    Params = BensonParams
    actions = (
        Signal("spray_valve_1_cmd", "1", 0.5, 0.5, description="spray 1 (before SH3) command"),
        Signal("spray_valve_2_cmd", "1", 0.5, 0.5, description="spray 2 (before SH4) command"),
    )
    outputs = (
        Signal("outlet_temp_C", "C", 535.0, 20.0, observed=False, description="true main steam"),
        _temp("outlet_temp_meas_C", 535.0, 20.0, "main steam (SH4 outlet) thermocouple"),
        _temp("evap_out_temp_meas_C", 410.0, 30.0, "evaporator outlet"),
        _temp("sh1_out_temp_meas_C", 450.0, 30.0, "SH1 outlet"),
        _temp("sh2_out_temp_meas_C", 495.0, 30.0, "SH2 outlet (attemperator 1 inlet)"),
        _temp("attemp1_out_temp_meas_C", 475.0, 30.0, "attemperator 1 outlet (SH3 inlet)"),
        _temp("sh3_out_temp_meas_C", 515.0, 30.0, "SH3 outlet (attemperator 2 inlet)"),
        _temp("attemp2_out_temp_meas_C", 500.0, 30.0, "attemperator 2 outlet (SH4 inlet)"),
        _temp("reheat_temp_meas_C", 530.0, 20.0, "hot reheat thermocouple"),
        Signal("reheat_temp_C", "C", 530.0, 20.0, observed=False, description="true hot reheat"),
        Signal("attemp2_out_temp_C", "C", 500.0, 30.0, observed=False),
        Signal("pressure_MPa", "MPa", 14.0, 5.0, description="main steam pressure"),
        Signal("steam_flow_kg_s", "kg/s", 280.0, 120.0, description="turbine steam flow"),
        Signal("power_MW", "MW", 330.0, 130.0, description="eq. (16)"),
        Signal("fuel_flow_kg_s", "kg/s", 17.0, 7.0),
        Signal("feedwater_flow_kg_s", "kg/s", 270.0, 110.0, description="economizer flow"),
        Signal("spray_valve_1", "1", 0.5, 0.5, description="valve 1 position feedback"),
        Signal("spray_valve_2", "1", 0.5, 0.5, description="valve 2 position feedback"),
        Signal("spray_flow_1_kg_s", "kg/s", 11.0, 11.0),
        Signal("spray_flow_2_kg_s", "kg/s", 7.5, 7.5),
        Signal("heat_absorption_MW", "MW", 200.0, 80.0, observed=False, description="SH1-SH4"),
        Signal(
            "steam_generation_point",
            "1",
            0.5,
            0.5,
            observed=False,
            description="evaporator length fraction where boiling starts",
        ),
        Signal("metal_temp_max_C", "C", 580.0, 40.0, observed=False, description="SH1-SH4"),
        Signal(
            "design_spray_kg_s",
            "kg/s",
            14.0,
            10.0,
            observed=False,
            description="total spray of the design openings at this load",
        ),
        Signal(
            "sh4_out_temp_C",
            "C",
            535.0,
            20.0,
            observed=False,
            description="true SH4 outlet (header inlet)",
        ),
    )
    setpoint_C = 535.0
    valves = ("spray_valve_1", "spray_valve_2")
    sprays = ("spray_flow_1_kg_s", "spray_flow_2_kg_s")
    extra_info = ("reheat_temp_C", "attemp2_out_temp_C", "pressure_MPa", "steam_flow_kg_s",
                  "power_MW", "heat_absorption_MW")  # fmt: skip

    pack = staticmethod(_pack)
    setpoint_param = "T_ms_C"
    control_loops = (
        ("attemp1_out_temp_meas_C", SCHEDULED),  # first stage: its outlet on a load schedule
        ("attemp2_out_temp_meas_C", MAIN),  # last stage: cascade on the main steam
    )
    design_spray = "design_spray_kg_s"

    def kernel(self):
        return step

    def steady_state(self, D: np.ndarray, setpoint_C: np.ndarray, X: np.ndarray) -> None:
        steady(D, setpoint_C + K0, self.P, X)
