"""Hardening: no NaN reaches an agent, bounded and typed inputs, exact shapes.

Registry-wide where the behaviour is generic; each defect found is a test here.
"""

from __future__ import annotations

from fractions import Fraction

import gymnasium as gym
import numpy as np
import pytest

import steamtemp_gym
from steamtemp_gym import plants
from steamtemp_gym.envs.corners import run_corners
from steamtemp_gym.envs.cost import interval_cost
from steamtemp_gym.envs.kernels import TRIP_REASONS
from steamtemp_gym.rewards import RewardConfig
from steamtemp_gym.scenarios import Scenario

IDS = steamtemp_gym.ENV_IDS
BENSON = "steamtemp/BensonSubcritical-v0"
CASCADE = "steamtemp/Cascade300MW-v0"


def _vec(env_id, n, **kw):
    return gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point", **kw)


# ------------------------------------------------------------------ 1. NaN never observed
def test_benson_low_load_cold_steam_stays_finite():
    """110 % -> 20 % with -40 % heat absorption and a -40 K setpoint: the HP exhaust falls
    below saturation; it is taken as dry-saturated steam at worst, never as water (which
    made the reheat NaN)."""
    sc = Scenario(
        name="r",
        duration_s=1800,
        load=[[0, 1.1], [394, 0.2]],
        heat_absorption_bias=[[0, 0.0], [100, -0.25]],
        setpoint_offset_C=[[0, 0.0], [100, -25.0]],
    )
    env = gym.make(BENSON, scenario=sc)
    env.reset(seed=0)
    core = env.unwrapped.core
    for _ in range(360):
        obs, r, term, trunc, info = env.step(np.zeros(2, dtype=np.float32))
        assert np.all(np.isfinite(obs)) and np.isfinite(r)
        assert np.all(np.isfinite(core.X)) and np.all(np.isfinite(core.Z))
        assert info["reheat_temp_C"] > 150.0  # never the table's 10 C floor (water)
        if term or trunc:
            break


@pytest.mark.parametrize("env_id", IDS)
def test_non_finite_state_is_a_documented_trip(env_id):
    """A plant leaving its valid region ends the episode: terminated, info says why, the
    observation and reward are finite; the vector env's other rows are untouched."""
    venv = _vec(env_id, 2, scenario="load_ramp_100_50")
    venv.reset(seed=0)
    a = np.zeros(venv.action_space.shape, dtype=np.float32)
    venv.step(a)
    ref = _vec(env_id, 2, scenario="load_ramp_100_50")
    ref.reset(seed=0)
    ref.step(a)
    venv.unwrapped.core.X[1, :] = np.nan  # row 1's physics breaks down
    obs, r, term, trunc, info = venv.step(a)
    obs_ref, r_ref, *_ = ref.step(a)
    assert term.tolist() == [False, True]
    assert info["trip_reason"][1] == "non_finite_state" and info["trip_reason"][0] == ""
    assert np.all(np.isfinite(obs)) and np.all(np.isfinite(r))
    assert r[1] <= -RewardConfig().trip_penalty
    np.testing.assert_array_equal(obs[0], obs_ref[0])
    assert r[0] == r_ref[0]
    obs, r, term, *_ = venv.step(a)  # autoreset: row 1 starts afresh, finite
    assert np.all(np.isfinite(venv.unwrapped.core.X)) and not term.any()


@pytest.mark.parametrize("env_id", IDS)
def test_trip_reasons_name_the_band_side(env_id):
    env = gym.make(env_id, scenario=Scenario(name="hot", duration_s=3600.0, load=0.75))
    _, info = env.reset(seed=0)
    assert info["trip_reason"] == ""
    closed = -np.ones(env.action_space.shape, dtype=np.float32)
    for _ in range(3600):
        *_, term, trunc, info = env.step(closed)
        if term or trunc:
            break
    # sprays closed: the outlet overheats, unless the plant holds it with its design spray
    assert info["trip_reason"] in ("", "outlet_above_trip_band")
    assert term == (info["trip_reason"] != "")


