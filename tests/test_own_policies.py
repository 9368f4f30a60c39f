"""Your own policy, with no edit to the package (agents/specs.py, agents/files.py): the
example factory of examples/ scored by the leaderboard CLI as its README says, a trained
agent's files (steamtemp-train's, RL Zoo's) scored exactly as the shipped agent, the
registration functions, ``steamtemp-check --policy`` taking the same names, and bad names
refused before anything runs.

Tiny scenarios on Cascade300MW (the cheapest plant) and ``--no-oracle`` keep these in
seconds.
"""

from __future__ import annotations

import json
import re
import shutil
from collections import OrderedDict
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import yaml

import agents
import baselines
from agents import files, specs
from agents import leaderboard as lb
from agents.evaluation import run_episode
from agents.leaderboard import episodes
from agents.leaderboard.plan import REFERENCE, policy_digest
from agents.leaderboard.records import strict
from steamtemp_gym import scenarios
from steamtemp_gym.scenarios import Scenario
from steamtemp_gym.testing import cli

ROOT = Path(__file__).parents[1]
EXAMPLE = ROOT / "examples" / "my_controller.py"
FACTORY = "examples/my_controller.py:make_controller"
ENV = "steamtemp/Cascade300MW-v0"
#: The shipped agent of ENV's plant.
ALGO = next(a for e, a in agents.shipped() if e == ENV)
TINY = Scenario(name="tiny", duration_s=60.0, load=((0.0, 1.0), (30.0, 0.95)))


@pytest.fixture
def tiny(tmp_path) -> Path:
    path = tmp_path / "tiny.yaml"
    path.write_text(yaml.safe_dump(TINY.to_dict()))
    return path


@pytest.fixture
def at_root(monkeypatch):
    """Run from the project's root, as examples/README.md says."""
    monkeypatch.chdir(ROOT)


def _run(tmp_path: Path, tiny: Path, policies: str, *extra: str) -> list[dict]:
    out = tmp_path / "out"
    lb.main(
        [
            "--envs",
            ENV,
            "--policies",
            policies,
            "--scenarios",
            str(tiny),
            "--seeds",
            "0,1",
            "--out",
            str(out),
            "--jobs",
            "1",
            "--no-oracle",
            *extra,
        ]
    )
    return json.loads((out / "leaderboard.json").read_text())["episodes"]


def _alone(policy_of_env, seed: int) -> dict:
    """The metrics of one episode run by agents.evaluation, as the leaderboard stores them."""
    env = gym.make(ENV, scenario=TINY)
    return strict(run_episode(env, policy_of_env(env), seed)["metrics"])


# --------------------------------------------------------------------------- example
def _readme_command() -> list[str]:
    text = (ROOT / "examples" / "README.md").read_text()
    (block,) = re.findall(r"<!-- example: shell -->\n```bash\n(.*?)```", text, re.S)
    return block.replace("\\\n", " ").split()


def test_example_readme_command_scores_the_factory(tmp_path, tiny, at_root, capsys):
    """The README's one command (on a tiny scenario): rows of the factory, scored by the
    leaderboard's evaluation exactly as a run of agents.evaluation scores it."""
    argv = _readme_command()
    assert argv[0] == "steamtemp-leaderboard" and FACTORY in argv[argv.index("--policies") + 1]
    assert "--no-oracle" in argv
    out = tmp_path / "out"
    lb.main(
        [*argv[1:], "--scenarios", str(tiny), "--seeds", "0,1", "--out", str(out), "--jobs", "1"]
    )
    rows = json.loads((out / "leaderboard.json").read_text())["episodes"]
    mine = {r["seed"]: r for r in rows if r["policy"] == FACTORY}
    assert sorted(mine) == [0, 1] and not any(r.get("error") for r in rows)
    from examples.my_controller import make_controller

    for seed, row in mine.items():
        assert row["metrics"] == _alone(make_controller, seed)
    cascade = next(r for r in rows if r["policy"] == "cascade_pi" and r["seed"] == 0)
    assert cascade["metrics"] != mine[0]["metrics"]  # another controller, not a rename
    assert FACTORY in (out / "leaderboard.md").read_text()


def test_factory_is_fingerprinted_by_its_file(tmp_path):
    mod = tmp_path / "ctl.py"
    mod.write_text(EXAMPLE.read_text())
    name = f"{mod}:make_controller"
    first = policy_digest(ENV, name)
    assert first.startswith(name + ":") and len(first) == len(name) + 65
    mod.write_text(EXAMPLE.read_text() + "\n# a comment changes no action\n")
    assert policy_digest(ENV, name) == first
    mod.write_text(EXAMPLE.read_text() + "\nANOTHER_VERSION = 2\n")
    assert policy_digest(ENV, name) != first


