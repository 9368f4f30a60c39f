"""Offline datasets (agents/datasets.py) and behaviour cloning from them
(agents/behaviour_cloning.py): a dataset of two episodes made by the command, read back
with Minari (episodes, infos with the cost, metadata); its reference scores are the
leaderboard's score ends and Minari's normalized score is the leaderboard's; bad flags are
refused before anything is written; a dataset with injected noise records the plant's
transitions and labels them with the policy's own actions; a cloned agent (with the
controller memory, or plain) is scored by the leaderboard."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

minari = pytest.importorskip("minari", reason="minari is in the [offline] extra, not [test]")
pytest.importorskip("jax", reason="Minari writes datasets through jax (minari[create])")
pytest.importorskip("h5py", reason="Minari's HDF5 storage (minari[hdf5])")

import gymnasium as gym  # noqa: E402

import baselines  # noqa: E402
from agents import behaviour_cloning, datasets, horizons, stats, validation  # noqa: E402
from agents.evaluation import run_episode  # noqa: E402
from agents.files import find  # noqa: E402
from agents.leaderboard import cli  # noqa: E402
from agents.leaderboard.records import EPISODES, read_record  # noqa: E402
from agents.tuning_terms import TUNING_TRAVEL_BUDGET  # noqa: E402
from agents.wrappers import ControllerMemory  # noqa: E402

ENV = "steamtemp/Cascade300MW-v0"
SCENARIO = "load_ramp_100_50"
DATASET = "steamtemp/Cascade300MW/cascade_pi_ff-v0"


@pytest.fixture(scope="module")
def data_dir(tmp_path_factory):
    path = tmp_path_factory.mktemp("minari")
    old = os.environ.get("MINARI_DATASETS_PATH")
    os.environ["MINARI_DATASETS_PATH"] = str(path)
    yield path
    if old is None:
        del os.environ["MINARI_DATASETS_PATH"]
    else:
        os.environ["MINARI_DATASETS_PATH"] = old


@pytest.fixture(scope="module")
def dataset(data_dir):
    args = "--env Cascade300MW-v0 --policy cascade_pi_ff --episodes 2 --seed 3 --eval-seeds 0"
    assert datasets.main([*args.split(), "--data-dir", str(data_dir)]) == 0
    return minari.load_dataset(DATASET)


@pytest.fixture(scope="module")
def agent_dir(dataset, tmp_path_factory):
    out = tmp_path_factory.mktemp("bc")
    behaviour_cloning.train(DATASET, out, epochs=2, max_seconds=30)
    return out


@pytest.fixture(scope="module")
def leaderboard(agent_dir, tmp_path_factory):
    """The leaderboard on the dataset's evaluation scenario and seed, with the cloned agent."""
    out = tmp_path_factory.mktemp("lb")
    cli.main(
        [
            "--policies",
            f"cascade_pi,zoo:{agent_dir}",
            "--envs",
            "Cascade300MW-v0",
            "--scenarios",
            SCENARIO,
            "--seeds",
            "0",
            "--no-mismatch",
            "--jobs",
            "1",
            "--out",
            str(out),
        ]
    )
    summary = json.loads((out / "leaderboard.json").read_text())
    rows = {r["policy"]: r for r in read_record(out / EPISODES)}
    return summary["plants"][ENV], rows


def test_the_dataset_holds_the_episodes_the_policy_runs(dataset):
    assert dataset.total_episodes == 2
    env = gym.make(ENV, scenario="random")
    seeds = [m["seed"] for m in dataset.storage.get_episode_metadata([0, 1])]
    assert seeds == [3, 4]
    for seed, ep in zip(seeds, dataset.iterate_episodes(), strict=True):
        ref = run_episode(env, baselines.make("cascade_pi_ff", env), seed)
        assert len(ep.actions) == len(ref["trace"]["time_s"]) - 1
        assert float(np.sum(ep.rewards)) == pytest.approx(ref["metrics"]["return"], abs=1e-9)
        np.testing.assert_array_equal(ep.infos["outlet_temp_C"], ref["trace"]["outlet_temp_C"])
        # the safe-RL cost is recorded: summed times dt it is the metric
        dt = env.unwrapped.plant.dt_s
        assert np.sum(ep.infos["cost"][1:] * dt) == pytest.approx(
            ref["metrics"]["time_outside_5K_s"], abs=1e-9
        )


