"""Distributed superheater: a chain of N heated segments (fluid + tube metal).

Per segment i = 1..N, with steam enthalpy h_i and metal temperature T_m,i as
states (the lumped segment model of the superheater literature, steam-side heat
transfer scaled as Dittus-Boelter, Nu = 0.023 Re^0.8 Pr^0.4; the n-division model
of Sagara et al. 1998, eq. (1)):

    M_f,i dh_i/dt      = W (h_{i-1} - h_i) + kA_i (T_m,i - T(p, h_i))
    C_m,i dT_m,i/dt    = Q_g,i - kA_i (T_m,i - T(p, h_i))
    kA_i               = kA_nom,i max(W/W_nom, 0.1)^m,  m = 0.8
    Q_g,i              = UA_g,i (T_g - T_m,i) + Q_rad,i

Steam-side heat transfer follows Dittus-Boelter (Nu = 0.023 Re^0.8 Pr^0.4, the
exponent m = 0.8 of Sagara et al. 1998); below 10 % of nominal flow it stops falling
(as ThermoPower does). The gas side is convective (UA_g, with the fouling
multiplier folded into UA_g by the caller) plus an optional radiant flux.
M_f,i = rho(p, h_i) V_i. T(p, h) is the IAPWS-IF97 table lookup of
steamtemp_gym.steam.

State layout of a chain starting at index ``off``: ``x[off + 2i] = T_m,i`` (K),
``x[off + 2i + 1] = h_i`` (J/kg): metal before fluid, so that the stiff
couplings d(fluid_i)/d(metal_i) and d(fluid_i)/d(fluid_{i-1}) are strictly
lower (see integrator.py). :func:`chain_pattern` lists them in row order.
"""

from __future__ import annotations

from steamtemp_gym._jit import njit
from steamtemp_gym.steam import T_dTdh_ph, T_ph, T_rho_ph

HTC_EXPONENT = 0.8  # m in Sagara et al. 1998 eq. (1); Dittus-Boelter Re exponent
HTC_FLOW_FLOOR = 0.1  # fraction of nominal flow below which kA stops falling (ThermoPower)


def chain_pattern(
    off: int, n: int, inlet_cols: tuple[int, ...] = (), flow_col: int = -1
) -> list[tuple[int, int]]:
    """Strictly-lower Jacobian couplings of a chain, in row order (row, col).

    Per fluid row h_i: the states the inlet enthalpy h0 depends on (``inlet_cols``,
    first segment only: valve opening, upstream enthalpy, ...), the flow state
    ``flow_col`` that sets W and p (if any), the upstream fluid h_{i-1} and the
    segment's metal. These are the stiff couplings into the fast fluid; the
    metal-from-fluid entry is the super-diagonal ``ju`` of a 2x2 block.
    """
    pat = []
    for i in range(n):
        if flow_col >= 0:
            pat.append((off + 2 * i, flow_col))
        row = off + 2 * i + 1
        if i == 0:
            pat += [(row, c) for c in inlet_cols]
        if flow_col >= 0:
            pat.append((row, flow_col))
        if i > 0:
            pat.append((row, off + 2 * i - 1))
        pat.append((row, off + 2 * i))
    return pat


@njit(cache=True, error_model="numpy")
def steam_side_kA(kA_nom, W, W_nom):
    """Steam-side conductance kA = kA_nom max(W/W_nom, 0.1)^0.8 (W/K) and dkA/dW."""
    r = W / W_nom
    if r < HTC_FLOW_FLOOR:
        return kA_nom * HTC_FLOW_FLOOR**HTC_EXPONENT, 0.0
    kA = kA_nom * r**HTC_EXPONENT
    return kA, HTC_EXPONENT * kA / W


