"""Final superheater (FSH) of a supercritical, sliding-pressure once-through boiler.

Source: Sagara et al. (JSME Int. J. Ser. C, 1998), Fig. 1 and eq. (1)
and (9): an n-division distributed heating surface with flow-dependent heat
transfer (Nusselt exponent m = 0.8), a spray attemperator at the FSH inlet fed
by the outlet of the superheater one step upstream, heat absorption Q and steam
flow M as disturbances whose *ratio* is disturbed by load changes (its Fig. 4),
heat absorption not measured. Segment physics: plants/superheater.py.

Model (states in SI):

- load dynamics (boiler master, unit coordinated control): steam flow
  fraction L_w follows the load demand L_d with tau_steam (turbine and sliding
  pressure). Firing is a coal unit's: the fuel demand L_d + T_bir dL_d/dt
  (boiler-input-rate feed-forward) reaches the burners through the coal mill
  (grinding and pulverized-coal inventory, lag tau_mill) and becomes heat through
  the furnace (lag tau_firing): two lags in series,

      dL_m/dt = (L_d + T_bir dL_d/dt - L_m)/tau_mill,   dL_f/dt = (L_m - L_f)/tau_firing.

  Fuel systems of pulverized-coal units respond with a dead time of tens of seconds
  and time constants of minutes (IEEE Working Group on Prime Mover and Energy
  Supply Models, "Dynamic models for fossil fueled steam units in power system
  studies", IEEE Trans. Power Systems 6(2), 753-761, 1991; G. Zhou, J. Si, C.W.
  Taft, "Modeling and simulation of C-E deep bowl pulverizer", IEEE Trans. Energy
  Conversion 15(3), 312-322, 2000); 60 s + 90 s: plausible defaults in that range,
  unverified for this unit. The BIR lead (30 s) compensates only part of the
  150 s lag, as on real units: during ramps L_f/L_w departs from 1, the
  disturbance of the ratio Q/M in Sagara et al. 1998 Fig. 4 and the main driver of the
  steam-temperature excursion (a feed-forward on the load demand and its rate can
  anticipate it).
- pressure slides with steam flow: p = p_nom above 90 % load, linear down to
  p_min at 30 % (turbine at fixed throttle opening, Stodola-like p ~ W).
- upstream superheater outlet enthalpy h_up (first-order lag tau_upstream)
  towards

      h_up* = h_sched(L_w) + [c_fwr (L_f/L_w - 1) + m(L_w) + c_bias b] (h_sched - h_fw),

  h_sched: the fuel/water-ratio (FWR) schedule, set so that the design spray
  fraction would hold T_out at every load; c_fwr (fwr_coupling): share of a
  firing/flow ratio error reaching the FSH inlet (once-through enthalpy balance
  h_out - h_fw = Q/W, partly corrected by the separator-temperature loop);
  m(L) = m_50 4 L (1 - L) (fwr_mismatch m_50 = 0.8 % of the enthalpy rise at 50 %
  load, zero at rated): the schedule is not perfect, as on every real unit (set at
  commissioning at a few loads; plausible default, unverified), so a frozen valve
  drifts after a load change and the design spray is not exactly what holds the
  setpoint at part load; b: the relative heat-absorption error D[2] (scenario
  bias and the coloured slagging/coal-quality disturbance), of which the share
  c_bias (bias_upstream_share 0.3, plausible default, unverified) reaches the
  upstream superheaters' outlet, the rest being corrected by the FWR loop; the
  FSH gas side sees b directly (below).
- design spray (output design_spray_kg_s): what the schedule is designed for,
  spray_design_fraction x W; the steady spray that holds T_out differs from it by
  the schedule error m(L) (0 at rated load, about +20 % at 50-75 % load).
- spray attemperator: feedwater after the HP heaters (T_fw falls with load),
  taken at feed-pump discharge p + dp_boiler (dp_boiler ~ W^2), linear valve,
  w_sp = v C_v sqrt(rho dp); mixing by mass and energy balance.
- FSH: N segments of fluid + tube metal (superheater.py), steam-side kA ~
  (W/W_nom)^0.8, convective gas side UA_g ~ L_f^0.6 times fouling times
  (1 + heat-absorption bias), gas temperature falling with firing.
- attemperator protection (built-in interlock, attemperator.protected_spray_out):
  spray is capped so the attemperator outlet stays >= Tsat(p) + 12 K; active only
  where the sliding pressure is subcritical (p < 21.56 MPa, below ~83 % load) and
  there far from binding (the full valve cools by < 100 K at ~500 C): kept for
  random actions at low load.
- outlet header and main-steam line to the turbine: the shared unheated steam line of
  superheater.py (pipe_rhs: n_line = 3 mixing cells of steam plus wall metal at the
  steam temperature, (rho V + C_m dT/dh) dh_k/dt = W (h_k-1 - h_k)), 20 m3 of steam and
  55 t of effective header/pipe/valve-chest metal: about 18 s of storage at rated flow,
  growing as 1/flow. The true outlet temperature outlet_temp_C is the turbine-inlet
  temperature after it (the FSH's own outlet is fsh_outlet_temp_C). Volume and metal are
  plausible defaults, unverified, set so that the true outlet's Tu/Tg for a spray step
  is about 0.3 (field step tests; VDI/VDE 3503, docs/references.md).
- actuator: valve lag, rate limit and saturation (valve.py); thermocouples in
  thermowells, two lags each, on the turbine-inlet main steam and the attemperator
  outlet (sensors.py).

Spray: design 4 % of the steam flow, valve capacity 12 % (valve at 0.33 at rated
load; 0.2-0.5 over fouling 0.85-1.15 and 35-100 % load; plausible defaults for a
once-through unit, unverified).

Nominal values: the paper gives h_a0 - h_e0 = 217.8 kJ/kg and T_a0 - T_e0 =
68.5 K across the FSH at rated load (eq. 9 normalization). With IAPWS-IF97 both
hold together at 24.8 MPa and 593 C outlet (inlet 524.5 C): the FSH of a
24.1 MPa / 593 C ultra-supercritical unit of the paper's era (turbine throttle
24.1 MPa after the main-steam-line drop). Rated flow 2270 t/h (the rated flow of
Toyoda and Wada 1999 Table 1, a unit of the same class). Tube geometry,
metal mass and gas-side figures are plausible defaults sized from the IDAES
320 MW platen and ClaRa figures (docs/references.md; unverified for this unit);
the gas-side conductance is sized so that the rated balance above holds.

Validation (tests/test_supercritical_fsh.py): rated steady state reproduces
217.8 kJ/kg and 68.5 K; steady states at 100/75/50 % hold the setpoint with
the valve inside its range; the linearized n-division model eq. (1)-(5)
reproduces Table 1 (delay nu n T); spray step responses at 100 % and 50 % load
(gain and time constant larger at 50 %; Tu/Tg of the true turbine-inlet
temperature 0.2-0.4, measured 0.30/0.30 true and 0.44/0.40 thermocouple at
100/50 %); the heat-absorption bias reaches h_up; the design-spray output against
the steady spray; the protection. Integrator accuracy: tests/test_integrator.py.

The package, one task per module: ``params`` (FSHParams, with the parameters' sources),
``layout`` (the outputs and the named slots of the packed parameters, states and
outputs), ``kernel`` (rhs, outputs and projection), ``steady_state`` (steady state),
``calibration`` (packing FSHParams and sizing the gas side and the fuel/water-ratio
schedule) and ``plant`` (the Plant class).
"""

