"""Offset-free linear MPC on the plant's own linearized physics (``mpc_linear``).

Sources: offset-free estimation and target calculation as in Pannocchia and Rawlings 2003
and Muske and Badgwell 2002 (docs/references.md): the model is augmented with integrating
disturbance states, as many as measured outputs, estimated by a Kalman filter; a steady
target is computed from the estimated disturbances and the regulator tracks it, so a
constant disturbance leaves no offset. The QP is solved by OSQP (Stellato et al. 2020),
the model reduced by square-root balanced truncation (Moore 1981; Laub et al. 1987).

Model. ``Plant.linearize`` and ``Plant.linearize_disturbances`` (the plant's own compiled
step, finite differences) at ``GRID_LOADS`` = 40, 60, 80, 100 % load: commands, the load
demand, its rate (the plants' boiler feed-forwards use it) and the heat-absorption bias
as inputs; the observed signals and the scored temperatures (``plant.outlet`` and the
``secondary`` ones, e.g. the MIMO reheat) as outputs. States no input reaches are dropped
(the plant-internal random generators of Cascade300MW); those of them that act on the rest
and are read directly by an observed signal (Cascade300MW's omega and omega_2) are
measured disturbances, known inputs over the coming interval. The states are scaled by
their peak response to steps of every input of its typical size, then balanced and
truncated (Hankel singular values below ``HSV_TOL`` of the largest) on the summed
Gramians of the four models, so the reduced models share one basis (16, 25, 27, 21 and 7
states for FSH, Benson, MIMO, Drum and Cascade; step responses within 0.2 % of the full
models). The local model at load L is the linear interpolation of the neighbouring grid
models at L rounded to ``LOAD_QUANTUM`` (held outside the grid), its QP matrices built
once per rounded load; the operating point (steady state, valve openings and outputs of
the undisturbed plant on ``OP_LOADS``) is interpolated at the exact load. The model works
in deviations from the operating point at the current load; when the load moves, the
state estimate is shifted by the change of the operating point.

Estimation. Augmented state [xi; q; p]: the reduced plant state xi, the heat-absorption
bias q (an input disturbance entering where the plant's own bias enters, a random walk
with the increments of an OU process of HEAT_STD and HEAT_TAU_S) and a random-walk output
disturbance p on every observed signal but the main-steam thermocouple (n_d = n_y; the
augmented model is detectable since q moves the main steam at steady state). Known
inputs: the applied commands, the load rate (differences of the observed load demand) and
the measured disturbances. Steady-state Kalman gain (filtered form, DARE) per grid model;
measurement noise NOISE_K on the thermocouples, V_REL of the scale on the other signals.
Bumpless start: at an episode start the plant is taken as steady and (xi, q, p) solved
from the first observation and valve openings.

Prediction and target. Over a horizon of HORIZON_T63 times the slowest 63 % time of an
actuator's effect on a scored temperature (clipped to [HORIZON_MIN_S, HORIZON_MAX_S]),
read at N_POINTS points; the measured load rate is assumed to continue RATE_HOLD_S (inside
[lowest op load, rated load]), then the load holds. Target: the steady commands that hold
every scored temperature at its setpoint with the estimated disturbances at the end of
that load path, the least change from the scheduled openings weighted by each actuator's
steady effect (on Benson and MIMO, with more actuators than scored temperatures, the
steady split between the sprays is that of the schedules).

QP (condensed; decision variables: command moves at ``MOVE_T63`` fractions of the 63 %
time, one slack per scored temperature)::

    min sum_j |y_j - r|^2 + sum_i R |du_i|^2 + sum_j S |u_j - u_s|^2 + RHO_SLACK |s|^2
        + RHO_SLACK_L 1's
    s.t. 0 <= u_i <= 1 (valve openings), |du_i| <= rate x interval (the plant's actuator
         rate limits, read from its params; none where the plant has no valve dynamics),
         |y_j - r| <= BAND_K + s at every SOFT_EVERY-th point, s >= 0 (soft bounds)

with weights per K^2 of every scored temperature (the reward weights them alike), R =
MOVE_WEIGHT N_POINTS g^2 and S = U_WEIGHT g^2, g the actuator's steady effect (K per
stroke) at that load. MOVE_WEIGHT is the move suppression, per plant (``MOVE_WEIGHTS``):
the smallest of ``MOVE_WEIGHT_LADDER`` = 0.01, 0.003, 0.001 whose valve travel stays
within ``TRAVEL_RATIO_MAX`` = 2 times that of ``cascade_pi_ff`` on two
commissioning tests (a -5 % heat-absorption step and cascade_pi's feed-forward ramp, both
with the named scenarios' noise; not evaluation scenarios; benchmarks/mpc_linear_tuning.py
measures them: 0.003 on the FSH and the drum unit, whose travel at 0.001 is 2.1-2.2 times
the reference's on the heat step, 0.001 on the others, at 0.5-1.3 times).

OSQP, one solver per row (set up at its episode start, so a row acts the same alone or in
a batch and a reset forgets everything), warm-started from the row's last solution and
started from the same rho each solve (adaptive rho on a fixed iteration count), matrices
updated only when the rounded load changes. The first move is applied (rate-limited and
clipped); a solve that does not succeed within 400 iterations holds the valves
(``stats["failures"]``). A call
whose estimate comes out non-finite (a non-finite observation) raises ValueError and
leaves the policy's state as it was.

Measured (docs/baselines.md: seeds 0-4, every plant, the six named and six held-out
scenarios, against ``cascade_pi_ff``): a better return in all 60 plant x scenario cells
(summed over the 12 scenarios: FSH -573 vs -1203, Benson -135 vs -324, MIMO -1618 vs
-3959, Drum -537 vs -1314, Cascade -3287 vs -3602), no trip, the quiet-stretch
peak-to-peak within max(2x, 1.5 K) everywhere; valve travel within 2x in 59 cells, 2.09x
on the MIMO heat_imbalance_step (the damper at its stop, the sprays dithering at theirs).
Offset after a constant +5 % heat-absorption step (tests/test_mpc_linear.py): <= 5e-4 K on
every plant, 1-5 K with ``disturbance_model=False``.
"""

