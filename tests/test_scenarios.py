"""Scenarios: named ones, the random training distribution, schedule evaluation in the kernel."""

import numpy as np
import pytest

from steamtemp_gym import scenarios
from steamtemp_gym.envs.core import eval_schedules
from steamtemp_gym.scenarios import RANDOM_DISTRIBUTION as DIST
from steamtemp_gym.scenarios import Scenario


def test_paper_load_ramp():
    s = scenarios.get("load_ramp_100_50")
    assert s.duration_s >= 3600
    assert s.value("load", 20 * 60) == 1.0 and s.value("load", 30 * 60) == 0.5
    assert s.value("load", 25 * 60) == pytest.approx(0.75)  # 5 %/min


@pytest.mark.parametrize("seed", range(40))
def test_random_scenarios_respect_the_documented_distribution(seed):
    s = scenarios.random_scenario(np.random.default_rng(seed))
    pts = np.array(s.load)
    lo, hi = DIST["load_range"]
    assert np.all((pts[:, 1] >= min(lo, DIST["initial_load"][0])) & (pts[:, 1] <= hi))
    dt, dl = np.diff(pts[:, 0]), np.abs(np.diff(pts[:, 1]))
    rates = dl[dt > 0] / dt[dt > 0] * 60.0
    assert np.all(rates <= DIST["ramp_rate_per_min"][1] + 1e-12)
    for name in ("noise_std_C", "heat_absorption_noise_std", "heat_absorption_noise_tau_s"):
        assert DIST[name][0] <= getattr(s, name) <= DIST[name][1]
    assert DIST["fouling"][0] <= s.value("fouling", 0.0) <= DIST["fouling"][1]


def test_random_is_seeded():
    a = scenarios.random_scenario(np.random.default_rng(7))
    b = scenarios.random_scenario(np.random.default_rng(7))
    c = scenarios.random_scenario(np.random.default_rng(8))
    assert a == b and a != c


def test_kernel_schedule_matches_python_interpolation():
    s = Scenario(
        name="x",
        duration_s=100.0,
        load=((0, 1.0), (10, 1.0), (30, 0.6), (30, 0.7)),
        setpoint_offset_C=((0, 0), (50, 0), (50, 5)),
        fouling=((0, 1.0), (100, 1.2)),
    )
    bp_t, bp_v, bp_n = np.zeros((1, 5, 8)), np.zeros((1, 5, 8)), np.ones((1, 5), np.int64)
    scenarios.pack(s, bp_t[0], bp_v[0], bp_n[0])
    D, sp, ou = np.zeros((1, 5)), np.zeros(1), np.zeros(1)
    for t in (0.0, 5.0, 20.0, 29.9, 30.0, 45.0, 50.0, 80.0, 200.0):
        eval_schedules(0, t, bp_t, bp_v, bp_n, 500.0, ou, D, sp)
        if t != 30.0:
            assert D[0, 0] == pytest.approx(s.value("load", t))
        assert D[0, 3] == pytest.approx(s.value("fouling", t))
        assert sp[0] == pytest.approx(500.0 + (5.0 if t >= 50 else 0.0))
    eval_schedules(0, 20.0, bp_t, bp_v, bp_n, 500.0, ou, D, sp)
    assert D[0, 1] == pytest.approx(-0.4 / 20.0)  # load slope (1/s) for the plants' feed-forward


def test_invalid_scenarios_raise():
    with pytest.raises(ValueError, match="duration_s"):
        Scenario(name="x", duration_s=-1.0)
    with pytest.raises(ValueError, match="fouling"):
        Scenario(name="x", duration_s=10.0, fouling=((0, -1.0),))
    with pytest.raises(ValueError, match="noise"):
        Scenario(name="x", duration_s=10.0, noise_std_C=float("nan"))
    with pytest.raises(ValueError, match="heat_absorption_noise_std"):
        Scenario(name="x", duration_s=10.0, heat_absorption_noise_std=0.5)
    with pytest.raises(ValueError, match="heat_absorption_noise_tau_s"):
        Scenario(name="x", duration_s=10.0, heat_absorption_noise_tau_s=0.0)
    with pytest.raises(ValueError, match="noise_std_C"):
        Scenario.from_dict({"name": "x", "duration_s": 10, "load": 1.0, "noise_std_C": "a"})
    with pytest.raises(ValueError, match="reserved"):
        scenarios.register(Scenario(name="random", duration_s=10.0))


def test_named_scenarios_carry_the_disturbances_of_real_operation():
    for name in scenarios.names():
        if name != scenarios.RANDOM:
            s = scenarios.get(name)
            for field, value in scenarios.NAMED_DISTURBANCES.items():
                assert getattr(s, field) == value, (name, field)
    s = Scenario(name="x", duration_s=10.0)  # left out: none of that disturbance
    assert s.noise_std_C == 0.0 and s.heat_absorption_noise_std == 0.0
    again = Scenario.from_dict({k: v for k, v in scenarios.get("load_cycle").to_dict().items()})
    assert again == scenarios.get("load_cycle")  # the YAML form keeps the new fields


def test_coloured_heat_absorption_is_an_ornstein_uhlenbeck_process():
    """Stationary std and autocorrelation exp(-lag dt / tau) of what the plant receives."""
    import gymnasium as gym

    std, tau = 0.03, 60.0
    sc = Scenario(name="ou", duration_s=4000.0, load=1.0, heat_absorption_bias=0.01,
                  heat_absorption_noise_std=std, heat_absorption_noise_tau_s=tau)  # fmt: skip
    venv = gym.make_vec("steamtemp/Cascade300MW-v0", num_envs=64,
                        vectorization_mode="vector_entry_point", scenario=sc)  # fmt: skip
    venv.reset(seed=0)
    core = venv.unwrapped.core
    a = np.zeros((64, 1), np.float32)
    x = [core.D[:, 2].copy()]
    for _ in range(3000):
        venv.step(a)
        x.append(core.D[:, 2].copy())
    x = np.array(x) - 0.01  # the scheduled bias plus the coloured part
    assert np.mean(x) == pytest.approx(0.0, abs=0.004)
    assert np.std(x) == pytest.approx(std, rel=0.05)  # stationary from the reset on
    assert np.std(x[0]) == pytest.approx(std, rel=0.3)
    for lag in (1, 60, 120):
        acf = np.mean(x[:-lag] * x[lag:]) / std**2
        assert acf == pytest.approx(np.exp(-lag / tau), abs=0.06)
