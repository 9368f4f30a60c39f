"""The design of ``mpc_linear`` (baselines/mpc_linear.py): the plant's own linearized
physics at a grid of loads, reduced to one balanced basis, augmented with integrating
disturbances and their Kalman filter, and the prediction matrices of the horizon.

Sources: Pannocchia and Rawlings 2003 and Muske and Badgwell 2002 (offset-free
estimation; docs/references.md); square-root balanced truncation (Moore 1981; Laub et
al. 1987).

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
"""

from __future__ import annotations

import json
from typing import Any, NamedTuple

import numpy as np

from baselines.commissioned import commissioned
from baselines.linear_models import balanced_basis, kalman_gain, reachable, steady_point
from steamtemp_gym import plants

#: Loads of the local models (fraction of rated) and of the steady operating-point tables.
GRID_LOADS = (0.4, 0.6, 0.8, 1.0)
OP_LOADS = tuple(np.round(np.arange(0.3, 1.101, 0.05), 2))
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
#: The move suppressions the commissioning rule chooses among, largest first (baselines/
#: mpc_linear.py, module docstring).
MOVE_WEIGHT_LADDER = (0.01, 0.003, 0.001)
P_REL = 0.002
W_REL = 0.1
#: Horizon: multiples of the slowest 63 % time, clipped (s); points; move instants.
HORIZON_T63, HORIZON_MIN_S, HORIZON_MAX_S = 4.0, 300.0, 1800.0
N_POINTS = 40
MOVE_T63 = (0.0, 0.1, 0.25, 0.5, 1.0, 2.0)
#: The measured load rate is assumed to continue this long (s), then the load holds.
RATE_HOLD_S = 300.0


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
    scaled = [
        (
            A[np.ix_(keep, keep)] / sx[:, None] * sx[None, :],
            B[keep] / sx[:, None],
            A[np.ix_(keep, md)] / sx[:, None],
            C[:, keep] * sx[None, :],
            D,
            Dd,
        )
        for A, B, C, D, Dd in raw
    ]
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


def _load_path(
    sL: np.ndarray, hr: np.ndarray, pts: np.ndarray, n_hold: int, dt: float
) -> np.ndarray:
    """(n_hold + 1, points, n_c): the scored outputs' response per unit load rate to a load
    that ramps for n steps, then holds (rate pulses plus the steps of the ramp)."""
    f = np.zeros((n_hold + 1, len(pts), sL.shape[1]))
    for n in range(1, n_hold + 1):
        i_r, i_l = pts - (n - 1), pts - n
        f[n] = (
            f[n - 1]
            + np.where((i_r > 0)[:, None], hr[np.maximum(i_r, 0)], 0.0)
            + dt * np.where((i_l > 0)[:, None], sL[np.maximum(i_l, 0)], 0.0)
        )
    return f


def rule_move_weight(env_id: str) -> float:
    """The commissioning rule's move suppression on a plant: what the plant declares
    (``commissioning["mpc_linear"]["move_weight"]``), else the middle of the ladder."""
    own = plants.plant_class(env_id).commissioning.get("mpc_linear", {})
    return own.get("move_weight", MOVE_WEIGHT_LADDER[1])


class _Layout(NamedTuple):
    """The sizes and index maps every grid model of one plant's design shares."""

    env_id: str
    r: int  # reduced plant states
    n_y: int  # observed signals
    n_c: int  # scored temperatures
    n_u: int  # commands
    n_md: int  # measured disturbances
    pair: list[int]  # per scored temperature, its thermocouple's observed row
    E: np.ndarray  # output disturbances on the observed signals
    Ec: np.ndarray  # and on the scored temperatures (through their thermocouples)
    Nh: int  # horizon (steps)
    pts: np.ndarray  # prediction points (steps)
    moves: np.ndarray  # move instants (steps)
    n_hold: int  # steps the measured load rate is assumed to continue
    dt: float


def _output_disturbances(
    pair: list[int], n_y: int, n_c: int
) -> tuple[list[int], np.ndarray, np.ndarray]:
    """(rows, E, Ec): the observed rows with a random-walk output disturbance (all but the
    main-steam thermocouple's) and where those disturbances enter the observed signals (E)
    and the scored temperatures (Ec, through their thermocouples)."""
    i_meas = pair[0]
    p_rows = [j for j in range(n_y) if j != i_meas]  # output disturbances
    n_p = len(p_rows)
    E = np.zeros((n_y, n_p))
    E[p_rows, np.arange(n_p)] = 1.0
    Ec = np.zeros((n_c, n_p))
    for c, j in enumerate(pair[1:], start=1):
        Ec[c, p_rows.index(j)] = 1.0
    return p_rows, E, Ec