from __future__ import annotations

import functools
import json
from typing import Any

import numpy as np
import scipy.sparse as sp

from baselines import tuning
from baselines.linear_models import balanced_basis, kalman_gain, reachable, steady_point
from baselines.loops import observation_layout, restart_rows
from baselines.tuning import Knob
from steamtemp_gym import plants

#: Loads of the local models (fraction of rated) and of the steady operating-point tables.
GRID_LOADS = (0.4, 0.6, 0.8, 1.0)
OP_LOADS = tuple(np.round(np.arange(0.3, 1.101, 0.05), 2))
#: The local model and its QP are those of the load rounded to this (fraction of rated).
LOAD_QUANTUM = 0.01
#: Disturbance channels of the model: two known inputs (load, its rate), one estimated.
CHANNELS = ("load", "load_rate_per_s", "heat_absorption_bias")
#: Typical sizes of the inputs (valve stroke, load, load rate 1/s, heat-absorption bias):
#: the input weights of the balanced truncation and of the state process noise.
SIZE_U, SIZE_LOAD, SIZE_RATE, SIZE_HEAT = 0.1, 0.1, 1e-3, 0.02
HSV_TOL, MAX_ORDER = 1e-4, 40
#: Kalman filter: thermocouple noise (K; the named scenarios' noise_std_C) and the other
#: signals' (fraction of their scale); the heat-absorption bias a random walk with the
#: increments of an OU process of std HEAT_STD and correlation time HEAT_TAU_S (the named
#: scenarios' coloured disturbance); output disturbances drifting P_REL of their scale per
#: step; state process noise W_REL times the inputs' typical sizes.
NOISE_K, V_REL = 0.25, 0.002
HEAT_STD, HEAT_TAU_S = 0.02, 300.0
P_REL = 0.002
W_REL = 0.1
#: Horizon: multiples of the slowest 63 % time, clipped (s); points; move instants.
HORIZON_T63, HORIZON_MIN_S, HORIZON_MAX_S = 4.0, 300.0, 1800.0
N_POINTS = 40
MOVE_T63 = (0.0, 0.1, 0.25, 0.5, 1.0, 2.0)
#: The measured load rate is assumed to continue this long (s), then the load holds.
RATE_HOLD_S = 300.0
#: Move suppression per plant (module docstring: the commissioning rule; benchmarks/
#: mpc_linear_tuning.py measures it) and the weight of the steady target.
MOVE_WEIGHTS = {
    "steamtemp/SupercriticalFSH-v0": 0.003,
    "steamtemp/BensonSubcritical-v0": 0.001,
    "steamtemp/BoilerTurbineMIMO-v0": 0.001,
    "steamtemp/DrumBoilerSH-v0": 0.003,
    "steamtemp/Cascade300MW-v0": 0.001,
}
#: The candidates of the rule, largest first, and the travel bound it keeps (x cascade_pi_ff).
MOVE_WEIGHT_LADDER = (0.01, 0.003, 0.001)
TRAVEL_RATIO_MAX = 2.0
U_WEIGHT = 0.01
#: Soft output bounds |y - r| <= BAND_K + s (the reward's inner band), their costs.
BAND_K = 5.0
RHO_SLACK, RHO_SLACK_L = 1e2, 1e1
SOFT_EVERY = 4
OSQP_SETTINGS = {"verbose": False, "adaptive_rho": True, "adaptive_rho_interval": 25,
                 "rho": 0.1, "eps_abs": 1e-6, "eps_rel": 1e-6, "max_iter": 400,
                 "polishing": False, "warm_starting": True}  # fmt: skip


