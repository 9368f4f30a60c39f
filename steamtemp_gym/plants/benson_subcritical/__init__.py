"""Neka 440 MW subcritical once-through Benson boiler with two spray attemperators.

Source: Ghaffari, Moosavian and Chaibakhsh (experimental
fuzzy modelling and control of a once-through boiler; unit 2 of the Neka power plant).
Plant data from its section IV: subcritical once-through Benson boiler, two-pass, single
reheat, one furnace; evaporator, four superheater units, reheater; main steam 18.1 MPa /
535 C, reheat 4.35 MPa / 530 C; feed pump discharge 28 MPa, HP heaters raise the
feedwater temperature by about 80 C; data sampled every 5 s (our control interval);
load ramps between 50 and 100 %. Segment physics: plants/superheater.py.

Model (SI inside the kernels):

- Sections (each a chain of N segments with steam/water enthalpy and tube-metal
  temperature states, ``superheater.py``; the paper's energy balance eq. (4)-(5)
  distributed along the tube, with T(p, h) from IAPWS-IF97 instead of its constant
  C_p; default segments in brackets): economizer [1], convective; evaporator [3],
  furnace-wall radiation, once-through: its enthalpy rises from subcooled water through
  the two-phase region (homogeneous density, T = Tsat(p)) to superheated steam (48 K at
  rated load), and the steam-generation point moves with the fuel/water ratio
  (``steam_generation_point``, 0.24 of the evaporator length at rated load); SH1 [2],
  low-temperature SH in the second pass, convective; SH2 [2], division panels, radiant;
  SH3 [2], platen at the furnace exit, convective; SH4 [3], final pendant, convective;
  reheater [2], convective. Flow is uniform along the water/steam path (mass storage is
  lumped into eq. (13)). Convective gas side UA_g ~ firing^0.6 times the fouling
  multiplier with an effective gas temperature falling with firing; the economizer's is
  its gas inlet temperature (600 C), which gives it the inlet-temperature sensitivity of
  a gas-limited counterflow economizer (dh_out/dh_in ~ 0.8). Radiant sections receive
  Q_rad ~ firing^0.9 (the furnace absorbs a larger share at low load). The scenario's
  heat-absorption bias multiplies the heat to SH1-SH4 and the reheater, and a share
  (bias_evap_share, 0.5) of it the evaporator's (furnace walls: a firing or
  slagging change is felt upstream too; plausible default, unverified). Each chain is
  evaluated at its outlet pressure: main-steam pressure plus a share (P_SHARE) of the
  boiler pressure drop dp_boiler (L_d)^2.
- Attemperators (``attemperator.py``): spray 1 between SH2 and SH3, spray 2 between SH3
  and SH4 (the paper places the spray "between the superheated steam at the outlet of
  the preceding component ... and the secondary superheater" without numbering the
  stages; two injections before the last two stages is the usual arrangement and the
  one chosen here). Mass and energy balance eq. (17)-(18) (no storage; eq. (20) is its
  constant-C_p form). Spray water is tapped at the feed-pump discharge (deaerator
  temperature; pressure 28 MPa at rated flow, head ~ flow^2; the scenario's spray-water
  temperature offset is a deaerator temperature offset, so it also shifts the
  feedwater), linear valves w = v C_v sqrt(rho dp), each with the lag and rate limit of
  ``valve.py``, whose travel over an interval is computed exactly (valve_travel; the
  physics sees the interval-mean opening). The two valves are the actions.
- Pressure, eq. (13): dp/dt = p0 / (tau m_v) (m_in - m_out) with m_in the water pumped
  into the boiler (economizer flow plus sprays), m_out the turbine flow, m_v the steam
  mass in SH1-SH4 at rated load and tau the paper's (dimensionless) storage factor,
  which here also lumps the evaporator water and metal storage of eq. (9) that the
  paper neglects (the paper's eq. (12)-(13) leave tau's units open; with p0/m_v in
  Pa/kg it is a pure number). tau = 4 gives a pressure time constant tau m_v / W_nom of
  56 s at rated load (plausible default, unverified).
- Turbine (eq. (14) and (16)): flow m_out = W_nom L_d p / p_sp(L_d) (throttle flow
  proportional to pressure at the valve opening the unit master sets for the demand
  L_d); sliding pressure p_sp(L): 8 MPa at 30 % load rising linearly to 18.1 MPa at
  100 %, constant above (the paper does not state the pressure mode; its Fig. 3 and 6,
  lost in the text extraction, show the outlet pressure during the load ramps; Benson
  units run sliding pressure). HP exhaust (cold reheat) temperature by the paper's
  polytropic expansion eq. (14), T_crh = T_ms (p_crh / p_ms)^((k-1)/k) with k = 1.27
  (the index that gives a typical cold reheat temperature), which gives 331 C
  cold reheat at rated load; reheat flow 90 % of the main steam (HP-heater extraction
  from the cold reheat line), reheat pressure proportional to reheat flow (IP turbine
  swallowing capacity), cold reheat above it by the reheater pressure drop. Power by
  eq. (16) for the HP turbine (eta_th = 0.35, paper: 0.30-0.40) and the IP+LP turbines
  (eta_th = 0.70, paper: 0.65-0.75) with C_p = 2.6 kJ/(kg K) (mean of IF97 C_p at the
  two turbine inlets) and T in K; it gives 437 MW at rated flow (440 MW unit).
- Unit controllers (built in): load demand L_d drives the economizer (feedwater) flow
  W_eco = (1 - s1 - s2) W_nom L_d (the flow measurement sits downstream of the spray
  tap, so the sprays add to the steam flow) and the fuel demand through the scheduled
  fuel/water ratio with boiler-input-rate lead T_bir dL_d/dt. A fuel/water-ratio trim
  (integral action on the evaporator outlet enthalpy, the Benson "enthalpy control")
  keeps the evaporator outlet at its setpoint schedule h_ev_setpoint(L). The design
  schedules are computed at construction so that with the design spray openings the
  main steam reaches 535 C at every load.
- Load changes (what drives the steam-temperature excursion of a gas/oil-fired
  once-through unit; no coal mill here, 001 names natural gas and oil):
  * Furnace: the heat release follows the fuel demand through one lag tau_furnace_s =
    20 s (gas valves and burners are fast; flame and furnace-gas heat release take some
    seconds to tens of seconds: G. Klefenz, Automatic Control of Steam Power Plants,
    3rd ed., Bibliographisches Institut, 1986, ch. on boiler dynamics; value a plausible
    default, unverified).
  * Ratio dynamics and heat storage: the feedwater follows the demand at once, the fuel
    through the furnace lag and the BIR lead, while the sliding pressure releases
    (down-ramp) or stores (up-ramp) heat in the evaporator and superheater metal. The
    BIR lead T_bir = 135 s is set by commissioning to roughly balance the stored heat; it
    does not exactly (plausible default, unverified; the residual fuel/water-ratio error
    of a 5 %/min ramp is a few %: 1 % of the ~2100 kJ/kg rise is ~20 kJ/kg at the
    evaporator outlet). The enthalpy trim is slow, as on real units (fwr_ki_per_s,
    integral only: it corrects over minutes; Klefenz op. cit.), so the ratio error
    travels to the superheaters.
  * Schedule error: the enthalpy setpoint is the design schedule plus a commissioning
    error e_50 4 L (1 - L), e_50 = fwr_schedule_error_kJ_kg = -30 kJ/kg (zero at rated
    load, where the unit was tuned; largest at half load; plausible default, unverified:
    real function generators are set from a few test loads). The design spray
    (output ``design_spray_kg_s``, the flow of the design openings at the current load)
    therefore holds the setpoint only at rated load; at half load the steady spray is
    about 24 % lower, and a frozen valve drifts about 10 K after a 100 -> 50 % change.
  * Outlet header and main-steam line (superheater.pipe_rhs): n_line = 3 mixing cells
    between SH4 and the turbine, steam 15 m3 and an effective 50 t of header, line and
    valve-chest metal taken in thermal equilibrium with the steam (the high-conductance
    limit; a 440 MW unit has about 100 t of main-steam piping and 30-50 t of stop/control
    valve bodies, of which the part that follows the steam within a minute counts;
    plausible default, unverified). Thermal transport time about 25 s at rated load,
    1/load slower at part load. ``outlet_temp_C`` is the turbine inlet after the line;
    the main-steam thermocouple measures it; the HP exhaust (eq. 14) follows it.
    ``sh4_out_temp_C`` is the SH4 outlet.
- Sensors (``sensors.py``): thermocouples in thermowells, a lag of a few seconds and
  one of some tens of seconds (the paper, section II), at the evaporator outlet, after
  SH1, SH2, attemperator 1, SH3, attemperator 2, SH4 (main steam) and at the reheater
  outlet. The reheat temperature is not controlled (the paper names no reheat control);
  it is observed and in info (``extra_info``).
- Range: the once-through mode (no separator recirculation), meant for 35-110 % load.

Validation (tests/test_benson_subcritical.py): true-outlet Tu/Tg of a spray-2 step 0.27
(100 %) and 0.28 (50 %), thermocouple 0.40 and 0.38 (field step tests ~0.3; 0.02 and
0.16 without the line); the bias reaches the evaporator outlet; the design spray equals
the rated steady spray; the furnace lag; rated steady state (18.1 MPa, 535 C,
reheat 530 C, eq. (16) power 437 MW, both sprays inside their range); steady states at
50/75/100 % (also disturbed) hold the setpoint with both valves in (0, 1); for every
section (economizer, evaporator, SH1-SH4, reheater) the paper's first-order model
eq. (7), T_out = (T_in + K m_fuel/m_in)/(1 + tau s), is fitted by least squares to our
open-loop responses to a +5 % fuel step and to an inlet-temperature step (5 s samples,
the section's simulated inputs fed as the paper fed its measured data). Result: eq. (7)
describes every section's fuel step (R^2 >= 0.993; K = 908, 4178, 1598, 1896, 1088, 645,
812 K and tau = 197, 105, 76, 66, 51, 49, 36 s from economizer to reheater; the
reheater's 36 s, 42 s before the main-steam line, because its inlet now lags); the
inlet-temperature responses are first order (R^2 >= 0.997 with a free gain), but eq. (7)'s
unit inlet gain (constant C_p) holds only for SH4 and the reheater (R^2 0.96, 0.99); the
gains are 0.65 (economizer), 1.17, 1.17, 1.19, 1.05 (evaporator, SH1-SH3), because
C_p of IF97 water/steam varies along these sections (for the radiant evaporator and SH2
the gain equals C_p(inlet)/C_p(outlet)). Pressure follows eq. (13). Over the 5 %/min
ramp one ROS2 step per 5 s stays within 0.015 K (main steam) of Radau and 0.043 K of 40
substeps with smoothly moving valves (0.02 K before the line and furnace lag), 0.04 K
with random valve steps of +-0.3 every interval (thermocouple reading: 0.10 K, its 5 s
lag being integrated at 5 s).

The package, one task per module: ``params`` (the sections and BensonParams, with
the parameter sources), ``layout`` (indices into the packed parameters, states and
outputs), ``kernel`` (rhs, outputs, projection and the compiled step, with the
integration notes), ``steady_state`` (steady state under the unit controllers),
``calibration`` (packing BensonParams and calibrating it against the design
point) and ``plant`` (the Plant class).
"""

