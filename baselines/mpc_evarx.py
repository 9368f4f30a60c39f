"""Model predictive control on the EV-ARX model (``mpc_evarx``) and on interpolated linear
ARX models (``mpc_arx``).

Source: Toyoda and Wada 1999 (docs/references.md), section 7.2 (eq. 21-23, Fig. 9: the
MPC beats the conventional PI under ramped load). The model is baselines/evarx.py, its
identification baselines/evarx_identification.py, the QP baselines/mpc_evarx_qp.py.

Structure. As in the paper, the controlled process is the boiler-turbine with its existing
controllers running (section 6: the model of Fig. 5 contains them, the identification of
section 7.1 excites it by bias signals on their commands). Here the existing controllers
are ``cascade_pi`` (every loop of ``plant.control_loops``, first stages included) and the
MPC moves one bias per actuator, added to the loop's command: u = clip(v_PI + b, 0, 1).
With b = 0 the policy is exactly cascade_pi, which is also the safety fallback.

Control (eq. 21-23). Every model interval Ts (about 20 s, evarx.TS_TARGET_S) the model
is frozen at the measured load (theta(w_k): eq. 23's A(w_k), B1(w_k), B2(w_k), the
linearization of the EV-ARX at the current load, on a 1 % load grid) and run in velocity
form (an unmeasured constant disturbance is carried as in GPC's CARIMA model). Its state
is the shift register of past outputs, biases and load changes, all measured, so no
observer is needed (eq. 23's observable canonical form realizes the same input-output
map). The measured load change Delta w enters as a known input, assumed to continue for
``DW_HOLD_S`` then stop (no preview of the schedule). Predictions cover ``HORIZON_S`` =
900 s. The condensed QP (decision variables: bias moves at ``MOVE_STEPS`` model
intervals, one slack per output; baselines/mpc_evarx_qp.py):

    min sum_k sum_j q_j (r_j - y_j(k))^2 + sum_m R_m ||db_m||^2 + sum_k,m R_abs,m b_m(k)^2
        + RHO_SLACK ||s||^2 + RHO_SLACK_L 1^T s
    s.t. max(-b_max, -v_PI) <= b(k) <= min(b_max, 1 - v_PI)   (eq. 21's |u| <= u_max,
                                                              valve openings in [0, 1])
         |db| <= min(move_limit, rate x Ts)                   (move limit, actuator rate)
         |y(k) - r| <= y_max_K + s, s >= 0 (every 5th point)  (eq. 21's |y| <= y_max, soft)

The bias term is eq. (22)'s J = sum u^T R u (R_abs); the output bound is eq. (21)'s,
softened (exact penalty) so the QP is always feasible. The tracking and move terms are
ours: eq. (22) alone does not act while the outputs are inside the bound, and without a
move term the biases chatter. Weights per K^2 of tracking error, q = (1,
``secondary_weight``, ...) (main steam first); R_m = ``move_weight`` N g_m^2 and R_abs,m
= ``bias_weight`` g_m^2, g_m the largest step-response magnitude of actuator m over the
horizon (the weights in units of the actuator's own effect). References: the observed
setpoint for the main steam, the value at the episode start for the other outputs (as
cascade_pi).

Knobs (``KNOBS``, constructor keywords; ``DEFAULTS``): ``move_weight``, ``bias_weight``,
``secondary_weight``, ``y_max_K``, ``move_limit`` (stroke per model interval), ``b_max``
(stroke). The paper gives the form of eq. (21)-(22) and no values: every default is ours,
chosen so that the valve travel stays within twice ``cascade_pi_ff``'s on the named ramp.

Solver: OSQP (Stellato et al. 2020), one solver per row: baselines/mpc_evarx_qp.py.
``policy.stats``: solves, iterations and solve times per solve, fallbacks by reason.

Safety layer (fallbacks, counted in ``policy.stats['fallbacks']``): the bias is taken back
towards zero by at most the move limit per interval (no jump of the valves) and the loops
act alone once it is zero, while

- ``sign``: the model frozen at the current load fails the monitor's sign check: the first
  lobe of its step response (evarx.first_lobe) has another sign than the closed loop's on
  a channel the step tests of the real closed loop at 50/75/100 % fix (``expected_signs``:
  the same sign at every load, at least ``SIGN_SIGNIFICANT`` of the output's largest
  lobe; on BoilerTurbineMIMO SP2 -> STE negative, RGD -> STE and RGD -> RTE positive). The
  closed loop's steady gains are zero (the loops integrate every bias out), so the first
  lobe is the signed gain the physics fixes;
- ``model``: the last one-interval prediction of an output missed by more than
  ``MONITOR_SIGMA`` times the model's one-interval RMS error on the validation ramp;
- ``band``: the main-steam error exceeds ``SAFE_FRACTION`` of the plant's upper trip band;
- ``qp``: the QP is not ``solved``.

Generalization: every plant, every actuator (a bias on each loop's command); outputs are
the measured main steam and every outer signal of ``control_loops``. The paper solves the
nonlinear problem by SQP; this is the linearized form (no SQP refinement). Measured
numbers and the claims' status: docs/baselines/mpc_evarx.md.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np

from baselines import tuning
from baselines.cascade_pi import CascadePI
from baselines.evarx import N_W, N_Y, Model, advance, first_lobe, split, step_responses
from baselines.evarx_identification import closed_loop_steps, controlled_outputs, identify
from baselines.loops import observation_layout, restart_rows
from baselines.mpc_evarx_qp import DEFAULTS, BiasQP
from baselines.tuning import Knob

HORIZON_S = 900.0
DW_HOLD_S = 300.0
MONITOR_SIGMA = 6.0
SAFE_FRACTION = 0.5
#: the first lobes of the closed-loop step tests whose sign the model monitor checks: the
#: same sign at every test load and at least this fraction of the output's largest lobe
SIGN_SIGNIFICANT = 0.25
#: Actuator rate (stroke/s) where a plant declares none.
DEFAULT_RATE_PER_S = 0.1
LOAD_GRID = np.round(np.arange(0.3, 1.201, 0.01), 2)


# -- prediction in velocity form ---------------------------------------------------------
def free_response(
    abc: tuple[np.ndarray, ...],
    dy: np.ndarray,
    du: np.ndarray,
    ddw: np.ndarray,
    du_now: np.ndarray,
    dw_now: float,
    n_hold: int,
    N: int,
) -> np.ndarray:
    """(N, n_out) output changes with the inputs held after the step ``du_now`` and Delta w
    held ``n_hold`` intervals, then zero.

    dy (N_Y, n_out) and du (n_b - 1, n_act) past differences, ddw (N_W,) the differences of
    Delta w from t back, newest first.
    """
    a, b, c = abc
    # each history in a buffer, newest first from row N - k at step k: the rows above it
    # take what the steps to come add (the output changes computed, zero bias moves, the
    # load step's end), so that no step copies a history
    n_y, n_u, n_w = len(dy), 1 + len(du), len(ddw)
    Y = np.zeros((N + n_y, dy.shape[1]))
    Y[N:] = dy
    U = np.zeros((N + n_u, du.shape[1]))
    U[N], U[N + 1 :] = du_now, du
    W = np.zeros(N + n_w)
    W[N:] = ddw
    if 1 <= n_hold <= N:  # Delta w ends after n_hold intervals
        W[N - n_hold] = -dw_now
    out, y = np.zeros((N, a.shape[0])), np.zeros(a.shape[0])
    for k in range(N):
        i = N - k
        d = advance(a, b, c, Y[i : i + n_y], U[i : i + n_u], W[i : i + n_w])
        y = y + d
        out[k] = y
        Y[i - 1] = d
    return out


def expected_signs(G: np.ndarray) -> np.ndarray:
    """(n_out, n_act) sign the model's first lobes must have (0: not checked) from the
    closed-loop step tests G (loads, N, n_out, n_act): the sign where every load agrees and
    the lobe is at least SIGN_SIGNIFICANT of the output's largest."""
    lobes = np.stack([first_lobe(g) for g in G])  # (loads, n_out, n_act)
    sig = np.abs(lobes).mean(0)
    ok = (np.abs(np.sign(lobes).sum(0)) == len(G)) & (
        sig >= SIGN_SIGNIFICANT * sig.max(1, keepdims=True)
    )
    return np.where(ok, np.sign(lobes[0]), 0.0)


