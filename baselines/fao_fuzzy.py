"""The fuzzy applied compensator (FAC) of the FAO controllers: its fuzzy inference.

Source: Sagara et al. 1998 (docs/references.md), section 4; the policies ``fao_sf`` and
``fao_fac`` are baselines/fao.py.

FAC (section 4): inputs Delta t_a = (T_a - T_set)/T0, T0 = 20 K, from the filtered
measured outlet, and Delta(U_2/U_3) = U_2hat/U_3 - (U_2/U_3)^nom(U_3) (the ratio is
already normalized by eq. (9), so its deviation enters unscaled); both clipped to
[-1, 1]; 7 triangular sets each (LN..LP, centres -1, -2/3, ..., 1, half-width 1/3, all
of the same shape as section 4 says of Fig. 5, which is not in the extracted text), the
FAM bank of eq. (11), min for the antecedents and product-sum for the consequents
(eq. (12)), centroid (eq. (13), which with equal symmetric output sets is the
omega-weighted mean of the set centres). Output xi_c scaled by KK1 = 0.45.
"""

from __future__ import annotations

import numpy as np

#: Fuzzy labels and their (output) centres delta_L; index 0..6 = LN, MN, SN, ZE, SP, MP, LP.
LABELS = ("LN", "MN", "SN", "ZE", "SP", "MP", "LP")
CENTRES = np.linspace(-1.0, 1.0, 7)
HALF_WIDTH = 1.0 / 3.0
_FAM_TEXT = """
LN LN MN MN MN SN SN
LN MN MN SN SN SN ZE
MN MN SN ZE SN ZE SP
MN SN ZE ZE ZE SP MP
SN ZE SP ZE SP MP MP
ZE SP SP SP MP MP LP
SP SP MP MP MP LP LP
"""
#: FAM bank of eq. (11): rows Delta t_a (LN..LP), columns Delta(U2/U3) (LN..LP), label index.
FAM = np.array([[LABELS.index(s) for s in row.split()] for row in _FAM_TEXT.strip().splitlines()])


def memberships(x: np.ndarray) -> np.ndarray:
    """Grades m_A(x) of the 7 triangular sets (..., 7) for inputs clipped to [-1, 1]."""
    x = np.clip(np.asarray(x, dtype=np.float64), -1.0, 1.0)
    return np.maximum(1.0 - np.abs(x[..., None] - CENTRES) / HALF_WIDTH, 0.0)


def fac_output(dta: np.ndarray, dratio: np.ndarray) -> np.ndarray:
    """xi_c of eq. (12)-(13) for inputs Delta t_a and Delta(U2/U3) (normalized, any shape).

    omega_(I,J) = min(m_I(Delta t_a), m_J(Delta(U2/U3))) (eq. 12's antecedent); each rule
    scales its consequent set (product) and the scaled sets are summed; since all output
    sets have the same area s_L, the centroid (eq. 13) is sum omega delta_L / sum omega.
    """
    ma, mr = memberships(dta), memberships(dratio)
    w = np.minimum(ma[..., :, None], mr[..., None, :])
    return (w * CENTRES[FAM]).sum(axis=(-2, -1)) / w.sum(axis=(-2, -1))
