"""Gain-scheduled LQ controller with integral action (LQI) and a steady-state Kalman filter.

Source: T.-S. Kim, "A Study on Water-Tube Boiler Modeling" (in Korean), M.Eng. thesis,
Dept. of Electrical Engineering, Inha University (docs/references.md, seed 003), chapter 5:
actuator constraints, saturation and rate limits (eq. 32, Fig. 10); the model augmented by
the integrated tracking error e_I, de_I/dt = delta r - delta y (eq. 33, Fig. 11); the LQ
cost J = integral of e_I' q e_I + delta u' R delta u (eq. 34), only the integrated error
and the input weighted; its algebraic Riccati equation (eq. 35); the control
u = u_o + delta u, delta u = -K_F delta x - K_I e_I (eq. 36); linear models at three
operating points (eq. 29-31). The thesis's weights (eq. 37) and operating points lost their
digits in the extraction and belong to its drum outputs (pressure, level, steam flow), so
none of its numbers are used here.

What is taken and how it is generalized:

- Models: ``Plant.linearize`` (steamtemp_gym/plants/base.py) at ``GRID_LOADS`` = 50, 75,
  100 % load (the thesis's three operating points; its own loads are not legible): the
  discrete model at the control interval by finite differences of the plant's compiled
  step, outputs = the observed plant outputs. The model-based design knows the plant's
  equations and parameters, never its hidden states or the scenario. States that no
  action reaches (exactly zero in the finite differences through every path: the
  plant-internal random generators of Cascade300MW) are dropped; the rest keep their
  physical coordinates (scaled by the peak of their response to a unit step of every
  action), so the gains of the three models can be interpolated entry by entry.
- Discrete LQI (the thesis designs in continuous time; here the discrete form at the
  control interval): augmented state [x; z] with z_k+1 = z_k + dt (r_k - y_k), y the
  measured main-steam temperature, cost sum q_y (c x)^2 + q_I z^2 + du' R du, gain from
  scipy.linalg.solve_discrete_are (no Riccati solver written here). The thesis's eq. 34
  weights the integrated error and the input only (q_y = 0); the output weight q_y is
  added here. Weights by Bryson's rule: R = 1/du_max^2, q_y = 1/e_max_K^2,
  q_I = 1/(e_max_K ti_factor tau)^2 with tau the 63 % time of the main-steam response to
  the MAIN valves at that load (the integrated error an e_max_K offset builds over
  ti_factor plant time constants).
- Kalman filter (the thesis measures its states; here they are estimated): steady-state,
  filtered form, from the DARE of (A', C'), on the model augmented offset-free
  (Pannocchia and Rawlings 2003; Muske and Badgwell 2002) with the heat-absorption bias q
  (an input disturbance entering where the plant's own bias enters,
  ``Plant.linearize_disturbances``; a random walk of intensity heat_walk per sqrt(s)) and a
  random-walk output disturbance on every observed signal but the main-steam thermocouple
  (P_REL of its scale per step); process noise W_REL^2 per scaled state; measurement
  noise: NOISE_K (the named scenarios' 0.25 K) on the thermocouples, V_REL of the signal
  scale on the others. The estimator is fed the actuators' applied commands (after the
  limits), which is also the anti-windup of the state part.
- Steady target (the disturbance and setpoint feed-forward): the commands and states
  (u_s, x_s) that hold the modelled main steam at the setpoint under the estimated q,
  linear in q and in the setpoint's change since the start dr; the control is
  du = u_s - K_x (x_hat - x_s) - K_I z. With q = dr = 0 this is the thesis's eq. 36.
- Scheduling: gains, filters and models interpolated linearly in the observed load
  demand between the grid models (held beyond 50 / 100 %); the operating point
  (steady outputs, valve openings and states of the undisturbed plant on OP_LOADS,
  interpolated) moves with the load: its valve openings act as a load feed-forward and
  the estimate is shifted by the change of the steady state when the load moves.
  Bumpless start: the estimate starts at the operating point and the start's offsets of
  the outputs and valves against it (disturbances present at t = 0) are held as biases.
- Actuator limits (eq. 32): the command is rate limited to the valve's own rate (the
  plant's actuator rate limit; none where the plant has no valve dynamics) and
  saturated to [0, 1]; anti-windup by conditional integration (z frozen while a MAIN
  valve is at a limit and the error would push it further).
- Actuators: the LQI moves the actuators whose loop is on the main-steam error
  (``control_loops`` outer == MAIN: a plant's only spray, or its last-stage spray where
  it has two stages). The other actuators (SCHEDULED first-stage sprays, a reheat
  damper) keep cascade_pi's loops, whose applied commands enter the estimator as known
  inputs. A plant's own loops (a drum's pressure on firing and level on feedwater) are
  part of the plant and of its linearization.

Knobs (``KNOBS``; constructor keywords, None = default): du_max, e_max_K, ti_factor,
heat_walk. The thesis's weights (eq. 37) lost their digits and belong to its drum
outputs, so the defaults are the benchmark's common tuning (agents/baseline_tuning.py,
stored in baselines/tuned/lqi.json), started from these commissioning values (:func:`start`):
du_max = 0.1 of the stroke, e_max_K = 1 K,
ti_factor = 1, heat_walk = 1.6e-3 (the named scenarios' coloured heat-absorption
disturbance, std 0.02 and 300 s, as a random walk). A plant may declare other starting
values (``commissioning["lqi"]`` on its class, each with the measurement that chose it),
chosen by hand so that the valve travel stays within 3x cascade_pi_ff's on the named and
held-out scenarios (3 seeds) and the quiet stretch after a ramp passes its check.

Measured. Linearization (tests/test_linearize.py): the linear model's response to a
1 % valve step matches the env's over 60 steps within 0.3 % of the peak on every observed
output of every plant (DrumBoilerSH 0.08 %). Claims on DrumBoilerSH (tests/test_lqi.py,
noise off, rated load, 2400 s): the integrator of the thesis form (no feed-forward)
removes the offset after a +5 K setpoint step and a +5 % heat-absorption step (below
0.05 K; with K_I = 0 the heat step leaves 3.8 K); a +15 K setpoint step with the valve's
rate limit holding the command back for 11 steps ends at 0.019 K. The estimated heat
absorption settles at the step's size. Named scenarios: docs/baselines.md.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np
from scipy.linalg import solve_discrete_are

from baselines import tuning
from baselines.cascade_pi import CascadePI
from baselines.commissioned import commissioned
from baselines.linear_models import interp_rows, kalman_gain, reachable, steady_point
from baselines.loops import into_stop, observation_layout, restart_rows
from baselines.tuning import Knob
from steamtemp_gym import plants
from steamtemp_gym.plants.base import MAIN

#: Operating points of the three linear models (fraction of rated load).
GRID_LOADS = (0.5, 0.75, 1.0)
#: Loads at which the steady operating points are tabulated (interpolated between).
OP_LOADS = tuple(np.round(np.arange(0.3, 1.201, 0.05), 2))
#: Kalman filter: process noise per scaled state, measurement noise of the thermocouples
#: (K; the named scenarios' noise_std_C) and of the other signals (fraction of their scale),
#: random-walk step of the output disturbances (fraction of their signal's scale).
W_REL = 0.01
NOISE_K = 0.25
V_REL = 0.01
P_REL = 0.002
#: Defaults of the knobs (all chosen; see the module docstring) and the plants' own.
DEFAULTS = {"du_max": 0.1, "e_max_K": 1.0, "ti_factor": 1.0, "heat_walk": 1.6e-3}
KNOBS = (
    Knob("du_max", 0.01, 1.0),
    Knob("e_max_K", 0.1, 100.0),
    Knob("ti_factor", 0.1, 10.0),
    Knob("heat_walk", 1e-4, 1e-2),
)


def start(env_id: str) -> dict[str, float]:
    """The commissioning values of the knobs on a plant (the common tuning's start)."""
    own = plants.plant_class(env_id).commissioning.get("lqi", {})
    return {k.name: own.get(k.name, DEFAULTS[k.name]) for k in KNOBS}


def defaults(env_id: str) -> tuple[float, ...]:
    """The knobs' default values on a plant, in :data:`KNOBS` order: the benchmark's stored
    tuning (baselines/tuned/lqi.json; the thesis gives no weights) where the plant has one,
    else :func:`start`."""
    values = tuning.stored_or("lqi", env_id, start(env_id))
    return tuple(values[k.name] for k in KNOBS)


def _t63(A: np.ndarray, B: np.ndarray, c: np.ndarray, dt: float) -> float:
    """63 % time (s) of the step response of output row c to the summed inputs B."""
    x, ys = np.zeros(A.shape[0]), []
    for _ in range(3000):
        x = A @ x + B.sum(axis=1)
        ys.append(c @ x)
    ys = np.abs(np.array(ys))
    return dt * (1 + int(np.argmax(ys >= 0.632 * ys[-1])))


def lq_gains(
    A: np.ndarray, Bm: np.ndarray, c: np.ndarray, dt: float, q_y: float, q_i: float, r: float
) -> tuple[np.ndarray, np.ndarray]:
    """(Kx, Kz) of the discrete LQI: x+ = A x + Bm du, z+ = z - dt c x, cost
    sum q_y (c x)^2 + q_i z^2 + r |du|^2 (scipy.linalg.solve_discrete_are)."""
    n, m = A.shape[0], Bm.shape[1]
    Aa = np.block([[A, np.zeros((n, 1))], [-dt * c[None, :], np.ones((1, 1))]])
    Ba = np.vstack([Bm, np.zeros((1, m))])
    Q = np.zeros((n + 1, n + 1))
    Q[:n, :n] = q_y * np.outer(c, c)
    Q[n, n] = q_i
    R = r * np.eye(m)
    P = solve_discrete_are(Aa, Ba, Q, R)
    K = np.linalg.solve(R + Ba.T @ P @ Ba, Ba.T @ P @ Aa)
    return K[:, :n], K[:, n]


def steady_targets(
    A: np.ndarray, Bm: np.ndarray, bq: np.ndarray, c: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(Nu_q, Nx_q, Nu_r, Nx_r): the steady commands u_s = Nu_q q + Nu_r dr and states
    x_s = Nx_q q + Nx_r dr with c x_s = dr under a constant heat-absorption bias q entering
    as bq and a setpoint dr (K) away from the operating point's (least-norm u_s)."""
    inv = np.linalg.inv(np.eye(A.shape[0]) - A)
    gu_pinv = np.linalg.pinv((c @ inv @ Bm)[None, :])[:, 0]
    Nu_q, Nu_r = -gu_pinv * float(c @ inv @ bq), gu_pinv
    return Nu_q, inv @ (Bm @ Nu_q + bq), Nu_r, inv @ (Bm @ Nu_r)


@commissioned(maxsize=32)
def design(env_id: str, params_json: str, knobs: tuple[float, ...] | None = None) -> dict[str, Any]:
    """The scheduled LQI design of a plant (cached): per grid load the scaled, reduced
    model (A, B, C, bq), the augmented Kalman gain M, LQ gains (Kx, Kz) and the
    disturbance feed-forward Kq; the operating-point tables. ``knobs``: values in
    :data:`KNOBS` order (None: the plant's defaults)."""
    knobs = knobs or defaults(env_id)
    plant = plants.make(env_id, **json.loads(params_json))
    main = [j for j, (_, o) in enumerate(plant.control_loops) if o == MAIN]
    observed = [s for s in plant.outputs if s.observed]
    i_meas = [s.name for s in observed].index(plant.outlet_measured)
    models = [plant.linearize(L) for L in GRID_LOADS]
    bqs = [plant.linearize_disturbances(L, ("heat_absorption_bias",))[0][:, 0] for L in GRID_LOADS]
    keep = np.zeros(plant.n_x, dtype=bool)
    for (A, B, *_), bq in zip(models, bqs, strict=True):
        keep |= reachable(A, np.column_stack([B, bq]))
    # state scale: peak response of each kept state to a unit step of every action, 100 %
    A, B = models[-1][0][np.ix_(keep, keep)], models[-1][1][keep]
    x, peak = np.zeros(A.shape[0]), np.zeros(A.shape[0])
    for _ in range(1500):
        x = A @ x + B.sum(axis=1)
        peak = np.maximum(peak, np.abs(x))
    sx = np.maximum(peak, 1e-9 * max(peak.max(), 1e-300))
    sy = np.array([s.scale for s in observed])
    vy = np.array([(NOISE_K / s.scale if s.noisy else V_REL) ** 2 for s in observed])
    dt = plant.dt_s
    p_rows = [j for j in range(len(observed)) if j != i_meas]  # output disturbances
    n_y, n_p = len(observed), len(p_rows)
    E = np.zeros((n_y, n_p))
    E[p_rows, np.arange(n_p)] = 1.0
    grid = []
    for (A, B, C, _), bq in zip(models, bqs, strict=True):
        A = A[np.ix_(keep, keep)] / sx[:, None] * sx[None, :]
        B = B[keep] / sx[:, None]
        bq = bq[keep] / sx
        C = C[:, keep] * sx[None, :] / sy[:, None]
        c_main = C[i_meas] * sy[i_meas]  # K per scaled state
        grid.append(_load_design(A, B, C, bq, c_main, main, E, vy, dt, knobs))
    ops = [steady_point(plant, L, [s.name for s in observed]) for L in OP_LOADS]
    ok = [k for k, (xo, uo, yo) in enumerate(ops) if np.all(np.isfinite(yo))]
    return {
        "grid": grid,
        "main": main,
        "keep": keep,
        "sx": sx,
        "sy": sy,
        "n": int(keep.sum()),
        "op_loads": np.array(OP_LOADS)[ok],
        "x_op": np.array([ops[k][0][keep] / sx for k in ok]),
        "u_op": np.array([ops[k][1] for k in ok]),
        "y_op": np.array([ops[k][2] for k in ok]),
    }


def _load_design(
    A: np.ndarray,
    B: np.ndarray,
    C: np.ndarray,
    bq: np.ndarray,
    c_main: np.ndarray,
    main: list[int],
    E: np.ndarray,
    vy: np.ndarray,
    dt: float,
    knobs: tuple[float, ...],
) -> dict[str, Any]:
    """The LQI design at one grid load of the reduced, scaled model (A, B, C, bq), ``c_main``
    the main steam temperature (K) per scaled state: the model augmented by the heat walk
    and the output disturbances ``E``, its Kalman gain M for the output noise variances
    ``vy``, the LQ gains (Kx, Kz) of the ``main`` actuators, the feed-forwards Kq and Kr and
    the spectral radii of the closed loop and of the estimator."""
    du_max, e_max, ti_factor, heat_walk = knobs
    n_y, n_p = E.shape
    n = A.shape[0]
    tau = _t63(A, B[:, main], c_main, dt)
    # Bryson's rule: the inverse squares of the largest wanted error, integral and move
    q_y, q_i, r = 1.0 / e_max**2, 1.0 / (e_max * ti_factor * tau) ** 2, 1.0 / du_max**2
    Kx, Kz = lq_gains(A, B[:, main], c_main, dt, q_y, q_i, r)
    Nu_q, Nx_q, Nu_r, Nx_r = steady_targets(A, B[:, main], bq, c_main)
    nz = n + 1 + n_p
    Az = np.eye(nz)
    Az[:n, :n], Az[:n, n] = A, bq
    Cz = np.hstack([C, np.zeros((n_y, 1)), E])
    W = np.diag(np.r_[np.full(n, W_REL**2), heat_walk**2 * dt, np.full(n_p, P_REL**2)])
    M = kalman_gain(Az, Cz, W, np.diag(vy))
    Aa = np.block([[A, np.zeros((n, 1))], [-dt * c_main[None, :], np.ones((1, 1))]])
    Ba = np.vstack([B[:, main], np.zeros((1, len(main)))])
    return {
        "A": Az,
        "B": np.vstack([B, np.zeros((1 + n_p, B.shape[1]))]),
        "C": Cz,
        "M": M,
        "Kx": Kx,
        "Kz": Kz,
        "Kq": Nu_q + Kx @ Nx_q,
        "Kr": Nu_r + Kx @ Nx_r,
        "bq": bq,
        "tau": tau,
        "rho_cl": float(np.abs(np.linalg.eigvals(Aa - Ba @ np.hstack([Kx, Kz[:, None]]))).max()),
        "rho_est": float(np.abs(np.linalg.eigvals(Az - M @ Cz @ Az)).max()),
    }


class LQI:
    """Gain-scheduled LQI with an offset-free steady-state Kalman filter (see module
    docstring).

    Args:
        env: The env (or vector env) the policy will act on.
        du_max: Bryson's largest wanted valve move (fraction of the stroke); R = 1/du_max^2.
        e_max_K: Bryson's largest wanted main-steam error (K): the output weight 1/e_max^2.
        ti_factor: The integrated error is weighted 1/(e_max_K ti_factor tau)^2, tau the
            63 % time of the main steam's response to the MAIN valves at that load.
        heat_walk: Random-walk intensity of the estimator's heat-absorption bias state
            (fraction of the rated heat absorption per sqrt(s)).

    Raises:
        ValueError: A knob that is not a positive finite number.
    """

    KNOBS = KNOBS
    knob_defaults = staticmethod(start)

    def __init__(
        self,
        env: Any,
        du_max: float | None = None,
        e_max_K: float | None = None,
        ti_factor: float | None = None,
        heat_walk: float | None = None,
    ) -> None:
        u = env.unwrapped
        plant = u.plant
        given = (du_max, e_max_K, ti_factor, heat_walk)
        self.knobs = {
            k.name: k.check(v, d) for k, v, d in zip(KNOBS, given, defaults(plant.id), strict=True)
        }
        params = json.dumps(getattr(u, "params_overrides", {}) or {}, sort_keys=True)
        self.d = design(plant.id, params, tuple(self.knobs.values()))
        names, self._scale, self._center = observation_layout(env)
        self.n_y = sum(s.observed for s in plant.outputs)
        self.n_x = self.d["n"]
        self.i_err = names.index("error_K")
        self.i_load = names.index("load_demand")
        self.i_valve = [names.index(v) for v in plant.valves]
        self.main = self.d["main"]
        self.other = [j for j in range(plant.n_u) if j not in self.main]
        self.pi = CascadePI(env) if self.other else None
        self.dt = plant.dt_s
        rates = plant.rate_limits
        self.max_move = np.array([rates[j] * self.dt for j in self.main])
        g = self.d["grid"]
        self._A = np.stack([m["A"] for m in g])
        self._B = np.stack([m["B"] for m in g])
        self._C = np.stack([m["C"] for m in g])
        self._M = np.stack([m["M"] for m in g])
        self._Kx = np.stack([m["Kx"] for m in g])
        self._Kz = np.stack([m["Kz"] for m in g])
        self._Kq = np.stack([m["Kq"] for m in g])
        self._Kr = np.stack([m["Kr"] for m in g])
        self.i_meas = [s.name for s in plant.outputs if s.observed].index(plant.outlet_measured)
        self.limited = np.zeros((1, len(self.main)), dtype=bool)
        self._st: dict[str, np.ndarray] | None = None

    def reset(self) -> None:
        self._st = None
        if self.pi is not None:
            self.pi.reset()

    def _weights(self, L: np.ndarray) -> np.ndarray:
        """(n, 3) interpolation weights of the grid models at loads L (held outside)."""
        return interp_rows(L, np.array(GRID_LOADS), np.eye(len(GRID_LOADS)))

    def _op(self, L: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        d = self.d
        xp = d["op_loads"]
        return (
            interp_rows(L, xp, d["x_op"]),
            interp_rows(L, xp, d["u_op"]),
            interp_rows(L, xp, d["y_op"]),
        )

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        obs = np.atleast_2d(np.asarray(observation, dtype=np.float64))
        y = obs * self._scale + self._center
        n = obs.shape[0]
        L = y[:, self.i_load]
        valve = y[:, self.i_valve]
        x_op, u_op, y_op = self._op(L)
        st = self._st
        fresh = st is None or st["xh"].shape[0] != n
        if fresh:
            st = self._st = {
                "xh": np.zeros((n, self._A.shape[1])),
                "z": np.zeros(n),
                "xop": x_op.copy(),
                "ub": np.zeros_like(valve),
                "yb": np.zeros((n, self.n_y)),
                "rb": np.zeros(n),
                "u": valve.copy(),
            }
        restart = restart_rows(fresh, n, episode_start)
        if restart.any():
            st["xh"][restart], st["z"][restart] = 0.0, 0.0
            st["xop"][restart] = x_op[restart]
            st["ub"][restart] = valve[restart] - u_op[restart]
            st["yb"][restart] = y[restart, : self.n_y] - y_op[restart]
            st["u"][restart] = valve[restart]
            st["rb"][restart] = y[restart, self.i_err]
        w = self._weights(L)
        xh = st["xh"].copy()
        xh[:, : self.n_x] -= x_op - st["xop"]  # the operating point moved with the load
        st["xop"] = x_op
        dy = (y[:, : self.n_y] - y_op - st["yb"]) / self.d["sy"]
        innov = dy[:, None, :] - np.einsum("gpn,bn->bgp", self._C, xh)
        xf = xh + np.einsum("bg,gnp,bgp->bn", w, self._M, innov)
        z = st["z"]
        Kx = np.einsum("bg,gmn->bmn", w, self._Kx)
        Kz = w @ self._Kz  # (n, m)
        e = y[:, self.i_err]
        # setpoint change since the start (its offset at the start is held with the biases)
        dr = e - st["rb"] + dy[:, self.i_meas] * self.d["sy"][self.i_meas]
        du = (
            -np.einsum("bmn,bn->bm", Kx, xf[:, : self.n_x])
            - Kz * z[:, None]
            + (w @ self._Kq) * xf[:, self.n_x, None]
            + (w @ self._Kr) * dr[:, None]
        )
        m = self.main
        u_prev = st["u"][:, m]
        demand = u_op[:, m] + st["ub"][:, m] + du
        u_main = np.clip(np.clip(demand, u_prev - self.max_move, u_prev + self.max_move), 0.0, 1.0)
        self.limited = u_main != demand  # the actuator limits (eq. 32) hold the command back
        push = -Kz * e[:, None]  # direction integration would move the valves
        held = into_stop(u_main, push)
        st["z"] = z + np.where(held.any(axis=1) | restart, 0.0, self.dt * e)
        u_all = valve.copy()
        u_all[:, m] = u_main
        if self.pi is not None:
            a_pi, _ = self.pi.predict(obs, episode_start=restart)
            u_all[:, self.other] = 0.5 * (np.atleast_2d(a_pi)[:, self.other] + 1.0)
        st["u"] = u_all
        du_all = u_all - u_op - st["ub"]
        st["xh"] = np.einsum(
            "bg,bgn->bn",
            w,
            np.einsum("gnk,bk->bgn", self._A, xf) + np.einsum("gnk,bk->bgn", self._B, du_all),
        )
        action = (2.0 * u_all - 1.0).astype(np.float32)
        return (action[0] if np.ndim(observation) == 1 else action), None
