"""One scenario vocabulary everywhere: ``gym.make(..., scenario=...)``, ``reset(options=
{"scenario": ...})`` (single and vector env), the leaderboard's ``--scenarios`` and
``steamtemp-check --scenario`` take the same forms (a name, ``heldout:<name>``,
``random``, a YAML file), and env ids work without the ``steamtemp/`` namespace in the
command lines. Cascade300MW (the cheapest plant) keeps these in seconds."""

from __future__ import annotations

import copy
import json
import re

import gymnasium as gym
import numpy as np
import pytest
import yaml

from agents import leaderboard as lb
from agents.leaderboard.plan import resolve_scenario
from steamtemp_gym import envs, scenarios
from steamtemp_gym.scenarios import Scenario, heldout
from steamtemp_gym.testing import cli

ENV = "steamtemp/Cascade300MW-v0"
SHORT = "Cascade300MW-v0"
TINY = Scenario(name="tiny", duration_s=60.0, load=((0.0, 1.0), (30.0, 0.95)))


@pytest.fixture
def tiny(tmp_path):
    path = tmp_path / "tiny.yaml"
    path.write_text(yaml.safe_dump(TINY.to_dict()))
    return str(path)


def _run(env, steps: int = 8, seed: int = 4, **reset) -> list:
    obs, info = env.reset(seed=seed, **reset)
    out = [obs]
    for k in range(steps):
        obs, r, term, trunc, info = env.step(
            np.full(env.action_space.shape, 0.1 * (k % 3), dtype=np.float32)
        )
        out += [obs, r, info["outlet_temp_C"]]
    return out


def _same(a: list, b: list) -> bool:
    return len(a) == len(b) and all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))


FORMS = ["setpoint_step", "heldout:mill_trip", "random", "{tiny}"]


def test_make_takes_held_out_names():
    env = gym.make(ENV, scenario="heldout:mill_trip")
    env.reset(seed=0)
    assert env.unwrapped.scenario == heldout.load("mill_trip")
    venv = gym.make_vec(
        ENV, num_envs=2, vectorization_mode="vector_entry_point", scenario="heldout:mill_trip"
    )
    venv.reset(seed=0)
    assert venv.unwrapped.core.scenario[1] == heldout.load("mill_trip")


@pytest.mark.parametrize("form", FORMS)
def test_reset_option_is_the_made_scenario_for_that_episode(form, tiny):
    """reset(options={"scenario": s}) runs as gym.make(scenario=s), bit for bit; the next
    reset without it is the env's own scenario again."""
    spec = form.format(tiny=tiny)
    made = _run(gym.make(ENV, scenario=spec))
    env = gym.make(ENV, scenario="load_cycle")
    assert _same(_run(env, options={"scenario": spec}), made)
    assert env.unwrapped.scenario.name == (
        "random" if spec == "random" else scenarios.resolve(spec, ENV).name
    )
    assert _same(_run(env), _run(gym.make(ENV, scenario="load_cycle")))
    assert env.unwrapped.scenario.name == "load_cycle"


def test_vector_reset_option_matches_single_envs(tiny):
    venv = gym.make_vec(
        ENV, num_envs=3, vectorization_mode="vector_entry_point", scenario="load_cycle"
    )
    sync = gym.vector.SyncVectorEnv([lambda: gym.make(ENV, scenario="load_cycle")] * 3)
    for v in (venv, sync):
        v.reset(seed=7, options={"scenario": "heldout:mill_trip"})
    assert [venv.unwrapped.core.scenario[i].name for i in range(3)] == ["mill_trip"] * 3
    a = np.zeros((3, 1), dtype=np.float32)
    for _ in range(5):
        (o1, r1, *_), (o2, r2, *_) = venv.step(a), sync.step(a)
        np.testing.assert_array_equal(o1, o2)
        np.testing.assert_array_equal(r1, r2)
    mask = np.array([False, True, False])  # a partial reset under another scenario
    venv.reset(options={"scenario": tiny, "reset_mask": mask})
    assert [venv.unwrapped.core.scenario[i].name for i in range(3)] == [
        "mill_trip",
        "tiny",
        "mill_trip",
    ]


