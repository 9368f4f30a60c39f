"""IAPWS-IF97 water/steam properties as compiled table lookups (numba).

Source: the IAPWS Industrial Formulation 1997 (forward equations of regions 1, 2, 3 and
the region-4 saturation line) as implemented by the ``iapws`` package, tabulated offline
by ``scripts/generate_steam_tables.py`` into ``if97_tables.npz`` (1.7 MB). No steam
library is called at run time; ``iapws`` is a generator / test dependency only.

Grid: pressure is split into three segments, 0.2 .. 16.529 MPa (psat(350 C)), 16.529 ..
22.064 MPa (the critical pressure; coordinate q = sqrt(pc - p), which makes the
sqrt-like saturation curves near the critical point smooth) and 22.064 .. 35 MPa. In each
segment the (p, h) plane is cut along the saturation curves h_l(p), h_v(p), the IF97
region boundaries (T = 623.15 K, B23 line) and the table edges h(p, 10 C), h(p, 800 C)
into 9 patches. A patch is a rectangle in (q, xi), xi = (h - lo(p)) / (hi(p) - lo(p)), so
its edges follow the saturation and boundary curves and nothing is interpolated across
a saturation kink or an IF97 region discontinuity. Both axes are piecewise uniform:
q steps from 0.02 MPa (0.2-0.5 MPa and just above pc) to 0.57 MPa; xi steps from
0.004 (superheated vapour next to saturation) to 0.005 (~5 kJ/kg, along the
pseudo-critical line) to 0.04; 25 630 nodes in all.

Method: T and rho are Hermite-bicubic in (q, xi): each node stores the value, d/dq,
d/dxi and d2/(dq dxi), with d/dxi analytic from IF97 (dT/dh = 1/cp,
drho/dh = -rho alpha_v / cp) and the q-derivatives from converged finite differences.
Boundary curves and saturation properties (Tsat, rho_l, rho_v, h_l, h_v) are cubic
Hermite in q. Inside the two-phase dome (p < pc, h_l < h < h_v) T = Tsat(p), dT/dh = 0
and rho is the homogeneous mixture density. ``h_pT`` inverts the T table exactly (binary
search over the patch column, then a safeguarded Halley solve of the cell's cubic), so
``h_pT(p, T_ph(p, h)) == h`` to round-off except within IF97's own region jumps.

Fast path: superheated steam in the rectangle 2 MPa <= p <= 35 MPa, 2850 <= h <= 3950
kJ/kg (``FAST_RECT``), which lies entirely in IF97 region 2 (max h_v = 2803 kJ/kg, B23
line h23 <= 2623 kJ/kg, h(35 MPa, 800 C) = 3996 kJ/kg), skips segment, patch and
boundary-curve evaluation: T and rho are plain Hermite bicubics on a uniform
0.5 MPa x 20 kJ/kg grid (67 x 56 nodes, 120 kB per quantity) with node derivatives from
the region-2 equation (d/dh and d/dp analytic, d2/dp dh by central differences). Where
it is used (and only there) ``h_pT`` inverts this table exactly: a start value from a
Hermite table of h(p, tau), tau = (T - T(p, 2850)) / (T(p, 3950) - T(p, 2850)), then a
Halley solve of the bracketing cell's cubic. Both paths agree on the rectangle's edges
h = 2850, h = 3950 and p = 2 MPa to 7e-5 K in T, 2e-5 relative in dT/dh, 2e-7 in rho,
1.4e-5 in drho/dh and 4e-4 kJ/kg in h_pT: the largest jump of a lookup crossing an
edge (p is clamped to 35 MPa before the test, so p = 35 MPa is no edge).

Domain: 0.2 MPa <= p <= 35 MPa, h(p, 10 C) <= h <= h(p, 800 C). Outside it every lookup
clamps to the table edge (finite values, never an out-of-bounds read; NaN inputs map to
the lower edge); ``check_domain`` raises ``ValueError`` instead (for env construction).
p within 100 Pa below pc is evaluated at pc - 100 Pa.

Measured accuracy against ``iapws.IAPWS97`` (tests/test_steam.py): T_ph max 5e-5 K over
1000 random (p, h), 7e-6 K along the pseudo-critical line (22.1-30 MPa, cp up to
3200 kJ/(kg K)), 8e-5 K just above the saturated-vapour line; h_pT max 2e-4 kJ/kg random,
1.2e-4 pseudo-critical, 1.3e-3 near saturation; rho_ph relative 5e-7 (single phase);
sat_p values relative 2e-7, their p-derivatives relative 8e-5; dT/dh vs 1/cp 2e-5. Fast
path (600 points, 200 of them within 40 kJ/kg of its lower h edge): T max 4e-5 K (2.1e-5
over 3000 uniform points; largest at 2-4 MPa next to that edge), rho relative 1.1e-7,
dT/dh vs 1/cp 2.3e-5, h_pT 1.2e-4 kJ/kg.

Cost (2.4 GHz AMD EPYC VM, batched numba loop over 1e6 random points with p 10-25 MPa,
h 3000-3400 kJ/kg, i.e. on the fast path): T_ph, T_dTdh_ph, rho_ph ~17.5 ns per call,
``T_rho_ph`` (T, dT/dh, rho and drho/dh at once) ~22 ns, h_pT ~70 ns. Elsewhere (patch
tables): T_ph ~50-60 ns, ``T_rho_ph`` ~70 ns, h_pT ~120 ns. First compile of all
functions ~6 s of CPU time (cached afterwards: ~1 s to load).

Units are SI throughout: p in Pa, h in J/kg, T in K, rho in kg/m3, cp in J/(kg K). All
public lookups are ``@njit(cache=True)`` scalar functions callable from Python and from
other jitted kernels. The tables are module-level constant arrays of < 1 MB each, which
numba freezes into the compiled code (and so can cache). ``_TABLES_SHA256`` (``tables.py``)
pins the data file; the generator updates it, which changes the package code and thereby
the folder of cached kernels.

Modules: ``digest`` (the table digest), ``tables`` (the data loaded and checked, the
constants), ``cubic`` (Hermite cells), ``patches`` (the patch tables), ``fast`` (the fast
path), ``properties`` (the public lookups).
"""

from __future__ import annotations

from steamtemp_gym.steam.properties import (
    T_dTdh_ph,
    T_ph,
    T_rho_ph,
    Tsat_p,
    check_domain,
    cp_pT,
    h_limits_p,
    h_pT,
    rho_drhodh_ph,
    rho_ph,
    sat_p,
)
from steamtemp_gym.steam.tables import FAST_RECT, P_CRIT, P_MAX, P_MIN, T_CRIT, T_MAX, T_MIN

__all__ = [
    "T_ph",
    "T_dTdh_ph",
    "h_pT",
    "rho_ph",
    "rho_drhodh_ph",
    "T_rho_ph",
    "sat_p",
    "Tsat_p",
    "cp_pT",
    "h_limits_p",
    "check_domain",
    "P_MIN",
    "P_MAX",
    "P_CRIT",
    "T_CRIT",
    "T_MIN",
    "T_MAX",
    "FAST_RECT",
]