# -- design --------------------------------------------------------------------------------
def _measured_disturbances(A: np.ndarray, C: np.ndarray, keep: np.ndarray) -> tuple[list, list]:
    """(states, rows): states outside ``keep`` that act on it and are read directly by an
    observed output row (a plant-internal disturbance the plant measures), and the rows."""
    states, rows = [], []
    for i in np.flatnonzero(~keep):
        if not np.any(A[keep, i] != 0.0):
            continue
        for j in range(C.shape[0]):
            if C[j, i] != 0.0 and np.count_nonzero(C[j]) == 1:
                states.append(int(i))
                rows.append(j)
                break
    return states, rows


def _t63(A: np.ndarray, b: np.ndarray, c: np.ndarray, n_steps: int) -> int:
    """Steps to 63 % of the final value of output row c's response to a step of input b."""
    x, ys = np.zeros(A.shape[0]), np.empty(n_steps)
    for k in range(n_steps):
        x = A @ x + b
        ys[k] = c @ x
    ys = np.abs(ys)
    return 1 + int(np.argmax(ys >= 0.632 * ys[-1]))


def _local_models(plant: Any, outs: list[str], n_y: int) -> tuple:
    """Grid models in scaled coordinates of the states the inputs reach, the mask and scale
    of those states and the measured disturbances (states, rows, gains)."""
    raw = []
    for L in GRID_LOADS:
        A, B, C, D = plant.linearize(L, outputs=outs)
        Bd, Dd = plant.linearize_disturbances(L, CHANNELS, outputs=outs)
        if np.any(D[n_y:] != 0.0) or np.any(Dd[n_y:] != 0.0):
            raise ValueError(f"{plant.id}: scored outputs with direct feed-through")
        raw.append((A, np.hstack([B, Bd]), C, D[:n_y], Dd[:n_y]))
    keep = np.zeros(plant.n_x, dtype=bool)
    for A, B, *_ in raw:
        keep |= reachable(A, B)
    md, md_rows = _measured_disturbances(raw[-1][0], raw[-1][2][:n_y], keep)
    md_gain = np.array([raw[-1][2][j, i] for i, j in zip(md, md_rows, strict=True)])
    size_in = np.array([SIZE_U] * plant.n_u + [SIZE_LOAD, SIZE_RATE, SIZE_HEAT])
    A, B = raw[-1][0][np.ix_(keep, keep)], raw[-1][1][keep] @ size_in
    x, peak = np.zeros(A.shape[0]), np.zeros(A.shape[0])
    for _ in range(1500):
        x = A @ x + B
        peak = np.maximum(peak, np.abs(x))
    sx = np.maximum(peak, 1e-9 * peak.max())
    scaled = [(A[np.ix_(keep, keep)] / sx[:, None] * sx[None, :], B[keep] / sx[:, None],
               A[np.ix_(keep, md)] / sx[:, None], C[:, keep] * sx[None, :], D, Dd)
              for A, B, C, D, Dd in raw]  # fmt: skip
    return scaled, keep, sx, size_in, (md_rows, md_gain)


def _pairs(plant: Any, G: np.ndarray, n_y: int, ctrl: list[str]) -> list[int]:
    """Per scored temperature, the observed signal with the same steady response (its
    thermocouple); the main steam's must be the plant's ``outlet_measured``."""
    pair = []
    for c, name in enumerate(ctrl):
        g = G[n_y + c]
        err = np.abs(G[:n_y] - g).max(axis=1) / np.abs(g).max()
        j = int(np.argmin(err))
        if err[j] > 1e-3:
            raise ValueError(f"{plant.id}: no observed signal measures {name}")
        pair.append(j)
    observed = [s.name for s in plant.outputs if s.observed]
    if observed[pair[0]] != plant.outlet_measured:
        raise ValueError(f"{plant.id}: {plant.outlet_measured} does not measure {plant.outlet}")
    return pair