# --------------------------------------------------------------------------- agent files
def _run0_stem() -> str:
    """The file stem of the shipped agent's run 0 (with or without the run index)."""
    return next(
        s
        for s in (files.stem(ENV, ALGO, 0), files.stem(ENV, ALGO))
        if (agents.ZOO / f"{s}.zip").is_file()
    )


def test_trained_agent_files_score_as_the_shipped_agent(tmp_path, tiny):
    """steamtemp-train's files (a copy of the shipped agent's run 0), named as a directory
    with zoo:, as a directory path and as the model .zip: rows identical to that run's
    (``sb3:<algo>``, or ``sb3:<algo>@run0`` where the zoo holds several runs)."""
    trained = tmp_path / "trained"
    trained.mkdir()
    stem = _run0_stem()
    for suffix in (".zip", ".json"):
        shutil.copy(agents.ZOO / (stem + suffix), trained / (stem + suffix))
    names = [f"zoo:{trained}", f"{trained}/", f"{trained / stem}.zip"]
    rows = _run(tmp_path, tiny, ",".join([f"sb3:{ALGO}", *names]))
    by = {(r["policy"], r["seed"]): r for r in rows}
    shipped = specs.training_runs(f"sb3:{ALGO}", ENV)[0]
    for name in names:
        for seed in (0, 1):
            assert by[name, seed]["metrics"] == by[shipped, seed]["metrics"], name
    digests = {n: policy_digest(ENV, n) for n in [shipped, *names]}
    assert len({d.rsplit(":", 1)[1] for d in digests.values()}) == 1  # the same files' hash


def test_agent_files_are_available_for_their_env_only(tmp_path):
    trained = tmp_path / "t"
    trained.mkdir()
    stem = _run0_stem()
    for suffix in (".zip", ".json"):
        shutil.copy(agents.ZOO / (stem + suffix), trained / (stem + suffix))
    spec = specs.parse(f"zoo:{trained}")
    assert spec.available(ENV) and not spec.available("steamtemp/DrumBoilerSH-v0")


def _rl_zoo_run(tmp_path: Path) -> tuple[Path, object, object]:
    """An RL Zoo run directory as rl_zoo3.train writes it (exp_manager.py: the model
    ``<name>.zip``, ``<name>/config.yml`` and ``args.yml`` as PyYAML dumps of OrderedDicts,
    ``<name>/vecnormalize.pkl``), of an untrained PPO with the controller memory and
    VecNormalize statistics from 200 random steps. Returns (run dir, model, VecNormalize)."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    from agents.wrappers import ControllerMemory

    memory = {"integral_time_s": 60.0, "integral_limit_K": 40.0, "history": 2, "history_stride": 3}
    venv = VecNormalize(DummyVecEnv([lambda: ControllerMemory(gym.make(ENV), **memory)]))
    venv.seed(0)
    venv.reset()
    rng = np.random.default_rng(0)
    for _ in range(200):
        venv.step(rng.uniform(-1, 1, (1, 1)).astype(np.float32))
    model = PPO("MlpPolicy", venv, seed=0, device="cpu", policy_kwargs={"net_arch": [16]})
    name = ENV.replace("/", "-")
    run = tmp_path / "logs" / "ppo" / f"{name}_1"
    (run / name).mkdir(parents=True)
    model.save(run / f"{name}.zip")
    venv.save(str(run / name / "vecnormalize.pkl"))
    config = OrderedDict(
        [
            ("env_wrapper", [{"agents.wrappers.ControllerMemory": memory}]),
            ("n_timesteps", 1000),
            ("normalize", "dict(norm_obs=True)"),
            ("policy", "MlpPolicy"),
        ]
    )
    (run / name / "config.yml").write_text(yaml.dump(config))
    args = OrderedDict([("algo", "ppo"), ("env", ENV), ("seed", 0)])
    (run / name / "args.yml").write_text(yaml.dump(args))
    return run, model, venv


def test_rl_zoo_run_acts_as_its_model_on_its_normalized_memory(tmp_path):
    """The loaded RL Zoo agent acts as SB3's predict on what RL Zoo's env stack (the memory
    wrapper, then VecNormalize frozen) shows the model, along a closed-loop episode."""
    run, model, venv = _rl_zoo_run(tmp_path)
    config = (run / ENV.replace("/", "-") / "config.yml").read_text()
    assert "python/object/apply:collections.OrderedDict" in config
    (agent,) = files.find(run)
    assert (agent.env_id, agent.algo, agent.layout) == (ENV, "ppo", files.RL_ZOO)
    assert files.find(agent.model) == [agent]
    policy = specs.parse(f"zoo:{run}").make(ENV, gym.make(ENV))
    venv.training = False
    from agents.wrappers import ControllerMemory

    env = ControllerMemory(
        gym.make(ENV, scenario=TINY),
        integral_time_s=60.0,
        integral_limit_K=40.0,
        history=2,
        history_stride=3,
    )
    n_raw = env.unwrapped.observation_space.shape[0]
    obs, _ = env.reset(seed=3)
    for _ in range(40):
        ours, _ = policy.predict(obs[:n_raw])  # the env's own observation
        theirs, _ = model.predict(venv.normalize_obs(obs[None]), deterministic=True)
        np.testing.assert_allclose(ours, theirs[0], atol=1e-5)
        obs, _, term, trunc, _ = env.step(ours)
        assert not (term or trunc)


def test_rl_zoo_run_is_scored_by_the_leaderboard(tmp_path, tiny):
    run, _, _ = _rl_zoo_run(tmp_path)
    rows = _run(tmp_path, tiny, f"zoo:{run}")
    mine = [r for r in rows if r["policy"] == f"zoo:{run}"]
    assert len(mine) == 2 and all(np.isfinite(r["metrics"]["iae_K_s"]) for r in mine)
    for r in mine:
        assert r["metrics"] == _alone(
            lambda env: specs.parse(f"zoo:{run}").make(ENV, env), r["seed"]
        )


# --------------------------------------------------------------------------- bad names
def _refused_argv(name: str, tiny: Path, out: Path) -> list[str]:
    """The leaderboard's arguments for a run of policy ``name`` that must be refused."""
    return [
        "--envs",
        ENV,
        "--policies",
        name,
        "--scenarios",
        str(tiny),
        "--out",
        str(out),
        "--no-oracle",
    ]


