"""The drum boiler plant's layout: its outputs, and the named slots of the packed
parameters P, the states x, the outputs z and the Jacobian entries the rhs fills
(steamtemp_gym/slots.py), with the Jacobian pattern."""

from __future__ import annotations

from steamtemp_gym._jit import njit
from steamtemp_gym.plants import drum as dr
from steamtemp_gym.plants.base import MILL_OUTPUT, Signal, design_spray_signal
from steamtemp_gym.plants.copies import Copy, kelvin
from steamtemp_gym.plants.superheater import chain_pattern, pipe_pattern
from steamtemp_gym.slots import blocks, slots

#: The physical outputs, in the order of z.
OUTPUTS = (
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
    design_spray_signal(2.0, 2.0, "scheduled design spray (function generator over load)"),
    Signal(
        "sh2_outlet_temp_C",
        "C",
        505.0,
        20.0,
        observed=False,
        description="final SH outlet, ahead of the outlet header and main-steam line",
    ),
    MILL_OUTPUT,
)
#: Index of each output in z, by name.
IZ = slots("DrumOutputs", *(s.name for s in OUTPUTS))

DSP_LOADS = (0.4, 0.6, 0.8, 1.0)  # loads of the design-spray function generator
FW_T0_K, FW_DT_K, N_FW = 273.15 + 80.0, 1.0, 261  # feedwater tables: 80 .. 340 C

#: The flat parameter vector P: the scalars, then the design-spray function generator
#: (spray in kg/s at DSP_LOADS), the drum block (drum.drum_block) and the feedwater tables
#: h(T), rho(T) at the feedwater pressure. ``N_P`` is its length.
IP, N_P = blocks(
    "DrumParams",
    *[(name, 1) for name in (
        "N", "WNOM", "PSP", "QNOM", "TFW", "DTFW", "CV", "DPSP", "DPSH",
        "KA1", "V1", "CM1", "UAG1", "TG1", "DTG1",
        "KA2", "V2", "CM2", "UAG2", "TG2", "DTG2", "GEXP",
        "TAUW", "TAUF", "KPP", "TIP", "KPL", "TIL", "TAUFW",
        "TAUV", "RATEV", "TC1", "TC2", "QSN", "TAUM", "TBIR", "NL", "LV", "MARG", "LCM")],
    ("DSP", len(DSP_LOADS)), ("DRUM", dr.N_DRUM_P), ("FW", 2 * N_FW),
)  # fmt: skip
#: The slots of P that hold a DrumBoilerParams field, in SI units
#: (steamtemp_gym/plants/copies.py).
COPIED = {
    "N": "n_segments", "QSN": "q_s_nom_kg_s", "PSP": Copy("p_drum_MPa", scale=1e6),
    "TFW": kelvin("T_fw_nom_C"), "DTFW": "dT_fw_dload_K", "DPSP": Copy("dp_spray_MPa", scale=1e6),
    "DPSH": Copy("dp_sh_nom_MPa", scale=1e6), "TG1": kelvin("Tg1_nom_C"), "DTG1": "dTg1_dload_K",
    "TG2": kelvin("Tg2_nom_C"), "DTG2": "dTg2_dload_K", "GEXP": "gas_flow_exponent",
    "TAUW": "tau_steam_s", "TAUF": "tau_firing_s", "KPP": "Kp_pressure", "TIP": "Ti_pressure_s",
    "KPL": "Kp_level_kg_s_m", "TIL": "Ti_level_s", "TAUFW": "tau_fw_s", "TAUV": "tau_valve_s",
    "RATEV": "valve_rate_per_s", "TC1": "tau_tc1_s", "TC2": "tau_tc2_s", "TAUM": "tau_mill_s",
    "TBIR": "T_bir_s", "NL": "n_line", "MARG": "attemp_margin_K",
}  # fmt: skip

