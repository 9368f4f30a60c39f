"""Neuro-PID cascade trained online by minimum error entropy (MEE) or mean squared error.

Source: Zhang et al. 2012 (J. Zhang, F. Zhang, M. Ren, G. Hou, F. Fang, "Cascade control
of superheated steam temperature with neuro-PID controller", ISA Transactions 51, 2012;
docs/references.md). Registry names ``neuro_pid_mee`` (the paper's controller) and
``neuro_pid_mse`` (its comparison: the same net trained by squared error).

Mechanism (paper Section 3, equation numbers of the paper):

- Outer (primary) loop: the incremental PID of eq. (4),
  u_k = u_(k-1) + k_p (e_k - e_(k-1)) + k_i e_k + k_d (e_k - 2 e_(k-1) + e_(k-2)),
  e = setpoint - measured outlet (through the 5 s DCS input filter of cascade_pi, so
  the derivative term does not differentiate raw sensor noise; the paper's plant has
  none). u is the setpoint deviation (K) of the inner loop.
- Gains from a three-layer perceptron, eq. (5)-(8), trained online during the episode
  by minimum error entropy (``mee``) or mean squared error (``mse``), eq. (2)-(19), each
  gain held within k_l0 (1 -+ 1/2) of its commissioning value k_l0:
  baselines/neuro_pid_net.py.

Learning rate (the one knob, ``KNOBS``; default the paper's eta = 1e-4 for both nets, as
Section 5 gives "same structure and parameters"). With it neither net learns much in an
episode: the MEE gradient carries lambda / (2 sigma^2) = 1/100 and a kernel below 0.14
where the MSE one carries e, so at equal eta the MEE net moves about a hundred times less.
:data:`ADAPTING_ETA` (MEE 1, MSE 1e-2) are the smallest rates of a decade ladder at which
training episodes of the ``random`` scenario move k_i by at least 10 % without holding it
at a bound (benchmarks/neuro_pid_eta.py; never a named or held-out scenario): the claim
tests compare MEE with MSE there too, between nets that adapt by about the same amount.
On those training episodes of the paper's plant, learning lowers the MEE net's return at
every eta, and raises the MSE net's only where eta is so large that it drives its gains to
their upper bounds (measured numbers in docs/baselines/neuro_pid.md).

Inner loop. The paper's secondary controller is the proportional G_C2 = 8 (Section 5)
ahead of the leading section G_plant2 = -2.01 / (1 + 16 s)^2. The text gives neither in
units, but the two chain (G_C2's output is G_plant2's input), and Section 2 names that
signal: "the manipulated variable is the position of spray water valves". So G_C2 is
valve position per K and G_plant2 K per unit of position: with the position in % of
stroke, as a DCS shows it, G_C2 = 8 %/K and G_plant2 = -2.01 K/%. Cascade300MW-v0 reads
G_plant2 as K per kg/s of spray (its docstring: the attemperator balance at 362 kg/s of
steam); the two readings agree only if 1 % of stroke passes 1 kg/s, a 100 kg/s valve:
28 % of the steam flow, where secondary sprays are sized for a few per cent and the
plant's own rated spray (4.5 kg/s) would sit at 4.5 % open. The plant keeps its 9 kg/s
valve (``spray_max_kg_s``), so one reading has to give. Read as 8 kg/s per K (the
paper's inner loop gain 16.1 kept), G_C2 strokes the valve by 0.89 of its travel per K
of thermocouple noise, and that loop has 22 deg of phase margin at T_s = 1 s with no
measurement filter and none behind a 3 s one (unstable). This module keeps the paper's
number in the paper's unit of position: G_C2 = 8 % of stroke per K (declared by
Cascade300MW: ``commissioning["neuro_pid"]["inner_p_pct_per_K"]``), 0.72 kg/s per K on the
plant, an inner loop gain of 1.45 at rated load (2.9 at 50 %, 4.1 at 35 %: the
leading-section gain grows as 1/load) with
a phase margin of 103 deg at rated load and 49 deg at 35 % behind the filter; the inner
closed loop (poles (-1 +- 1.2 j) / 16 s at rated load) stays well faster than the
outer 4 x 22.3 s lags, as Section 2 asks. The P acts on the intermediate temperature
through the same first-order 5 s input filter (cascade_pi.FILTER_S) as every
measurement the baselines read: a DCS filters thermocouples so, and 5 s is short
against the section's 16 s lags. Section 4 step (1) allows a P or PI secondary; on the
other plants the MAIN loops keep cascade_pi_ff's identified, load-scheduled inner PI (and
its 5 s filter), with the neuro-PID as its outer controller. Every MAIN loop of a plant
gets its own net; SCHEDULED first stages, single loops on other signals (the reheat
damper) and actuators without a loop are cascade_pi_ff's loops without its feed-forward
(the paper's mechanism concerns the main-steam cascade only).

Commissioning PID (the net's starting point and the centre of the gains' bounds) and
initial weights, from closed-loop steps of the inner setpoint at cascade_pi's GAIN_LOADS,
SIMC PI and load-scheduled: baselines/neuro_pid_commissioning.py.

Disturbance inputs. Cascade300MW-v0 measures the paper's omega (outer, K) and omega_2
(inner, kg/s): the observation entries ``omega_K`` and ``omega2_kg_s``. The other plants
have no such signals; the net gets the measured proxies its plant declares
(``commissioning["neuro_pid"]["disturbance_signals"]``): the firing
rate minus the load demand (heat release ahead of or behind the steam flow: the outer,
heat-absorption disturbance; in units of the load-demand scale 0.25), the load-demand
rate (first-order filter 60 s, 5 %/min -> 1) and the attemperator inlet temperature
(deviation from the episode start over its signal scale: the inner disturbance).
Note that in eq. (4) the disturbances act only through the gains, which multiply
error terms: with zero error the neuro-PID does not move, so the "feed-forward" the
paper ascribes to these inputs is gain scheduling by disturbance, not an additive
feed-forward.

Anti-windup (velocity form): with the paper's P secondary (or no inner loop) the outer
output u is clamped where the valve reaches a stop; with an inner PI an increment is
discarded while the valve is saturated in its direction (conditional integration, as
cascade_pi). Bumpless start: u = 0 (inner setpoint = the inner temperature at the episode
start), valve at its start position; a scheduled inner PI's integral is rescaled where its
gain moves (as cascade_pi_ff's).

Claims of the paper and what reproduces: the Claims table of docs/baselines/neuro_pid.md and
tests/test_neuro_pid.py; realism (valve travel, limit cycles) on every plant:
benchmarks/neuro_pid_realism.py.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from baselines.cascade_pi import FILTER_S, GAIN_LOADS, CascadePI
from baselines.loops import input_filter, into_stop, observation_layout, pi_position, restart_rows
from baselines.neuro_pid_commissioning import commissioning_gains, inner_p_valve_per_K
from baselines.neuro_pid_net import (
    ETA,
    LAMBDA,
    N_IN,
    N_W,
    SIGMA_K,
    WINDOW,
    gain_bounds,
    initial_weights,
    npid_step,
)
from baselines.tuning import Knob
from steamtemp_gym.plants.base import MAIN

LOAD_RATE_FILTER_S, LOAD_RATE_UNIT = 60.0, 0.05 / 60.0  # 5 %/min -> 1
ERR_SCALE_K = 20.0  # the observation's error scale (steamtemp_gym.signals.T0_K)
#: Learning rates at which the nets adapt alike without saturating (training episodes move
#: k_i by 23 % and 26 %; the MEE gradient is ~100 times smaller): benchmarks/neuro_pid_eta.py.
ADAPTING_ETA = {"mee": 1.0, "mse": 1e-2}


class NeuroPID:
    """Neuro-PID on every MAIN loop over its inner loop; cascade_pi_ff's loops elsewhere.

    Args:
        env: The env (or vector env) the policy acts on.
        criterion: ``"mee"`` (minimum error entropy, the paper's) or ``"mse"``.
        k0: Optional commissioning gains (k_p0, k_i0, k_d0[, direction]) per action, used at
            every load instead of :func:`commissioning_gains`.
        force_u: If given, the outer output is held at this value (commissioning tests;
            no training).
        eta: Learning rate of eq. (9), (13) (None: the paper's 1e-4).
    """

    @staticmethod
    def knob_defaults(env_id: str) -> dict[str, float]:
        """The paper's learning rate (Section 5), both variants' start."""
        return {"eta": ETA}

    def __init__(
        self,
        env: Any,
        criterion: str = "mee",
        k0: Any = None,
        force_u: float | None = None,
        eta: float | None = None,
    ) -> None:
        if criterion not in ("mee", "mse"):
            raise ValueError(f"criterion must be 'mee' or 'mse', got {criterion!r}")
        eta = ETA if eta is None else float(eta)
        if not (math.isfinite(eta) and eta >= 0.0):
            raise ValueError(f"eta must be a finite learning rate >= 0, got {eta!r}")
        u = env.unwrapped
        plant = u.plant
        self.mee = criterion == "mee"
        self.eta = eta
        self.force_u = force_u
        # the non-MAIN loops, and the inner PI tuning (load-scheduled, as cascade_pi_ff's)
        self.pi = CascadePI(env, gain_schedule=True)
        names, self._scale, self._center = observation_layout(env)
        self.i_err, self.i_load = names.index("error_K"), names.index("load_demand")
        self.i_fire = names.index("firing_rate") if "firing_rate" in names else None
        self.i_valve = [names.index(n) for n in plant.valves]
        self.dt = plant.dt_s
        self.a_filter = float(np.exp(-self.dt / FILTER_S))
        self.a_load = float(np.exp(-self.dt / LOAD_RATE_FILTER_S))
        self.main = [j for j, (_, o) in enumerate(plant.control_loops) if o == MAIN]
        self.inner = [
            names.index(plant.control_loops[j][0]) if plant.control_loops[j][0] else None
            for j in self.main
        ]
        self.p_inner = inner_p_valve_per_K(plant)
        own = plant.commissioning.get("neuro_pid", {})
        prox = own.get("disturbance_signals") or (
            "firing_minus_load" if self.i_fire is not None else "load_rate",
            "load_rate",
        )
        self.proxies = [(p, names.index(p) if p in names else None) for p in prox]
        params = json.dumps(getattr(u, "params_overrides", {}) or {}, sort_keys=True)
        if force_u is None and k0 is None:
            self.loads = np.array(GAIN_LOADS)
            table = commissioning_gains(NeuroPID, plant.id, params)
        else:
            k = np.asarray(k0, float)
            if k.shape[1] == 3:
                k = np.column_stack([k, np.ones(len(k))])
            self.loads, table = np.ones(1), k[None]
        self.k0 = table  # (loads, actions, 4)
        main = table[:, self.main, :3]
        #: (loads, MAIN loops, 3) commissioning gains k_l0 at each load
        self.k0_main = main
        self.w0 = np.array([initial_weights(table[-1, j, :3])[0] for j in self.main])
        self.direction = table[-1, self.main, 3] if len(self.main) else np.zeros(0)
        self._st: dict[str, np.ndarray] | None = None
        self.gains = np.zeros((1, len(self.main), 3))  # last PID gains per row and MAIN loop
        self.outputs = np.zeros((1, len(self.main), 3))  # and the net's outputs g in (0, 1)

    def reset(self) -> None:
        self._st = None
        self.pi.reset()

    def commissioning(self, load: np.ndarray) -> np.ndarray:
        """(rows, MAIN loops, 3) commissioning gains k_l0 at each row's load demand,
        interpolated linearly between GAIN_LOADS (held beyond them)."""
        n, nm = len(load), len(self.main)
        out = np.empty((n, nm, 3))
        for c in range(nm):
            for m in range(3):
                out[:, c, m] = np.interp(load, self.loads, self.k0_main[:, c, m])
        return out

    # -- state ---------------------------------------------------------------------
    def _new_state(self, n: int) -> dict[str, np.ndarray]:
        nm = len(self.main)
        nu = n * nm
        return {
            "y0": np.zeros((n, len(self._scale))),
            "yf": np.zeros((n, len(self._scale))),
            "Lf": np.zeros(n),
            "E": np.zeros((n, nm, 3)),
            "u": np.zeros((n, nm)),
            "ii": np.zeros((n, nm)),
            "kci": np.zeros((n, nm)),
            "W": np.zeros((nu, N_W)),
            "G": np.zeros((nu, N_W)),
            "V": np.zeros(nu),
            "Ebuf": np.zeros((nu, WINDOW)),
            "Sbuf": np.zeros((nu, WINDOW, N_W)),
            "nbuf": np.zeros(nu, np.int64),
            "head": np.zeros(nu, np.int64),
        }

    def _restart(self, st: dict[str, np.ndarray], rows: np.ndarray, y: np.ndarray) -> None:
        nm = len(self.main)
        st["y0"][rows], st["yf"][rows], st["Lf"][rows] = y[rows], y[rows], y[rows, self.i_load]
        st["E"][rows] = y[rows, self.i_err][:, None, None]
        st["u"][rows], st["ii"][rows], st["kci"][rows] = 0.0, 0.0, 0.0
        units = (np.flatnonzero(rows)[:, None] * nm + np.arange(nm)).ravel()
        st["W"][units] = np.tile(self.w0, (rows.sum(), 1)) if nm else 0.0
        st["G"][units], st["nbuf"][units], st["head"][units] = 0.0, 0, 0
        st["V"][units] = (
            1.0 / (math.sqrt(2.0 * math.pi) * math.sqrt(2.0) * SIGMA_K) if self.mee else 0.0
        )

    def _inputs(self, st: dict[str, np.ndarray], y: np.ndarray) -> np.ndarray:
        """Net inputs (n, N_IN): normalized errors and the two disturbance signals."""
        n = y.shape[0]
        x = np.empty((n, N_IN))
        x[:, :3] = st["E"][:, 0, :] / ERR_SCALE_K
        for c, (name, i) in enumerate(self.proxies):
            if name == "firing_minus_load":
                x[:, 3 + c] = (y[:, self.i_fire] - y[:, self.i_load]) / self._scale[self.i_load]
            elif name == "load_rate":
                x[:, 3 + c] = (y[:, self.i_load] - st["Lf"]) / LOAD_RATE_FILTER_S / LOAD_RATE_UNIT
            elif name in ("omega_K", "omega2_kg_s"):
                x[:, 3 + c] = (y[:, i] - self._center[i]) / self._scale[i]
            else:  # a temperature: deviation from the episode start
                x[:, 3 + c] = (y[:, i] - st["y0"][:, i]) / self._scale[i]
        return x

    def _adapted_outputs(
        self, st: dict[str, np.ndarray], y: np.ndarray, load: np.ndarray
    ) -> np.ndarray:
        """(rows, MAIN loops) new outputs u of the outer loops: the net adapts its weights
        to the errors in ``st["E"]`` and sets each loop's PID gains between the bounds
        around its commissioning gains at the load demand, which move u (eq. (4))."""
        n, nm = y.shape[0], len(self.main)
        E = st["E"]
        x = np.repeat(self._inputs(st, y), nm, axis=0)
        gains = np.empty((n * nm, 3))
        base, scale = gain_bounds(self.commissioning(load).reshape(n * nm, 3))
        npid_step(
            x,
            E.reshape(n * nm, 3),
            st["W"],
            st["G"],
            st["V"],
            st["Ebuf"],
            st["Sbuf"],
            st["nbuf"],
            st["head"],
            base,
            scale,
            self.mee,
            SIGMA_K,
            LAMBDA,
            WINDOW,
            self.eta,
            gains,
        )
        gains = gains.reshape(n, nm, 3)
        self.gains = gains
        self.outputs = ((gains.reshape(n * nm, 3) - base) / scale).reshape(n, nm, 3)
        e0, e1, e2 = E[..., 0], E[..., 1], E[..., 2]  # this step's error and the two before
        du = np.stack([e0 - e1, e0, e0 - 2.0 * e1 + e2], axis=-1)  # the P, I and D increments
        return st["u"] + self.direction * np.einsum("nml,nml->nm", gains, du)  # eq. (4)

    # -- predict -------------------------------------------------------------------
    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        obs = np.atleast_2d(np.asarray(observation, dtype=np.float64))
        action, _ = self.pi.predict(obs, episode_start=episode_start)  # non-MAIN loops
        action = np.array(action, dtype=np.float32, copy=True)
        y = obs * self._scale + self._center
        n = obs.shape[0]
        st = self._st
        fresh = st is None or st["y0"].shape != y.shape
        if fresh:
            st = self._st = self._new_state(n)
        restart = restart_rows(fresh, n, episode_start)
        if restart.any():
            self._restart(st, restart, y)
        yf = st["yf"]
        input_filter(yf, y, self.a_filter, restart)  # DCS input filter
        load = y[:, self.i_load]
        st["Lf"] += (1.0 - self.a_load) * (load - st["Lf"])
        nm = len(self.main)
        if nm == 0:
            return (action[0] if np.ndim(observation) == 1 else action), None
        E = st["E"]
        E[:, :, 1:] = E[:, :, :2].copy()
        E[:, :, 0] = yf[:, self.i_err][:, None]  # setpoint - measured outlet, filtered
        if self.force_u is None:
            u_new = self._adapted_outputs(st, y, load)
        else:
            u_new = np.full((n, nm), float(self.force_u))
        v0 = st["y0"][:, self.i_valve]
        pi_gains = self.pi.loop_gains  # the inner PIs' scheduled gains at this step's load
        for c, j in enumerate(self.main):
            i_in = self.inner[c]
            vj = v0[:, j]
            if i_in is None:  # no inner temperature: the outer output moves the valve
                u_new[:, c] = np.clip(u_new[:, c], -vj, 1.0 - vj)  # velocity-form saturation
                v = vj + u_new[:, c]
                push = np.zeros(n)
            elif self.p_inner is not None:  # the paper's P secondary, reverse acting
                dyf = yf[:, i_in] - st["y0"][:, i_in]  # through the DCS input filter
                # velocity-form saturation: u held where the valve reaches its stop
                u_new[:, c] = np.clip(
                    u_new[:, c], dyf - (1.0 - vj) / self.p_inner, dyf + vj / self.p_inner
                )
                v = vj - self.p_inner * (u_new[:, c] - dyf)
                push = np.zeros(n)
            else:  # cascade_pi_ff's load-scheduled inner PI on the filtered inner temperature
                kc_i = np.broadcast_to(pi_gains[:, j, 2], (n,))
                ti_i = np.broadcast_to(pi_gains[:, j, 3], (n,))
                prev = st["kci"][:, c]
                ratio = np.divide(prev, kc_i, out=np.ones(n), where=(prev != 0.0) & (kc_i != 0.0))
                st["ii"][:, c] *= ratio  # bumpless: kc times the integral is continuous
                st["kci"][:, c] = kc_i
                e_i = u_new[:, c] - (yf[:, i_in] - st["y0"][:, i_in])
                v, _ = pi_position(vj, kc_i, e_i, st["ii"][:, c], self.dt, ti_i)
                push = kc_i * (u_new[:, c] - st["u"][:, c])
            sat = into_stop(v, push)
            st["u"][:, c] = np.where(sat, st["u"][:, c], u_new[:, c])  # anti-windup
            action[:, j] = 2.0 * np.clip(v, 0.0, 1.0) - 1.0
        return (action[0] if np.ndim(observation) == 1 else action), None


class NeuroPIDMEE(NeuroPID):
    """The paper's neuro-PID trained by minimum error entropy (registry: neuro_pid_mee).

    ``eta`` is the one knob (default: the paper's 1e-4); its box spans a net that does not
    learn within an episode (1e-5) to the adapting rate (1, :data:`ADAPTING_ETA`). Faster
    rates drive the gains to their bounds, where the loop limit-cycles under sensor noise
    (eta 10 on BensonSubcritical-v0's held-out high-noise scenario).
    """

    KNOBS = (Knob("eta", 1e-5, 1.0),)

    def __init__(self, env: Any, eta: float | None = None, **kwargs: Any) -> None:
        super().__init__(env, criterion="mee", eta=eta, **kwargs)


class NeuroPIDMSE(NeuroPID):
    """The same net trained by mean squared error (registry: neuro_pid_mse).

    ``eta`` is the one knob (default: the paper's 1e-4, both nets have "same structure and
    parameters", Section 5); the MSE gradient being ~100 times the MEE one, its box is
    shifted down by two decades: 1e-6 (no learning) to the adapting rate 1e-2
    (:data:`ADAPTING_ETA`), beyond which the gains are driven to their bounds.
    """

    KNOBS = (Knob("eta", 1e-6, 1e-2),)

    def __init__(self, env: Any, eta: float | None = None, **kwargs: Any) -> None:
        super().__init__(env, criterion="mse", eta=eta, **kwargs)


class Recorder:
    """Wraps a :class:`NeuroPID` and records, after every ``predict``, the PID gains, the
    net outputs g (gain / bound) and the weights of the first MAIN loop of every row
    (diagnostics: the claim tests and benchmarks/neuro_pid_eta.py)."""

    def __init__(self, pol: NeuroPID) -> None:
        self.pol = pol
        self.gains: list[np.ndarray] = []
        self.outputs: list[np.ndarray] = []
        self.weights: list[np.ndarray] = []

    def reset(self) -> None:
        self.pol.reset()
        self.gains, self.outputs, self.weights = [], [], []

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        out = self.pol.predict(observation, state, episode_start, deterministic)
        nm = len(self.pol.main)
        self.gains.append(self.pol.gains[:, 0].copy())
        self.outputs.append(self.pol.outputs[:, 0].copy())
        self.weights.append(self.pol._st["W"][::nm].copy())
        return out
