"""The plant class of ``steamtemp/BoilerTurbineMIMO-v0``."""

from __future__ import annotations

from steamtemp_gym.plants.base import MAIN, SCHEDULED, Plant, Signal
from steamtemp_gym.plants.boiler_turbine_mimo.calibration import pack_params
from steamtemp_gym.plants.boiler_turbine_mimo.kernel import ACTUATORS, KERNELS, step
from steamtemp_gym.plants.boiler_turbine_mimo.layout import OUTPUTS
from steamtemp_gym.plants.boiler_turbine_mimo.params import BoilerTurbineParams
from steamtemp_gym.plants.boiler_turbine_mimo.steady_state import steady as _steady
from steamtemp_gym.plants.perturb import BOILER_VARIANTS

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
    outputs = OUTPUTS
    setpoint_C = 538.0
    control_loops = (
        ("sp1_out_temp_meas_C", SCHEDULED),  # first stage: its outlet on a load schedule
        ("sp2_out_temp_meas_C", MAIN),  # second stage: cascade on the main steam
        (None, "reheat_temp_meas_C"),  # damper holds the reheat temperature
    )
    valves = ("sp1_valve", "sp2_valve", "rgd_damper")
    sprays = ("sp1_flow_kg_s", "sp2_flow_kg_s")
    design_spray = "design_spray_kg_s"
    circulation = "once_through"
    perturbation_groups = {
        "heat_transfer": (
            "alpha_sh_W_m2K",
            "alpha_rh_W_m2K",
            "platen_kA_film_MW_K",
            "platen_kA_wall_MW_K",
        ),
        "metal_heat_capacity": ("c_metal_J_kgK", "platen_metal_MJ_K"),
        "firing_lag": ("tau_mill_s", "tau_firing_s"),
        "sensor_lag": ("tau_tc1_s", "tau_tc2_s"),
    }
    mismatch_variants = BOILER_VARIANTS
    commissioning = {
        "mpc_linear": {"move_weight": 0.001},
        "neuro_pid": {"disturbance_signals": ("firing_minus_load", "load_rate")},
    }
    # kept short: every info key costs time on every env step (about 0.05 us in the single
    # env, 0.15 us in the vector env at one row)
    extra_info = (
        "reheat_temp_C",
        "sp1_out_temp_C",
        "sp2_out_temp_C",
        "pressure_MPa",
        "heat_absorption_MW",
    )

    pack = staticmethod(pack_params)
    steady = staticmethod(_steady)
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
                if s.name == "fuel_bias"
                else s
                for s in type(self).outputs
            )
            self.n_u = len(self.actions)

    def kernel(self):
        return step