@pytest.mark.parametrize("env_id", IDS)
def test_corner_scenarios_never_give_non_finite_values(env_id):
    """Corner-biased scenarios (loads at the range ends, biases and fouling at their
    limits, jumps and fast ramps) under random-walk and bang-bang actions: 0 non-finite
    observations or rewards, observations within the transmitter range, valves in [0, 1].
    (benchmarks/fuzz_corners.py runs the same for longer.)"""
    c = run_corners(env_id, num_envs=8, steps=300, seed=1)
    assert c["steps"] == 2400
    assert c["non_finite"] == 0 and c["out_of_range"] == 0, c
    assert c["trips"]["non_finite_state"] == 0, c
    assert c["episodes"] >= 8


# ------------------------------------------------------ 2. scenarios that cannot start
def test_scenario_the_plant_cannot_start_is_rejected_with_the_value():
    env = gym.make(
        "steamtemp/DrumBoilerSH-v0", scenario=Scenario(name="slagged", duration_s=60.0, fouling=0.6)
    )
    with pytest.raises(ValueError, match=r"cannot start.*fouling = 0\.6"):
        env.reset(seed=0)
    with pytest.raises(RuntimeError, match="reset"):  # nothing half-started
        env.step(np.zeros(1, dtype=np.float32))


@pytest.mark.parametrize("env_id", IDS)
def test_every_start_is_a_steady_state_near_the_setpoint(env_id):
    """Named and random scenarios start within START_BAND_K of the setpoint (no trip at
    the first step, whatever the action)."""
    from steamtemp_gym.envs.start import START_BAND_K

    venv = _vec(env_id, 16, scenario="random")
    _, info = venv.reset(seed=5)
    e = info["setpoint_C"] - info["outlet_temp_C"]
    assert np.all(np.abs(e) <= START_BAND_K + 3 * 0.04 * 40)  # + the coloured disturbance


# ---------------------------------------------------------------- 4. action shapes, types
@pytest.mark.parametrize("env_id", [BENSON, "steamtemp/DrumBoilerSH-v0"])
def test_action_shapes_are_exact(env_id):
    venv = _vec(env_id, 3, scenario="setpoint_step")
    venv.reset(seed=0)
    n_u = venv.single_action_space.shape[0]
    before = venv.unwrapped.core.X.copy()
    for shape in [(n_u, 3), (3 * n_u,), (1, 3, n_u), (3,), (3, n_u + 1)]:
        if shape == (3, n_u):
            continue
        with pytest.raises(ValueError, match=rf"expected \(3, {n_u}\)"):
            venv.step(np.zeros(shape))
    np.testing.assert_array_equal(venv.unwrapped.core.X, before)
    venv.step(np.zeros((3, n_u)))
    env = gym.make(env_id, scenario="setpoint_step")
    env.reset(seed=0)
    with pytest.raises(ValueError, match=rf"expected \({n_u},\)"):
        env.step(np.zeros((1, n_u)))
    env.step(np.zeros(n_u))


def test_action_dtypes():
    env = gym.make(BENSON, scenario="setpoint_step")
    ref = gym.make(BENSON, scenario="setpoint_step")
    env.reset(seed=0)
    ref.reset(seed=0)
    for dtype in (np.float16, np.float32, np.float64, np.longdouble, np.int8, np.int64):
        a = np.array([0.0, 1.0]).astype(dtype)
        o1 = env.step(a)[0]
        o2 = ref.step(np.array([0.0, 1.0]))[0]
        np.testing.assert_array_equal(o1, o2)
    for bad in (
        ["0.5", "0.5"],
        np.array([1 + 0j, 0j]),
        np.array([True, False]),
        np.array([None, None]),
        [[0.1], [0.2, 0.3]],
    ):
        with pytest.raises(ValueError, match="action"):
            env.step(bad)


