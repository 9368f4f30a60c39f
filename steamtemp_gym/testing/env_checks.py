"""Env contracts, one named check each (the vector env's is in vector_checks.py).

Every check takes a registered id (or an env factory, see subjects.py) and raises an
AssertionError saying what failed, where (seed, step) and the call that reproduces it.
``quick=True`` shortens the long runs (``steamtemp-check --quick``).
"""

from __future__ import annotations

import copy
import dataclasses
import pickle
import warnings
from typing import Any

import gymnasium as gym
import numpy as np

from steamtemp_gym import scenarios
from steamtemp_gym.envs.kernels import TRIP_REASONS
from steamtemp_gym.scenarios.stress import corner_scenario
from steamtemp_gym.signals import OBS_LIMIT
from steamtemp_gym.testing.subjects import CheckSkipped, EnvTarget, env_check, resolve_policy

#: info keys every env reports (README, "info"), with their units.
INFO_UNITS: dict[str, str] = {
    "outlet_temp_C": "C",
    "measured_temp_C": "C",
    "measured_temp_noise_free_C": "C",
    "setpoint_C": "C",
    "load": "fraction of rated",
    "spray_valve": "opening 0-1",
    "spray_flow_kg_s": "kg/s",
    "time_s": "s",
    "trip_reason": "'' or a TRIP_REASONS entry",
}
#: Shape of a rendered frame (the 8 x 6 in trend display at 80 dpi, envs/render.py).
FRAME_SHAPE = (480, 640, 3)
#: Bounds a physical steam temperature stays within in every accepted run, C.
STEAM_C = (100.0, 900.0)
#: A steady start holds the setpoint within this, K (named scenarios, before any step).
STEADY_START_K = 0.05


def fingerprint(obs: Any, reward: Any, terminated: Any, truncated: Any, info: dict) -> bytes:
    """Exact bytes of one step's output (bit-for-bit comparisons; info keys sorted)."""
    parts = [
        np.asarray(obs, dtype=np.float64).tobytes(),
        np.float64(reward).tobytes(),
        bytes([bool(terminated), bool(truncated)]),
    ]
    for k in sorted(info):
        v = info[k]
        parts.append(
            k.encode()
            + (str(v).encode() if isinstance(v, str) else np.asarray(v, dtype=np.float64).tobytes())
        )
    return b"|".join(parts)


def motion(rng: np.random.Generator, a: np.ndarray, k: int) -> np.ndarray:
    """Random-walk actions, with bang-bang stretches (20 of every 40 steps)."""
    if k % 40 < 20:
        return np.clip(a + rng.normal(0.0, 0.3, a.shape), -1.0, 1.0).astype(np.float32)
    return np.sign(rng.uniform(-1.0, 1.0, a.shape)).astype(np.float32)


def _run(env: gym.Env, seed: int, steps: int) -> list[bytes]:
    obs, info = env.reset(seed=seed)
    env.action_space.seed(seed)
    out = [fingerprint(obs, 0.0, False, False, info)]
    for _ in range(steps):
        obs, r, term, trunc, info = env.step(env.action_space.sample())
        out.append(fingerprint(obs, r, term, trunc, info))
        if term or trunc:
            obs, info = env.reset()
            out.append(fingerprint(obs, 0.0, False, False, info))
    return out


def first_difference(a: list, b: list) -> int | None:
    """Index of the first differing entry (or of the shorter end); None if equal."""
    for k, (x, y) in enumerate(zip(a, b, strict=False)):
        if x != y:
            return k
    return None if len(a) == len(b) else min(len(a), len(b))


# ------------------------------------------------------------------------ API conformance
@env_check
def check_gymnasium_env(target: EnvTarget, quick: bool = False) -> None:
    """Gymnasium's ``check_env`` passes (spaces, reset/step signatures, seeding)."""
    from gymnasium.utils.env_checker import check_env

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        check_env(target.make().unwrapped, skip_render_check=True)