def test_metadata(dataset):
    meta = dataset.storage.metadata
    assert meta["dataset_id"] == DATASET
    assert meta["algorithm_name"] == "cascade_pi_ff"
    assert meta["author"] and meta["description"] and meta["code_permalink"]
    eval_env = dataset.recover_environment(eval_env=True)
    assert eval_env.spec.id == ENV and eval_env.spec.kwargs["scenario"] == SCENARIO
    assert dataset.recover_environment().spec.kwargs["scenario"] == "random"
    assert meta["num_episodes_average_score"] == 1
    plan = json.loads(meta["steamtemp_episodes"])
    assert [p["seed"] for p in plan] == [3, 4]


def test_reference_scores_are_the_leaderboards_score_ends(dataset, leaderboard):
    plant, rows = leaderboard
    ref = plant["reference"][SCENARIO]
    assert dataset.storage.metadata["ref_min_score"] == ref["zero_return"]
    assert dataset.storage.metadata["ref_max_score"] == ref["one_return"]
    assert ref["zero_return"] == rows["cascade_pi_ff"]["metrics"]["return"]


def test_minaris_normalized_score_is_the_leaderboards(dataset, leaderboard):
    plant, rows = leaderboard
    ref = plant["reference"][SCENARIO]
    assert ref["headroom"] >= stats.MIN_SPAN * abs(ref["zero_return"])  # where they agree
    for name in ("cascade_pi", "oracle", "frozen_valve"):
        ret = np.array([rows[name]["metrics"]["return"]])
        ours = stats.normalize(ret, ref["zero_return"], ref["one_return"])
        theirs = minari.get_normalized_score(dataset, ret)
        assert abs(float(theirs[0]) - float(ours[0])) <= 1e-9
        # one seed: the scenario's mean score is this episode's
        cell = plant["scenarios"][SCENARIO][name]["normalized_score"]
        assert abs(float(theirs[0]) - cell) <= 1e-9


def test_a_cloned_agent_is_a_trained_agents_files_scored_by_the_leaderboard(
    dataset, agent_dir, leaderboard
):
    (files,) = find(agent_dir)
    files.check()
    assert (files.env_id, files.algo) == (ENV, "bc")
    meta = json.loads(files.meta[0].read_text())
    assert meta["dataset"] == DATASET and meta["sb3_class"] == "TD3"
    # the imitation agents' observation pipeline: controller memory and output filter
    assert meta["memory"] == behaviour_cloning.memory_of(ENV)
    assert meta["action_filter_s"] == round(horizons.action_filter(ENV), 5) > 0
    policy = files.load()
    assert policy.actor is not None  # the MLP in float64 NumPy
    obs, _ = behaviour_cloning.transitions(dataset)
    a = policy.predict(obs[:50])[0]
    assert a.shape == (50, 1) and np.all(np.abs(a) <= 1)
    plant, rows = leaderboard
    name = f"zoo:{agent_dir}"
    assert not rows[name].get("error")
    assert np.isfinite(plant["scenarios"][SCENARIO][name]["normalized_score"])


def _refused(capsys, *args: str) -> str:
    with pytest.raises(SystemExit) as exc:
        datasets.main(list(args))
    assert exc.value.code == 2
    return capsys.readouterr().err


@pytest.mark.parametrize(
    "args, says",
    [
        (["--policy", "cascade_pi_ff", "--episodes", "0"], "--episodes must be in 1"),
        (["--policy", "cascade_pi_ff", "--episodes", "two"], "--episodes must be an integer"),
        (["--policy", "cascade_pi_ff", "--seed", "-1"], "--seed must be in 0"),
        (["--policy", "cascade_pi_ff", "--mixed", "1.5"], "a fraction in (0, 1]"),
        (["--policy", "cascade_pi_ff", "--noise", "0"], "a fraction of the stroke in (0, 0.5]"),
        (["--policy", "cascade_pi_ff", "--noise", "0.6"], "a fraction of the stroke in (0, 0.5]"),
        (["--policy", "cascade_pi_ff", "--noise", "much"], "a fraction of the stroke"),
        (["--policy", "no_such_policy"], "unknown policy 'no_such_policy'"),
        (["--policy", "cascade_pi_ff", "--env", "NoSuchPlant-v0"], "argument --env"),
        (["--policy", "cascade_pi_ff", "--eval-scenario", "random"], "not 'random'"),
        (
            ["--policy", "cascade_pi_ff", "--eval-scenario", "no_such_scenario"],
            "argument --eval-scenario",
        ),
        (["--policy", "cascade_pi_ff", "--eval-seeds", "0,-2"], "integers >= 0"),
        (["--policy", "cascade_pi_ff", "--name", "a b"], "argument --name"),
        (["--episodes", "2"], "--policy"),
    ],
)
def test_bad_flags_are_refused_and_write_nothing(capsys, monkeypatch, tmp_path, args, says):
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "d"))  # restored after
    err = _refused(capsys, "--data-dir", str(tmp_path / "d"), *args)
    assert says in err
    assert not (tmp_path / "d" / "steamtemp").exists()