def test_action_of_any_byte_order_is_accepted():
    """Big-endian float actions step as the same values in native order, through both
    paths of check_action (single env, vector env)."""
    env, ref = (gym.make(CASCADE, scenario="setpoint_step") for _ in range(2))
    venv, vref = (_vec(CASCADE, 2, scenario="setpoint_step") for _ in range(2))
    for e in (env, ref, venv, vref):
        e.reset(seed=0)
    for dtype in (">f8", ">f4", "<f8"):
        native = np.dtype(dtype).newbyteorder("=")
        a, b = np.array([0.3], dtype=dtype), np.array([[0.3], [-0.2]], dtype=dtype)
        np.testing.assert_array_equal(env.step(a)[0], ref.step(a.astype(native))[0])
        np.testing.assert_array_equal(venv.step(b)[0], vref.step(b.astype(native))[0])


def test_masked_actions_are_refused_unless_nothing_is_masked():
    env, ref = (gym.make(CASCADE, scenario="setpoint_step") for _ in range(2))
    env.reset(seed=0)
    ref.reset(seed=0)
    with pytest.raises(ValueError, match="1 masked entries"):
        env.step(np.ma.masked_array([0.3], mask=[True]))
    venv = _vec(CASCADE, 2, scenario="setpoint_step")
    venv.reset(seed=0)
    with pytest.raises(ValueError, match="1 masked entries"):
        venv.step(np.ma.masked_array([[0.3], [0.2]], mask=[[False], [True]]))
    np.testing.assert_array_equal(
        env.step(np.ma.masked_array([0.3], mask=[False]))[0], ref.step(np.array([0.3]))[0]
    )


def test_integers_beyond_int64_are_actions_and_tensors_are_refused_with_value_error():
    env, ref = (gym.make(CASCADE, scenario="setpoint_step") for _ in range(2))
    env.reset(seed=0)
    ref.reset(seed=0)
    for big in (10**30, [10**30]):  # clipped to the valve's stop, as 1 is
        np.testing.assert_array_equal(env.step(big)[0], ref.step(np.array([1.0]))[0])
    with pytest.raises(ValueError, match="float range"):
        env.step([10**400])
    torch = pytest.importorskip("torch")
    with pytest.raises(ValueError, match="action must be an array.*RuntimeError"):
        env.step(torch.tensor([0.3], requires_grad=True))


def test_reset_options_and_num_envs_are_checked_with_value_error():
    env = gym.make(CASCADE, scenario="setpoint_step")
    with pytest.raises(ValueError, match=r"option\(s\) \['a', 1\]; valid: \['scenario'\]"):
        env.reset(options={1: 0, "a": 0})
    with pytest.raises(ValueError, match="must be a dict or None, got str"):
        env.reset(options="ab")
    venv = _vec(CASCADE, 2, scenario="setpoint_step")
    with pytest.raises(ValueError, match="must be a dict or None, got str"):
        venv.reset(options="ab")
    with pytest.raises(ValueError, match=r"unknown reset option\(s\) \['a', 1\]"):
        venv.reset(options={1: 0, "a": 0})
    with pytest.raises(ValueError, match="num_envs must be a positive integer, got True"):
        _vec(CASCADE, True)


# ------------------------------------------------------- 5./6. parameter types and bounds
@pytest.mark.parametrize(
    "env_id, params, match",
    [
        ("steamtemp/SupercriticalFSH-v0", {"dt_s": "2"}, "dt_s must be of type float"),
        ("steamtemp/SupercriticalFSH-v0", {"dt_s": None}, "dt_s must be of type float"),
        ("steamtemp/DrumBoilerSH-v0", {"n_segments": 2.5}, "n_segments must be of type int"),
        ("steamtemp/DrumBoilerSH-v0", {"n_segments": True}, "n_segments must be of type int"),
        ("steamtemp/BoilerTurbineMIMO-v0", {"fuel_bias_action": "no"}, "fuel_bias_action"),
        ("steamtemp/Cascade300MW-v0", {"load_dependent": "False"}, "load_dependent"),
        ("steamtemp/SupercriticalFSH-v0", {"n_substeps": 2.5}, "n_substeps"),
        ("steamtemp/SupercriticalFSH-v0", {"n_substeps": 10**6}, "n_substeps"),
        ("steamtemp/BensonSubcritical-v0", {"dt_s": 1e6}, "dt_s"),
        ("steamtemp/SupercriticalFSH-v0", {"tube_length_m": 1e9}, "tube_length_m"),
        ("steamtemp/SupercriticalFSH-v0", {"n_segments": 2**70}, "n_segments .*physical range"),
        ("steamtemp/SupercriticalFSH-v0", {"dt_s": 10**400}, "dt_s must be finite"),
        ("steamtemp/SupercriticalFSH-v0", {"tube_length_m": Fraction(10**12)}, "tube_length_m"),
        ("steamtemp/Cascade300MW-v0", {1: 0.0, "dt_s": 1.0}, "names must be strings, got 1"),
    ],
)
def test_parameters_are_typed_and_bounded(env_id, params, match):
    with pytest.raises(ValueError, match=match):
        gym.make(env_id, params=params)