@env_check
def check_sb3_env(target: EnvTarget, quick: bool = False) -> None:
    """Stable-Baselines3's ``check_env`` passes (skipped without the [agents] extra)."""
    try:
        from stable_baselines3.common.env_checker import check_env
    except ImportError:
        raise CheckSkipped(
            "stable_baselines3 is not installed (pip install 'steamtemp-gym[agents]')"
        ) from None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        check_env(target.make().unwrapped, warn=False)


@env_check
def check_spaces_match_signals(target: EnvTarget, quick: bool = False) -> None:
    """Observation and action spaces agree with ``env.unwrapped.signals``: one named entry
    with a unit and a finite positive scale per space entry, observations in
    [-OBS_LIMIT, OBS_LIMIT], actions in [-1, 1], and ``signals.decode`` gives back the
    physical values that ``info`` reports."""
    env = target.make(scenario="setpoint_step")
    sig, plant = env.unwrapped.signals, env.unwrapped.plant
    obs_space, act_space = env.observation_space, env.action_space
    assert isinstance(obs_space, gym.spaces.Box) and isinstance(act_space, gym.spaces.Box), (
        f"spaces must be Boxes, got {obs_space} and {act_space}"
    )
    assert obs_space.shape == (len(sig.observation),), (
        f"observation space {obs_space.shape} but {len(sig.observation)} observation signals"
    )
    assert act_space.shape == (len(sig.action),), (
        f"action space {act_space.shape} but {len(sig.action)} action signals"
    )
    assert np.all(act_space.low == -1.0) and np.all(act_space.high == 1.0), (
        f"action space must be [-1, 1], got [{act_space.low}, {act_space.high}]"
    )
    assert np.all(obs_space.low == -OBS_LIMIT) and np.all(obs_space.high == OBS_LIMIT), (
        f"observation space must be [-{OBS_LIMIT}, {OBS_LIMIT}]"
    )
    for group in (sig.observation, sig.action):
        names = [s.name for s in group]
        assert len(set(names)) == len(names), f"duplicate signal names in {names}"
        for s in group:
            assert isinstance(s.name, str) and s.name and isinstance(s.unit, str) and s.unit, (
                f"signal {s!r} needs a name and a unit"
            )
            assert np.isfinite(s.center) and np.isfinite(s.scale) and s.scale > 0, (
                f"signal {s.name}: centre {s.center} and scale {s.scale} must be finite, scale > 0"
            )
    obs, info = env.reset(seed=0)
    for k in range(3):
        dec = sig.decode(obs)
        assert list(dec) == [s.name for s in sig.observation], "decode() keys != signal names"
        where = f"(scenario setpoint_step, seed 0, step {k})"
        for name, value in (
            ("setpoint_C", info["setpoint_C"]),
            ("load_demand", info["load"]),
            (plant.outlet_measured, info["measured_temp_C"]),
            ("error_K", info["setpoint_C"] - info["measured_temp_C"]),
        ):
            assert np.isclose(dec[name], value, rtol=1e-9, atol=1e-9), (
                f"decode(obs)[{name!r}] = {dec[name]!r} but info says {value!r} {where}"
            )
        batch = sig.decode(np.stack([obs, obs]))
        assert all(np.shape(v) == (2,) for v in batch.values()), "decode() of a batch"
        obs, _, _, _, info = env.step(act_space.sample())
    opening = sig.decode_action(np.array([[-1.0], [0.0], [1.0]]).repeat(len(sig.action), 1))
    for j, s in enumerate(sig.action):
        assert np.allclose(opening[s.name], [0.0, 0.5, 1.0]), (
            f"decode_action: action -1, 0, 1 of {s.name} (entry {j}) must open 0, 0.5, 1"
        )


