"""Plant identification by open-loop step tests through the env (what a commissioning
engineer does on site): hold the unit at a constant load, step one valve, record
the measured signals, and read off gain, Tu and Tg with the metrics module
(steamtemp_gym.metrics.step_response_metrics). Used to tune the baselines.
"""

from __future__ import annotations

from dataclasses import dataclass

import gymnasium as gym
import numpy as np

from steamtemp_gym.metrics import step_response_metrics
from steamtemp_gym.scenarios import Scenario


@dataclass(frozen=True)
class FOPDT:
    """First order plus dead time K exp(-theta s)/(tau s + 1), from Tu (theta) and Tg (tau)."""

    K: float
    tau_s: float
    theta_s: float


def _record(env, a: np.ndarray) -> tuple[np.ndarray, list[dict]]:
    """Time and, per sample, the decoded observation merged with info (observation wins)."""
    obs, info = env.reset(seed=0)
    sig = env.unwrapped.signals
    t, rec = [0.0], [{**info, **sig.decode(obs)}]
    while True:
        obs, _, term, trunc, info = env.step(a.astype(np.float32))
        t.append(info["time_s"])
        rec.append({**info, **sig.decode(obs)})
        if term or trunc:
            return np.array(t), rec


def step_test(
    env_id: str,
    valve: int,
    signals: list[str],
    *,
    load: float = 1.0,
    dv: float = 0.05,
    duration_s: float = 2400.0,
    params: dict | None = None,
) -> dict[str, FOPDT]:
    """Step valve ``valve`` by ``dv`` (opening) at constant ``load``; FOPDT of each signal.

    Signals are observed names (what a commissioning engineer records) or, for analysis,
    info keys such as the true ``outlet_temp_C``.

    The test is run twice with the same seed, with and without the step, and the
    response is their difference: the plant's own random disturbances (same seed,
    same sequence) cancel, as a commissioning engineer would wish they did.

    Returns:
        Signal name -> FOPDT with K in signal units per unit valve opening.
    """
    sc = Scenario(name="step_test", duration_s=duration_s, load=((0.0, load),))
    env = gym.make(env_id, scenario=sc, params=params or {})
    _, info = env.reset(seed=0)
    hold = 2.0 * np.atleast_1d(info["spray_valve"]).astype(float) - 1.0
    stepped = hold.copy()
    stepped[valve] += 2.0 * dv
    t, base = _record(env, hold)
    _, rec = _record(env, stepped)
    out = {}
    for name in signals:
        if name not in base[0]:
            raise ValueError(f"{env_id} has no signal {name!r}; known: {sorted(base[0])}")
        y = np.array([r[name] - r0[name] for r, r0 in zip(rec, base, strict=True)])
        m = step_response_metrics(t, y)
        out[name] = FOPDT(K=m["gain"] / dv, tau_s=m["Tg_s"], theta_s=m["Tu_s"])
    return out


def simc_pi(model: FOPDT, tau_c: float | None = None) -> tuple[float, float]:
    """SIMC PI tuning (Skogestad, J. Process Control 13, 2003): (Kc, Ti_s).

    Kc = tau / (K (tau_c + theta)), Ti = min(tau, 4 (tau_c + theta)), default tau_c = theta
    (the "tight control, good robustness" choice). Kc has the sign of 1/K.
    """
    theta = max(model.theta_s, 1e-3)
    tc = theta if tau_c is None else tau_c
    return model.tau_s / (model.K * (tc + theta)), min(model.tau_s, 4.0 * (tc + theta))