def test_bad_reset_option_names_every_form_and_changes_nothing():
    env = gym.make(ENV, scenario="setpoint_step")
    env.reset(seed=1)
    twin = copy.deepcopy(env)
    for bad, words in [
        ({"scenario": "nope"}, ["nope", "setpoint_step", "heldout:mill_trip", "'random'", ".yaml"]),
        ({"scenario": "heldout:nope"}, ["heldout:nope", "heldout:mill_trip"]),
        ({"no_such": 1}, ["no_such", "scenario"]),
    ]:
        with pytest.raises(ValueError) as exc:
            env.reset(seed=9, options=bad)
        assert all(w in str(exc.value) for w in words), str(exc.value)
    a = np.zeros(1, dtype=np.float32)
    assert np.array_equal(env.step(a)[0], twin.step(a)[0])  # not reset
    state = env.unwrapped.np_random.bit_generator.state
    assert state == twin.unwrapped.np_random.bit_generator.state  # not reseeded
    venv = gym.make_vec(ENV, num_envs=2, vectorization_mode="vector_entry_point")
    with pytest.raises(ValueError, match="heldout:mill_trip"):
        venv.reset(options={"scenario": "nope"})
    with pytest.raises(ValueError, match="no_such.*reset_mask"):
        venv.reset(options={"no_such": 1})


def test_env_ids_without_namespace():
    assert envs.resolve_id(SHORT) == ENV == envs.resolve_id(ENV)
    with pytest.raises(ValueError, match="valid ids: .*steamtemp/Cascade300MW-v0"):
        envs.resolve_id("Nope-v0")
    envs.register_variant("one/Twin-v0", ENV)
    envs.register_variant("two/Twin-v0", ENV)
    try:
        with pytest.raises(ValueError, match="ambiguous.*one/Twin-v0.*two/Twin-v0"):
            envs.resolve_id("Twin-v0")
        assert envs.resolve_id("one/Twin-v0") == "one/Twin-v0"
    finally:
        for i in ("one/Twin-v0", "two/Twin-v0"):
            gym.registry.pop(i, None)


def test_leaderboard_takes_short_ids_and_every_scenario_form(tmp_path, tiny):
    out = tmp_path / "out"
    lb.main(
        [
            "--envs",
            f"{SHORT},{ENV}",
            "--policies",
            "frozen_valve",
            "--scenarios",
            f"{tiny},random",
            "--seeds",
            "0",
            "--out",
            str(out),
            "--jobs",
            "1",
            "--no-oracle",
        ]
    )
    doc = json.loads((out / "leaderboard.json").read_text())
    assert doc["run"]["envs"] == [ENV]  # one env: the two spellings are one id
    assert {r["scenario"] for r in doc["episodes"]} == {tiny, "random"}
    assert not any(r.get("error") for r in doc["episodes"])


def test_leaderboard_scenario_error_lists_every_form(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        lb.main(
            ["--envs", SHORT, "--scenarios", "nope", "--out", str(tmp_path / "o"), "--no-oracle"]
        )
    err = capsys.readouterr().err
    assert exc.value.code == 2
    assert all(
        w in err for w in ["nope", "setpoint_step", "heldout:mill_trip", "'random'", ".yaml"]
    ), err


def test_check_cli_takes_short_ids_and_scenarios(capsys):
    code = cli.main(
        [
            SHORT,
            "--no-env-checks",
            "--policy",
            "cascade_pi",
            "--check",
            "check_completes_a_scenario",
            "--scenario",
            "heldout:mill_trip",
            "--scenario",
            "random",
        ]
    )
    out = capsys.readouterr().out
    assert code == 0, out
    for sc in ("heldout:mill_trip", "random"):
        assert re.search(
            rf"Cascade300MW-v0\s+cascade_pi\s+check_completes_a_scenario"
            rf"\[{sc}\]\s+PASS",
            out,
        ), out
    with pytest.raises(SystemExit) as exc:
        cli.main([SHORT, "--policy", "cascade_pi", "--scenario", "heldout:nope"])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and "heldout:mill_trip" in err and "'random'" in err
    with pytest.raises(SystemExit) as exc:
        cli.main(["Nope-v0"])
    assert exc.value.code == 2 and "steamtemp/Cascade300MW-v0" in capsys.readouterr().err


def test_named_scenarios_are_resolved_by_one_function():
    """The leaderboard resolves as gym.make does (one function, no second parser)."""
    for spec in ("setpoint_step", "heldout:mill_trip", "random"):
        assert resolve_scenario(spec, ENV) == scenarios.resolve(spec, ENV)