@env_check
def check_info_keys_and_units(target: EnvTarget, quick: bool = False) -> None:
    """``info`` holds the documented keys (:data:`INFO_UNITS`, the plant's secondary
    temperatures and extras) at reset and every step, each a finite number in a physical
    range (an array per valve where there are several), ``time_s`` counted in steps of dt,
    ``trip_reason`` "" while running; episodes start steady at the setpoint."""
    env = target.make(scenario="setpoint_step")
    plant = env.unwrapped.plant
    required = set(INFO_UNITS) | {n for n, _ in plant.secondary} | set(plant.extra_info)
    obs, info = env.reset(seed=0)
    missing = sorted(required - set(info))
    assert not missing, f"info at reset lacks {missing} (has {sorted(info)})"
    assert abs(info["outlet_temp_C"] - info["setpoint_C"]) <= STEADY_START_K, (
        f"not a steady start: outlet {info['outlet_temp_C']:.3f} C, setpoint "
        f"{info['setpoint_C']:.3f} C (scenario setpoint_step, seed 0)"
    )
    keys = set(info)
    env.action_space.seed(0)
    for k in range(0, 31):
        where = f"(scenario setpoint_step, seed 0, step {k})"
        assert set(info) == keys, f"info keys changed {where}: {sorted(set(info) ^ keys)}"
        assert info["time_s"] == k * plant.dt_s, f"time_s {info['time_s']} != {k} x dt {where}"
        assert info["trip_reason"] == "", f"trip_reason {info['trip_reason']!r} {where}"
        for key, v in info.items():
            if key == "trip_reason":
                continue
            arr = np.asarray(v, dtype=np.float64)
            assert np.all(np.isfinite(arr)), f"info[{key!r}] = {v!r} is not finite {where}"
        n_valves = len(plant.valves)
        assert np.shape(info["spray_valve"]) == (() if n_valves == 1 else (n_valves,)), (
            f"info['spray_valve'] shape {np.shape(info['spray_valve'])} for {n_valves} valves"
        )
        checks = {
            "outlet_temp_C": STEAM_C,
            "measured_temp_C": STEAM_C,
            "measured_temp_noise_free_C": STEAM_C,
            "load": scenarios.LIMITS["load"],
            "spray_valve": (0.0, 1.0),
            "spray_flow_kg_s": (0.0, np.inf),
        }
        checks.update({name: STEAM_C for name, _ in plant.secondary})
        for key, (lo, hi) in checks.items():
            arr = np.asarray(info[key])
            assert np.all((arr >= lo) & (arr <= hi)), (
                f"info[{key!r}] = {info[key]!r} outside [{lo}, {hi}] ({INFO_UNITS.get(key, 'C')})"
                f" {where}"
            )
        lim = scenarios.LIMITS["setpoint_offset_C"]
        off = info["setpoint_C"] - plant.setpoint_C
        assert lim[0] <= off <= lim[1], f"setpoint offset {off} K outside {lim} {where}"
        obs, _, term, trunc, info = env.step(env.action_space.sample())
        assert not (term or trunc), f"setpoint_step ended at step {k + 1}"


@env_check
def check_determinism(target: EnvTarget, quick: bool = False) -> None:
    """Same seed, same trajectory, bit for bit (observations, rewards, flags, info), also
    on a re-seeded env; another seed gives another trajectory."""
    steps = 60 if quick else 300
    a = _run(target.make(scenario="random"), 3, steps)
    env = target.make(scenario="random")
    _run(env, 7, 10)
    for label, b in (
        ("a second env", _run(target.make(scenario="random"), 3, steps)),
        ("the same env re-seeded", _run(env, 3, steps)),
    ):
        k = first_difference(a, b)
        assert k is None, (
            f"{label} differs from the first at step {k} (scenario random, seed 3, "
            f"action_space seeded 3)"
        )
    assert first_difference(a, _run(target.make(scenario="random"), 4, steps)) is not None, (
        "seeds 3 and 4 give the same trajectory: the seed is ignored"
    )