from steamtemp_gym.plants.base import K0
from steamtemp_gym.plants.supercritical_fsh.calibration import pack_params
from steamtemp_gym.plants.supercritical_fsh.kernel import (
    KERNELS,
    boundary,
    outputs,
    pressure,
    project,
    rhs,
    spray_water,
    table,
)
from steamtemp_gym.plants.supercritical_fsh.layout import (
    INLET_COLS,
    IP,
    IX,
    IZ,
    N_P,
    N_TAB,
    OUTPUTS,
    TAB_LOADS,
    s_line,
    s_mill,
)
from steamtemp_gym.plants.supercritical_fsh.params import P_CRIT_PA, FSHParams
from steamtemp_gym.plants.supercritical_fsh.plant import SupercriticalFSH
from steamtemp_gym.plants.supercritical_fsh.steady_state import steady

__all__ = [
    # the plant and its parameters
    "SupercriticalFSH",
    "FSHParams",
    "K0",
    "P_CRIT_PA",
    # kernels, steady state and packing
    "rhs",
    "outputs",
    "project",
    "steady",
    "KERNELS",
    "spray_water",
    "boundary",
    "pressure",
    "table",
    "pack_params",
    # the layout: outputs and the named slots of P, x and z
    "OUTPUTS",
    "IP",
    "IX",
    "IZ",
    "N_P",
    "N_TAB",
    "TAB_LOADS",
    "INLET_COLS",
    "s_line",
    "s_mill",
]