from steamtemp_gym.plants.base import K0
from steamtemp_gym.plants.benson_subcritical.calibration import pack_params
from steamtemp_gym.plants.benson_subcritical.kernel import (
    cold_reheat,
    derivatives,
    design_spray,
    firing,
    fuel_demand,
    h_ev_setpoint,
    outputs,
    p_setpoint,
    project,
    reheat,
    rhs,
    step,
    table,
)
from steamtemp_gym.plants.benson_subcritical.layout import IP, IX, IZ, OUTPUTS
from steamtemp_gym.plants.benson_subcritical.params import P_SHARE, SEC, SECTIONS, BensonParams
from steamtemp_gym.plants.benson_subcritical.plant import BensonSubcritical
from steamtemp_gym.plants.benson_subcritical.steady_state import (
    section_enthalpies,
    section_temperatures,
    steady,
)

__all__ = [
    # the plant, its parameters and sections
    "BensonSubcritical",
    "BensonParams",
    "K0",
    "SECTIONS",
    "SEC",
    "P_SHARE",
    # kernels and steady state
    "rhs",
    "derivatives",
    "outputs",
    "project",
    "step",
    "steady",
    "firing",
    "fuel_demand",
    "p_setpoint",
    "h_ev_setpoint",
    "cold_reheat",
    "design_spray",
    "section_enthalpies",
    "section_temperatures",
    "pack_params",
    "reheat",
    "table",
    # the layout: outputs and the named slots of P, x and z (the section blocks, tables and
    # thermowells in the layout module)
    "OUTPUTS",
    "IP",
    "IX",
    "IZ",
]