def _horizon(
    Ar: np.ndarray, Br: np.ndarray, Cr: np.ndarray, n_y: int, n_c: int, n_u: int, dt: float
) -> tuple[int, int, np.ndarray, np.ndarray, int]:
    """(t63, Nh, pts, moves, n_hold) in steps: the slowest 63 % time of an actuator's effect
    on a scored temperature (rated-load model), the horizon, its points, the move instants
    and how long the measured load rate is assumed to continue."""
    t63 = max(
        _t63(Ar, Br[:, m], Cr[n_y + c], int(HORIZON_MAX_S / dt))
        for m in range(n_u)
        for c in range(n_c)
    )
    Nh = int(np.clip(HORIZON_T63 * t63 * dt, HORIZON_MIN_S, HORIZON_MAX_S) / dt)
    pts = np.unique(np.round(np.linspace(Nh / N_POINTS, Nh, N_POINTS)).astype(int))
    moves = np.unique(np.round(np.array(MOVE_T63) * t63).astype(int))
    moves = moves[moves < Nh]
    n_hold = int(round(RATE_HOLD_S / dt))
    return t63, Nh, pts, moves, n_hold


def _noise(
    observed: list, p_rows: list[int], r: int, dt: float, noise_K: float, heat_std: float
) -> tuple[np.ndarray, ...]:
    """(V, W): the Kalman filter's measurement noise (``noise_K`` on the thermocouples) and
    process noise of the augmented state (the heat-absorption bias's increments from an OU
    process of std ``heat_std``); W's block of the plant states is set per grid model
    (:func:`_grid_model`)."""
    n_z = r + 1 + len(p_rows)
    V = np.diag([(noise_K if s.noisy else V_REL * s.scale) ** 2 for s in observed])
    W = np.zeros((n_z, n_z))
    W[r, r] = (heat_std * np.sqrt(1.0 - np.exp(-2.0 * dt / HEAT_TAU_S))) ** 2
    W[r + 1 :, r + 1 :] = np.diag([(P_REL * observed[j].scale) ** 2 for j in p_rows])
    return V, W


def _grid_model(
    model: tuple, T: np.ndarray, Ti: np.ndarray, W: np.ndarray, V: np.ndarray, lay: _Layout
) -> dict[str, Any]:
    """One grid load's reduced augmented model, Kalman gain, prediction matrices and steady
    gains; ``W``'s block of the plant states is set to this model's process noise."""
    As, Bs, Bm, Cs, Dm, Dd = model
    r, n_y, n_c, n_u, n_md = lay.r, lay.n_y, lay.n_c, lay.n_u, lay.n_md
    E, Ec, pts, moves = lay.E, lay.Ec, lay.pts, lay.moves
    n_z = W.shape[0]
    Ar, Bu, Bmd = Ti @ As @ T, Ti @ Bs[:, :n_u], Ti @ Bm
    bL, br, bq = (Ti @ Bs[:, n_u + k] for k in range(3))
    Cm = Cs[:n_y] @ T
    Cc = Cm[lay.pair]  # the scored temperatures as their thermocouples read them
    Az = np.eye(n_z)
    Az[:r, :r], Az[:r, r] = Ar, bq
    Bz = np.zeros((n_z, n_u + 1 + n_md))  # known inputs: commands, load rate, measured
    Bz[:r, :n_u], Bz[:r, n_u], Bz[:r, n_u + 1 :] = Bu, br, Bmd
    Cmz = np.hstack([Cm, Dd[:, 2:3], E])
    Ccz = np.hstack([Cc, np.zeros((n_c, 1)), Ec])
    Gx = W_REL * np.hstack([Bu * SIZE_U, bL[:, None] * SIZE_LOAD, bq[:, None] * SIZE_HEAT])
    W[:r, :r] = Gx @ Gx.T + 1e-12 * np.eye(r)
    M = kalman_gain(Az, Cmz, W, V)
    Phi, Su, sL, hr, Pm = _responses(Az, Ccz, Ar, Bu, bL, br, Bmd, Cc, lay.Nh)
    Sd = np.zeros((len(pts), n_c, len(moves), n_u))  # the moves' dynamic matrix
    for i, t0 in enumerate(moves):
        Sd[pts > t0, :, i, :] = Su[pts[pts > t0] - t0]
    inv = np.linalg.inv(np.eye(r) - Ar)
    init = np.hstack([(Cm @ inv @ bq + Dd[:, 2])[:, None], E])
    if np.linalg.cond(init) > 1e12:
        raise ValueError(f"{lay.env_id}: the disturbance model is not detectable")
    return {
        "Az": Az,
        "Bz": Bz,
        "Cmz": Cmz,
        "M": M,
        "Dm": Dm,
        "DdL": Dd[:, 0],
        "Ddr": Dd[:, 1],
        "Phi": Phi[pts],
        "Gam": Su[pts],
        "Pm": Pm[pts],
        "f": _load_path(sL, hr, pts, lay.n_hold, lay.dt),
        "Sd": Sd.reshape(len(pts) * n_c, len(moves) * n_u),
        "Gu": Cc @ inv @ Bu,
        "Gq": Cc @ inv @ bq,
        "GL": Cc @ inv @ bL,
        "Init": init,
        "InitU": Cm @ inv @ Bu + Dm,
        "InitM": Cm @ inv @ Bmd,
        "inv": inv,
        "Bu": Bu,
        "bq": bq,
        "Bmd": Bmd,
    }


