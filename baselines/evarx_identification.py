"""Identification of the EV-ARX and interpolated-ARX models through the env: the
excitation runs, the closed-loop step tests and the fits (baselines/evarx.py).

Source: Toyoda and Wada 1999 (docs/references.md), section 7.1 (identification test,
comparison with linear ARX models interpolated by load, Fig. 8). Used by
baselines/mpc_evarx.py.

The identified process is the paper's: the boiler-turbine *with its existing controllers
running* (section 6, Fig. 5-6), excited by M-sequence *bias signals* added to the
controllers' commands while the load demand is ramped (section 7.1). Here the existing
controllers are ``cascade_pi`` and the model's inputs are the biases b added to each
actuator's command (SP1, SP2, RGD on BoilerTurbineMIMO; the paper's FF bias has no
counterpart: firing is run inside the plants).

Data (:func:`record`): a commissioning scenario built in code (``TRAIN_LOAD``, run
``TRAIN_REPEATS`` times: 50-100 % at 2-5 %/min; not an evaluation scenario) with
cascade_pi running and maximal-length PRBS biases (9-bit LFSR, clock ``PRBS_CLOCK_S``,
amplitude ``PRBS_AMP`` of stroke, one phase per actuator), with the named scenarios'
noise. Validation on a separate ramp (``VALID_LOAD``, other phases and seed) by
simulation (eq. 14); fit % = 100 (1 - ||y - yhat|| / ||y - mean y||) per output.
Comparison (section 7.1): linear ARX models of the same structure identified the same
way (simulation error) from runs of ``ARX_RUN_S`` at constant loads ``ARX_LOADS`` (the
paper's 25/50/75/90 % of its range mapped onto 50-100 %), coefficients interpolated
linearly in load; at constant load Delta w = 0, so they carry no load-change term (nor
does the paper's scheme).

Step tests of the real closed loop (:func:`closed_loop_steps`): at ``STEP_LOADS``, no
noise, a ``STEP_DB`` bias step on one actuator against the same run without it. The
loops integrate, so every bias is integrated out and the closed loop's steady gains are
zero; the signed gain physics fixes is the first lobe of the response
(:func:`baselines.evarx.first_lobe`). Measured numbers are in docs/baselines/mpc_evarx.md.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

import numpy as np

from baselines.cascade_pi import CascadePI
from baselines.commissioned import commissioned
from baselines.evarx import (
    ARX_LOADS,
    EE_ITERS,
    SEQ_STARTS,
    TS_TARGET_S,
    Model,
    fit_evarx,
    fit_output_error,
    fit_percent,
    lstsq_scaled,
    regressors,
    sequences,
    simulate,
)
from baselines.loops import observation_layout
from steamtemp_gym import plants
from steamtemp_gym.plants.base import MAIN, SCHEDULED
from steamtemp_gym.scenarios import Scenario

PRBS_CLOCK_S, PRBS_AMP = 20.0, 0.2
#: measurement noise and coloured heat-absorption noise of the identification runs
NOISE = {
    "noise_std_C": 0.25,
    "heat_absorption_noise_std": 0.02,
    "heat_absorption_noise_tau_s": 300.0,
}
#: commissioning ramps (t_s, load): 2-5 %/min over 50-100 %
TRAIN_LOAD = (
    (0.0, 1.0),
    (300.0, 1.0),
    (900.0, 0.5),
    (1500.0, 0.5),
    (2400.0, 0.8),
    (2700.0, 0.8),
    (3100.0, 0.6),
    (3500.0, 0.6),
    (4100.0, 1.0),
    (4700.0, 1.0),
    (5300.0, 0.7),
    (5900.0, 0.7),
    (6900.0, 0.9),
    (7500.0, 0.9),
)
#: the commissioning ramps are run this many times in a row (one record)
TRAIN_REPEATS = 3
VALID_LOAD = (
    (0.0, 0.9),
    (300.0, 0.9),
    (825.0, 0.55),
    (1400.0, 0.55),
    (2240.0, 0.95),
    (2600.0, 0.95),
    (3100.0, 0.7),
    (3600.0, 0.7),
    (4100.0, 0.9),
    (4500.0, 0.9),
)
#: duration (s) of each constant-load run of the interpolated ARX models
ARX_RUN_S = 5400.0
#: closed-loop step tests: loads, bias step (stroke), settle time before it and length (s)
STEP_LOADS = (0.5, 0.75, 1.0)
STEP_DB, STEP_PRE_S, STEP_S = 0.05, 200.0, 1600.0


def prbs(n: int, clock: int, phase: int) -> np.ndarray:
    """+-1 maximal-length sequence (9-bit LFSR, x^9 + x^5 + 1), each bit held ``clock``
    samples, started ``phase`` bits into the period (511)."""
    reg, bits = 0x1FF, []
    for _ in range(511):
        bits.append(reg & 1)
        fb = (reg ^ (reg >> 4)) & 1
        reg = (reg >> 1) | (fb << 8)
    seq = 2.0 * np.array(bits) - 1.0
    return seq[(np.arange(n) // clock + phase) % 511]


def controlled_outputs(plant: Any) -> list[str]:
    """The measured main-steam temperature plus every outer signal of ``control_loops``."""
    return [plant.outlet_measured] + [
        o for _, o in plant.control_loops if o not in (None, MAIN, SCHEDULED)
    ]


def _run(
    env_id: str, params_json: str, sc: Scenario, seed: int, bias: Callable[[int, int], np.ndarray]
) -> dict[str, np.ndarray]:
    """cascade_pi through the env with ``bias(n_steps, n_act)[k]`` added to the commands;
    y are the deviations of the controlled outputs from their references (the setpoint for
    the main steam, the value at the start for the others: cascade_pi's)."""
    import gymnasium as gym

    env = gym.make(env_id, scenario=sc, params=json.loads(params_json))
    plant = env.unwrapped.plant
    names, scale, center = observation_layout(env)
    iy = [names.index(o) for o in controlled_outputs(plant)]
    il = names.index("load_demand")
    pol = CascadePI(env)
    n = int(round(sc.duration_s / plant.dt_s))
    b = bias(n + 1, plant.n_u)
    obs, _ = env.reset(seed=seed)
    ref = (obs * scale + center)[iy]
    Y, U, W = [], [], []
    for k in range(n):
        a, _ = pol.predict(obs)
        x = obs * scale + center
        ref[0] = x[names.index("setpoint_C")]
        Y.append(x[iy] - ref)
        W.append(x[il])
        U.append(b[k])
        u = np.clip((np.asarray(a, float) + 1.0) / 2.0 + b[k], 0.0, 1.0)
        obs, _, term, trunc, _ = env.step((2.0 * u - 1.0).astype(np.float32))
        if term:
            raise RuntimeError(f"{env_id}: identification run tripped at step {k}")
        if trunc:
            break
    return {"y": np.array(Y), "u": np.array(U), "w": np.array(W)}


def record(
    env_id: str, params_json: str, load: tuple, seed: int, phase: int, amp: float = PRBS_AMP
) -> dict[str, np.ndarray]:
    """One excitation run through the env: cascade_pi plus PRBS biases on every actuator.

    Returns y (T, n_out) measured output deviations (STE, RTE), u (T, n_act) the biases
    applied after observing y, w (T,) the load demand, all at the control interval.
    """
    sc = Scenario(name="mpc_identification", duration_s=float(load[-1][0]), load=load, **NOISE)
    dt = plants.make(env_id, **json.loads(params_json)).dt_s
    clock = max(1, int(round(PRBS_CLOCK_S / dt)))

    def bias(n: int, na: int) -> np.ndarray:
        return np.stack([prbs(n, clock, phase + 97 * j) for j in range(na)], 1) * amp

    return _run(env_id, params_json, sc, seed, bias)


def repeated(load: tuple, times: int, gap_s: float = 300.0) -> tuple:
    """A load schedule run ``times`` times in a row, ``gap_s`` apart (held in between)."""
    T = load[-1][0] + gap_s
    return tuple((t + r * T, L) for r in range(times) for t, L in load)


@commissioned(maxsize=16)
def closed_loop_steps(env_id: str, params_json: str = "{}") -> np.ndarray:
    """Step tests of the real closed loop (module docstring): (len(STEP_LOADS), N, n_out,
    n_act) responses per unit bias, sampled at the model interval after the step
    (y(k + 1 .. k + N) for a step at k, as :meth:`Model.step_response`)."""
    plant = plants.make(env_id, **json.loads(params_json))
    n = max(1, int(round(TS_TARGET_S / plant.dt_s)))
    i0 = int(round(STEP_PRE_S / plant.dt_s))
    N = int(STEP_S / (n * plant.dt_s))
    idx = i0 + n * np.arange(1, N + 1)
    out = np.zeros((len(STEP_LOADS), N, len(controlled_outputs(plant)), plant.n_u))
    for li, L in enumerate(STEP_LOADS):
        sc = Scenario(
            name="closed_loop_step",
            duration_s=STEP_PRE_S + STEP_S + 2 * n * plant.dt_s,
            load=((0.0, L),),
        )
        base = _run(env_id, params_json, sc, 0, lambda k, na: np.zeros((k, na)))["y"]
        for m in range(plant.n_u):

            def bias(k: int, na: int, m: int = m) -> np.ndarray:
                b = np.zeros((k, na))
                b[i0:, m] = STEP_DB
                return b

            y = _run(env_id, params_json, sc, 0, bias)["y"]
            out[li, :, :, m] = (y[idx] - base[idx]) / STEP_DB
    return out


@commissioned(maxsize=16)
def identify(env_id: str, params_json: str = "{}") -> dict[str, Any]:
    """EV-ARX and interpolated-ARX models of a plant with their validation numbers (cached).

    Returns a dict: ``evarx`` and ``arx`` (:class:`Model`), ``fit_pct`` (kind -> simulation
    fit % per output on the validation ramp), ``fit_pct_1step`` (kind -> the same with the
    equation-error estimates, the first stage), ``rms_1step`` (kind -> one-interval-ahead
    prediction error RMS per output on the validation ramp, K), ``outputs`` (names) and
    ``cost`` (kind -> per fit, the simulation-error cost at the start and the end).
    """
    plant = plants.make(env_id, **json.loads(params_json))
    n = max(1, int(round(TS_TARGET_S / plant.dt_s)))
    outs = controlled_outputs(plant)
    n_out, n_act = len(outs), plant.n_u
    train = record(env_id, params_json, repeated(TRAIN_LOAD, TRAIN_REPEATS), seed=101, phase=0)
    valid = record(env_id, params_json, VALID_LOAD, seed=202, phase=250)
    phi, w, y = (a[:: max(1, n // SEQ_STARTS)] for a in regressors(train, n))
    fits = [fit_evarx(phi, w, y[:, j], iters=EE_ITERS) for j in range(n_out)]
    th0, ga0 = np.array([f[0] for f in fits]), np.array([f[1] for f in fits])
    th, ga, info = fit_output_error(th0, ga0, *sequences(train, n))
    ev0 = Model("evarx", n_out, n_act, n, theta=th0, gamma=ga0)
    ev = Model("evarx", n_out, n_act, n, theta=th, gamma=ga)
    arx0, arx, costs = [], [], [info["cost"]]
    for k, L in enumerate(ARX_LOADS):
        d = record(env_id, params_json, ((0.0, L), (ARX_RUN_S, L)), seed=300 + k, phase=50 * k)
        ph, _, yy = (a[:: max(1, n // SEQ_STARTS)] for a in regressors(d, n))
        c0 = np.array([lstsq_scaled(ph, yy[:, j]) for j in range(n_out)])
        sph, sw, sy = sequences(d, n)
        c, _, inf = fit_output_error(c0[:, None], np.zeros((n_out, 0)), sph, sw, sy)
        arx0.append(c0)
        arx.append(c[:, 0])
        costs.append(inf["cost"])
    ax0 = Model("arx", n_out, n_act, n, arx=np.array(arx0))
    ax = Model("arx", n_out, n_act, n, arx=np.array(arx))
    phv, wv, yv = regressors(valid, n)
    rms = {m.kind: np.sqrt(np.mean((yv - m.one_step(phv, wv)) ** 2, 0)) for m in (ev, ax)}
    return {
        "evarx": ev,
        "arx": ax,
        "outputs": outs,
        "rms_1step": rms,
        "fit_pct": {m.kind: fit_percent(*simulate(m, valid)) for m in (ev, ax)},
        "fit_pct_1step": {m.kind: fit_percent(*simulate(m, valid)) for m in (ev0, ax0)},
        "cost": {"evarx": costs[:1], "arx": costs[1:]},
    }
