"""Packed parameters of the drum boiler plant: indices of the scalars, the design-spray
function generator, the drum block and the feedwater tables in the flat vector P, of the
states in x and of the outputs in z, and the Jacobian pattern the rhs fills."""

from __future__ import annotations

from steamtemp_gym._jit import njit
from steamtemp_gym.plants import drum as dr
from steamtemp_gym.plants.superheater import chain_pattern, pipe_pattern

(I_N, I_WNOM, I_PSP, I_QNOM, I_TFW, I_DTFW, I_CV, I_DPSP, I_DPSH,
 I_KA1, I_V1, I_CM1, I_UAG1, I_TG1, I_DTG1,
 I_KA2, I_V2, I_CM2, I_UAG2, I_TG2, I_DTG2, I_GEXP,
 I_TAUW, I_TAUF, I_KPP, I_TIP, I_KPL, I_TIL, I_TAUFW,
 I_TAUV, I_RATEV, I_TC1, I_TC2, I_QSN) = range(34)  # fmt: skip
I_TAUM, I_TBIR, I_NL, I_LV, I_MARG, I_LCM = 34, 35, 36, 37, 38, 39
I_DSP = 40  # design-spray function generator: spray (kg/s) at DSP_LOADS
DSP_LOADS = (0.4, 0.6, 0.8, 1.0)
I_DRUM = I_DSP + len(DSP_LOADS)  # drum parameter block (drum.drum_block)
I_FW = I_DRUM + dr.N_DRUM_P  # feedwater tables h(T), rho(T) at p_fw
FW_T0_K, FW_DT_K, N_FW = 273.15 + 80.0, 1.0, 261  # 80 .. 340 C
N_P = I_FW + 2 * N_FW
SHARE_1 = 0.4  # share of the SH pressure drop upstream of the primary SH's steam

# State indices
S_W, S_LF, S_IP, S_IL, S_QF, S_V = 0, 1, 2, 3, 4, 5
S_DRUM = 6  # V_wt, p, alpha_r, V_sd
S_P = S_DRUM + dr.PD
S_CHAIN1 = 10  # primary SH (2n states), then the final SH (2n states)
# then the coal mill (1), the outlet header / main-steam line (n_line cells), and the
# thermowells (their inputs are then lower couplings): offsets from
# sensors(n, n_line): main-steam thermocouple lags 1, 2, attemperator-outlet lags 1, 2
T_TC1, T_TC2, T_TA1, T_TA2 = 0, 1, 2, 3
DRUM_INPUT_COLS = (S_W, S_LF, S_QF, S_V)  # states the drum's inputs q_s, q_f, Q depend on
# Offsets in jl (order of pattern())
J_QF = 0
J_DRUM = 2
J_CHAIN1 = J_DRUM + 4 * len(DRUM_INPUT_COLS)


@njit(cache=True)
def s_mill(n):
    """State index of the coal-mill output (fraction of rated fuel) for n segments per SH."""
    return S_CHAIN1 + 4 * n


@njit(cache=True)
def s_line(n):
    """State index of the first outlet-header / main-steam-line cell (enthalpy, J/kg)."""
    return S_CHAIN1 + 4 * n + 1


@njit(cache=True)
def sensors(n, nl):
    """Index of the first thermowell state for n segments per SH and nl line lags."""
    return S_CHAIN1 + 4 * n + 1 + nl


# Output indices (order of DrumBoilerSH.outputs)
(Z_TOUT, Z_TOUTM, Z_TATT, Z_TATTM, Z_TPRI, Z_W, Z_PD, Z_LEVEL, Z_QF, Z_LF, Z_V, Z_WSP,
 Z_PMS, Z_QS, Z_QSH, Z_QEV, Z_TMMAX, Z_AR, Z_QDC, Z_DSP, Z_TSH2, Z_MILL) = range(22)  # fmt: skip


def fired_pattern(off: int, n: int, inlet_cols: tuple[int, ...]) -> list[tuple[int, int]]:
    """chain_pattern (flow column W) with the firing column before each metal row's entry."""
    out = []
    for r, c in chain_pattern(off, n, inlet_cols, S_W):
        if (r - off) % 2 == 0 and (not out or out[-1][0] != r):
            out.append((r, S_LF))
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
    c2 = S_CHAIN1 + 2 * n
    sl = S_CHAIN1 + 4 * n + 1
    st = sl + nl
    return (
        [(S_QF, S_W), (S_QF, S_IL)]
        + dr.input_pattern(S_DRUM, DRUM_INPUT_COLS)
        + fired_pattern(S_CHAIN1, n, (S_P,))
        + fired_pattern(c2, n, (S_W, S_V, c2 - 1))
        + [(sl - 1, S_IP), (sl - 1, S_P)]
        + pipe_pattern(sl, nl, (c2 + 2 * n - 1,))
        + [(st, st - 1), (st + 1, st), (st + 2, S_W), (st + 2, S_V), (st + 2, c2 - 1)]
        + [(st + 3, st + 2)]
    )
