"""The plant class of ``steamtemp/BensonSubcritical-v0``."""

from __future__ import annotations

from steamtemp_gym.plants.base import MAIN, SCHEDULED, Plant, Signal
from steamtemp_gym.plants.benson_subcritical.calibration import pack_params
from steamtemp_gym.plants.benson_subcritical.kernel import step
from steamtemp_gym.plants.benson_subcritical.layout import OUTPUTS
from steamtemp_gym.plants.benson_subcritical.params import BensonParams
from steamtemp_gym.plants.benson_subcritical.steady_state import steady as _steady
from steamtemp_gym.plants.perturb import BOILER_VARIANTS


class BensonSubcritical(Plant):
    """Plant of ``steamtemp/BensonSubcritical-v0`` (Ghaffari et al.)."""

    id = "steamtemp/BensonSubcritical-v0"
    source = "Ghaffari, Moosavian and Chaibakhsh, K. N. Toosi Univ. of Technology"
    Params = BensonParams
    actions = (
        Signal("spray_valve_1_cmd", "1", 0.5, 0.5, description="spray 1 (before SH3) command"),
        Signal("spray_valve_2_cmd", "1", 0.5, 0.5, description="spray 2 (before SH4) command"),
    )
    outputs = OUTPUTS
    setpoint_C = 535.0
    valves = ("spray_valve_1", "spray_valve_2")
    sprays = ("spray_flow_1_kg_s", "spray_flow_2_kg_s")
    extra_info = (
        "reheat_temp_C",
        "attemp2_out_temp_C",
        "pressure_MPa",
        "steam_flow_kg_s",
        "power_MW",
        "heat_absorption_MW",
    )

    pack = staticmethod(pack_params)
    steady = staticmethod(_steady)
    setpoint_param = "T_ms_C"
    control_loops = (
        ("attemp1_out_temp_meas_C", SCHEDULED),  # first stage: its outlet on a load schedule
        ("attemp2_out_temp_meas_C", MAIN),  # last stage: cascade on the main steam
    )
    design_spray = "design_spray_kg_s"
    circulation = "once_through"
    perturbation_groups = {
        "heat_transfer": (
            "kA_eco_MW_K",
            "kA_evap_MW_K",
            "kA_sh1_MW_K",
            "kA_sh2_MW_K",
            "kA_sh3_MW_K",
            "kA_sh4_MW_K",
            "kA_rh_MW_K",
        ),
        "metal_heat_capacity": ("c_metal_J_kgK",),
        "firing_lag": ("tau_furnace_s",),
        "sensor_lag": ("tau_tc1_s", "tau_tc2_s"),
    }
    mismatch_variants = BOILER_VARIANTS
    commissioning = {
        "mpc_linear": {"move_weight": 0.001},
        # at ti_factor 1 the quiet stretch after load_ramp_100_50 swings 2.46 K against
        # its bound of 2.4 K
        "lqi": {"ti_factor": 0.5},
        "neuro_pid": {"disturbance_signals": ("load_rate", "sh3_out_temp_meas_C")},
    }

    def kernel(self):
        return step