#: The states: feedwater, firing and the pressure and level loops' integrators, the feed
#: lag and the spray valve, the drum (drum.PD and its other offsets), then the primary SH
#: (2n states) and the final SH (2n states); the coal mill, the outlet header / main-steam
#: line cells and the thermowells follow (:func:`s_mill`, :func:`s_line`, :func:`sensors`).
IX, _ = blocks("DrumStates", ("W", 1), ("LF", 1), ("IP", 1), ("IL", 1), ("QF", 1), ("V", 1),
               ("DRUM", 4), ("CHAIN1", 1))  # drum: V_wt, p, alpha_r, V_sd  # fmt: skip
#: the drum pressure state
S_P = IX.DRUM + dr.PD
#: The thermowells, offsets from :func:`sensors`: main-steam thermocouple lags 1, 2,
#: attemperator-outlet lags 1, 2.
IW = slots("DrumThermowells", "TC1", "TC2", "TA1", "TA2")
DRUM_INPUT_COLS = (IX.W, IX.LF, IX.QF, IX.V)  # states the drum's inputs q_s, q_f, Q depend on
#: Offsets in jl (order of :func:`pattern`): the feed lag's row, the drum rows, the chains.
IJ, _ = blocks("DrumJacobian", ("QF", 2), ("DRUM", 4 * len(DRUM_INPUT_COLS)), ("CHAIN1", 1))
SHARE_1 = 0.4  # share of the SH pressure drop upstream of the primary SH's steam


@njit(cache=True)
def s_mill(n):
    """State index of the coal-mill output (fraction of rated fuel) for n segments per SH."""
    return IX.CHAIN1 + 4 * n


@njit(cache=True)
def s_line(n):
    """State index of the first outlet-header / main-steam-line cell (enthalpy, J/kg)."""
    return IX.CHAIN1 + 4 * n + 1


@njit(cache=True)
def sensors(n, nl):
    """Index of the first thermowell state for n segments per SH and nl line lags."""
    return IX.CHAIN1 + 4 * n + 1 + nl


def fired_pattern(off: int, n: int, inlet_cols: tuple[int, ...]) -> list[tuple[int, int]]:
    """chain_pattern (flow column W) with the firing column before each metal row's entry."""
    out = []
    for r, c in chain_pattern(off, n, inlet_cols, IX.W):
        if (r - off) % 2 == 0 and (not out or out[-1][0] != r):
            out.append((r, IX.LF))
        out.append((r, c))
    return out


def pattern(n: int, nl: int) -> list[tuple[int, int]]:
    """Strictly-lower Jacobian pattern (row, col), sorted by row, in the order rhs fills jl.

    Feedwater on steam flow and the level integrator; the drum rows on the inputs' states
    (W, L_f, q_f, spray valve); the primary SH (inlet h_v(p): drum pressure) and the final
    SH (inlet from W, the valve and the primary outlet), each with the flow column W and
    the firing column L_f on the metal rows; the mill on the boiler master's integrator
    and the drum pressure; the line lags on the final SH's outlet enthalpy and on each
    other; the thermowells on the temperatures they measure (the main-steam line's outlet;
    W, valve and primary outlet for the attemperator).
    """
    c2 = IX.CHAIN1 + 2 * n
    sl = IX.CHAIN1 + 4 * n + 1
    st = sl + nl
    return (
        [(IX.QF, IX.W), (IX.QF, IX.IL)]
        + dr.input_pattern(IX.DRUM, DRUM_INPUT_COLS)
        + fired_pattern(IX.CHAIN1, n, (S_P,))
        + fired_pattern(c2, n, (IX.W, IX.V, c2 - 1))
        + [(sl - 1, IX.IP), (sl - 1, S_P)]
        + pipe_pattern(sl, nl, (c2 + 2 * n - 1,))
        + [(st, st - 1), (st + 1, st), (st + 2, IX.W), (st + 2, IX.V), (st + 2, c2 - 1)]
        + [(st + 3, st + 2)]
    )