@commissioned(maxsize=16)
def design(
    env_id: str, params_json: str, noise_K: float = NOISE_K, heat_std: float = HEAT_STD
) -> dict[str, Any]:
    """The MPC of a plant (cached): per grid load the reduced augmented model, Kalman gain,
    prediction matrices and steady gains; horizon, points, moves; operating-point tables.
    ``noise_K`` and ``heat_std``: the thermocouple noise and heat-absorption variability the
    Kalman filter assumes (the module docstring's NOISE_K and HEAT_STD by default; larger
    noise or a smaller variability detune the estimator)."""
    plant = plants.make(env_id, **json.loads(params_json))
    observed = [s for s in plant.outputs if s.observed]
    ctrl = [plant.outlet] + [n for n, _ in plant.secondary]
    n_y, n_c, n_u, dt = len(observed), len(ctrl), plant.n_u, plant.dt_s
    scaled, keep, sx, size_in, (md_rows, md_gain) = _local_models(
        plant, [s.name for s in observed] + ctrl, n_y
    )
    scale_y = np.array([s.scale for s in observed] + [1.0] * n_c)
    T, Ti, hsv = balanced_basis(
        [(A, B * size_in, C / scale_y[:, None]) for A, B, _, C, *_ in scaled], HSV_TOL, MAX_ORDER
    )
    r = T.shape[1]
    As, Bs, _, Cs, *_ = scaled[-1]
    pair = _pairs(plant, Cs @ np.linalg.solve(np.eye(len(As)) - As, Bs), n_y, ctrl)
    p_rows, E, Ec = _output_disturbances(pair, n_y, n_c)
    t63, Nh, pts, moves, n_hold = _horizon(Ti @ As @ T, Ti @ Bs, Cs @ T, n_y, n_c, n_u, dt)
    V, W = _noise(observed, p_rows, r, dt, noise_K, heat_std)
    lay = _Layout(env_id, r, n_y, n_c, n_u, len(md_rows), pair, E, Ec, Nh, pts, moves, n_hold, dt)
    grid = [_grid_model(model, T, Ti, W, V, lay) for model in scaled]
    ops = [steady_point(plant, L, [s.name for s in observed] + ctrl) for L in OP_LOADS]
    ok = [k for k, (_, _, y) in enumerate(ops) if np.all(np.isfinite(y))]
    rates = np.array(plant.rate_limits)
    return {
        "grid": grid,
        "r": r,
        "n_p": len(p_rows),
        "n_y": n_y,
        "n_c": n_c,
        "n_md": len(md_rows),
        "md_rows": md_rows,
        "md_gain": md_gain,
        "Ec": Ec,
        "pts": pts,
        "moves": moves,
        "Nh": Nh,
        "n_hold": n_hold,
        "t63_s": t63 * dt,
        "hsv": hsv,
        "rates": rates,
        "op_loads": np.array(OP_LOADS)[ok],
        "op": np.array(
            [np.concatenate([Ti @ (ops[k][0][keep] / sx), ops[k][1], ops[k][2]]) for k in ok]
        ),
        "op_cols": np.cumsum([0, r, n_u, n_y, n_c]),
        "secondary_sp": np.array([s for _, s in plant.secondary]),
    }