def _responses(Az, Ccz, Ar, Bu, bL, br, Bmd, Cc, Nh) -> tuple[np.ndarray, ...]:  # noqa: ANN001
    """Over 0..Nh steps: free response of the augmented state, step responses of the
    commands and the load, pulse responses of the load rate and the measured disturbances
    (scored outputs)."""
    n_c, n_u, r = Cc.shape[0], Bu.shape[1], Ar.shape[0]
    Phi = np.zeros((Nh + 1, n_c, Az.shape[0]))
    Su, sL, hr = np.zeros((Nh + 1, n_c, n_u)), np.zeros((Nh + 1, n_c)), np.zeros((Nh + 1, n_c))
    Pm = np.zeros((Nh + 1, n_c, Bmd.shape[1]))
    Ak = np.eye(Az.shape[0])
    xu, xl, xr, xm = np.zeros((r, n_u)), np.zeros(r), br.copy(), Bmd.copy()
    for j in range(1, Nh + 1):
        Ak = Az @ Ak
        Phi[j] = Ccz @ Ak
        xu, xl = Ar @ xu + Bu, Ar @ xl + bL
        Su[j], sL[j], hr[j], Pm[j] = Cc @ xu, Cc @ xl, Cc @ xr, Cc @ xm
        xr, xm = Ar @ xr, Ar @ xm
    return Phi, Su, sL, hr, Pm


def _load_path(sL: np.ndarray, hr: np.ndarray, pts: np.ndarray, n_hold: int,
               dt: float) -> np.ndarray:  # fmt: skip
    """(n_hold + 1, points, n_c): the scored outputs' response per unit load rate to a load
    that ramps for n steps, then holds (rate pulses plus the steps of the ramp)."""
    f = np.zeros((n_hold + 1, len(pts), sL.shape[1]))
    for n in range(1, n_hold + 1):
        i_r, i_l = pts - (n - 1), pts - n
        f[n] = (f[n - 1] + np.where((i_r > 0)[:, None], hr[np.maximum(i_r, 0)], 0.0)
                + dt * np.where((i_l > 0)[:, None], sL[np.maximum(i_l, 0)], 0.0))  # fmt: skip
    return f


