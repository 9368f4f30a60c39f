"""The supercritical final superheater's layout: its outputs, and the named slots of the
packed parameters P (scalars and load tables), the states x and the outputs z
(steamtemp_gym/slots.py)."""

from __future__ import annotations

import numpy as np

from steamtemp_gym._jit import njit
from steamtemp_gym.plants.base import MILL_OUTPUT, Signal, design_spray_signal
from steamtemp_gym.plants.copies import Copy, kelvin
from steamtemp_gym.slots import blocks, slots

#: The physical outputs, in the order of z.
OUTPUTS = (
    Signal("outlet_temp_C", "C", 593.0, 20.0, observed=False, description="true FSH outlet"),
    Signal("outlet_temp_meas_C", "C", 593.0, 20.0, noisy=True, description="thermocouple"),
    Signal("attemp_out_temp_C", "C", 525.0, 30.0, observed=False),
    Signal("attemp_out_temp_meas_C", "C", 525.0, 30.0, noisy=True),
    Signal("attemp_in_temp_C", "C", 545.0, 30.0, noisy=True, description="upstream SH outlet"),
    Signal("steam_flow_kg_s", "kg/s", 472.0, 160.0),
    Signal("pressure_MPa", "MPa", 17.0, 8.0),
    Signal("spray_valve", "1", 0.5, 0.5, description="valve position feedback"),
    Signal("spray_flow_kg_s", "kg/s", 20.0, 20.0),
    Signal("firing_rate", "1", 0.75, 0.3, description="fuel flow, fraction of rated"),
    Signal("heat_absorption_MW", "MW", 100.0, 50.0, observed=False, description="hidden"),
    Signal("metal_temp_max_C", "C", 620.0, 40.0, observed=False),
    design_spray_signal(
        14.0, 14.0, "spray the FWR schedule is designed for: design fraction x flow"
    ),
    Signal(
        "fsh_outlet_temp_C",
        "C",
        593.0,
        20.0,
        observed=False,
        description="FSH outlet, ahead of the outlet header and main-steam line",
    ),
    MILL_OUTPUT,
)
#: Index of each output in z, by name.
IZ = slots("FSHOutputs", *(s.name for s in OUTPUTS))

TAB_LOADS = np.linspace(0.2, 1.2, 21)  # loads of the schedule tables
N_TAB = TAB_LOADS.shape[0]
#: The flat parameter vector P: the scalars, then the load tables over TAB_LOADS (upstream
#: enthalpy h_up and its offset from the spray water, spray-water enthalpy, cp, dcp/dT and
#: density). ``N_P`` is its length.
IP, N_P = blocks(
    "FSHParams",
    *[(name, 1) for name in (
        "N", "WNOM", "PNOM", "PMIN", "SLH", "SLL", "KA", "V", "CM", "UAG", "TGN", "DTG", "GEXP",
        "CV", "DPB", "TFW", "DTFW", "TAUF", "TBIR", "TAUW", "TAUUP", "FWR",
        "TAUV", "RATEV", "TC1", "TC2", "TAUM", "MIS", "BUP", "NL", "LV", "SPD", "MARG", "LCM")],
    *[(name, N_TAB) for name in ("HUP", "DHUP", "HFW", "CPFW", "DCPFW", "RHOFW")],
)  # fmt: skip
#: The slots of P that hold an FSHParams field, in SI units (steamtemp_gym/plants/copies.py).
COPIED = {
    "N": "n_segments", "WNOM": "W_nom_kg_s", "PNOM": Copy("p_nom_MPa", scale=1e6),
    "PMIN": Copy("p_min_MPa", scale=1e6), "SLH": "slide_high_load", "SLL": "slide_low_load",
    "TGN": kelvin("Tg_nom_C"), "DTG": "dTg_dload_K", "GEXP": "gas_flow_exponent",
    "DPB": Copy("dp_boiler_nom_MPa", scale=1e6), "TFW": kelvin("T_fw_nom_C"),
    "DTFW": "dT_fw_dload_K", "TAUF": "tau_firing_s", "TBIR": "T_bir_s", "TAUW": "tau_steam_s",
    "TAUUP": "tau_upstream_s", "FWR": "fwr_coupling", "TAUV": "tau_valve_s",
    "RATEV": "valve_rate_per_s", "TC1": "tau_tc1_s", "TC2": "tau_tc2_s", "TAUM": "tau_mill_s",
    "MIS": "fwr_mismatch", "BUP": "bias_upstream_share", "NL": "n_line",
    "SPD": "spray_design_fraction", "MARG": "attemp_margin_K",
}  # fmt: skip
#: The states: firing, steam flow, the upstream enthalpy, the spray valve and the
#: thermowells (main steam lags 1, 2; attemperator outlet lags 1, 2), then the FSH chain
#: (2 n states), the coal mill and the n_line line cells.
IX = slots("FSHStates", "LF", "LW", "HUP", "V", "TC1", "TC2", "TA1", "TA2", "CHAIN")
INLET_COLS = (IX.HUP, IX.V)  # states the FSH inlet enthalpy depends on


@njit(cache=True)
def s_mill(n):
    """State index of the coal-mill output (fraction of rated fuel) for n FSH segments."""
    return IX.CHAIN + 2 * n


@njit(cache=True)
def s_line(n):
    """State index of the first outlet-header / main-steam-line cell (enthalpy, J/kg)."""
    return IX.CHAIN + 2 * n + 1
