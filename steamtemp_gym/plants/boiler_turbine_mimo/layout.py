"""The boiler-turbine unit's layout: its outputs, and the named slots of the packed
parameters P (scalars and load schedules), the states x and the outputs z
(steamtemp_gym/slots.py), with the Jacobian pattern the rhs fills."""

from __future__ import annotations

import numpy as np

from steamtemp_gym.plants.base import Signal, design_spray_signal
from steamtemp_gym.plants.boiler_turbine_mimo.params import BoilerTurbineParams
from steamtemp_gym.plants.copies import Copy, kelvin
from steamtemp_gym.plants.superheater import chain_pattern, pipe_pattern
from steamtemp_gym.slots import blocks, slots

#: The physical outputs, in the order of z.
OUTPUTS = (
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
    design_spray_signal(30.0, 20.0, "total spray of the design openings at this steam flow"),
    Signal(
        "final_sh_out_temp_C",
        "C",
        538.0,
        20.0,
        observed=False,
        description="true final SH outlet (header inlet)",
    ),
    Signal(
        "reheater_out_temp_C",
        "C",
        566.0,
        20.0,
        observed=False,
        description="true reheater outlet (hot-reheat line inlet)",
    ),
)
#: Index of each output in z, by name.
IZ = slots("MimoOutputs", *(s.name for s in OUTPUTS))

#: The load schedules over TAB_LOADS: table k at IP.TAB + k * N_TAB.
TAB_LOADS = np.linspace(0.2, 1.2, 21)
N_TAB = TAB_LOADS.shape[0]
ITAB = slots("MimoTables", "HUP", "RISE", "HSP", "RHOSP", "CPSP", "CRHR", "HCRH", "CPCRH", "TCRH")
#: The flat parameter vector P: the scalars (segments of the primary, platen, final and
#: reheater; per-section heat transfer, volume, metal and gas; loops, valves, thermowells;
#: the design spray and RGD openings and the RTE setpoint), three spare entries, then the
#: load schedules. ``N_P`` is its length.
IP, N_P = blocks(
    "MimoParams",
    *[(name, 1) for name in (
        "N1", "N2", "N3", "N4", "WNOM", "PNOM", "PMIN", "KNEE", "LMIN", "PRH", "PRHMIN", "FRH",
        "KAF_P", "KAW_P", "V_P", "CM_P", "UAG_P", "TG_P",
        "KAF_PL", "KAW_PL", "V_PL", "CM_PL", "Q_PL",
        "KAF_F", "KAW_F", "V_F", "CM_F", "UAG_F", "TG_F",
        "KAF_R", "KAW_R", "V_R", "CM_R", "UAG_R", "TG_R",
        "DTG", "GEXP", "REXP", "RMAX", "RNOM", "PLGR", "CV1", "CV2", "DPB",
        "TAUF", "TBIR", "TAUW", "TAUUP", "FWR", "TAUHP", "FBACT", "FBMAX", "TAUFB",
        "TAUV", "RATEV", "TAUD", "RATED", "TC1", "TC2", "JOFF_PL", "JOFF_F", "JOFF_R",
        "VD", "GD", "TRH", "DTGR",
        "TAUM", "HERR", "BUP", "NL", "LCM", "LV", "NRL", "RLCM", "RLV", "JOFF_L", "JOFF_RL")],
    ("spare", 3), ("TAB", len(ITAB) * N_TAB),
)  # fmt: skip
#: The slots of P that hold a BoilerTurbineParams field, in SI units
#: (steamtemp_gym/plants/copies.py).
COPIED = {
    "N1": "n_seg_primary", "N2": "n_seg_platen", "N3": "n_seg_final", "N4": "n_seg_reheat",
    "WNOM": "W_nom_kg_s", "PNOM": Copy("p_nom_MPa", scale=1e6),
    "PMIN": Copy("p_min_MPa", scale=1e6), "KNEE": "slide_knee_load", "LMIN": "slide_min_load",
    "PRH": Copy("p_rh_nom_MPa", scale=1e6), "PRHMIN": Copy("p_rh_min_MPa", scale=1e6),
    "FRH": "reheat_flow_fraction",
    "KAF_PL": Copy("platen_kA_film_MW_K", scale=1e6),
    "KAW_PL": Copy("platen_kA_wall_MW_K", scale=1e6), "V_PL": "platen_volume_m3",
    "CM_PL": Copy("platen_metal_MJ_K", scale=1e6),
    "TG_P": kelvin("Tg_primary_C"), "TG_F": kelvin("Tg_final_C"), "TG_R": kelvin("Tg_reheat_C"),
    "DTG": "dTg_dload_K", "GEXP": "gas_flow_exponent", "REXP": "radiant_exponent",
    "DTGR": "dTg_reheat_dload_K", "RMAX": "recirc_max_fraction",
    "PLGR": "platen_recirc_sensitivity", "DPB": Copy("dp_boiler_nom_MPa", scale=1e6),
    "TAUF": "tau_firing_s", "TBIR": "T_bir_s", "TAUW": "tau_steam_s",
    "TAUUP": "tau_upstream_s", "FWR": "fwr_coupling", "TAUHP": "tau_hp_s",
    "FBACT": "fuel_bias_action", "FBMAX": "fuel_bias_max", "TAUFB": "tau_fuel_bias_s",
    "TAUV": "tau_valve_s", "RATEV": "valve_rate_per_s", "TAUD": "tau_damper_s",
    "RATED": "damper_rate_per_s", "TC1": "tau_tc1_s", "TC2": "tau_tc2_s",
    "VD": "valve_design_opening", "GD": "rgd_design_opening", "TRH": kelvin("T_rh_C"),
    "TAUM": "tau_mill_s", "HERR": Copy("fwr_schedule_error_kJ_kg", scale=1e3),
    "BUP": "bias_upstream_share", "NL": "n_line", "NRL": "n_rh_line",
}  # fmt: skip
#: The states; the chains follow from CHAIN (primary, platen, final, reheater), then the
#: main-steam line and hot-reheat line cells. MILL: coal flow out of the mills, fraction
#: of rated firing.
IX = slots("MimoStates", "LF", "LW", "HUP", "V1", "V2", "G", "FB", "CRH",
           "TS1", "TS2", "TR1", "TR2", "A11", "A12", "A21", "A22", "MILL", "CHAIN")  # fmt: skip


def patterns(params: BoilerTurbineParams) -> list[tuple[int, int]]:
    """Strictly-lower Jacobian pattern of the unit (the four chains, in row order)."""
    n1, n2, n3, n4 = (
        params.n_seg_primary,
        params.n_seg_platen,
        params.n_seg_final,
        params.n_seg_reheat,
    )
    o_p = IX.CHAIN
    o_pl = o_p + 2 * n1
    o_f = o_pl + 2 * n2
    o_r = o_f + 2 * n3
    o_l = o_r + 2 * n4
    o_rl = o_l + params.n_line
    return (
        chain_pattern(o_p, n1, (IX.HUP,), IX.LW)
        + chain_pattern(o_pl, n2, (o_pl - 1, IX.V1, IX.V2), IX.LW)
        + chain_pattern(o_f, n3, (o_f - 1, IX.V2), IX.LW)
        + chain_pattern(o_r, n4, (IX.CRH,), IX.LW)
        + pipe_pattern(o_l, params.n_line, (o_r - 1,), IX.LW)
        + pipe_pattern(o_rl, params.n_rh_line, (o_l - 1,), IX.LW)
    )