@functools.lru_cache(maxsize=16)
def design(env_id: str, params_json: str) -> dict[str, Any]:
    """The MPC of a plant (cached): per grid load the reduced augmented model, Kalman gain,
    prediction matrices and steady gains; horizon, points, moves; operating-point tables."""
    plant = plants.make(env_id, **json.loads(params_json))
    observed = [s for s in plant.outputs if s.observed]
    ctrl = [plant.outlet] + [n for n, _ in plant.secondary]
    n_y, n_c, n_u, dt = len(observed), len(ctrl), plant.n_u, plant.dt_s
    scaled, keep, sx, size_in, (md_rows, md_gain) = _local_models(
        plant, [s.name for s in observed] + ctrl, n_y)  # fmt: skip
    scale_y = np.array([s.scale for s in observed] + [1.0] * n_c)
    T, Ti, hsv = balanced_basis([(A, B * size_in, C / scale_y[:, None])
                                 for A, B, _, C, *_ in scaled], HSV_TOL, MAX_ORDER)  # fmt: skip
    r = T.shape[1]
    As, Bs, _, Cs, *_ = scaled[-1]
    pair = _pairs(plant, Cs @ np.linalg.solve(np.eye(len(As)) - As, Bs), n_y, ctrl)
    i_meas = pair[0]
    p_rows = [j for j in range(n_y) if j != i_meas]  # output disturbances
    n_p, n_md = len(p_rows), len(md_rows)
    n_z = r + 1 + n_p
    E = np.zeros((n_y, n_p))
    E[p_rows, np.arange(n_p)] = 1.0
    Ec = np.zeros((n_c, n_p))
    for c, j in enumerate(pair[1:], start=1):
        Ec[c, p_rows.index(j)] = 1.0
    Ar, Br, Cr = Ti @ As @ T, Ti @ Bs, Cs @ T
    t63 = max(_t63(Ar, Br[:, m], Cr[n_y + c], int(HORIZON_MAX_S / dt))
              for m in range(n_u) for c in range(n_c))  # fmt: skip
    Nh = int(np.clip(HORIZON_T63 * t63 * dt, HORIZON_MIN_S, HORIZON_MAX_S) / dt)
    pts = np.unique(np.round(np.linspace(Nh / N_POINTS, Nh, N_POINTS)).astype(int))
    moves = np.unique(np.round(np.array(MOVE_T63) * t63).astype(int))
    moves = moves[moves < Nh]
    n_hold = int(round(RATE_HOLD_S / dt))
    V = np.diag([(NOISE_K if s.noisy else V_REL * s.scale) ** 2 for s in observed])
    W = np.zeros((n_z, n_z))
    W[r, r] = (HEAT_STD * np.sqrt(1.0 - np.exp(-2.0 * dt / HEAT_TAU_S))) ** 2
    W[r + 1:, r + 1:] = np.diag([(P_REL * observed[j].scale) ** 2 for j in p_rows])
    grid = []
    for As, Bs, Bm, Cs, Dm, Dd in scaled:
        Ar, Bu, Bmd = Ti @ As @ T, Ti @ Bs[:, :n_u], Ti @ Bm
        bL, br, bq = (Ti @ Bs[:, n_u + k] for k in range(3))
        Cm = Cs[:n_y] @ T
        Cc = Cm[pair]  # the scored temperatures as their thermocouples read them
        Az = np.eye(n_z)
        Az[:r, :r], Az[:r, r] = Ar, bq
        Bz = np.zeros((n_z, n_u + 1 + n_md))  # known inputs: commands, load rate, measured
        Bz[:r, :n_u], Bz[:r, n_u], Bz[:r, n_u + 1:] = Bu, br, Bmd
        Cmz = np.hstack([Cm, Dd[:, 2:3], E])
        Ccz = np.hstack([Cc, np.zeros((n_c, 1)), Ec])
        Gx = W_REL * np.hstack([Bu * SIZE_U, bL[:, None] * SIZE_LOAD, bq[:, None] * SIZE_HEAT])
        W[:r, :r] = Gx @ Gx.T + 1e-12 * np.eye(r)
        M = kalman_gain(Az, Cmz, W, V)
        Phi, Su, sL, hr, Pm = _responses(Az, Ccz, Ar, Bu, bL, br, Bmd, Cc, Nh)
        Sd = np.zeros((len(pts), n_c, len(moves), n_u))  # the moves' dynamic matrix
        for i, t0 in enumerate(moves):
            Sd[pts > t0, :, i, :] = Su[pts[pts > t0] - t0]
        inv = np.linalg.inv(np.eye(r) - Ar)
        init = np.hstack([(Cm @ inv @ bq + Dd[:, 2])[:, None], E])
        if np.linalg.cond(init) > 1e12:
            raise ValueError(f"{env_id}: the disturbance model is not detectable")
        grid.append({
            "Az": Az, "Bz": Bz, "Cmz": Cmz, "M": M, "Dm": Dm, "DdL": Dd[:, 0], "Ddr": Dd[:, 1],
            "Phi": Phi[pts], "Gam": Su[pts], "Pm": Pm[pts], "f": _load_path(sL, hr, pts,
                                                                             n_hold, dt),
            "Sd": Sd.reshape(len(pts) * n_c, len(moves) * n_u),
            "Gu": Cc @ inv @ Bu, "Gq": Cc @ inv @ bq, "GL": Cc @ inv @ bL,
            "Init": init, "InitU": Cm @ inv @ Bu + Dm, "InitM": Cm @ inv @ Bmd,
            "inv": inv, "Bu": Bu, "bq": bq, "Bmd": Bmd,
        })  # fmt: skip
    ops = [steady_point(plant, L, [s.name for s in observed] + ctrl) for L in OP_LOADS]
    ok = [k for k, (_, _, y) in enumerate(ops) if np.all(np.isfinite(y))]
    rates = np.array(plant.rate_limits)
    return {
        "grid": grid, "r": r, "n_p": n_p, "n_y": n_y, "n_c": n_c, "n_md": n_md,
        "md_rows": md_rows, "md_gain": md_gain, "Ec": Ec, "pts": pts, "moves": moves,
        "Nh": Nh, "n_hold": n_hold, "t63_s": t63 * dt, "hsv": hsv, "rates": rates,
        "op_loads": np.array(OP_LOADS)[ok],
        "op": np.array([np.concatenate([Ti @ (ops[k][0][keep] / sx), ops[k][1], ops[k][2]])
                        for k in ok]),
        "op_cols": np.cumsum([0, r, n_u, n_y, n_c]),
        "secondary_sp": np.array([s for _, s in plant.secondary]),
    }  # fmt: skip


# -- the QP of one row ---------------------------------------------------------------------
class _QP:
    """OSQP on the condensed QP of one row: a dense pattern fixed at setup, values updated."""

    def __init__(self, H: np.ndarray, A: np.ndarray) -> None:
        import osqp

        nz, nc = H.shape[0], A.shape[0]
        self.P_rc = np.nonzero(np.triu(np.ones((nz, nz))).T)[::-1]  # (rows, cols), CSC order
        self.A_rc = np.nonzero(np.ones((nc, nz)).T)[::-1]
        self.solver = osqp.OSQP()
        self.solver.setup(P=sp.csc_matrix((H[self.P_rc], self.P_rc), (nz, nz)),
                          q=np.zeros(nz), A=sp.csc_matrix((A[self.A_rc], self.A_rc), (nc, nz)),
                          l=np.full(nc, -np.inf), u=np.full(nc, np.inf),
                          **OSQP_SETTINGS)  # fmt: skip
        self.key: int | None = None

    def solve(self, key: int, H: np.ndarray, A: np.ndarray, g: np.ndarray, lo: np.ndarray,
              hi: np.ndarray, warm: tuple | None) -> Any:  # fmt: skip
        """Solve with the matrices of local model ``key`` (sent only when the key changes),
        from rho and the given warm start: the result depends on the row's data only."""
        s = self.solver
        if key != self.key:
            s.update(q=g, l=lo, u=hi, Px=H[self.P_rc], Ax=A[self.A_rc])
            self.key = key
        else:
            s.update(q=g, l=lo, u=hi)
        s.update_settings(rho=OSQP_SETTINGS["rho"])
        if warm is not None:
            s.warm_start(x=warm[0], y=warm[1])
        return s.solve(raise_error=False)


