"""The Benson boiler's layout: its outputs, and the named slots of the packed parameters
P (scalars, per-section blocks, load schedules), the states x and the outputs z
(steamtemp_gym/slots.py)."""

from __future__ import annotations

import numpy as np

from steamtemp_gym.plants.base import Signal, design_spray_signal
from steamtemp_gym.plants.copies import Copy
from steamtemp_gym.slots import blocks, slots


def _temp(name: str, center: float, scale: float, what: str) -> Signal:
    return Signal(name, "C", center, scale, noisy=True, description=what)


#: The physical outputs, in the order of z.
OUTPUTS = (
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
    design_spray_signal(14.0, 10.0, "total spray of the design openings at this load"),
    Signal(
        "sh4_out_temp_C",
        "C",
        535.0,
        20.0,
        observed=False,
        description="true SH4 outlet (header inlet)",
    ),
)
#: Index of each output in z, by name.
IZ = slots("BensonOutputs", *(s.name for s in OUTPUTS))

#: The fields of a section's block in P (IP.SEC + NF * k + field for section k).
IF = slots("BensonSectionFields", "N", "OFF", "JOFF", "KA", "V", "CM", "UAG", "TGN", "QRAD", "WN")
NF = len(IF)
#: The load schedules over TAB_LOADS: table k at IP.TAB + k * N_TAB.
TAB_LOADS = np.linspace(0.2, 1.2, 21)
N_TAB = TAB_LOADS.shape[0]
ITB = slots("BensonTables", "FUEL", "HEV", "H3", "HFW", "CPFW", "HSP", "CPSP", "RHOSP", "HCRH")
N_TB = len(ITB)
#: The flat parameter vector P: the scalars, five spare entries, the blocks of the seven
#: sections (economizer .. SH4, reheater) and the load schedules. ``N_P`` is its length.
IP, N_P = blocks(
    "BensonParams",
    *[(name, 1) for name in (
        "WNOM", "WECO", "PNOM", "PMIN", "SLL", "DPB", "DPPUMP", "PRH", "DPRH", "WRHN", "RHF",
        "CSTOR", "CV1", "CV2", "GCOEF", "GEXP", "REXP", "KE", "CPT", "ETAHP", "ETAIP", "PCOND",
        "CPRAT", "TBIR", "KP", "KI", "TAUV", "RATEV", "TC1", "TC2", "FNOM", "V1D",
        "V2D", "NX", "STRIM", "S0", "JSEN", "TAUF", "HERR", "BEV", "LOFF", "NL", "LCM", "LV",
        "JLINE")],
    ("spare", 5), ("SEC", NF * 7), ("TAB", N_TB * N_TAB),
)  # fmt: skip
#: The slots of P that hold a BensonParams field, in SI units
#: (steamtemp_gym/plants/copies.py).
COPIED = {
    "WNOM": "W_nom_kg_s", "PNOM": Copy("p_nom_MPa", scale=1e6),
    "PMIN": Copy("p_min_MPa", scale=1e6), "SLL": "slide_low_load",
    "DPB": Copy("dp_boiler_MPa", scale=1e6), "PRH": Copy("p_rh_nom_MPa", scale=1e6),
    "DPRH": Copy("dp_reheater_MPa", scale=1e6), "RHF": "rh_flow_fraction",
    "GCOEF": "gas_temp_coeff", "GEXP": "gas_flow_exponent", "REXP": "radiant_exponent",
    "CPT": "cp_turbine_J_kgK", "ETAHP": "eta_hp", "ETAIP": "eta_iplp",
    "PCOND": Copy("p_condenser_kPa", scale=1e3), "TBIR": "T_bir_s", "KP": "fwr_kp",
    "KI": "fwr_ki_per_s", "TAUV": "tau_valve_s", "RATEV": "valve_rate_per_s", "TC1": "tau_tc1_s",
    "TC2": "tau_tc2_s", "TAUF": "tau_furnace_s",
    "HERR": Copy("fwr_schedule_error_kJ_kg", scale=1e3), "BEV": "bias_evap_share", "NL": "n_line",
}  # fmt: skip
#: The states: pressure, valves and furnace heat release, the chains from IX.CHAINS on
#: (economizer .. SH4, the main-steam line cells from P[IP.LOFF], the reheater), the 8
#: thermowells (from P[IP.S0]) and last the fuel/water-ratio trim (P[IP.STRIM]), so that
#: its coupling to the evaporator outlet enthalpy is strictly lower (in the Jacobian pattern).
IX = slots("BensonStates", "P", "V1", "V2", "F", "CHAINS")
#: The thermowells, in the order of their states.
ISEN = slots("BensonThermowells", "EV", "SH1", "SH2", "ATT1", "SH3", "ATT2", "MS", "RH")
N_SENS = len(ISEN)
#: Whether the chains' Jacobian pattern carries the pressure column (see integrator.py).
PRESSURE_JAC = True
