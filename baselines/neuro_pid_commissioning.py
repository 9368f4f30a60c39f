"""The neuro-PID's commissioning: the PID the net starts from (and centres the gains'
bounds on) and the net's initial weights, from closed-loop step tests of the outer process.

Source: Zhang et al. 2012 (docs/references.md); the controller is baselines/neuro_pid.py,
the net baselines/neuro_pid_net.py.

The outer process (inner setpoint -> measured outlet, the inner loop closed and the other
loops run as baselines/neuro_pid.py runs them) is identified at each load of cascade_pi's
GAIN_LOADS (50, 75, 100 %) by a closed-loop step of the inner setpoint (+2 K, at most a
quarter of the valve stroke through a P secondary; constant load, no noise, a scenario
built in code, :func:`outer_models`), read as FOPDT (Tu, Tg by
steamtemp_gym.metrics.step_response_metrics) with the 5 s filter added to the dead time.
SIMC PI (Skogestad, J. Process Control 13, 2003, tau_c = theta) gives K_c and T_i; in eq.
(4)'s increments k_p0 = K_c, k_i0 = K_c T_s / T_i, and k_d0 = KD0 = 0.05 (the
commissioning tuning is a PI; g cannot output 0; a model-based derivative gain, e.g. the
IMC-PID's T_d = tau theta / (2 tau + theta), is k_d ~ 10 on the claim plant and would put
the 0.25 K sensor noise on the valve), all divided by the number of MAIN loops (as
cascade_pi shares the main-steam loop gain). The commissioning gains, and with them the
gains' bounds, are interpolated linearly in the load demand between those loads (held
beyond them), as cascade_pi_ff schedules its PI: a tuning read at rated load alone
limit-cycles at 35 % load (the held-out deep ramp). Weights are drawn once, uniform on
[-0.5, 0.5] with numpy's default_rng(INIT_SEED = 0) (the same for every loop, plant and
episode), and the output-layer biases are then set so that the net outputs g = 1/2, i.e.
exactly (k_p0, k_i0, k_d0), at zero input (the same weights at every load). ``reset()``
and ``episode_start`` restore these weights: the net relearns every episode, as the
paper's online training does.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np

from baselines.cascade_pi import FILTER_S, GAIN_LOADS, simc_pi
from baselines.commissioned import commissioned
from baselines.identification import FOPDT
from steamtemp_gym import plants
from steamtemp_gym.metrics import step_response_metrics
from steamtemp_gym.plants.base import MAIN
from steamtemp_gym.scenarios import Scenario

#: Initial derivative gain of eq. (4) (K per K): the commissioning tuning is a PI, g cannot
#: output 0; 0.05 is a derivative time of ~0.1 s at the claim plant's k_p0 (negligible).
KD0 = 0.05
#: Inner-setpoint step (K) of the commissioning test, and its length (s).
STEP_K, STEP_DURATION_S = 2.0, 2400.0


def inner_p_valve_per_K(plant: Any) -> float | None:
    """The paper's G_C2 (Section 5: G_C2 = 8, read as % of valve stroke per K of the
    filtered intermediate temperature) in valve stroke (fraction) per K, on the plant that
    declares it (``commissioning["neuro_pid"]["inner_p_pct_per_K"]``), None elsewhere."""
    pct = plant.commissioning.get("neuro_pid", {}).get("inner_p_pct_per_K")
    return None if pct is None else pct / 100.0


@commissioned(maxsize=48)
def outer_models(
    controller: type, env_id: str, params_json: str, load: float = 1.0
) -> tuple[FOPDT | None, ...]:
    """Per action: FOPDT of inner setpoint -> measured outlet (MAIN loops) at ``load``, else
    None. ``controller`` is the NeuroPID class, which runs the step tests (``force_u``).

    Closed-loop step of the inner setpoint by STEP_K at a constant ``load`` without noise (a
    scenario built here, not an evaluation one), run twice with the same seed, with and
    without the step, so the plant's own seeded disturbances cancel (as in step_test).
    """
    import gymnasium as gym

    sc = Scenario(name="npid_commissioning", duration_s=STEP_DURATION_S, load=((0.0, load),))
    env = gym.make(env_id, scenario=sc, params=json.loads(params_json))
    plant = env.unwrapped.plant
    out: list[FOPDT | None] = [None] * len(plant.control_loops)
    for j, (inner, outer) in enumerate(plant.control_loops):
        if outer != MAIN:
            continue
        p_in = inner_p_valve_per_K(plant)
        # the step stays linear: at most a quarter of the valve stroke through a P secondary
        step = (STEP_K if p_in is None else min(STEP_K, 0.25 / p_in)) if inner else 0.05
        recs = []
        for du in (0.0, step):
            pol = controller(env, force_u=du, k0=np.full((len(plant.control_loops), 3), 0.5))
            obs, _ = env.reset(seed=0)
            t, y = [0.0], [float(env.unwrapped.signals.decode(obs)[plant.outlet_measured])]
            while True:
                a, _ = pol.predict(obs)
                obs, _, term, trunc, info = env.step(a)
                t.append(info["time_s"])
                y.append(float(env.unwrapped.signals.decode(obs)[plant.outlet_measured]))
                if term or trunc:
                    break
            recs.append(np.array(y))
        m = step_response_metrics(np.array(t), recs[1] - recs[0])
        out[j] = FOPDT(m["gain"] / step, m["Tg_s"], m["Tu_s"] + FILTER_S)
    return tuple(out)


@commissioned(maxsize=16)
def commissioning_gains(controller: type, env_id: str, params_json: str) -> np.ndarray:
    """(len(GAIN_LOADS), actions, 4) table: (k_p0, k_i0, k_d0) of eq. (4) per action at each
    load of :data:`GAIN_LOADS` (zeros off MAIN), and the loop direction (sign of the outer
    gain) as a 4th column; see the module docstring. ``controller``: as for
    :func:`outer_models`."""
    dt = plants.make(env_id, **json.loads(params_json)).dt_s
    table = []
    for load in GAIN_LOADS:
        models = outer_models(controller, env_id, params_json, load)
        n_main = sum(m is not None for m in models)
        out = np.zeros((len(models), 4))
        for j, m in enumerate(models):
            if m is None:
                continue
            kc, ti = simc_pi(m)
            kc = abs(kc) / n_main
            out[j] = (kc, kc * dt / ti, KD0, np.sign(m.K))
        table.append(out)
    return np.array(table)
