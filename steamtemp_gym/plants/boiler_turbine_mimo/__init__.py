"""Supercritical once-through boiler-turbine with its existing controllers (MIMO: STE and RTE).

Source: Toyoda and Wada (Kyushu Univ. Research Reports, 1999). Section 3, eq. (1)-(6):
a heat-exchanger section of fluid and tube metal whose eigenvalues move with steam flow
(Table 1: time constants 6.5 s and 137 s at 2270 t/h, 8.3 s and 217 s at 1135 t/h; the
extracted eigenvalue -0.046 lost a digit, 1/217 s = 0.0046 1/s). Section 6, Fig. 5-6: a
boiler-turbine model with the existing controllers built in; inputs MWD (megawatt demand),
FF (fuel flow), SP1/SP2 (primary/secondary spray valve), RGD (gas recirculation damper);
outputs STE/RTE (main/reheat steam temperature), strongly load dependent between 25 % and
90 % load. The paper gives no plant data beyond Table 1 and the rated flow; everything else
is a plausible default for a 2270 t/h (about 700 MW) supercritical unit, unverified.

Steam path (states in SI; superheater.py chains of fluid enthalpy + tube metal):

    evaporator/separator outlet h_up -> primary SH (convective, rear pass)
      -> SP1 attemperator -> secondary SH (platen, radiant: the eq. (1)-(6) section)
      -> SP2 attemperator -> final SH (convective, furnace exit) -> STE
    HP turbine exhaust (cold reheat) -> reheater (convective, rear pass) -> RTE

- Heat-exchanger section, eq. (1)-(3): per segment, fluid M dh/dt = w (h_in - h) + UA (T_m - T)
  and metal M_m c_m dT_m/dt = q - UA (T_m - T) (the fluid state is the outlet, subscript l).
  Eq. (4)-(6): UA = A / ((r_o - r_i)/(2k) + 1/h) with h ~ Re^0.8 ~ w^0.8, i.e. a wall
  conductance in series with a Dittus-Boelter film (``tube_kA``; the film part is the shared
  ``steam_side_kA``). The secondary SH (platen) is that section exactly: radiant heat q
  independent of the metal temperature, lumped as one segment by default
  (``n_seg_platen = 1``). Its effective volume, metal heat capacity and conductances are
  chosen so that the eigenvalues of its 2x2 Jacobian block at the plant's own operating
  points reproduce Table 1 (tests/test_boiler_turbine_mimo.py). Reproduction note: with a
  steel wall and a supercritical-steam film no tube geometry gives Table 1. The table needs
  a steam residence of about 10 s (fast mode) together with a steam-side NTU
  UA/(w c_p) below about 1 and a UA that falls by only about 25 % for half the flow; a tube
  bank of that volume has about ten times that conductance. The platen's parameters are
  therefore effective lumped values, not a geometry. The product of the two eigenvalues,
  w UA / (M M_m c_m), halves for half the flow only if the steam density falls by less
  than about 25 %. A full linear slide (about 14 MPa at 1135 t/h) cannot meet Table 1. At
  16 MPa the best fit of the four platen values still misses by 11 %; at 20.8 MPa it is
  within 4 %. The pressure program is therefore a modified sliding one (below).
  Primary and final SH and the reheater are convective: n segments each, kA from tube
  geometry by eq. (4)-(5), gas side UA_g (T_g - T_m) with UA_g ~ (gas flow)^0.6.
- Existing controllers (built in, Fig. 5): boiler-turbine coordinated control. Steam flow
  follows MWD (tau_steam; turbine governor and pressure control). The fuel demand is MWD
  plus a boiler-input-rate lead T_bir dMWD/dt plus the FF bias; the heat release follows
  it through the coal mills (one lag tau_mill_s = 100 s: grinding, the pulverised-coal
  inventory of the mill and the pipes to the burners; a mill's output answers a feeder
  change with a delay of tens of seconds and a time constant of one to two minutes,
  N. W. Rees and G. Q. Fan, "Modelling and control of pulverised fuel coal mills", in
  D. Flynn (ed.), Thermal Power Plant Simulation and Control, IEE Power and Energy
  Series 43, 2003) and the furnace (tau_firing_s = 15 s); values plausible defaults,
  unverified. The BIR lead (30 s) anticipates only part of these lags: on a 5 %/min ramp
  the firing trails the steam flow by about (115 - 30 - 20) s x rate, 5 % of rated.
  Feedwater follows the boiler input demand, and the fuel/water-ratio (intermediate-
  temperature) loop holds the evaporator outlet enthalpy h_up on its setpoint schedule:
  the design schedule plus a commissioning error e_50 4 L (1 - L) (e_50 =
  fwr_schedule_error_kJ_kg = -30 kJ/kg: zero at rated load, largest at half load;
  plausible default, unverified), so the design sprays (output ``design_spray_kg_s``)
  hold STE only at rated load (at half load the steady spray is about 19 % lower and a
  frozen valve drifts about 16 K after a load change). A ratio error of heat to the
  evaporator, L_f (1 + s_b bias) / L_w - 1, shifts h_up by fwr_coupling times the
  enthalpy rise from the feedwater (the loop corrects the rest), with the evaporator lag
  tau_upstream; s_b = bias_upstream_share = 0.5 is the share of the heat-absorption bias
  felt by the furnace walls (plausible default, unverified).
- SH outlet header and main-steam line (superheater.pipe_rhs): n_line = 3 mixing cells
  between the final SH and the turbine, 20 m3 of steam and an effective 100 t of header,
  line and valve-chest metal in thermal equilibrium with the steam (the high-conductance
  limit; a 700 MW unit has 150-200 t of main-steam piping plus the valve bodies, of which
  the part following the steam within a minute counts; plausible default, unverified).
  Thermal transport time about 30 s at rated flow, 1/load longer at part load. The hot-
  reheat line likewise (2 cells, 60 m3, 30 t). STE (``outlet_temp_C``) and RTE are the
  turbine-inlet temperatures after the lines; the thermocouples measure them; the HP
  exhaust follows the turbine-inlet STE. ``final_sh_out_temp_C`` and
  ``reheater_out_temp_C`` are the stage outlets.
- The existing steam-temperature loops (SP1 on the secondary-SH inlet,
  SP2 on STE, RGD on RTE) are removed: the agent drives SP1, SP2 and RGD directly,
  and optionally the FF bias (``fuel_bias_action=True`` adds a fourth action, a bias
  of +-fuel_bias_max of rated firing on the fuel demand). With the option off the bias
  is held at zero.
- Pressure (modified sliding pressure): p_nom above ``slide_knee_load`` (90 %), then
  quadratic down to p_min (14 MPa) at ``slide_min_load`` (25 % load), constant below; 20.8
  MPa at 50 % load. Superheater pressure 25.0 MPa at rated (24.1 MPa turbine throttle after
  the main-steam-line drop). One pressure for all superheater stages. Reheat pressure is
  proportional to steam flow (4.3 MPa at rated).
- Sprays: feedwater after the HP heaters (T_fw falls with load) at feed-pump discharge
  p + dp_boiler (dp ~ W^2), linear valves w = v C_v sqrt(rho dp). Valves are sized so that
  half opening passes the design spray fraction. Mixing is a mass and energy balance
  (attemperator.py). The sprays are taken off downstream of the evaporator flow, so the
  primary SH carries W - w1 - w2 and the platen W - w2.
- Gas side: gas recirculation fraction r = r_max * RGD. Gas flow through the convective
  passes ~ firing (1 + r); radiant heat to the platen ~ firing^0.85 (1 - s_gr (r - r_nom)).
  Gas temperatures fall with firing. More recirculation therefore moves heat from the
  furnace to the convective reheater and superheaters (reheat temperature control by gas
  recirculation). Fouling multiplies the convective UA_g. The heat-absorption bias
  multiplies the gas-side heat of every superheater and the reheater.
- Reheater inlet: HP turbine exhaust temperature T_crh = T_ms (p_rh/p)^kappa (kappa from
  the rated point, T_crh 330 C) through the HP-turbine/cold-reheat-line lag tau_hp. This
  couples STE into RTE.
- Actuators: valve lag and rate limit (valve.py); the damper is slower. Thermowells with
  two lags (sensors.py) on STE, RTE and both attemperator outlets.

Validation (tests/test_boiler_turbine_mimo.py):

- Table 1: the platen section's Jacobian eigenvalues within 10 %. Measured: 6.50 s and
  133.0 s at 2270 t/h (Table 1: 6.5 s, 137 s), and 8.10 s and 223.0 s at 1135 t/h
  (Table 1: 8.3 s, 217 s; 8.01 s and 225.2 s before the schedule error moved the
  half-load operating point).
- Steady states at 25/50/90/100 % load hold STE and RTE with SP1, SP2 and RGD inside (0, 1).
  RGD reaches 0.23, 0.60, 0.38 and 0.25 at these loads. It stays inside only for a
  gas-side fouling factor of about 0.92-1.06 at every load (0.85-1.07 at rated); outside
  that band RTE starts off its setpoint.
- SP2 step: Tu/Tg of the true STE 0.31 (100 %) and 0.35 (50 %), thermocouple 0.48 and
  0.49 (field step tests ~0.3; 0.02 and 0.20 without the main-steam line). The bias
  reaches h_up; the mill and furnace lags; the design spray equals the rated steady spray.
- Step responses of STE and RTE to SP1, SP2 and RGD at 25 % and 90 % load
  (metrics.step_response_metrics), with a gain or time-constant ratio >= 1.5 (Fig. 6).
  The time constants (Tu + Tg) are 2.4 to 5.2 times longer at 25 %. The gains per valve
  stroke change by at most 1.43x; the FF gain changes 3.8x.
- ROS2 at dt = 2 s against 16 substeps over a load ramp: 0.05 K (STE), 0.02 K (RTE); the
  mill and furnace lags are solved exactly over the interval outside ROS2 (step).

The package, one task per module: ``params`` (BoilerTurbineParams, with the rated
point), ``layout`` (indices into the packed parameters, states and outputs, and the
Jacobian pattern), ``kernel`` (rhs, outputs, projection and the compiled step),
``steady_state`` (steady state under the built-in controllers), ``calibration``
(packing BoilerTurbineParams and calibrating it against the rated point) and ``plant``
(the Plant class).
"""

