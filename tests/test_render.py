"""The trend display: traces land where their values are, the display is incremental."""

from __future__ import annotations

import numpy as np
import pytest

from steamtemp_gym.envs.render import HEIGHT, WIDTH, TrendDisplay


def _info(t: float, temp: float, sp: float = 540.0, valve=(0.5,)) -> dict:
    return {
        "time_s": t,
        "outlet_temp_C": temp,
        "measured_temp_C": temp,
        "setpoint_C": sp,
        "load": 0.8,
        "spray_flow_kg_s": 5.0,
        "spray_valve": np.array(valve),
    }


def test_traces_land_on_their_values_and_frames_are_copies():
    d = TrendDisplay("test", 600.0, _info(0.0, 540.0), spray_max_kg_s=20.0, valve_names=("spray",))
    first = d.frame()
    assert first.shape == (HEIGHT, WIDTH, 3) and first.dtype == np.uint8
    for k in range(1, 61):
        d.add(_info(10.0 * k, 540.0 + 20.0 * (k >= 30)))  # a 20 K step at 5 min
    img = d.frame()
    temp = d.axes[0]
    red = np.array([214, 39, 40])  # tab:red, the true outlet
    col = round(temp.x(8.0))  # minute 8: after the step
    rows = np.flatnonzero(np.all(img[:, col] == red, axis=1))
    assert rows.size and abs(rows.mean() - temp.y(560.0)) <= 1.5
    col = round(temp.x(2.0))
    rows = np.flatnonzero(np.all(img[:, col] == red, axis=1))
    assert rows.size and abs(rows.mean() - temp.y(540.0)) <= 1.5
    # the step is joined: the columns of its segment (4:50 to 5:00) span the whole rise
    cols = slice(round(temp.x(290 / 60)), round(temp.x(5.0)) + 1)
    rows = np.flatnonzero(np.all(img[:, cols] == red, axis=2).any(axis=1))
    assert rows.max() - rows.min() >= abs(temp.y(560.0) - temp.y(540.0)) - 2
    # beyond the current time nothing is drawn yet
    later = slice(round(temp.x(10.0)) + 2, None)
    assert np.array_equal(img[:, later], d.background[:, later])
    img[:] = 0  # frame() returned a copy
    assert d.frame().any()


def test_values_outside_the_axis_are_drawn_at_its_edge():
    d = TrendDisplay("test", 600.0, _info(0.0, 540.0), spray_max_kg_s=20.0)
    d.add(_info(60.0, float("nan")))
    d.add(_info(120.0, 900.0))
    temp = d.axes[0]
    col = round(temp.x(2.0))
    red = np.array([214, 39, 40])
    rows = np.flatnonzero(np.all(d.frame()[:, col] == red, axis=1))
    assert rows.size and rows.min() >= temp.rows[0] - 1


def test_render_before_reset_is_an_error():
    import gymnasium as gym

    import steamtemp_gym  # noqa: F401

    env = gym.make("steamtemp/Cascade300MW-v0", render_mode="rgb_array")
    with pytest.raises(RuntimeError, match="reset"):
        env.unwrapped.render()


def test_secondary_temperatures_have_their_own_panel():
    first = dict(_info(0.0, 540.0, valve=(0.5, 0.5, 0.3)), reheat_temp_C=566.0)
    d = TrendDisplay(
        "test",
        600.0,
        first,
        spray_max_kg_s=20.0,
        valve_names=("SP1", "SP2", "RGD"),
        secondary=(("reheat_temp_C", 566.0),),
    )
    for k in range(1, 61):
        d.add(
            dict(
                _info(10.0 * k, 540.0, valve=(0.5, 0.5, 0.3)),
                reheat_temp_C=566.0 - 15.0 * (k >= 30),
            )
        )  # a 15 K drop at 5 min
    temp, reheat, load, act, spray = d.axes
    assert reheat.top > temp.bottom and load.top > reheat.bottom
    red = np.array([214, 39, 40])
    img = d.frame()
    col = round(reheat.x(8.0))
    rows = np.flatnonzero(np.all(img[:, col] == red, axis=1))
    rows = rows[(rows >= reheat.rows[0]) & (rows <= reheat.rows[1])]
    assert rows.size and abs(rows.mean() - reheat.y(551.0)) <= 1.5
    # the main steam held its setpoint meanwhile
    rows = np.flatnonzero(np.all(img[temp.rows[0] : temp.rows[1], col] == red, axis=1))
    assert rows.size and abs(rows.mean() + temp.rows[0] - temp.y(540.0)) <= 1.5


@pytest.mark.parametrize("env_id", sorted(__import__("steamtemp_gym").ENV_IDS))
def test_every_plant_shows_every_scored_temperature_and_actuator(env_id):
    """Each plant's frame: one temperature panel per scored temperature (main steam and
    ``Plant.secondary``), each actuator's trace in its own colour, named as in
    ``signals.action``."""
    import gymnasium as gym

    import steamtemp_gym  # noqa: F401
    from steamtemp_gym.envs import render

    env = gym.make(env_id, scenario="load_ramp_100_50", render_mode="rgb_array")
    _, info = env.reset(seed=0)
    for _ in range(20):
        _, _, _, _, info = env.step(env.action_space.sample())
    u = env.unwrapped
    d = u._display
    assert len(d.axes) == 1 + len(u.plant.secondary) + 3
    assert [k for k, _ in d.secondary] == [k for k, _ in u.plant.secondary]
    n = len(u.signals.action)
    assert np.atleast_1d(info["spray_valve"]).size == n
    act = d.axes[-2]
    region = env.render()[act.rows[0] : act.rows[1] + 1, round(act.left) + 2 : round(act.x(1.0))]
    for j in range(n):
        color = render.rgb(render.VALVE_COLORS[j % len(render.VALVE_COLORS)])
        assert np.all(region == color, axis=2).any(), (env_id, j)
    assert len(set(map(tuple, d.valve_colors))) == n
    assert d.valve_names == tuple(s.description.removesuffix(" command") for s in u.signals.action)