@env_check
def check_pickle_and_deepcopy(target: EnvTarget, quick: bool = False) -> None:
    """An env pickled or deep-copied mid-episode continues exactly as the original, and
    independently of it."""
    env = target.make(scenario="random")
    env.reset(seed=5)
    for _ in range(5):
        env.step(np.full(env.action_space.shape, 0.1, dtype=np.float32))
    clones = {"pickle": pickle.loads(pickle.dumps(env)), "deepcopy": copy.deepcopy(env)}
    rng = np.random.default_rng(0)
    for k in range(10):
        a = rng.uniform(-1, 1, env.action_space.shape).astype(np.float32)
        ref = fingerprint(*env.step(a))
        for how, clone in clones.items():
            assert fingerprint(*clone.step(a)) == ref, (
                f"the {how} copy (made after 5 steps, scenario random, seed 5) differs from "
                f"the original {k + 1} steps later"
            )


def _drive(env: gym.Env, policy: Any, seed: int, max_steps: int | None) -> tuple[int, dict, bool]:
    """Run ``policy`` from reset(seed) to the end (or max_steps); (steps, last info, ended)."""
    obs, info = env.reset(seed=seed)
    policy.reset()
    name, k = env.unwrapped.scenario.name, 0
    while max_steps is None or k < max_steps:
        obs, r, term, trunc, info = env.step(policy.predict(obs)[0])
        k += 1
        assert np.all(np.isfinite(obs)) and np.isfinite(r), (
            f"non-finite observation or reward (scenario {name}, seed {seed}, step {k})"
        )
        assert not term, (
            f"tripped ({info['trip_reason']}) at t = {info['time_s']} s under the reference "
            f"controller (scenario {name}, seed {seed}, step {k})"
        )
        if trunc:
            return k, info, True
    return k, info, False


@env_check
def check_named_scenarios_run_to_end(target: EnvTarget, quick: bool = False) -> None:
    """Every named scenario of the plant starts, runs under the reference controller
    (``cascade_pi``) without a trip and is truncated exactly at its ``duration_s``.
    Quick: the shortest one to its end, the others for 60 steps."""
    plant_id = target.make().unwrapped.plant.id
    names = [n for n in scenarios.names(plant_id) if n != scenarios.RANDOM]
    assert names, f"{plant_id} has no named scenario"
    shortest = min(names, key=lambda n: scenarios.get(n, plant_id).duration_s)
    make_policy = resolve_policy("cascade_pi").make
    for name in names:
        env = target.make(scenario=name)
        limit = 60 if quick and name != shortest else None
        steps, info, ended = _drive(env, make_policy(env), 0, limit)
        if limit is None:
            dur, dt = env.unwrapped.scenario.duration_s, env.unwrapped.plant.dt_s
            assert ended and abs(info["time_s"] - dur) < 1e-6, (
                f"scenario {name} ended at t = {info['time_s']} s, not at its duration {dur} s"
            )
            assert steps == round(dur / dt), f"scenario {name}: {steps} steps for {dur} s / {dt}"


def _expect_value_error(what: str, fn: Any, *args: Any, **kwargs: Any) -> str:
    try:
        fn(*args, **kwargs)
    except ValueError as exc:
        return str(exc)
    except Exception as exc:
        got = f"{type(exc).__name__}: {exc}"
        raise AssertionError(f"{what}: expected ValueError, got {got}") from exc
    raise AssertionError(f"{what} was accepted; it must raise ValueError")


def _bad_actions(n_u: int) -> list[tuple[str, Any]]:
    z = np.zeros(n_u)
    cases = [
        ("NaN", np.full(n_u, np.nan)),
        ("+inf", np.full(n_u, np.inf)),
        ("-inf", np.full(n_u, -np.inf)),
        ("one entry too many", np.zeros(n_u + 1)),
        ("a batch of one, shape (1, n)", z[None, :]),
        ("3-d", np.zeros((2, 2, 2))),
        ("strings", ["0.5"] * n_u),
        ("complex", z.astype(complex)),
        ("bool", z.astype(bool)),
        ("None", None),
        ("a masked array with a masked entry", np.ma.masked_array(z, mask=z == 0)),
    ]
    if n_u > 1:
        cases.append(("a column, shape (n, 1)", z[:, None]))
    return cases