from steamtemp_gym.plants.base import K0
from steamtemp_gym.plants.boiler_turbine_mimo.calibration import pack_params
from steamtemp_gym.plants.boiler_turbine_mimo.kernel import (
    ACTUATORS,
    KERNELS,
    N_U_HELD,
    design_spray,
    firing_travel,
    fuel_demand,
    offsets,
    outputs,
    project,
    rhs,
    step,
    table,
)
from steamtemp_gym.plants.boiler_turbine_mimo.layout import (
    IP,
    ITAB,
    IX,
    IZ,
    N_TAB,
    OUTPUTS,
    patterns,
)
from steamtemp_gym.plants.boiler_turbine_mimo.params import BoilerTurbineParams
from steamtemp_gym.plants.boiler_turbine_mimo.plant import BoilerTurbineMIMO
from steamtemp_gym.plants.boiler_turbine_mimo.steady_state import steady

__all__ = [
    # the plant and its parameters
    "BoilerTurbineMIMO",
    "BoilerTurbineParams",
    "K0",
    # kernels, steady state and packing
    "rhs",
    "outputs",
    "project",
    "step",
    "steady",
    "fuel_demand",
    "firing_travel",
    "design_spray",
    "KERNELS",
    "ACTUATORS",
    "N_U_HELD",
    "patterns",
    "pack_params",
    "offsets",
    "table",
    # the layout: outputs and the named slots of P, x, z and the load schedules
    "OUTPUTS",
    "IP",
    "IX",
    "IZ",
    "ITAB",
    "N_TAB",
]
