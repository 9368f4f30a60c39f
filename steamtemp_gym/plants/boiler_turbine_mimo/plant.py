"""The plant class of ``steamtemp/BoilerTurbineMIMO-v0``."""

from __future__ import annotations

import numpy as np

from steamtemp_gym.plants.base import MAIN, SCHEDULED, Plant, Signal
from steamtemp_gym.plants.boiler_turbine_mimo.calibration import _pack
from steamtemp_gym.plants.boiler_turbine_mimo.kernel import ACTUATORS, KERNELS, step
from steamtemp_gym.plants.boiler_turbine_mimo.params import K0, BoilerTurbineParams
from steamtemp_gym.plants.boiler_turbine_mimo.steady_state import steady

_FUEL_BIAS_ACTION = Signal(
    "fuel_bias_cmd",
    "1",
    0.5,
    0.5,
    description="FF bias on the fuel demand, 0.5 = none, +-fuel_bias_max",
)


class BoilerTurbineMIMO(Plant):
    """Plant of ``steamtemp/BoilerTurbineMIMO-v0`` (Toyoda and Wada 1999).

    Actions: SP1, SP2 spray valves and the RGD damper (plus the FF bias with
    ``params={"fuel_bias_action": True}``). ``outlet`` is STE; RTE is observed (measured)
    and reported in ``info["reheat_temp_C"]``.
    """

    id = "steamtemp/BoilerTurbineMIMO-v0"
    source = "Toyoda and Wada, Kyushu Univ. Research Reports 4(2), 1999"
    Params = BoilerTurbineParams
    actions = (
        Signal("sp1_valve_cmd", "1", 0.5, 0.5, description="primary spray SP1 valve command"),
        Signal("sp2_valve_cmd", "1", 0.5, 0.5, description="secondary spray SP2 valve command"),
        Signal("rgd_damper_cmd", "1", 0.5, 0.5, description="gas recirculation damper RGD"),
    )
    outputs = (
        Signal("outlet_temp_C", "C", 538.0, 20.0, observed=False, description="true STE"),
        Signal("outlet_temp_meas_C", "C", 538.0, 20.0, noisy=True, description="STE thermocouple"),
        Signal("reheat_temp_C", "C", 566.0, 20.0, observed=False, description="true RTE"),
        Signal("reheat_temp_meas_C", "C", 566.0, 20.0, noisy=True, description="RTE thermocouple"),
        Signal("sp1_out_temp_C", "C", 440.0, 30.0, observed=False, description="platen inlet"),
        Signal("sp1_out_temp_meas_C", "C", 440.0, 30.0, noisy=True),
        Signal("sp2_out_temp_C", "C", 498.0, 30.0, observed=False, description="final SH inlet"),
        Signal("sp2_out_temp_meas_C", "C", 498.0, 30.0, noisy=True),
        Signal("cold_reheat_temp_C", "C", 310.0, 40.0, noisy=True, description="HP exhaust"),
        Signal("steam_flow_kg_s", "kg/s", 400.0, 250.0),
        Signal("pressure_MPa", "MPa", 20.0, 6.0),
        Signal("sp1_valve", "1", 0.5, 0.5, description="SP1 position feedback"),
        Signal("sp2_valve", "1", 0.5, 0.5, description="SP2 position feedback"),
        Signal("rgd_damper", "1", 0.5, 0.5, description="RGD position feedback"),
        Signal("fuel_bias", "1", 0.5, 0.5, observed=False, description="FF bias, 0.5 = none"),
        Signal("sp1_flow_kg_s", "kg/s", 15.0, 15.0),
        Signal("sp2_flow_kg_s", "kg/s", 12.0, 12.0),
        Signal("firing_rate", "1", 0.65, 0.35, description="fuel flow, fraction of rated"),
        Signal("heat_absorption_MW", "MW", 450.0, 200.0, observed=False, description="SH, hidden"),
        Signal("reheat_heat_MW", "MW", 300.0, 150.0, observed=False, description="hidden"),
        Signal("metal_temp_max_C", "C", 620.0, 40.0, observed=False),
        Signal(
            "design_spray_kg_s",
            "kg/s",
            30.0,
            20.0,
            observed=False,
            description="total spray of the design openings at this steam flow",
        ),  # fmt: skip
        Signal(
            "final_sh_out_temp_C",
            "C",
            538.0,
            20.0,
            observed=False,
            description="true final SH outlet (header inlet)",
        ),  # fmt: skip
        Signal(
            "reheater_out_temp_C",
            "C",
            566.0,
            20.0,
            observed=False,
            description="true reheater outlet (hot-reheat line inlet)",
        ),  # fmt: skip
    )
    setpoint_C = 538.0
    control_loops = (
        ("sp1_out_temp_meas_C", SCHEDULED),  # first stage: its outlet on a load schedule
        ("sp2_out_temp_meas_C", MAIN),  # second stage: cascade on the main steam
        (None, "reheat_temp_meas_C"),  # damper holds the reheat temperature
    )
    valves = ("sp1_valve", "sp2_valve", "rgd_damper")
    sprays = ("sp1_flow_kg_s", "sp2_flow_kg_s")
    design_spray = "design_spray_kg_s"
    # kept short: every info key costs about 1 us per env step
    extra_info = (
        "reheat_temp_C",
        "sp1_out_temp_C",
        "sp2_out_temp_C",
        "pressure_MPa",
        "heat_absorption_MW",
    )

    pack = staticmethod(_pack)
    kernels = KERNELS
    actuators = ACTUATORS
    setpoint_param = "T_ms_C"

    def __init__(self, **overrides) -> None:
        super().__init__(**overrides)
        self.reheat_setpoint_C = self.params.T_rh_C
        self.secondary = (("reheat_temp_C", self.params.T_rh_C),)  # RTE is scored too
        if self.params.fuel_bias_action:
            self.actions = type(self).actions + (_FUEL_BIAS_ACTION,)
            self.valves = type(self).valves + ("fuel_bias",)
            self.outputs = tuple(
                Signal(s.name, s.unit, s.center, s.scale, True, s.noisy, s.description)
                if s.name == "fuel_bias" else s
                for s in type(self).outputs
            )  # fmt: skip
            self.n_u = len(self.actions)

    def kernel(self):
        return step

    def steady_state(self, D: np.ndarray, setpoint_C: np.ndarray, X: np.ndarray) -> None:
        steady(D, setpoint_C + K0, self.P, X)