def test_an_existing_dataset_is_refused(capsys, monkeypatch, dataset, data_dir):
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(data_dir))
    err = _refused(
        capsys, "--env", "Cascade300MW-v0", "--policy", "cascade_pi_ff", "--data-dir", str(data_dir)
    )
    assert "exists already" in err
    assert minari.load_dataset(DATASET).total_episodes == 2  # unchanged


def test_a_mixed_dataset_draws_its_episodes_from_the_seed():
    plan = datasets.episode_plan("mpc_linear", 200, 7, mixed=0.5)
    assert plan == datasets.episode_plan("mpc_linear", 200, 7, mixed=0.5)
    detuned = [p for p in plan if p["policy"] == datasets.DETUNED]
    assert 60 < len(detuned) < 140
    for p in detuned:
        assert set(p["knobs"]) == {"outer_gain", "outer_reset", "inner_gain", "inner_reset"}
        assert all(0.25 <= v <= 4.0 for v in p["knobs"].values())
    assert [p["seed"] for p in plan] == list(range(7, 207))
    assert datasets.dataset_name("sb3:ppo") == "sb3-ppo"
    assert datasets.dataset_name("mpc_linear", 0.5) == "mpc_linear-mixed"
    assert datasets.dataset_name("mpc_linear", noise=0.05) == "mpc_linear-noisy5"
    assert datasets.dataset_name("sb3:ppo", 0.5, 0.025) == "sb3-ppo-mixed-noisy2-5"


NOISY = "steamtemp/Cascade300MW/cascade_pi_ff-noisy5-v0"


@pytest.fixture(scope="module")
def noisy(data_dir):
    args = "--env Cascade300MW-v0 --policy cascade_pi_ff --episodes 1 --seed 3 --eval-seeds 0"
    assert datasets.main([*args.split(), "--noise", "0.05", "--data-dir", str(data_dir)]) == 0
    return minari.load_dataset(NOISY)


def test_injected_noise_drives_the_plant_and_the_policys_own_action_is_the_label(noisy):
    (ep,) = list(noisy.iterate_episodes())
    label = ep.infos[datasets.POLICY_ACTION]
    assert np.isnan(label[0]).all()  # the reset's: no action yet
    label = label[1:]
    # the label is what the policy chose on the recorded observations
    env = gym.make(ENV, scenario="random")
    policy = baselines.make("cascade_pi_ff", env)
    policy.reset()
    chosen = [
        policy.predict(o, episode_start=np.array([i == 0]))[0]
        for i, o in enumerate(ep.observations[:-1])
    ]
    np.testing.assert_array_equal(np.asarray(chosen, np.float64).reshape(label.shape), label)
    # the recorded actions are the noisy ones the plant got: they reproduce its rewards
    env.reset(seed=3)
    rewards = [env.step(a)[1] for a in ep.actions]
    np.testing.assert_array_equal(rewards, ep.rewards)
    noise = np.asarray(ep.actions, np.float64) - label
    free = np.abs(np.asarray(ep.actions)) < 1.0  # where the clip did not act
    assert 0.05 < noise[free].std() < 0.2  # 0.05 of the stroke is 0.1 in action units
    lag1 = np.corrcoef(noise[:-1, 0], noise[1:, 0])[0, 1]
    assert lag1 > 0.9  # low-pass: a time constant of many control intervals
    meta = noisy.storage.metadata
    assert "DART" in meta["description"]
    (plan,) = json.loads(meta["steamtemp_episodes"])
    tau = datasets.NOISE_FACTOR * sum(horizons.time_scale(ENV))
    assert plan["noise"] == {"sigma": 0.05, "tau_s": pytest.approx(tau)}
    # behaviour cloning learns from the label
    _, y = behaviour_cloning.transitions(noisy)
    np.testing.assert_array_equal(y, label.reshape(y.shape))


def test_the_same_flags_give_the_same_noise(noisy, data_dir):
    again = datasets.record(ENV, "cascade_pi_ff", 1, 3, noise=0.05, eval_seeds=(0,), version=1)
    (a,), (b,) = list(noisy.iterate_episodes()), list(again.iterate_episodes())
    np.testing.assert_array_equal(a.actions, b.actions)


