"""Natural-circulation drum boiler with primary superheater, spray attemperator and final SH.

Source: Kim, "A Study on Water-Tube Boiler Modeling", M.Eng. thesis, Inha Univ.: a
natural-circulation water-tube drum boiler in the Astrom-Bell form, inputs steam flow q_s, feedwater
q_f and riser heat Q_r (its Fig. 2), balances eq. (1)-(8), descriptor form eq. (21),
steady state eq. (22), step responses Fig. 6-8 and linearization at three operating
points eq. (23)-(31). Digits were lost in the extraction, so the drum parameters are
Astrom and Bell's (Automatica 36, 2000, 363-378; docs/references.md); the drum
model itself (four states V_wt, p, alpha_r, V_sd) is in drum.py.

Plant (states in SI; the env acts on the spray valve only):

- turbine / steam valve: the unit runs boiler-follow: the turbine load controller
  moves the governor valve so that main-steam flow W follows the load demand
  L_d W_nom through a first-order lag tau_steam (valve and load loop); drum pressure
  is held by the boiler (below), so the valve never needs to compensate pressure.
- drum pressure PI on firing (boiler master): firing demand
  u_f = L_d + T_bir dL_d/dt + K_p (p_sp - p)/p_sp + I_p, dI_p/dt = K_p/T_i (p_sp - p)/p_sp
  (load feed-forward with a boiler-input-rate lead; the feed-forward L_d is not the
  steady firing need Q(L)/Q_nom, which is larger per unit at low load: the imperfect
  static feed-forward of real units, removed by the integrator). Coal firing: u_f
  reaches the burners through the coal mill (grinding and pulverized-coal inventory,
  lag tau_mill) and heat through the furnace (lag tau_firing), two lags in series,
  dL_m/dt = (u_f - L_m)/tau_mill, dL_f/dt = (L_m - L_f)/tau_firing (fuel systems of
  pulverized-coal units: dead time of tens of seconds and time constants of minutes,
  IEEE Working Group on Prime Mover and Energy Supply Models, "Dynamic models for
  fossil fueled steam units in power system studies", IEEE Trans. Power Systems 6(2),
  753-761, 1991; G. Zhou, J. Si, C.W. Taft, "Modeling and simulation of C-E deep bowl
  pulverizer", IEEE Trans. Energy Conversion 15(3), 312-322, 2000). The BIR lead (45 s)
  compensates part of the 120 s of lags: during ramps the firing lags the steam flow,
  the main driver of the steam-temperature excursion. Heat to the risers
  Q = L_f Q_nom (Q_nom: Astrom-Bell's rated 85 MW).
- three-element level control: feedwater demand q_s + K_l (0 - l) + I_l,
  dI_l/dt = -K_l/T_l l, feedwater flow lags the demand by tau_fw (pump and valve).
- drum (drum.py) fed with q_s = W - w_sp (spray water bypasses the drum) and
  feedwater at T_fw = T_fw,nom - dT_fw (1 - W/W_nom) (HP heaters).
- primary SH: saturated steam h_v(p) at q_s, N segments of steam + tube metal
  (superheater.py), convective gas side UA_g1 L_f^0.6 (fouling, 1 + heat-absorption
  bias), gas temperature T_g1 = T_g1,nom - dT_g1 (1 - L_f).
- spray attemperator (attemperator.py): feedwater taken at drum-feed temperature
  (242 C at rated load, Astrom-Bell) plus the scenario's spray-water offset, linear
  valve w_sp = v C_v sqrt(rho dp_spray) across a constant pump-head margin dp_spray;
  mass and energy mixing. Built-in interlock (attemperator.protected_spray_out): the
  spray is capped so that the attemperator outlet stays >= Tsat(p_1) + 12 K (no water
  reaches the final SH; plants keep 10-15 K), whatever the valve; at 50 % load the
  fully open valve would pass ~18 % of the steam flow, the cap holds it to ~Tsat + 12 K.
  The heat-absorption bias (D[2]) multiplies both SH gas sides, so it reaches the
  primary SH outlet (upstream of the spray) as well as the final SH.
- final SH: N segments at main-steam flow W, gas side as the primary's at a hotter
  gas temperature (platen / pendant section). Steam pressures along the SH:
  p_1 = p - 0.4 dp_SH (W/W_nom)^2 (primary), p_2 = p - dp_SH (W/W_nom)^2 (main steam).
- outlet header and main-steam line to the turbine: the shared unheated steam line of
  superheater.py (pipe_rhs: n_line = 3 mixing cells of steam plus wall metal at the
  steam temperature), 2 m3 of steam and 5.5 t of effective metal: about 24 s of storage
  at rated flow, growing as 1/flow (plausible defaults, unverified, set so that the true
  outlet's Tu/Tg for a spray step is ~0.3 as in field step tests; VDI/VDE 3503).
  outlet_temp_C is the turbine-inlet temperature after it; the final SH's own outlet is
  sh2_outlet_temp_C.
- design spray (output design_spray_kg_s): the commissioning function generator,
  linear between the undisturbed steady sprays at 40/60/80/100 % load (exact there,
  within ~3 % between them; extrapolated linearly below 40 %).
- actuator and sensors: spray valve lag, rate limit and saturation (valve.py);
  thermocouples in thermowells on the main steam (turbine inlet) and attemperator
  outlet (sensors.py).

Validation (tests/test_drum_boiler.py): the rated steady state against Astrom-Bell's
(p 8.5 MPa, q_s 50 kg/s, Q 85.2 vs ~86 MW, q_dc 1190 vs ~1195 kg/s, alpha_r 0.0507 vs
~0.051, all within 3 %); the descriptor form against the mass and energy balances it
is derived from; shrink and swell (a +10 kg/s steam step raises the level by 3.8 cm
within 10 s open loop; a +10 % load step raises it by 2.3 cm under the loops);
linearization at 50/75/100 % load by finite differences of the rhs: the whole plant
and the drum with its PI loops are stable, the open-loop drum responses 150 s after a
step have the signs of the thesis's Fig. 6-8 (steam flow lowers pressure and level,
feedwater raises level and lowers pressure, heat raises pressure and level), and the
linear model follows the nonlinear drum (thesis Fig. 9). The open-loop drum with q_s
imposed has one slightly unstable pressure mode (+1e-4 to +2e-4 1/s: h_s falls with p
at 8.5 MPa, so less energy leaves with the same steam mass as pressure rises) next to
the zero of the mass balance; the pressure loop removes both. Spray step: more spray
lowers the outlet (-17.0 K per kg/s, t63 146 s at 100 % load; -32.4 K per kg/s, t63
252 s at 50 %; Tu/Tg of the true outlet 0.27/0.29, thermocouple 0.36/0.37); the
design spray inside the valve range at 35-100 % load and fouling 0.85-1.15; the
protection holding the attemperator outlet at Tsat + 12 K with the valve fully open.
ROS2 against Radau as above; every state at rest in the steady states.

The package, one task per module: ``params`` (DrumBoilerParams, with the parameters'
sources), ``layout`` (indices into the packed parameters, states and outputs, and the
Jacobian pattern), ``kernel`` (rhs, outputs and projection, with the integration
notes), ``steady_state`` (steady state), ``calibration`` (packing DrumBoilerParams and
calibrating it against the rated design) and ``plant`` (the Plant class). The drum
itself is plants/drum.py.
"""