def _bad_module(tmp_path: Path) -> Path:
    path = tmp_path / "not_a_policy.py"
    path.write_text(
        "VALUE = 3\n\ndef make(env):\n    return object()\n\n"
        "def broken(env):\n    raise RuntimeError('no plant for me')\n"
    )
    return path


BAD = [
    ("no_such_module_xyz:make", ["cannot import", "no_such_module_xyz"]),
    ("examples/my_controller.py:nope", ["has no attribute", "nope"]),
    ("examples/no_such_file.py:make", ["cannot import", "no_such_file.py"]),
    ("{bad}:VALUE", ["not callable"]),
    ("{bad}:make", ["no predict and no reset"]),
    ("{bad}:broken", ["RuntimeError", "no plant for me"]),
    ("zoo:/no/such/dir", ["no file or directory"]),
    ("zoo:{tmp}", ["holds no trained agent"]),
    ("{tmp}/model.zip", ["no file or directory"]),
    ("nope", ["unknown policy", "cascade_pi", "sb3:ppo", "module:callable", "zoo:DIR"]),
    ("sb3:nope", ["no shipped trained agent 'sb3:nope'", "sb3:ppo"]),
]


@pytest.mark.parametrize(("name", "words"), BAD, ids=[n for n, _ in BAD])
def test_bad_policy_is_an_argparse_error_of_both_clis(name, words, tmp_path, tiny, at_root, capsys):
    name = name.format(bad=_bad_module(tmp_path), tmp=tmp_path)
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as exc:
        lb.main(_refused_argv(name, tiny, out))
    err = capsys.readouterr().err
    assert exc.value.code == 2 and "--policies" in err and "Traceback" not in err
    assert all(w in err for w in words), err
    assert not out.exists()
    with pytest.raises(SystemExit) as exc:
        cli.main([ENV, "--policy", name, "--no-env-checks"])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and "--policy" in err and all(w in err for w in words), err


# ------------------------------------------------- agent files that do not fit their env
FSH = "steamtemp/SupercriticalFSH-v0"


def _mislabelled(tmp_path: Path) -> Path:
    """The FSH agent's files named and labelled as an agent of ENV."""
    algo = next(a for e, a in agents.shipped() if e == FSH)
    src = next(
        s
        for s in (files.stem(FSH, algo, 0), files.stem(FSH, algo))
        if (agents.ZOO / f"{s}.zip").is_file()
    )
    d = tmp_path / "mislabelled"
    d.mkdir()
    stem = files.stem(ENV, algo)
    shutil.copy(agents.ZOO / f"{src}.zip", d / f"{stem}.zip")
    meta = json.loads((agents.ZOO / f"{src}.json").read_text())
    (d / f"{stem}.json").write_text(json.dumps(dict(meta, env_id=ENV)))
    return d


