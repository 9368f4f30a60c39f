"""Policy contracts (the ``predict`` of Stable-Baselines3 that every baseline and agent has),
one named check each: ``check_x(name_or_factory, env_id_or_factory, quick=False)``.

A policy is a baseline name (``baselines.make(name, env)``) or a factory ``make(env)``
returning an object with ``predict(observation, state=None, episode_start=None,
deterministic=True) -> (action, state)`` (batched over a leading env axis) and ``reset()``.
"""

from __future__ import annotations

import inspect
from typing import Any

import numpy as np

from steamtemp_gym import scenarios
from steamtemp_gym.signals import OBS_LIMIT
from steamtemp_gym.testing.subjects import EnvTarget, PolicyTarget, policy_check

#: The SB3 predict parameters, in order.
PREDICT_PARAMS = ("observation", "state", "episode_start", "deterministic")
#: Scenario of the short runs (the 000 paper's load ramp: every loop moves).
RAMP = "load_ramp_100_50"
#: Scenario of the quick no-trip check (the shortest named scenario of every plant).
QUICK_SCENARIO = "setpoint_step"
SEEDS_FULL = (0, 1, 2)


def _actions(
    policy: Any, env: Any, seed: int, steps: int, call_reset: bool = True, first_start: bool = True
) -> np.ndarray:
    """Actions of ``policy`` on ``env`` from reset(seed) for ``steps`` steps (or the end)."""
    obs, _ = env.reset(seed=seed)
    if call_reset:
        policy.reset()
    out = []
    for k in range(steps):
        start = np.array([first_start and k == 0])
        a, _ = policy.predict(obs, episode_start=start, deterministic=True)
        out.append(np.asarray(a, dtype=np.float64).copy())
        obs, _, term, trunc, _ = env.step(a)
        if term or trunc:
            break
    return np.array(out)


def _first_step_differing(a: np.ndarray, b: np.ndarray) -> int | None:
    if a.shape != b.shape:
        return min(len(a), len(b))
    rows = np.flatnonzero(~np.all(a == b, axis=tuple(range(1, a.ndim))))
    return int(rows[0]) if rows.size else None


@policy_check
def check_predict_signature(policy: PolicyTarget, target: EnvTarget, quick: bool = False) -> None:
    """``predict(observation, state=None, episode_start=None, deterministic=...)`` returns
    ``(action, state)`` with a float action of the action space's shape; ``reset()`` exists."""
    env = target.make(scenario=RAMP)
    p = policy.make(env)
    assert callable(getattr(p, "reset", None)), "the policy has no reset()"
    params = inspect.signature(p.predict).parameters
    assert tuple(params)[:4] == PREDICT_PARAMS, (
        f"predict parameters {tuple(params)}, expected {PREDICT_PARAMS} (SB3's)"
    )
    for name in PREDICT_PARAMS[1:3]:
        assert params[name].default is None, f"predict's {name} must default to None"
    obs, _ = env.reset(seed=0)
    for how, out in (
        ("positional", p.predict(obs)),
        (
            "keywords",
            p.predict(
                observation=obs, state=None, episode_start=np.array([True]), deterministic=True
            ),
        ),
    ):
        assert isinstance(out, tuple) and len(out) == 2, (
            f"predict ({how}) must return (action, state), got {type(out).__name__}"
        )
        a = np.asarray(out[0])
        assert a.shape == env.action_space.shape and a.dtype.kind == "f", (
            f"predict ({how}) gave an action of shape {a.shape} dtype {a.dtype}, expected "
            f"{env.action_space.shape} float"
        )