# -- the controller ------------------------------------------------------------------------
class MPCLinear:
    """Offset-free linear MPC (see module docstring).

    Args:
        env: The env (or vector env) the policy will act on.
        disturbance_model: Estimate the heat-absorption and output disturbances (the
            offset-free design); False holds them at zero (no offset-free estimation).
        move_weight: Move suppression; u_weight: weight of the steady target (the ``KNOBS``;
            default: the benchmark's stored tuning, baselines/tuned/mpc_linear.json, where
            the plant has one, else the commissioning rule's MOVE_WEIGHTS entry and U_WEIGHT).
    """

    #: Searched by agents.baseline_tuning from the commissioning rule's values.
    KNOBS = (Knob("move_weight", 1e-4, 0.1), Knob("u_weight", 1e-3, 1.0))

    @staticmethod
    def knob_defaults(env_id: str) -> dict[str, float]:
        """The commissioning rule's move suppression and U_WEIGHT."""
        return {"move_weight": MOVE_WEIGHTS.get(env_id, MOVE_WEIGHT_LADDER[1]),
                "u_weight": U_WEIGHT}  # fmt: skip

    def __init__(self, env: Any, disturbance_model: bool = True, move_weight: float | None = None,
                 u_weight: float | None = None) -> None:  # fmt: skip
        u = env.unwrapped
        plant = u.plant
        base = tuning.stored_or("mpc_linear", plant.id, self.knob_defaults(plant.id))
        move_weight = base["move_weight"] if move_weight is None else move_weight
        u_weight = base["u_weight"] if u_weight is None else u_weight
        for name, v in (("move_weight", move_weight), ("u_weight", u_weight)):
            if not (isinstance(v, (int, float)) and np.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be a positive finite number, got {v!r}")
        params = json.dumps(getattr(u, "params_overrides", {}) or {}, sort_keys=True)
        self.d = d = design(plant.id, params)
        self.estimate_disturbances = bool(disturbance_model)
        self._weights = (float(move_weight), float(u_weight))
        names, self._scale, self._center = observation_layout(env)
        self.n_u = n_u = plant.n_u
        self.i_sp = names.index("setpoint_C")
        self.i_load = names.index("load_demand")
        self.i_valve = [names.index(v) for v in plant.valves]
        self.dt = plant.dt_s
        n_pts, n_mv, n_c = len(d["pts"]), len(d["moves"]), d["n_c"]
        nv = n_mv * n_u
        self.soft = np.arange(SOFT_EVERY - 1, n_pts, SOFT_EVERY)
        n_s = len(self.soft) * n_c
        on = (d["pts"][:, None] > d["moves"][None, :]).astype(float)  # move i acts at point j
        self._Cb = np.kron(on, np.eye(n_u))  # commands at the points per move
        # constraint rows: openings at the moves, moves, soft bounds (two sides), slacks
        self._A0 = np.zeros((2 * nv + 2 * n_s + n_c, nv + n_c))
        self._A0[:nv, :nv] = np.kron(np.tril(np.ones((n_mv, n_mv))), np.eye(n_u))
        self._A0[nv:2 * nv, :nv] = np.eye(nv)
        Es = np.tile(np.eye(n_c), (len(self.soft), 1))
        self._A0[2 * nv:2 * nv + n_s, nv:] = -Es
        self._A0[2 * nv + n_s:2 * nv + 2 * n_s, nv:] = Es
        self._A0[2 * nv + 2 * n_s:, nv:] = np.eye(n_c)
        seg = np.diff(np.append(d["moves"], d["Nh"]))
        seg[0] = 1  # the first move happens in one interval, later ones over their block
        self.max_move = np.kron(seg, d["rates"] * self.dt)
        inf = np.full(n_s, np.inf)
        self._lo0 = np.concatenate([np.zeros(nv), -self.max_move, -inf, np.full(n_s, -BAND_K),
                                    np.zeros(n_c)])  # fmt: skip
        self._hi0 = np.concatenate([np.zeros(nv), self.max_move, np.full(n_s, BAND_K), inf,
                                    np.full(n_c, np.inf)])  # fmt: skip
        self._g0 = np.concatenate([np.zeros(nv), np.full(n_c, RHO_SLACK_L)])
        self._local: dict[int, dict[str, Any]] = {}
        self.stats = {"solves": 0, "iterations": 0, "failures": 0}
        self._rows: list[dict[str, Any] | None] | None = None

    def reset(self) -> None:
        self._rows = None

    # -- scheduling ----------------------------------------------------------------------
    def _model(self, L: float) -> tuple[int, dict[str, Any]]:
        """(key, local model): the grid models interpolated at L rounded to LOAD_QUANTUM
        (held outside the grid) and the QP matrices of that model, built once per key."""
        xp = GRID_LOADS
        key = int(round(min(max(L, xp[0]), xp[-1]) / LOAD_QUANTUM))
        m = self._local.get(key)
        if m is not None:
            return key, m
        Lq = key * LOAD_QUANTUM
        i = min(max(int(np.searchsorted(xp, Lq)) - 1, 0), len(xp) - 2)
        a = min(max((Lq - xp[i]) / (xp[i + 1] - xp[i]), 0.0), 1.0)
        g0, g1 = self.d["grid"][i], self.d["grid"][i + 1]
        m = {k: (1.0 - a) * g0[k] + a * g1[k] for k in g0 if k != "f"}
        m["f"] = (g0["f"], g1["f"], a)
        d, Sd = self.d, m["Sd"]
        nv, n_c, n_pts, n_mv = Sd.shape[1], d["n_c"], len(d["pts"]), len(d["moves"])
        gu2 = np.abs(m["Gu"]).max(axis=0) ** 2 + 1e-12  # (K per stroke)^2 at this load
        mw, uw = self._weights
        CbS = 2.0 * self._Cb.T * np.tile(uw * gu2, n_pts)[None, :]
        H = np.zeros((nv + n_c, nv + n_c))
        H[:nv, :nv] = 2.0 * (Sd.T @ Sd + np.diag(np.tile(mw * n_pts * gu2, n_mv))) \
            + CbS @ self._Cb  # fmt: skip
        H[nv:, nv:] = 2.0 * RHO_SLACK * np.eye(n_c)
        n_s = len(self.soft) * n_c
        Ssoft = Sd.reshape(n_pts, n_c, nv)[self.soft].reshape(n_s, nv)
        A = self._A0.copy()
        A[2 * nv:2 * nv + n_s, :nv] = Ssoft
        A[2 * nv + n_s:2 * nv + 2 * n_s, :nv] = Ssoft
        G, Wi = m["Gu"], 1.0 / gu2  # target: least change, weighted by the steady effects
        m.update(H=H, A=A, SdT2=2.0 * Sd.T, CbS=CbS,
                 Gpinv=Wi[:, None] * (G.T @ np.linalg.inv((G * Wi) @ G.T)))  # fmt: skip
        self._local[key] = m
        return key, m

    def _op(self, L: float) -> list[np.ndarray]:
        """[xi_op, u_op, ym_op, yc_op] interpolated at load L (held outside the table)."""
        xp, table, c = self.d["op_loads"], self.d["op"], self.d["op_cols"]
        i = min(max(int(np.searchsorted(xp, L)) - 1, 0), len(xp) - 2)
        a = min(max((L - xp[i]) / (xp[i + 1] - xp[i]), 0.0), 1.0)
        row = (1.0 - a) * table[i] + a * table[i + 1]
        return [row[c[k]:c[k + 1]] for k in range(4)]

    def _md(self, y: np.ndarray, ym_op: np.ndarray) -> np.ndarray:
        """The measured disturbance states' deviations from the operating point."""
        rows = self.d["md_rows"]
        return (y[rows] - ym_op[rows]) / self.d["md_gain"]

    # -- one row ---------------------------------------------------------------------------
    def _start(self, y: np.ndarray, L: float, m: dict[str, Any], op: list) -> dict[str, Any]:
        """Row state at an episode start: the plant taken as steady, its disturbances solved
        from the first observation (bumpless)."""
        _, u_op, ym_op, _ = op
        u0 = np.clip(y[self.i_valve], 0.0, 1.0)
        md = self._md(y, ym_op)
        if self.estimate_disturbances:
            rhs = y[: self.d["n_y"]] - ym_op - m["InitU"] @ (u0 - u_op) - m["InitM"] @ md
            qp = np.linalg.solve(m["Init"], rhs)
        else:
            qp = np.zeros(1 + self.d["n_p"])
        xi = m["inv"] @ (m["Bu"] @ (u0 - u_op) + m["bq"] * qp[0] + m["Bmd"] @ md)
        return {"z": np.concatenate([xi, qp]), "u": u0, "L": L, "op": op, "md": md,
                "warm": None, "qp": None}  # fmt: skip

    def _row(self, st: dict[str, Any] | None, y: np.ndarray) -> dict[str, Any]:
        """The next state of one row (``st`` None: an episode start); ``st`` is not changed."""
        d = self.d
        L = min(max(float(y[self.i_load]), d["op_loads"][0]), d["op_loads"][-1])
        key, m = self._model(L)
        op = self._op(L)
        xi_op, u_op, ym_op, yc_op = op
        r = d["r"]
        if st is None:
            st, rate = self._start(y, L, m, op), 0.0
            z = st["z"]
        else:  # time update over the last interval, the frame moved to this load's op
            rate = (L - st["L"]) / self.dt
            known = np.concatenate([st["u"] - st["op"][1], [rate], st["md"]])
            z = m["Az"] @ st["z"] + m["Bz"] @ known
            z[:r] -= xi_op - st["op"][0]
            feed = m["Dm"] @ (st["u"] - u_op) + m["DdL"] * (st["L"] - L) + m["Ddr"] * rate
            z = z + m["M"] @ (y[: d["n_y"]] - ym_op - feed - m["Cmz"] @ z)
            if not self.estimate_disturbances:
                z[r:] = 0.0
        md = self._md(y, ym_op)
        # the assumed load path: the measured rate for n_eff steps, then held
        n_eff = d["n_hold"]
        if rate > 0.0:
            n_eff = min(n_eff, int(max(1.0 - L, 0.0) / (rate * self.dt)))
        elif rate < 0.0:
            n_eff = min(n_eff, int(max(L - d["op_loads"][0], 0.0) / (-rate * self.dt)))
        dL_end = rate * self.dt * n_eff
        # target: the steady commands holding the references at the end of the load path
        ref = np.concatenate([[y[self.i_sp]], d["secondary_sp"]])
        b = ref - yc_op - m["Gq"] * z[r] - d["Ec"] @ z[r + 1:] - m["GL"] * dL_end
        du_ref = self._op(L + dL_end)[1] - u_op
        du_s = du_ref + m["Gpinv"] @ (b - m["Gu"] @ du_ref)
        # free response and the QP
        u_prev = st["u"]
        f0, f1, a = m["f"]
        free = (yc_op + m["Phi"] @ z + m["Gam"] @ (u_prev - u_op) + m["Pm"] @ md
                + ((1.0 - a) * f0[n_eff] + a * f1[n_eff]) * rate)  # fmt: skip
        e0 = (free - ref).reshape(-1)
        n_pts, n_c, n_mv = len(d["pts"]), d["n_c"], len(d["moves"])
        nv, n_s = n_mv * self.n_u, len(self.soft) * n_c
        g = self._g0.copy()
        g[:nv] = m["SdT2"] @ e0 + m["CbS"] @ np.tile(u_prev - u_op - du_s, n_pts)
        esoft = e0.reshape(n_pts, n_c)[self.soft].reshape(n_s)
        lo, hi = self._lo0.copy(), self._hi0.copy()
        lo[:nv], hi[:nv] = np.tile(-u_prev, n_mv), np.tile(1.0 - u_prev, n_mv)
        lo[2 * nv + n_s:2 * nv + 2 * n_s] -= esoft
        hi[2 * nv:2 * nv + n_s] -= esoft
        qp = st["qp"] or _QP(m["H"], m["A"])
        res = qp.solve(key, m["H"], m["A"], g, lo, hi, st["warm"])
        self.stats["solves"] += 1
        self.stats["iterations"] += int(res.info.iter)
        warm = st["warm"]
        if res.info.status in ("solved", "solved inaccurate") and np.all(np.isfinite(res.x)):
            du0, warm = res.x[: self.n_u], (res.x.copy(), res.y.copy())
        else:
            self.stats["failures"] += 1
            du0 = np.zeros(self.n_u)
        lim = self.max_move[: self.n_u]
        u_new = np.clip(u_prev + np.clip(du0, -lim, lim), 0.0, 1.0)
        return {"z": z, "u": u_new, "L": L, "op": op, "md": md, "warm": warm, "qp": qp}

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        obs = np.atleast_2d(np.asarray(observation, dtype=np.float64))
        y = obs * self._scale + self._center
        n = obs.shape[0]
        fresh = self._rows is None or len(self._rows) != n
        restart = restart_rows(fresh, n, episode_start)
        rows = [None if fresh or restart[b] else self._rows[b] for b in range(n)]
        with np.errstate(invalid="ignore", over="ignore"):  # non-finite rows are refused below
            new = [self._row(rows[b], y[b]) for b in range(n)]
        bad = [b for b, s in enumerate(new) if not (np.all(np.isfinite(s["z"]))
                                                    and np.all(np.isfinite(s["u"])))]
        if bad:
            raise ValueError(f"mpc_linear: non-finite estimate for rows {bad} of the "
                             f"observation; the policy's state is unchanged")  # fmt: skip
        self._rows = new
        u = np.array([s["u"] for s in new])
        action = (2.0 * u - 1.0).astype(np.float32)
        return (action[0] if np.ndim(observation) == 1 else action), None