def _zoo_without_wrapper(tmp_path: Path) -> Path:
    """An RL Zoo run trained with the controller memory whose config.yml lost env_wrapper."""
    run, _, _ = _rl_zoo_run(tmp_path)
    config = run / ENV.replace("/", "-") / "config.yml"
    config.write_text(yaml.dump(OrderedDict([("n_timesteps", 1000), ("policy", "MlpPolicy")])))
    return run


def _corrupt(tmp_path: Path) -> Path:
    """The shipped agent's files with the model .zip cut short."""
    d = tmp_path / "corrupt"
    d.mkdir()
    stem = _run0_stem()
    shutil.copy(agents.ZOO / f"{stem}.json", d / f"{stem}.json")
    (d / f"{stem}.zip").write_bytes((agents.ZOO / f"{stem}.zip").read_bytes()[:300])
    return d


UNFIT = [
    (
        _mislabelled,
        ["does not fit steamtemp/Cascade300MW-v0", "observations of shape", "another env"],
    ),
    (
        _zoo_without_wrapper,
        ["does not fit", "without controller memory", "config.yml has no env_wrapper"],
    ),
    (_corrupt, ["is not a Stable-Baselines3 model file", "corrupt"]),
]


@pytest.mark.parametrize(("make", "words"), UNFIT, ids=[m.__name__ for m, _ in UNFIT])
def test_agent_files_that_do_not_fit_their_env_are_refused_when_named(
    make, words, tmp_path, tiny, capsys
):
    """A model of another env, an RL Zoo run without its memory wrapper and a corrupt .zip
    are refused by both CLIs before anything runs, naming the shapes (each episode failed
    with a broadcast or matmul error, or 'No data found')."""
    name = f"zoo:{make(tmp_path)}"
    with pytest.raises(ValueError) as exc:
        specs.parse(name)
    assert all(w in str(exc.value) for w in words), str(exc.value)
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as code:
        lb.main(_refused_argv(name, tiny, out))
    assert code.value.code == 2 and not out.exists()
    err = capsys.readouterr().err
    assert all(w in err for w in words), err
    with pytest.raises(SystemExit) as code:
        cli.main([ENV, "--policy", name, "--no-env-checks"])
    err = capsys.readouterr().err
    assert code.value.code == 2 and all(w in err for w in words), err


def test_shipped_agents_fit_their_envs():
    """Every shipped agent's model fits its env (checked when its name is parsed)."""
    for name in specs.shipped_names():
        spec = specs.parse(name)
        for env_id in spec.envs:
            for run in agents.runs(env_id, spec.target):
                files.steamtemp_files(agents.ZOO, env_id, spec.target, run).check()


# --------------------------------------------------------------------------- steamtemp-check
def test_check_cli_takes_sb3_names_and_factories(at_root, capsys):
    code = cli.main(
        [
            ENV,
            "--no-env-checks",
            "--check",
            "check_predict_signature",
            "--policy",
            f"sb3:{ALGO}",
            "--policy",
            FACTORY,
        ]
    )
    out = capsys.readouterr().out
    assert code == 0, out
    assert re.search(rf"Cascade300MW-v0\s+sb3:{ALGO}\s+check_predict_signature\s+PASS", out)
    assert re.search(
        rf"Cascade300MW-v0\s+{re.escape(FACTORY)}\s+check_predict_signature\s+PASS", out
    )


# --------------------------------------------------------------------------- registration
@pytest.fixture
def registry(monkeypatch):
    """baselines' and scenarios' registries restored after the test."""
    monkeypatch.setattr(baselines, "REGISTRY", dict(baselines.REGISTRY))
    monkeypatch.setattr(baselines, "NAMES", baselines.NAMES)
    monkeypatch.setattr(scenarios.registry, "_REGISTRY", dict(scenarios.registry._REGISTRY))


