"""Superheated steam temperature of a 300 MW boiler as a two-section cascade plant.

Source: Zhang, Zhang, Ren, Hou, Fang, "Cascade control of superheated steam
temperature with neuro-PID controller", ISA Transactions 51, 2012,
Section 2 (Fig. 2, Fig. 3) and Section 5. The paper's plant is two transfer
functions in series, sampled every T_s = 1 s:

- leading section (Plant2, attemperator and water/steam mixing, inner loop),
  spray command -> intermediate temperature y_i after the secondary spray:
  G_plant2(s) = -2.01 / (1 + 16 s)^2;
- inertia section (Plant1, high-temperature superheater, outer loop),
  intermediate temperature -> superheated steam temperature y:
  G_plant1(s) = 2.09 / (1 + 22.3 s)^4;
- omega_2 enters the inner loop, omega the outer loop (Fig. 3); both
  non-Gaussian, measured, and fed to the paper's neuro-PID; their PDFs (Fig. 5)
  are not in the extracted text.

The secondary P controller G_C2 = 8 and the neuro-PID are the paper's
*controller*, not part of this plant: the action is the spray valve command,
the plant outputs the intermediate temperature (observed: what an inner loop
uses) and the outlet temperature.

Units and scaling (the paper gives none). Temperatures are deviations in K from
the operating point T_out = 535 C (the paper's setpoint) and T_i = T_out -
``ht_rise_K`` (470 C; plausible default, unverified). The controller output u
of the paper is read as the spray-water flow deviation in kg/s: through the
attemperator balance dT_i/dw_sp = -(h_s - h_w) / (W c_p,s), the paper's gain of
-2.01 K per unit corresponds, with IAPWS-IF97 at 17.5 MPa (steam at 470 C,
h_s = 3180.7 kJ/kg, c_p,s = 3.34 kJ/(kg K); spray water at 175 C,
h_w = 750.2 kJ/kg), to a steam flow W = 362 kg/s (1300 t/h), against ~285 kg/s
(1025 t/h) of a typical 300 MW drum boiler, and the series spray-to-outlet gain
-4.20 K/(kg/s) compares with the ~-3.5 K/(kg/s) at 100 % load of a superheater
model with the IDAES 320 MW platen geometry (docs/references.md): the kg/s reading
is consistent within ~25 %, a
valve-percent reading (-420 K over the stroke) or a normalized one (-4 K over
the stroke) is not. The valve command v in [0, 1] maps to spray flow
w_sp = v * ``spray_max_kg_s`` (linear installed characteristic, no valve
dynamics: the paper's leading section starts at the controller output), and
u = w_sp - w_sp0(load), the deviation from the spray that holds 535 C in the
undisturbed plant at that load, w_sp0 linear in load between
``spray_half_load_kg_s`` at 50 % and ``spray_rated_kg_s`` at 100 % (plausible
defaults, unverified: drum-boiler convective superheaters need less spray at
low load). In these units the paper's G_C2 = 8 is 8 kg/s per K, i.e.
8 / ``spray_max_kg_s`` of valve stroke per K.

Model (states: deviations x_1..x_n of the n = 2 + 4 lags, plus the disturbance
generator). Continuous time, with inner input u_in and outer input q (K):

    T2 dx_1/dt = K2(L) u_in - x_1,      T2 dx_2/dt = x_1 - x_2,        y_i = x_2
    T1 dx_3/dt = K1(L) (x_2 + q) - x_3, T1 dx_k/dt = x_(k-1) - x_k,    y = x_6

    u_in = w_sp (1 - c_sw dT_sw) - w_sp0(L) + omega_2
    q    = c_q ((1 + heat_absorption_bias) * fouling - 1) + omega

Exact zero-order-hold discretization (matrix exponential of the augmented
system, inputs held over each 1 s step), so the sampled step responses equal the
transfer functions' at the sample instants. The common disturbance vocabulary
maps as follows:

- heat_absorption_bias and fouling: relative change r = (1 + bias) fouling - 1
  of the high-temperature superheater's heat absorption; at fixed flow and
  inlet the section's temperature rise ``ht_rise_K`` scales with it, so q is an
  outer-section input disturbance c_q r with c_q = ht_rise_K / 2.09 (a step r
  moves the outlet by ht_rise_K r at rated load).
- spray_water_temp_offset_C dT_sw: warmer spray water cools less, the same
  spray flow acts as w_sp (1 - c_sw dT_sw) with c_sw = c_p,w / (h_s - h_w)
  (IF97 at ``attemp_pressure_MPa``, ``spray_water_temp_C`` and T_i): an
  inner-section input disturbance.
- load: the spray demand w_sp0(L) (a load ramp is an inner input disturbance)
  and, with ``load_dependent`` (default True), the section gains and time
  constants (table below).
- noise_std_C: sensor noise on the measured outlet and intermediate
  temperatures (added by the env).

Load dependence (``load_dependent=True``): K2(L) = -2.01 L^-a_K2,
K1(L) = 2.09 L^-a_K1, T2(L) = 16 L^-a_T s, T1(L) = 22.3 L^-a_T s, exactly the
paper's pair at L = 1. Defaults a_K2 = 1 (the attemperator balance above is
exactly proportional to 1/W), a_K1 = 0 (an inlet-to-outlet temperature gain of
a heated tube bank does not grow at low flow), a_T = 1: in superheater models with the
IDAES 320 MW platen geometry the spray-to-outlet gain and time constants both grow
roughly as 1/load (-3.5 K per kg/s and ~70 s at 100 % vs -11 K per kg/s and
~190 s at 37 %, i.e. gain ~ L^-1.15, time ~ L^-1.0). Toyoda and Wada's table
(Toyoda and Wada 1999, Table 1: 137 s at 2270 t/h, 217 s at 1135 t/h)
shows a milder L^-0.66 on the slow mode; set ``load_time_exponent`` to use it.
With the defaults:

    ======  ============  =======  ============  =======  ===================
    load    K2 (K s/kg)   T2 (s)   K1 (K/K)      T1 (s)   spray->outlet K s/kg
    ======  ============  =======  ============  =======  ===================
    100 %   -2.01         16.0     2.09          22.3     -4.20
    75 %    -2.68         21.3     2.09          29.7     -5.60
    50 %    -4.02         32.0     2.09          44.6     -8.40
    37 %    -5.43         43.2     2.09          60.3     -11.35
    ======  ============  =======  ============  =======  ===================

Named scenarios of this plant: ``setpoint_step_535_545`` (Section 5: 535 C,
step to 545 C at 500 s, rated load, 2000 s) and ``load_ramp_100_50_100_2pct``
(100 -> 50 % at 2 %/min after 500 s, hold 20 min, back, hold 15 min: AGC-rate
ramps: AGC moves coal units at 1-2 %/min, through the load-dependent dynamics).
The model load is the load demand, clipped to 20-120 %; the discretized
matrices are tabulated at 1 % load steps (exact there, linearly interpolated in
between; the 100 % entry is exact).

Non-Gaussian disturbances (in the spirit of Fig. 5; its PDFs are not in the
extracted text, the choice here is ours), drawn once per sample and held over it
(the paper's omega_k), both measured (observed), the value shown in an
observation being the one acting over the coming step:

- omega (outer, K at the inertia-section input: flue-gas/heat-absorption
  fluctuations): uniform on [-a, a], a = ``omega_halfwidth_K`` (flat, bounded;
  excess kurtosis -1.2), and *coloured*: slagging, coal quality and mill changes
  vary over minutes, not from one second to the next. omega = a (2 Phi(g) - 1)
  with g a unit Gaussian AR(1) process, g_k+1 = c g_k + sqrt(1 - c^2) n_k,
  c = exp(-T_s / ``omega_corr_time_s``) (a Gaussian copula: the marginal stays
  exactly uniform, the autocorrelation is that of g mapped through Phi, close to
  exp(-t / tau)). ``omega_corr_time_s`` = 150 s (a correlation time of 100-200 s)
  and a = 3 K put the closed-loop tracking error std of a SIMC-tuned cascade PI
  on ``setpoint_step_535_545`` in the order of the paper's 1.7 K (Section 5:
  0.51 / 1.72 K mean / std with its MSE-trained neuro-PID, 0.45 / 1.70 K by MEE;
  measured numbers in benchmarks/difficulty.py and tests/test_cascade_300mw.py).
  ``omega_corr_time_s = 0`` gives the white sequence of the paper's omega_k.
- omega_2 (inner, kg/s at the leading-section input: spray-water flow
  fluctuations, the paper's "attemperator water mass flow"): white, centred
  exponential b (E - 1), E ~ Exp(1), b = ``omega2_scale_kg_s`` = 0.8 kg/s
  (skewness 2, one-sided surges; open-loop outlet std 0.26 K at 100 %).

The steady state at a reset includes the episode's initial omega values (the
plant starts at rest with the disturbances it has at t = 0).

They are deterministic: counter-based (steamtemp_gym/rng.py: a function of a
per-episode seed, the step counter and the channel), with the seed and counter
kept in the plant state. The env seeds them from the episode's key
(``seed_rows``), so the same env seed gives the same omega sequences (every
policy faces the same disturbance at a given seed) and the vector env matches
the single env.

Validation (tests/test_cascade_300mw.py): step metrics (gain, Tu, Tg, t90 by
steamtemp_gym.metrics.step_response_metrics) of the leading section (valve ->
intermediate), the inertia section (heat-absorption step -> outlet) and the
series (valve -> outlet) within 1 % of the analytic values (those of K/(1+Ts)^n
for the sections, the exact series response for the series); sampled step responses
equal scipy.signal.step of the continuous
transfer functions; load table monotone and equal to the paper's pair at 100 %;
disturbance statistics; the ``setpoint_step_535_545`` scenario (535 C, step to
545 C at 500 s as in Section 5) and the paper's cascade (G_C2 = 8 plus an outer
PI) tracking it.

The package, one task per module: ``params`` (CascadeParams, with the parameters'
sources), ``layout`` (the outputs and the named slots of the packed parameters, states
and outputs), ``discretization`` (the sections' exact zero-order-hold models over load,
packed into P), ``kernel`` (the compiled step and steady state), ``plant`` (the Plant
class) and ``scenarios`` (the paper's named scenarios, the class's ``scenarios``).
"""

from steamtemp_gym.plants.base import K0
from steamtemp_gym.plants.cascade_300mw.discretization import (
    block,
    continuous_model,
    pack_params,
    zoh,
)
from steamtemp_gym.plants.cascade_300mw.kernel import SEED_SALT, steady, step
from steamtemp_gym.plants.cascade_300mw.layout import IP, IX, IZ, LOAD_STEP, N_GRID, OUTPUTS
from steamtemp_gym.plants.cascade_300mw.params import (
    LOAD_MAX,
    LOAD_MIN,
    PLANT_ID,
    CascadeParams,
)
from steamtemp_gym.plants.cascade_300mw.plant import Cascade300MW

__all__ = [
    # the plant, its parameters and its discretization
    "Cascade300MW",
    "CascadeParams",
    "K0",
    "PLANT_ID",
    "LOAD_MIN",
    "LOAD_MAX",
    "continuous_model",
    "zoh",
    "block",
    "pack_params",
    "step",
    "steady",
    "SEED_SALT",
    # the layout: outputs and the named slots of P, x and z
    "OUTPUTS",
    "IP",
    "IX",
    "IZ",
    "LOAD_STEP",
    "N_GRID",
]