# -- the controller ----------------------------------------------------------------------
class MPCEVARX:
    """Bias MPC over cascade_pi on the EV-ARX model (see module docstring).

    Args:
        env: The env (or vector env) the policy acts on.
        model: ``"evarx"`` (the paper's) or ``"arx"`` (linear ARX models interpolated by load).
        move_weight, bias_weight, secondary_weight, y_max_K, move_limit, b_max: the knobs
            (``KNOBS``; None = ``DEFAULTS``, all chosen: the paper gives eq. 21-22's form,
            no values).
    """

    model_kind = "evarx"

    @staticmethod
    def knob_defaults(env_id: str) -> dict[str, float]:
        """The common tuning's start: the chosen :data:`DEFAULTS`."""
        return dict(DEFAULTS)

    KNOBS: tuple[Knob, ...] = (
        Knob("move_weight", 1e-3, 10.0),
        Knob("bias_weight", 1e-3, 10.0),
        Knob("secondary_weight", 0.1, 10.0),
        Knob("y_max_K", 1.0, 20.0),
        Knob("move_limit", 0.002, 0.1),
        Knob("b_max", 0.02, 0.3),
    )

    def __init__(
        self,
        env: Any,
        model: str | None = None,
        *,
        move_weight: float | None = None,
        bias_weight: float | None = None,
        secondary_weight: float | None = None,
        y_max_K: float | None = None,
        move_limit: float | None = None,
        b_max: float | None = None,
    ) -> None:
        kind = model or self.model_kind
        if kind not in ("evarx", "arx"):
            raise ValueError(f"unknown model {kind!r}; valid: ['evarx', 'arx']")
        given = {
            "move_weight": move_weight,
            "bias_weight": bias_weight,
            "secondary_weight": secondary_weight,
            "y_max_K": y_max_K,
            "move_limit": move_limit,
            "b_max": b_max,
        }
        u = env.unwrapped
        plant = u.plant
        # the paper gives no weights: the benchmark's common tuning is the default
        base = tuning.stored_or(f"mpc_{kind}", plant.id, DEFAULTS)
        self.knobs = {k.name: k.check(given[k.name], base[k.name]) for k in self.KNOBS}
        params = json.dumps(getattr(u, "params_overrides", {}) or {}, sort_keys=True)
        ident = identify(plant.id, params)
        self.model: Model = ident[kind]
        self.fit_pct = ident["fit_pct"][kind]
        self.monitor_K = MONITOR_SIGMA * ident["rms_1step"][kind]
        #: signs the model's first lobes must have (0: not checked), from closed-loop steps
        self.expected_signs = expected_signs(closed_loop_steps(plant.id, params))
        names, self._scale, self._center = observation_layout(env)
        self.i_y = [names.index(o) for o in controlled_outputs(plant)]
        self.i_sp = names.index("setpoint_C")
        self.i_load = names.index("load_demand")
        self.n = self.model.n
        self.Ts = self.n * plant.dt_s
        self.N = int(round(HORIZON_S / self.Ts))
        self.n_hold = int(round(DW_HOLD_S / self.Ts))
        self.e_safe_K = SAFE_FRACTION * plant.trip_band_K[1]
        rates = np.array(plant.rate_limits)
        rates[np.isinf(rates)] = DEFAULT_RATE_PER_S
        self.move_max = np.minimum(rates * self.Ts, self.knobs["move_limit"])
        self.qp = BiasQP(len(self.i_y), plant.n_u, self.N, self.move_max, self.knobs)
        self.cpi = CascadePI(env)
        self.n_b = split(self.model.coef(1.0), self.model.n_out, self.model.n_act)[1].shape[1]
        self._hist = max(N_Y, self.n_b, N_W + 1) * self.n + 1
        self._frozen_cache: dict[int, tuple] = {}
        self.stats: dict[str, Any] = {
            "solves": 0,
            "iterations": [],
            "solve_time_s": [],
            "fallbacks": {"qp": 0, "model": 0, "sign": 0, "band": 0},
        }
        self._st: dict[str, Any] | None = None

    def reset(self) -> None:
        self._st = None
        self.cpi.reset()

    def _frozen(self, w: float) -> tuple[tuple[np.ndarray, ...], dict[str, np.ndarray], bool]:
        """(a, b, c), the QP matrices of the model frozen at the grid load nearest w, and
        whether its first lobes have the expected signs (the monitor's sign check)."""
        g = int(np.argmin(np.abs(LOAD_GRID - w)))
        if g not in self._frozen_cache:
            m = self.model
            abc = split(m.coef(float(LOAD_GRID[g])), m.n_out, m.n_act)
            G = step_responses(abc[0], abc[1], self.N)
            sign_ok = self.signs_ok(G)
            self._frozen_cache[g] = (abc, self.qp.matrices(G), sign_ok)
        return self._frozen_cache[g]

    def signs_ok(self, G: np.ndarray) -> bool:
        """Whether step responses G (N, n_out, n_act) have first lobes of the expected signs."""
        e = self.expected_signs
        return bool(np.all((e == 0) | (np.sign(first_lobe(G)) == e)))

    def _new_state(self, nb: int) -> dict[str, Any]:
        no, na, H = len(self.i_y), self.qp.n_act, self._hist
        return {
            "Y": np.zeros((nb, H, no)),
            "U": np.zeros((nb, H, na)),
            "W": np.zeros((nb, H)),
            "ref": np.zeros((nb, no)),
            "b": np.zeros((nb, na)),
            "k": np.zeros(nb, int),
            "yhat": np.full((nb, no), np.nan),
            "warm": [None] * nb,
        }

    def _restart(self, st: dict[str, Any], rows: np.ndarray, y: np.ndarray) -> None:
        for r in np.flatnonzero(rows):
            st["Y"][r], st["W"][r], st["U"][r] = y[r, self.i_y], y[r, self.i_load], 0.0
            st["ref"][r], st["b"][r], st["k"][r] = y[r, self.i_y], 0.0, 0
            st["yhat"][r] = np.nan
            st["warm"][r] = (np.zeros(self.qp.nz), np.zeros(self.qp.nc))
            self.qp.restart(int(r))

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        obs = np.atleast_2d(np.asarray(observation, dtype=np.float64))
        y = obs * self._scale + self._center
        nb = obs.shape[0]
        fresh = self._st is None or self._st["Y"].shape[0] != nb
        if fresh:
            self._st = self._new_state(nb)
        st = self._st
        restart = restart_rows(fresh, nb, episode_start)
        if restart.any():
            self._restart(st, restart, y)
        a_pi, _ = self.cpi.predict(obs, episode_start=restart)
        v_pi = (np.asarray(a_pi, dtype=np.float64).reshape(nb, -1) + 1.0) / 2.0
        st["Y"][:, :-1], st["Y"][:, -1] = st["Y"][:, 1:], y[:, self.i_y]
        st["W"][:, :-1], st["W"][:, -1] = st["W"][:, 1:], y[:, self.i_load]
        for r in np.flatnonzero(st["k"] % self.n == 0):
            self._solve_row(st, r, y[r], v_pi[r])
        st["k"] += 1
        st["U"][:, :-1], st["U"][:, -1] = st["U"][:, 1:], st["b"]
        u = np.clip(v_pi + st["b"], 0.0, 1.0)
        action = (2.0 * u - 1.0).astype(np.float32)
        return (action[0] if np.ndim(observation) == 1 else action), None

    def _solve_row(self, st: dict[str, Any], r: int, yr: np.ndarray, v_pi: np.ndarray) -> None:
        """Choose the bias of row r for the next model interval (QP or fallback)."""
        n = self.n
        Y, U, W = st["Y"][r], st["U"][r], st["W"][r]  # newest last; U up to t - 1
        abc, mats, sign_ok = self._frozen(W[-1])
        idx = -1 - n * np.arange(max(N_Y, N_W) + 2)
        yl, wl = Y[idx], W[idx]  # y(t), y(t - n), ...
        dwl = wl[:-1] - wl[1:]  # Delta w(t), Delta w(t - n), ...
        ub = np.stack(
            [U[len(U) - (lag + 1) * n : len(U) - lag * n].mean(0) for lag in range(self.n_b)]
        )  # block means of the past biases
        b_max = self.knobs["b_max"]
        lo_b = np.maximum(-b_max, -v_pi)
        hi_b = np.minimum(b_max, 1.0 - v_pi)
        b_last = np.clip(st["b"][r], lo_b, hi_b)
        yf = Y[-1] + free_response(
            abc,
            (yl[:-1] - yl[1:])[:N_Y],
            (ub[:-1] - ub[1:])[: self.n_b - 1],
            (dwl[:-1] - dwl[1:])[:N_W],
            b_last - ub[0],
            dwl[0],
            self.n_hold,
            self.N,
        )
        ref = st["ref"][r].copy()
        ref[0] = yr[self.i_sp]
        reason = None
        if not sign_ok:
            reason = "sign"
        elif np.any(np.abs(Y[-1] - st["yhat"][r]) > self.monitor_K):  # nan: no prediction yet
            reason = "model"
        elif abs(yr[self.i_sp] - Y[-1, 0]) > self.e_safe_K:
            reason = "band"
        else:
            ok, moves, warm, info = self.qp.solve(
                mats, ref - yf, b_last, lo_b, hi_b, st["warm"][r], row=r
            )
            self.stats["solves"] += 1
            self.stats["iterations"].append(int(info.iter))
            self.stats["solve_time_s"].append(float(info.solve_time))
            if ok:
                st["warm"][r] = warm
            else:
                reason = "qp"
        if reason:  # back to the plain loops, the bias removed at the move limit
            self.stats["fallbacks"][reason] += 1
            b_new = b_last - np.clip(b_last, -self.move_max, self.move_max)
        else:
            b_new = np.clip(b_last + np.clip(moves[0], -self.move_max, self.move_max), lo_b, hi_b)
        # the model's prediction of y one interval ahead under b_new, for the monitor
        st["yhat"][r] = yf[0] + mats["S"][: self.model.n_out, : self.qp.n_act] @ (b_new - b_last)
        st["b"][r] = b_new


class MPCARX(MPCEVARX):
    """The same MPC on linear ARX models identified at fixed loads, interpolated by load."""

    model_kind = "arx"