def test_register_a_baseline(registry, at_root):
    from examples.my_controller import SingleLoopPI, make_controller

    baselines.register("single_loop_pi", make_controller)
    baselines.register("single_loop_pi", make_controller)  # the same again: nothing happens
    assert baselines.NAMES[-1] == "single_loop_pi" and "single_loop_pi" not in baselines.SHIPPED
    made = baselines.make("single_loop_pi", gym.make(ENV))  # checked, as every baseline
    assert isinstance(made.policy, SingleLoopPI) and made.n_obs == 9
    assert specs.parse("single_loop_pi").kind == specs.BASELINE
    baselines.register("by_ref", "examples.my_controller:make_controller")
    assert isinstance(baselines.make("by_ref", gym.make(ENV)).policy, SingleLoopPI)
    before = baselines.NAMES
    for name, factory, word in [
        ("cascade_pi", make_controller, "shipped"),
        ("single_loop_pi", SingleLoopPI, "already registered"),
        ("a:b", make_controller, "letter"),
        ("a,b", make_controller, "letter"),
        ("", make_controller, "letter"),
        ("x", 3, "callable"),
        ("x", "not a ref", "callable"),
    ]:
        with pytest.raises(ValueError, match=word):
            baselines.register(name, factory)
    assert baselines.NAMES == before


def test_registered_baseline_reaches_a_worker_through_import(registry, tmp_path, tiny, monkeypatch):
    """--import: the leaderboard knows the name, and a worker that has not imported the
    module (a spawned process, a Ray task) imports it before it builds the policy."""
    (tmp_path / "my_registry.py").write_text(
        "import baselines\nfrom examples.my_controller import make_controller\n"
        "baselines.register('single_loop_pi', make_controller)\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.syspath_prepend(str(ROOT))
    monkeypatch.delitem(__import__("sys").modules, "my_registry", raising=False)
    rows = _run(tmp_path, tiny, "single_loop_pi", "--import", "my_registry")
    assert {r["policy"] for r in rows} >= {"single_loop_pi"} and not any(
        r.get("error") for r in rows
    )
    # a fresh worker: the registry without the name, the module not imported
    monkeypatch.setattr(baselines, "REGISTRY", dict(baselines.REGISTRY))
    del baselines.REGISTRY["single_loop_pi"]
    monkeypatch.delitem(__import__("sys").modules, "my_registry")
    unit = episodes.Unit(ENV, "tiny", TINY, "single_loop_pi", [0], "fp", None, ("my_registry",))
    (row,), _ = episodes.run_unit(unit)
    assert row.get("error") is None and np.isfinite(row["metrics"]["iae_K_s"])


def test_register_a_scenario(registry, tmp_path, capsys):
    sc = Scenario(name="my_ramp", duration_s=60.0, load=((0.0, 1.0), (20.0, 0.9)))
    scenarios.register(sc)
    scenarios.register(sc)  # the same again: nothing happens
    assert "my_ramp" in scenarios.names(ENV)
    assert gym.make(ENV, scenario="my_ramp").unwrapped._scenario_spec == sc
    for bad, word in [
        (Scenario(name="my_ramp", duration_s=30.0), "already registered"),
        (Scenario(name="setpoint_step", duration_s=30.0), "already registered"),
        (Scenario(name="heldout:x", duration_s=30.0), "held-out"),
        (Scenario(name="a.yaml", duration_s=30.0), "file"),
        (Scenario(name="a,b", duration_s=30.0), "list"),
    ]:
        with pytest.raises(ValueError, match=word):
            scenarios.register(bad)
    assert scenarios.get("setpoint_step").duration_s != 30.0


def test_a_new_tuning_changes_only_its_controllers_fingerprints(tmp_path, monkeypatch):
    """A baseline's stored tuning on the env is part of its rows' fingerprint (its own and its
    ``_tuned`` row's), and no other row's: retuning one controller on one plant reruns its
    rows there only, not the oracle's, the agents' or another controller's."""
    from baselines import tuning

    other = "steamtemp/SupercriticalFSH-v0"
    names = ["cascade_pi", "cascade_pi_tuned", "cascade_pi_ff", "lqi", "oracle", REFERENCE]
    before = {(e, n): policy_digest(e, n) for e in (ENV, other) for n in names}
    stored = tuning.TUNED
    monkeypatch.setattr(tuning, "TUNED", tmp_path)
    for f in stored.glob("*.json"):
        shutil.copy(f, tmp_path)
    assert {(e, n): policy_digest(e, n) for e, n in before} == before
    src = json.loads(tuning.path("cascade_pi").read_text())
    src["plants"][ENV]["knobs"]["outer_gain"] *= 1.5
    tuning.path("cascade_pi").write_text(json.dumps(src))
    changed = [k for k in before if policy_digest(*k) != before[k]]
    assert changed == [(ENV, "cascade_pi"), (ENV, "cascade_pi_tuned")]