@policy_check
def check_batched_equals_unbatched(
    policy: PolicyTarget, target: EnvTarget, quick: bool = False
) -> None:
    """One policy on a vector env of 3 sub-envs acts as 3 policies on single envs seeded
    alike: to 1e-9, or to the policy's declared ``batch_tolerance`` (a float32 network's
    matrix products round differently with the batch size)."""
    n, steps = 3, 40 if quick else 200
    venv = target.make_vec(n, scenario=RAMP)
    batched = policy.make(venv)
    obs_b, _ = venv.reset(seed=0)
    envs = [target.make(scenario=RAMP) for _ in range(n)]
    singles = [policy.make(e) for e in envs]
    obs_s = [e.reset(seed=i)[0] for i, e in enumerate(envs)]
    start = np.ones(n, dtype=bool)
    for k in range(steps):
        a_b, _ = batched.predict(obs_b, episode_start=start, deterministic=True)
        a_s = [
            p.predict(o, episode_start=start[:1], deterministic=True)[0]
            for p, o in zip(singles, obs_s, strict=True)
        ]
        shape = (n, venv.single_action_space.shape[0])
        assert np.shape(a_b) == shape, f"batched actions of shape {np.shape(a_b)}, not {shape}"
        tol = float(getattr(batched, "batch_tolerance", 1e-9))
        assert np.allclose(a_b, np.stack(a_s), rtol=tol, atol=tol), (
            f"batched {a_b.tolist()} != unbatched {np.stack(a_s).tolist()} (scenario {RAMP}, "
            f"vector env seed 0 / single envs seeds 0-{n - 1}, step {k})"
        )
        start[:] = False
        obs_b, *_ = venv.step(a_b)
        obs_s = [e.step(a)[0] for e, a in zip(envs, a_s, strict=True)]


@policy_check
def check_policy_determinism(policy: PolicyTarget, target: EnvTarget, quick: bool = False) -> None:
    """Two fresh policies on two envs with the same seed act identically, bit for bit."""
    steps = 100 if quick else 600
    runs = []
    for _ in range(2):
        env = target.make(scenario=RAMP)
        runs.append(_actions(policy.make(env), env, 0, steps))
    k = _first_step_differing(*runs)
    assert k is None, f"the actions differ at step {k} (scenario {RAMP}, seed 0)"


@policy_check
def check_reset_clears_state(policy: PolicyTarget, target: EnvTarget, quick: bool = False) -> None:
    """After an episode, ``reset()`` (and, separately, ``episode_start=True``) makes the
    policy act as a fresh one."""
    steps = 60 if quick else 300
    env = target.make(scenario=RAMP)
    for how, call_reset, first_start in (
        ("reset()", True, False),
        ("episode_start=True", False, True),
    ):
        fresh = _actions(policy.make(env), env, 0, steps, call_reset, first_start)
        used = policy.make(env)
        _actions(used, env, 1, steps)  # an episode with another seed: state to forget
        again = _actions(used, env, 0, steps, call_reset, first_start)
        k = _first_step_differing(fresh, again)
        assert k is None, (
            f"after {how} the policy acts differently from a fresh one at step {k} "
            f"(scenario {RAMP}, seed 0, after {steps} steps of seed 1)"
        )


@policy_check
def check_actions_in_bounds(policy: PolicyTarget, target: EnvTarget, quick: bool = False) -> None:
    """Actions are finite and inside [-1, 1]: along a load ramp and for 64 arbitrary
    observations of the observation space (a batch of them, 20 calls)."""
    env = target.make(scenario=RAMP)
    acts = _actions(policy.make(env), env, 0, 200 if quick else 10**6)
    bad = np.flatnonzero(~np.all(np.isfinite(acts) & (np.abs(acts) <= 1.0), axis=1))
    assert not bad.size, (
        f"action {acts[bad[0]].tolist()} at step {bad[0]} (scenario {RAMP}, seed 0)"
    )
    n = 64
    venv = target.make_vec(n, scenario=RAMP)
    p = policy.make(venv)
    venv.reset(seed=0)
    rng = np.random.default_rng(0)
    n_obs = venv.single_observation_space.shape[0]
    for k in range(20):
        obs = rng.uniform(-OBS_LIMIT, OBS_LIMIT, size=(n, n_obs))
        a = np.asarray(p.predict(obs, episode_start=np.full(n, k == 0))[0])
        ok = np.all(np.isfinite(a) & (np.abs(a) <= 1.0), axis=1)
        assert ok.all(), (
            f"action {a[~ok][0].tolist()} for observation {obs[~ok][0].tolist()} (uniform "
            f"observations, np.random.default_rng(0), call {k})"
        )