from steamtemp_gym.plants.base import K0
from steamtemp_gym.plants.drum_boiler.calibration import pack_params
from steamtemp_gym.plants.drum_boiler.kernel import KERNELS, boundary, outputs, project, rhs
from steamtemp_gym.plants.drum_boiler.layout import (
    DSP_LOADS,
    IP,
    IW,
    IX,
    IZ,
    OUTPUTS,
    S_P,
    pattern,
    s_line,
    s_mill,
    sensors,
)
from steamtemp_gym.plants.drum_boiler.params import DrumBoilerParams
from steamtemp_gym.plants.drum_boiler.plant import DrumBoilerSH
from steamtemp_gym.plants.drum_boiler.steady_state import steady

__all__ = [
    # the plant and its parameters
    "DrumBoilerSH",
    "DrumBoilerParams",
    "K0",
    # kernels, steady state, packing and the state layout
    "rhs",
    "outputs",
    "project",
    "steady",
    "KERNELS",
    "pattern",
    "s_mill",
    "s_line",
    "sensors",
    "pack_params",
    "boundary",
    # the layout: outputs and the named slots of P, x, z and the Jacobian
    "OUTPUTS",
    "DSP_LOADS",
    "IP",
    "IX",
    "IZ",
    "IW",
    "S_P",
]