def test_parameters_accept_numpy_numbers():
    p = plants.make("steamtemp/Cascade300MW-v0", dt_s=np.float32(1.0), lead_order=np.int64(2))
    assert p.dt_s == 1.0


@pytest.mark.parametrize(
    "reward, match",
    [
        ({"w_abs": 1e308}, "w_abs"),
        ({"T0_K": 1e-200}, "T0_K"),
        ({"trip_penalty": -1}, "trip"),
        ({"w_move": True}, "w_move"),
        ({"band_K": "5"}, "band_K"),
        ({"w_sq": float("inf")}, "w_sq"),
        ({"w_abs": Fraction(10**9)}, "w_abs"),
        ({"w_abs": 10**400}, "w_abs"),
        ({1: 0.0, "a": 0.0}, r"unknown reward option\(s\) \['a', 1\]"),
    ],
)
def test_reward_options_are_bounded(reward, match):
    with pytest.raises(ValueError, match=match):
        gym.make(IDS[0], reward=reward)


def test_reward_options_accept_any_real_number():
    a = gym.make(CASCADE, scenario="setpoint_step", reward={"w_abs": Fraction(1, 2)})
    b = gym.make(CASCADE, scenario="setpoint_step", reward={"w_abs": 0.5})
    a.reset(seed=0)
    b.reset(seed=0)
    assert a.step(np.array([0.1]))[1] == b.step(np.array([0.1]))[1]