@env_check
def check_bad_inputs_rejected(target: EnvTarget, quick: bool = False) -> None:
    """NaN, infinite, wrong-shape, wrong-orientation and non-numeric actions, unknown options
    (of make, reset, scenario, reward, params), non-finite or negative parameters and a
    step before reset raise a ValueError (RuntimeError for the step) that names the thing,
    and change nothing: the env then steps as an untouched copy does."""
    fresh = target.make(scenario="setpoint_step").unwrapped
    try:
        fresh.step(np.zeros(fresh.action_space.shape, dtype=np.float32))
        raise AssertionError("step() before reset() was accepted")
    except RuntimeError:
        pass
    env = target.make(scenario="setpoint_step")
    env.reset(seed=0)
    twin = copy.deepcopy(env)
    n_u = env.action_space.shape[0]
    for what, bad in _bad_actions(n_u):
        msg = _expect_value_error(f"action {what}", env.unwrapped.step, bad)
        assert "action" in msg, f"the error for action {what} does not say 'action': {msg!r}"
    a = np.full(n_u, 0.2, dtype=np.float32)
    assert fingerprint(*env.step(a)) == fingerprint(*twin.step(a)), (
        "rejected actions changed the env (it no longer steps as a copy made before them)"
    )
    if target.has_native_vector_env:
        _vector_bad_actions(target, n_u)
    for what, kwargs, needle in (
        ("an unknown make() option", {"no_such_option": 1}, "no_such_option"),
        ("an unknown scenario", {"scenario": "no_such_scenario"}, "valid"),
        ("an unknown reward option", {"reward": {"no_such_weight": 1.0}}, "no_such_weight"),
        ("an unknown plant parameter", {"params": {"no_such_param": 1.0}}, "no_such_param"),
        ("an unknown render_mode", {"render_mode": "bogus"}, "render_mode"),
    ):
        with warnings.catch_warnings():  # gymnasium warns of the bogus render_mode first
            warnings.simplefilter("ignore")
            msg = _expect_value_error(what, target.make, **kwargs)
        assert needle in msg, f"the error for {what} does not name {needle!r}: {msg!r}"
    msg = _expect_value_error("an unknown reset() option", env.reset, options={"no_such": 1})
    assert "no_such" in msg, f"the error for an unknown reset option does not name it: {msg!r}"
    _expect_value_error(
        "reset() options with keys of mixed types", env.reset, options={1: 0, "no_such": 1}
    )
    _expect_value_error("reset() options that are not a dict", env.reset, options="ab")
    params_cls = type(env.unwrapped.plant.params)
    defaults = params_cls()
    for f in dataclasses.fields(params_cls):
        v = getattr(defaults, f.name)
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            msg = _expect_value_error(
                f"params {{{f.name!r}: nan}}", target.make, params={f.name: float("nan")}
            )
            assert f.name in msg, f"the error for a NaN {f.name} does not name it: {msg!r}"
        if isinstance(v, float) and v > 0:
            _expect_value_error(
                f"params {{{f.name!r}: -1e12}}", target.make, params={f.name: -1e12}
            )


def _vector_bad_actions(target: EnvTarget, n_u: int) -> None:
    n = n_u + 1  # transposed actions then have another shape
    venv, twin = (target.make_vec(n, scenario="setpoint_step") for _ in range(2))
    venv.reset(seed=0)
    twin.reset(seed=0)
    nan_row = np.zeros((n, n_u))
    nan_row[1] = np.nan
    for what, bad in (
        ("transposed, shape (n_actuators, num_envs)", np.zeros((n_u, n))),
        ("flattened", np.zeros(n * n_u)),
        ("one row", np.zeros(n_u)),
        ("NaN in one row", nan_row),
    ):
        msg = _expect_value_error(f"vector env action {what}", venv.step, bad)
        assert "action" in msg, f"the error for vector action {what} does not say 'action'"
    a = np.full((n, n_u), 0.2, dtype=np.float32)
    o1, r1, *_ = venv.step(a)
    o2, r2, *_ = twin.step(a)
    assert np.array_equal(o1, o2) and np.array_equal(r1, r2), (
        "rejected actions changed the vector env"
    )
    _expect_value_error("an unknown vector reset() option", venv.reset, options={"no_such": 1})
    _expect_value_error("vector reset() options that are not a dict", venv.reset, options="ab")


