"""Packed parameters of the Benson boiler: indices of the scalars, the per-section
blocks and the load schedules in the flat vector P, of the states in x and of the
outputs in z (frozen into the kernels as module constants)."""

from __future__ import annotations

import numpy as np

# Scalars (indices into P; frozen into the kernels as module constants).
(I_WNOM, I_WECO, I_PNOM, I_PMIN, I_SLL, I_DPB, I_DPPUMP, I_PRH, I_DPRH, I_WRHN, I_RHF,
 I_CSTOR, I_CV1, I_CV2, I_GCOEF, I_GEXP, I_REXP, I_KE, I_CPT, I_ETAHP, I_ETAIP, I_PCOND,
 I_CPRAT, I_TBIR, I_KP, I_KI, I_TAUV, I_RATEV, I_TC1, I_TC2, I_FNOM, I_V1D,
 I_V2D, I_NX, I_STRIM, I_S0, I_JSEN, I_TAUF, I_HERR, I_BEV, I_LOFF, I_NL, I_LCM, I_LV,
 I_JLINE) = range(45)  # fmt: skip
# Per-section block: I_SEC + NF * k + field
I_SEC = 50
F_N, F_OFF, F_JOFF, F_KA, F_V, F_CM, F_UAG, F_TGN, F_QRAD, F_WN = range(10)
NF = 10
# Load schedules over TAB_LOADS
TAB_LOADS = np.linspace(0.2, 1.2, 21)
N_TAB = TAB_LOADS.shape[0]
I_TAB = I_SEC + NF * 7
TB_FUEL, TB_HEV, TB_H3, TB_HFW, TB_CPFW, TB_HSP, TB_CPSP, TB_RHOSP, TB_HCRH = range(9)
N_TB = 9
N_P = I_TAB + N_TB * N_TAB
# States: pressure, valves and furnace heat release, the chains from S_CHAINS on (economizer
# .. SH4, the main-steam line cells from P[I_LOFF], the reheater), the 8 thermowells (from
# P[I_S0]) and last the fuel/water-ratio trim (P[I_STRIM]), so that its coupling to the
# evaporator outlet enthalpy is strictly lower (in the Jacobian pattern).
S_P, S_V1, S_V2, S_F = range(4)
S_CHAINS = 4
N_SENS = 8
SEN_EV, SEN_SH1, SEN_SH2, SEN_ATT1, SEN_SH3, SEN_ATT2, SEN_MS, SEN_RH = range(N_SENS)
#: Whether the chains' Jacobian pattern carries the pressure column (see integrator.py).
PRESSURE_JAC = True
# Output indices (order of BensonSubcritical.outputs)
(Z_TMS, Z_TMS_M, Z_TEV_M, Z_TSH1_M, Z_TSH2_M, Z_TATT1_M, Z_TSH3_M, Z_TATT2_M, Z_TRH_M, Z_TRH,
 Z_TATT2, Z_P, Z_W, Z_PWR, Z_FUEL, Z_WFW, Z_V1, Z_V2, Z_WSP1, Z_WSP2, Z_Q, Z_SGP,
 Z_TMMAX, Z_WDES, Z_TSH4) = range(25)  # fmt: skip