def test_the_clones_memory_is_the_agents_and_plain_has_none(noisy, tmp_path):
    env = gym.make(ENV)
    memory = behaviour_cloning.memory_of(ENV)
    x, y = behaviour_cloning.transitions(noisy, memory, env)
    plain_x, _ = behaviour_cloning.transitions(noisy)
    # the env's observation first, then the memory, restarted with the episode
    np.testing.assert_array_equal(x[:, : plain_x.shape[1]], plain_x)
    online = ControllerMemory(gym.make(ENV), **memory).observation_space.shape
    assert x.shape == (len(y), *online) and online[0] > plain_x.shape[1]
    model, meta = behaviour_cloning.train(NOISY, tmp_path, plain=True, epochs=1, run=2)
    assert model.name == "steamtemp__Cascade300MW-v0__bc__run2.zip"
    doc = json.loads(meta.read_text())
    assert doc["memory"] is None and doc["action_filter_s"] is None and doc["run"] == 2
    (files,) = find(tmp_path)
    files.check()


def test_the_zoo_command_chooses_the_noise_on_validation_and_fits_three_runs(monkeypatch, tmp_path):
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "data"))
    monkeypatch.setattr(
        behaviour_cloning, "ZOO_DATASET", {"policy": "cascade_pi_ff", "episodes": 1, "seed": 3}
    )
    monkeypatch.setattr(behaviour_cloning, "ZOO_NOISES", (0.05, 0.2))
    argv = ["--zoo", "--env", "Cascade300MW-v0", "--out", str(tmp_path / "zoo")]
    assert behaviour_cloning.main(argv) == 0
    for noise in ("5", "20"):  # recorded: they were missing
        assert minari.load_dataset(f"steamtemp/Cascade300MW/cascade_pi_ff-noisy{noise}-v0")
    runs = find(tmp_path / "zoo")
    assert sorted(f.model.name for f in runs) == [
        "steamtemp__Cascade300MW-v0__bc.zip",
        "steamtemp__Cascade300MW-v0__bc__run1.zip",
        "steamtemp__Cascade300MW-v0__bc__run2.zip",
    ]
    metas = [json.loads(f.meta[0].read_text()) for f in runs]
    assert sorted(m["training"]["seed"] for m in metas) == [0, 1, 2]
    choice = metas[0]["noise_choice"]
    assert set(choice["noises"]) == {"0.05", "0.2"}
    # the chosen dataset is the better validated clone, as a checkpoint is chosen
    a, b = (choice["noises"][k] for k in ("0.05", "0.2"))
    want = "20" if validation.better_checkpoint(b, a, TUNING_TRAVEL_BUDGET) else "5"
    assert choice["dataset"] == f"steamtemp/Cascade300MW/cascade_pi_ff-noisy{want}-v0"
    assert all(m["dataset"] == choice["dataset"] for m in metas)
    for f in runs:
        f.check()


def _spoiled(tmp_path, data_dir, how: str):
    """A copy of the test dataset in a data folder of its own, spoiled as ``how`` says."""
    import shutil

    folder = tmp_path / "spoiled"
    shutil.copytree(data_dir / "steamtemp" / "Cascade300MW", folder / "steamtemp" / "Cascade300MW")
    where = folder / "steamtemp" / "Cascade300MW" / "cascade_pi_ff-v0"
    hdf5 = where / "data" / "main_data.hdf5"
    meta = where / "data" / "metadata.json"
    if how == "truncated":
        hdf5.write_bytes(hdf5.read_bytes()[: hdf5.stat().st_size // 2])
    elif how == "empty":
        hdf5.write_bytes(b"")
    elif how == "garbage metadata":
        meta.write_text("{not json")
    elif how == "another plant":  # recorded on Cascade300MW, labelled SupercriticalFSH
        m = json.loads(meta.read_text())
        spec = json.loads(m["env_spec"])
        spec["id"] = "steamtemp/SupercriticalFSH-v0"
        m["env_spec"] = json.dumps(spec)
        meta.write_text(json.dumps(m))
    return folder


@pytest.mark.parametrize("how", ["truncated", "empty", "garbage metadata", "another plant"])
def test_a_spoiled_dataset_is_a_bad_dataset_flag(
    capsys, monkeypatch, tmp_path, dataset, data_dir, how
):
    """A dataset whose files are damaged, or that names another plant than the one it was
    recorded on, ends behaviour cloning with exit 2 naming --dataset (it ended in a
    traceback: IndexError for the other plant), and nothing is written to --out."""
    folder = _spoiled(tmp_path, data_dir, how)
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(folder))  # restored after
    out = tmp_path / "bc"
    with pytest.raises(SystemExit) as exc:
        behaviour_cloning.main(
            ["--dataset", DATASET, "--out", str(out), "--epochs", "1", "--data-dir", str(folder)]
        )
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "argument --dataset" in err and "Traceback" not in err
    assert not out.exists() or not any(out.iterdir())
    if how == "another plant":
        assert "recorded on another env" in err