@env_check
def check_physical_under_random_and_corner_runs(target: EnvTarget, quick: bool = False) -> None:
    """Random scenarios (vector env) and corner-biased ones (scenarios/stress.py), both under
    random-walk and bang-bang actions: every observation and reward finite, observations in
    the transmitter range, steam temperatures in (100, 900) C, valves in [0, 1], spray >= 0,
    and no ``non_finite_state`` trip."""
    n, steps = (8, 300) if quick else (32, 1500)
    venv = target.make_vec(n, scenario="random")
    venv.reset(seed=123)
    rng = np.random.default_rng(1)
    a = np.zeros(venv.action_space.shape, dtype=np.float32)
    for k in range(steps):
        a = motion(rng, a, k)
        obs, r, term, trunc, info = venv.step(a)
        _assert_physical(
            obs,
            r,
            info,
            f"(vector env, {n} rows, scenario random, seed 123, actions rng 1, step {k + 1})",
        )
    rng = np.random.default_rng(2)
    n_corners, rejected = (4 if quick else 16), 0
    for c in range(n_corners):
        while True:
            sc = corner_scenario(rng)
            env = target.make(scenario=sc)
            try:
                env.reset(seed=c)
                break
            except ValueError:  # a start the plant cannot hold: refused, redraw
                rejected += 1
                assert rejected < 20 * n_corners, "almost every corner scenario is refused"
        a = np.zeros(env.action_space.shape, dtype=np.float32)
        for k in range(300):
            a = motion(rng, a, k)
            obs, r, term, trunc, info = env.step(a)
            _assert_physical(
                obs,
                r,
                info,
                f"(corner scenario {c} of steamtemp_gym.scenarios."
                f"stress.corner_scenario(np.random.default_rng(2)) "
                f"draws, seed {c}, step {k + 1}): {sc}",
            )
            if term or trunc:
                break


def _assert_physical(obs: np.ndarray, r: Any, info: dict, where: str) -> None:
    assert np.all(np.isfinite(obs)) and np.all(np.isfinite(r)), f"non-finite value {where}"
    assert np.all(np.abs(obs) <= OBS_LIMIT), f"observation outside +-{OBS_LIMIT} {where}"
    t = np.asarray(info["outlet_temp_C"])
    assert np.all((t > STEAM_C[0]) & (t < STEAM_C[1])), f"outlet temperature {t} C {where}"
    v = np.asarray(info["spray_valve"])
    assert np.all((v >= 0.0) & (v <= 1.0)), f"valve opening {v} outside [0, 1] {where}"
    assert np.all(np.asarray(info["spray_flow_kg_s"]) >= 0.0), f"negative spray flow {where}"
    assert not np.any(np.asarray(info["trip_reason"]) == TRIP_REASONS[-1]), (
        f"the plant left its valid region (non_finite_state trip) {where}"
    )


@env_check
def check_render_frame(target: EnvTarget, quick: bool = False) -> None:
    """``render_mode="rgb_array"`` gives a uint8 frame of :data:`FRAME_SHAPE` with a trend
    drawn on it, the same shape every call; without a render mode ``render()`` is None."""
    env = target.make(scenario="setpoint_step", render_mode="rgb_array")
    env.reset(seed=0)
    for k in range(2):
        for _ in range(5):
            env.step(env.action_space.sample())
        img = env.render()
        assert isinstance(img, np.ndarray) and img.dtype == np.uint8, (
            f"render() gave {type(img).__name__} {getattr(img, 'dtype', '')}, not uint8"
        )
        assert img.shape == FRAME_SHAPE, f"frame shape {img.shape} != {FRAME_SHAPE} (call {k})"
        assert img.std() > 5, "the frame is blank"
    plain = target.make(scenario="setpoint_step")
    plain.reset(seed=0)
    assert plain.render() is None, "render() without a render_mode must return None"