def _bad_observations(obs: np.ndarray) -> list[tuple[str, Any]]:
    n = obs.shape[0]
    one_nan = obs.copy()
    one_nan[n // 2] = np.nan
    return [
        ("all NaN", np.full(n, np.nan)),
        ("one NaN entry", one_nan),
        ("+inf", np.full(n, np.inf)),
        ("-inf in a batch", np.full((2, n), -np.inf)),
        ("one entry short", obs[:-1]),
        ("one entry too many", np.append(obs, 0.0)),
        ("a batch of another width", np.zeros((2, n + 1))),
        ("3-d", obs[None, None]),
        ("an empty batch, shape (0, n)", np.zeros((0, n))),
        ("None", None),
        ("strings", ["0.1"] * n),
        ("complex", obs.astype(complex)),
        ("episode_start of another shape", (obs, np.array([True, False, True]))),
    ]


@policy_check
def check_bad_observations_rejected(
    policy: PolicyTarget, target: EnvTarget, quick: bool = False
) -> None:
    """Mid-episode, NaN, infinite, misshapen (short, long, 3-d, an empty batch), ``None``,
    string and complex observations and an ``episode_start`` of another shape raise a
    ``ValueError``, and change nothing: the policy then acts as a copy that never saw
    them, bit for bit (logged plant data holds such values; a policy must not carry them)."""
    steps, bad_at = (20, 5) if quick else (60, 10)
    env = target.make(scenario=RAMP)
    p, twin = policy.make(env), policy.make(env)
    obs, _ = env.reset(seed=0)
    for k in range(steps):
        if k == bad_at:
            for what, bad in _bad_observations(obs):
                o, start = bad if isinstance(bad, tuple) else (bad, np.array([False]))
                try:
                    p.predict(o, episode_start=start, deterministic=True)
                except ValueError:
                    continue
                except Exception as exc:
                    raise AssertionError(
                        f"predict of an observation {what}: expected "
                        f"ValueError, got {type(exc).__name__}: {exc}"
                    ) from exc
                raise AssertionError(
                    f"predict accepted an observation {what}; it must raise ValueError"
                )
        start = np.array([k == 0])
        a = np.asarray(p.predict(obs, episode_start=start, deterministic=True)[0])
        b = np.asarray(twin.predict(obs, episode_start=start, deterministic=True)[0])
        assert np.array_equal(a, b), (
            f"after the rejected observations (step {bad_at}) the policy acts {a.tolist()} at "
            f"step {k}, a copy that never saw them {b.tolist()} (scenario {RAMP}, seed 0)"
        )
        obs, _, term, trunc, _ = env.step(a)
        if term or trunc:
            break


def _episode_without_trip(policy: PolicyTarget, target: EnvTarget, name: str, seed: int) -> None:
    env = target.make(scenario=name)
    p = policy.make(env)
    obs, info = env.reset(seed=seed)
    p.reset()
    start, k = True, 0
    while True:
        a, _ = p.predict(obs, episode_start=np.array([start]), deterministic=True)
        start, k = False, k + 1
        obs, _, term, trunc, info = env.step(a)
        assert not term, (
            f"tripped ({info['trip_reason']}) at t = {info['time_s']} s "
            f"(scenario {name}, seed {seed}, step {k})"
        )
        if trunc:
            return


@policy_check
def check_completes_a_scenario(
    policy: PolicyTarget, target: EnvTarget, quick: bool = False, scenario: Any = QUICK_SCENARIO
) -> None:
    """The policy runs ``scenario`` (default the named ``setpoint_step``; any form
    ``gym.make`` takes: a name, ``heldout:<name>``, ``random``, a YAML file), seed 0, to
    its end without a trip."""
    _episode_without_trip(policy, target, scenario, 0)


@policy_check
def check_completes_every_scenario(
    policy: PolicyTarget, target: EnvTarget, quick: bool = False
) -> None:
    """The policy runs every named scenario of the plant, seeds 0-2, to its end without a
    trip (slow: minutes per policy and plant; skipped by ``--quick``)."""
    plant_id = target.make().unwrapped.plant.id
    for name in scenarios.names(plant_id):
        if name != scenarios.RANDOM:
            for seed in SEEDS_FULL:
                _episode_without_trip(policy, target, name, seed)
