"""Temperature sensors: thermocouple in a thermowell as two first-order lags.

    dT_1/dt = (T - T_1)/tau_1,   dT_2/dt = (T_1 - T_2)/tau_2,   measured = T_2

One lag of a few seconds and one of tens of seconds (the thermowell dynamics
described by C. Maffezzoni, "Boiler-turbine dynamics in power-plant control",
Control Engineering Practice 5 (1997); the values are plausible defaults). Returns
derivatives and diagonal Jacobian entries.
"""

from __future__ import annotations

from steamtemp_gym._jit import njit


@njit(cache=True, error_model="numpy")
def thermowell_rhs(T, T1, T2, tau1, tau2):
    """(dT1/dt, dT2/dt, dd1/dT1, dd2/dT2) of the two-lag thermowell."""
    return (T - T1) / tau1, (T1 - T2) / tau2, -1.0 / tau1, -1.0 / tau2