def test_reward_is_finite_at_the_largest_accepted_weights():
    import dataclasses

    from steamtemp_gym.rewards import MAX_WEIGHT, RewardConfig

    ranges = {f.name: f.metadata["range"] for f in dataclasses.fields(RewardConfig)}
    big = {f: MAX_WEIGHT for f in ("w_abs", "w_sq", "w_band", "w_spray", "w_move", "w_secondary")}
    assert all(ranges[f][1] == MAX_WEIGHT for f in big)
    big.update(T0_K=ranges["T0_K"][0], trip_penalty=ranges["trip_penalty"][1], band_K=0.0)
    env = gym.make("steamtemp/Cascade300MW-v0", scenario="load_ramp_100_50", reward=big)
    env.reset(seed=0)
    for k in range(600):
        a = np.array([1.0 if (k // 20) % 2 else -1.0], dtype=np.float32)
        _, r, term, trunc, _ = env.step(a)
        assert np.isfinite(r)
        if term or trunc:
            break


# ------------------------------------------------------------------------------ 7. time
def test_time_is_counted_not_summed():
    sc = Scenario(name="hour", duration_s=3600.0, load=1.0)
    env = gym.make("steamtemp/Cascade300MW-v0", scenario=sc, params={"dt_s": 0.1})
    env.reset(seed=0)
    a = np.zeros(1, dtype=np.float32)
    n = 0
    while True:
        *_, term, trunc, info = env.step(a)
        n += 1
        if term or trunc:
            break
    assert n == 36000 and info["time_s"] == 36000 * 0.1


# ------------------------------------------------------------------- 9. vector env API
def test_vector_reset_seeds_of_any_integer_type():
    venv = _vec(IDS[-1], 3, scenario="random")
    o1, _ = venv.reset(seed=np.int64(3))
    o2, _ = venv.reset(seed=3)
    np.testing.assert_array_equal(o1, o2)
    o3, _ = venv.reset(seed=[np.int32(3), np.uint8(4), 5])
    np.testing.assert_array_equal(o1, o3)
    for bad in (-1, 2.5, "3", [1, 2], True):
        with pytest.raises(ValueError, match="seed"):
            venv.reset(seed=bad)


def test_vector_partial_reset_and_independent_info_masks():
    venv = _vec(IDS[-1], 3, scenario="load_ramp_100_50")
    venv.reset(seed=0)
    a = np.zeros(venv.action_space.shape, dtype=np.float32)
    for _ in range(5):
        obs_before, *_ = venv.step(a)
    mask = np.array([False, True, False])
    obs, info = venv.reset(seed=[None, 11, None], options={"reset_mask": mask})
    np.testing.assert_array_equal(obs[[0, 2]], obs_before[[0, 2]])
    assert info["time_s"][1] == 0.0 and info["time_s"][0] > 0
    assert info["_time_s"].tolist() == [False, True, False]
    info["_time_s"][0] = True  # masks are independent arrays
    assert not info["_load"][0]
    ref = _vec(IDS[-1], 3, scenario="load_ramp_100_50")
    ref_obs, _ = ref.reset(seed=[0, 11, 2])
    np.testing.assert_array_equal(obs[1], ref_obs[1])  # as a fresh reset with that seed
    for bad in (np.array([1, 0, 1]), np.array([True, False]), [True, False, True]):
        with pytest.raises(ValueError, match="reset_mask"):
            venv.reset(options={"reset_mask": bad})
    with pytest.raises(ValueError, match="unknown reset option"):
        venv.reset(options={"foo": 1})


# -------------------------------------------------------------------- 10. sensor in info
@pytest.mark.parametrize("env_id", IDS)
def test_info_reports_what_the_sensor_reported(env_id):
    env = gym.make(env_id, scenario="setpoint_step")
    obs, info = env.reset(seed=0)
    sig = env.unwrapped.signals
    for _ in range(3):
        obs, *_, info = env.step(np.zeros(env.action_space.shape, dtype=np.float32))
        meas = sig.decode(obs)[env.unwrapped.plant.outlet_measured]
        assert info["measured_temp_C"] == pytest.approx(meas, abs=1e-9)
        assert info["measured_temp_C"] != info["measured_temp_noise_free_C"]  # noise 0.25 K


@pytest.mark.parametrize("env_id", IDS)
def test_info_carries_each_rows_own_values(env_id):
    """Single-env and vector info (written by the compiled step and by reset) hold row b's
    outputs, reading, time, setpoint, load, spray and constraint cost, after a reset and
    after steps."""
    sc = Scenario(
        name="distinct",
        duration_s=600.0,
        load=((0.0, 0.85), (600.0, 0.8)),
        fouling=((0.0, 1.05),),
        setpoint_offset_C=((0.0, 0.0), (600.0, -3.0)),
    )
    venv = _vec(env_id, 2, scenario=sc)
    _, vinfo = venv.reset(seed=0)
    core = venv.unwrapped.core
    plant = core.plant
    idx = plant.index
    a = np.zeros(venv.action_space.shape, dtype=np.float32)
    prev_error = [None, None]  # the outlet's error at the last info: the interval's cost
    for k in range(3):
        for b in range(2):
            z, row = core.Z[b], core.info_row(b)
            error = z[idx[plant.outlet]] - core.sp[b]
            cost = 0.0 if prev_error[b] is None else interval_cost(prev_error[b], error)
            prev_error[b] = error
            expect = {
                "outlet_temp_C": z[idx[plant.outlet]],
                "measured_temp_noise_free_C": z[idx[plant.outlet_measured]],
                "measured_temp_C": core.meas[b],
                "time_s": k * plant.dt_s,
                "setpoint_C": core.sp[b],
                "load": core.D[b, 0],
                "spray_flow_kg_s": sum(z[idx[s]] for s in plant.sprays),
                "trip_reason": "",
                "cost": cost,
                "cost_band": cost,
            }
            expect.update({name: z[idx[name]] for name in plant.extra_info})
            valves = [z[idx[v]] for v in plant.valves]
            expect["spray_valve"] = valves[0] if len(valves) == 1 else np.array(valves)
            assert row.keys() == expect.keys() == {k for k in vinfo if not k.startswith("_")}
            for key, value in expect.items():
                np.testing.assert_array_equal(row[key], value, err_msg=key)
                np.testing.assert_array_equal(vinfo[key][b], value, err_msg=key)
        kept = {key: np.copy(v) for key, v in vinfo.items()}
        kept_row = {key: np.copy(v) for key, v in row.items()}
        _, _, _, _, vinfo_next = venv.step(a)
        row_next = core.info_row(1)
        for key in kept:  # a step writes fresh arrays, it does not change those handed out
            np.testing.assert_array_equal(vinfo[key], kept[key], err_msg=key)
        for key in kept_row:
            np.testing.assert_array_equal(row[key], kept_row[key], err_msg=key)
        assert row_next["time_s"] != row["time_s"]
        vinfo = vinfo_next


@pytest.mark.parametrize("copier", ["pickle", "deepcopy"])
def test_a_copied_env_steps_as_the_original(copier):
    """Pickle and deepcopy drop the compiled entry points and the info dict maker and make
    them again: the copy's observations, rewards and info equal the original's."""
    import copy
    import pickle

    env = gym.make("steamtemp/BoilerTurbineMIMO-v0", scenario="load_following").unwrapped
    env.reset(seed=3)
    a = np.full(env.action_space.shape, 0.1, dtype=np.float32)
    env.step(a)  # the entry points exist now
    twin = pickle.loads(pickle.dumps(env)) if copier == "pickle" else copy.deepcopy(env)
    for _ in range(3):
        obs, r, term, trunc, info = env.step(a)
        obs2, r2, term2, trunc2, info2 = twin.step(a)
        np.testing.assert_array_equal(obs, obs2)
        assert (r, term, trunc) == (r2, term2, trunc2)
        assert info.keys() == info2.keys()
        for key in info:
            np.testing.assert_array_equal(info[key], info2[key], err_msg=key)


# -------------------------------------------------------- 3. tables shared across rows
def test_schedule_tables_are_shared_across_rows():
    n = 10_000
    ts = np.linspace(0.0, 3600.0, n)
    sc = Scenario(
        name="dense",
        duration_s=3600.0,
        load=tuple(zip(ts, 0.8 + 0.1 * np.sin(ts / 300.0), strict=True)),
    )
    venv = _vec("steamtemp/Cascade300MW-v0", 256, scenario=sc)
    venv.reset(seed=0)
    core = venv.unwrapped.core
    assert core.bp_t.shape[0] == 1 and core.bp_t.nbytes < 1_000_000
    venv.step(np.zeros(venv.action_space.shape))
    assert TRIP_REASONS[0] == ""


def test_a_plant_class_with_its_own_step_is_stepped_through_it():
    """Core calls the kernel directly with prebuilt arguments for few rows; a plant whose
    class overrides ``step`` (e.g. a user's wrapper) must still be stepped through it."""
    from steamtemp_gym.envs.core import Core
    from steamtemp_gym.scenarios import get

    base = plants.plant_class("steamtemp/Cascade300MW-v0")
    calls = []

    class Counted(base):
        def step(self, X, U, D, Z, dt=None):
            calls.append(X.shape[0])
            super().step(X, U, D, Z, dt)

    for cls, expected in ((Counted, 3), (base, 0)):
        calls.clear()
        core = Core(cls(), 1, RewardConfig())
        core.reset_row(0, get("setpoint_step"), 7)
        n_reset = len(calls)
        for _ in range(3):
            core.step(np.zeros((1, core.plant.n_u)))
        assert len(calls) - n_reset == expected