@njit(cache=True, error_model="numpy")
def chain_rhs(
    x,
    off,
    n,
    h0,
    dh0,
    W,
    dW,
    p,
    dp,
    kA,
    dkA,
    V,
    Cm,
    UAg,
    Tg,
    Qrad,
    f,
    jd,
    ju,
    jl,
    joff,
    want_jac,
    flow,
):
    """Right-hand side of an n-segment chain, writing f (and jd, ju, jl from joff).

    Args:
        x: Plant state vector. off: index of the chain's first state. n: segments.
        h0: Inlet enthalpy (J/kg). dh0: tuple of its derivatives by the states
            ``inlet_cols`` of chain_pattern.
        W: Steam mass flow (kg/s); dW its derivative by the flow state.
        p: Pressure (Pa); dp its derivative by the flow state.
        kA: Steam-side conductance per segment at this flow (W/K); dkA = d(kA)/dW.
        V: Steam volume per segment (m3). Cm: metal heat capacity per segment (J/K).
        UAg: Gas-side conductance per segment (W/K). Tg: gas temperature (K).
        Qrad: Radiant heat per segment (W).
        f, jd, ju, jl: Outputs (derivatives, Jacobian diagonal, 2x2-block entries,
            lower couplings). joff: index of the chain's first entry in jl.
        want_jac: Whether to fill jd, ju and jl. flow: whether the pattern has a flow column.

    Returns:
        (total heat to the steam in W, outlet temperature in K, max metal temperature in K).
    """
    h_prev = h0
    q_tot = 0.0
    T = 0.0
    tm_max = 0.0
    dTdp = 0.0
    if want_jac and flow:
        # one (dT/dp)_h per chain, at its middle segment: A need only approximate J
        h_mid = x[off + 2 * (n // 2) + 1]
        dTdp = (T_ph(p + 1.0e3, h_mid) - T_ph(p, h_mid)) * 1.0e-3
    for i in range(n):
        im = off + 2 * i
        ih = im + 1
        Tm = x[im]
        h = x[ih]
        T, dTdh, rho, _ = T_rho_ph(p, h)
        Mf = rho * V
        q_s = kA * (Tm - T)
        q_g = UAg * (Tg - Tm) + Qrad
        f[ih] = (W * (h_prev - h) + q_s) / Mf
        f[im] = (q_g - q_s) / Cm
        q_tot += q_s
        if Tm > tm_max:
            tm_max = Tm
        if want_jac:
            if flow:
                # metal row: d/d(flow) of -kA (Tm - T(p, h))
                jl[joff] = (-dkA * dW * (Tm - T) + kA * dTdp * dp) / Cm
                joff += 1
            if i == 0:
                for dh in dh0:
                    jl[joff] = W * dh / Mf
                    joff += 1
            if flow:
                jl[joff] = (dW * (h_prev - h) + dkA * dW * (Tm - T) - kA * dTdp * dp) / Mf
                joff += 1
            if i > 0:
                jl[joff] = W / Mf
                joff += 1
            jl[joff] = kA / Mf
            joff += 1
            jd[ih] = -(W + kA * dTdh) / Mf
            jd[im] = -(UAg + kA) / Cm
            ju[im] = kA * dTdh / Cm
        h_prev = h
    return q_tot, T, tm_max


@njit(cache=True, error_model="numpy")
def chain_steady(x, off, n, h0, W, p, kA, UAg, Tg, Qrad):
    """Write the steady state of a chain for inlet enthalpy h0 into x; return outlet h.

    Solves, segment by segment, W (h_i - h_{i-1}) = kA (T_m - T(p, h_i)) = Q_g(T_m)
    by Newton's method on h_i (the same balances as chain_rhs with d/dt = 0).
    """
    h_prev = h0
    for i in range(n):
        # Q_g(Tm) = UAg (Tg - Tm) + Qrad and kA (Tm - T) = Q  =>  Tm = T + Q/kA,
        # Q = (UAg (Tg - T) + Qrad) / (1 + UAg/kA).
        h = h_prev
        for _ in range(50):
            T, dTdh = T_dTdh_ph(p, h)
            q = (UAg * (Tg - T) + Qrad) / (1.0 + UAg / kA)
            dq = -UAg * dTdh / (1.0 + UAg / kA)
            g = W * (h - h_prev) - q
            step = g / (W - dq)
            h -= step
            if abs(step) < 1e-6:
                break
        T, _ = T_dTdh_ph(p, h)
        q = (UAg * (Tg - T) + Qrad) / (1.0 + UAg / kA)
        x[off + 2 * i] = T + q / kA
        x[off + 2 * i + 1] = h
        h_prev = h
    return h_prev


# ------------------------------------------------------------------ unheated steam line
# Outlet header and main-steam line between the last superheater and the turbine (added for
# the transport delay of the main steam). Thick-walled pipe whose wall is taken in thermal
# equilibrium with the steam (the high-NTU limit of the fluid/metal segment above: the
# metal-to-steam conductance is much larger than W c_p per segment). Per segment k = 1..n:
#
#     (rho(p, h_k) V_k + C_m,k dT/dh(p, h_k)) dh_k/dt = W (h_{k-1} - h_k)
#
# a thermal front that travels at the speed W c_p / (c_m m'_m + rho A c_p) and disperses
# over the n mixing cells (tanks in series). Heat loss to the surroundings is neglected.
# A real line with a finite conductance passes part of a change sooner, so the metal mass
# of a plant is an effective value (see the plants' docstrings).


def pipe_cells(
    n: int, volume_m3: float, metal_t: float, c_metal_J_kgK: float
) -> tuple[float, float]:
    """Steam volume V_k (m3) and wall heat capacity C_m,k (J/K) of each of the n equal
    cells of a line of the given volume and wall metal mass (t)."""
    return volume_m3 / n, metal_t * 1e3 * c_metal_J_kgK / n


def pipe_pattern(
    off: int, n: int, inlet_cols: tuple[int, ...] = (), flow_col: int = -1
) -> list[tuple[int, int]]:
    """Strictly-lower Jacobian couplings of an n-cell pipe at ``off`` (one h state per cell)."""
    pat = []
    for i in range(n):
        row = off + i
        if i == 0:
            pat += [(row, c) for c in inlet_cols]
        if flow_col >= 0:
            pat.append((row, flow_col))
        if i > 0:
            pat.append((row, row - 1))
    return pat


@njit(cache=True, error_model="numpy")
def pipe_rhs(x, off, n, h0, dh0, W, dW, p, V, Cm, f, jd, jl, joff, want_jac, flow):
    """Right-hand side of the n-cell pipe (see above); returns its outlet temperature (K)
    and dT/dh there (K kg/J).

    Args: as chain_rhs; V steam volume (m3) and Cm metal heat capacity (J/K) per cell;
    dW the derivative of W by the flow state (pattern column ``flow_col`` if ``flow``).
    """
    h_prev = h0
    T = dTdh = 0.0
    for i in range(n):
        h = x[off + i]
        T, dTdh, rho, _ = T_rho_ph(p, h)
        M = rho * V + Cm * dTdh
        f[off + i] = W * (h_prev - h) / M
        if want_jac:
            if i == 0:
                for dh in dh0:
                    jl[joff] = W * dh / M
                    joff += 1
            if flow:
                jl[joff] = dW * (h_prev - h) / M
                joff += 1
            if i > 0:
                jl[joff] = W / M
                joff += 1
            jd[off + i] = -W / M
        h_prev = h
    return T, dTdh


@njit(cache=True, error_model="numpy")
def pipe_steady(x, off, n, h0):
    """Steady state of the pipe (no heat loss): every cell at the inlet enthalpy h0."""
    for i in range(n):
        x[off + i] = h0
    return h0
