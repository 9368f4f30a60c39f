"""Independent training runs of an agent: the run-indexed file names (agents/files.py),
the zoo's runs (agents.runs; a file without a run index is run 0), the policy names of
runs (agents/specs.py), ``python -m agents.train --zoo --runs K`` with its flags checked,
tiny runs trained locally and as Ray tasks (the same files either way), and the
leaderboard scoring each run of a zoo agent and reporting the agent once."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml
from stand_ins import refused_entry

import agents
from agents import files, specs, stats, train, train_config, train_runs, training, validation
from agents import leaderboard as lb

ENV = "steamtemp/BensonSubcritical-v0"  # 5 s control interval: short validation episodes
TINY_PPO = {
    ENV: {
        "n_envs": 2,
        "policy": "MlpPolicy",
        "n_steps": 64,
        "batch_size": 64,
        "n_epochs": 1,
        "policy_kwargs": "dict(net_arch=dict(pi=[8], vf=[8]))",
    }
}
TINY_SCENARIO = "name: tiny\nduration_s: 60\nload: [[0, 1.0], [30, 0.95]]\n"


# --------------------------------------------------------------------------- names
@pytest.mark.parametrize(
    ("env_id", "algo", "run"),
    [
        ("steamtemp/Cascade300MW-v0", "ppo", None),
        ("steamtemp/Cascade300MW-v0", "ppo", 0),
        ("steamtemp/DrumBoilerSH-v0", "sac_caps", 2),
        ("steamtemp/X-v0", "ppo_residual", 10),
        ("MyEnv-v1", "td3", 99),
        ("a/b/c-v0", "recurrentppo", 1),
    ],
)
def test_stems_read_back(env_id, algo, run):
    name = files.stem(env_id, algo, run)
    assert files.parse_stem(name) == (env_id, algo, run)
    assert name.endswith(algo if run is None else f"{algo}__run{run}")


def test_the_stem_of_a_run():
    name = files.stem("steamtemp/Cascade300MW-v0", "ppo", 2)
    assert name == "steamtemp__Cascade300MW-v0__ppo__run2"
    assert files.parse_stem("steamtemp__Cascade300MW-v0__ppo") == (
        "steamtemp/Cascade300MW-v0",
        "ppo",
        None,
    )


@pytest.mark.parametrize(
    "name",
    [
        "",
        "ppo",
        "__ppo",
        "steamtemp__X-v0__",
        "steamtemp__X-v0__ppo__",
        "e__ppo__run",
        "e__ppo__run01",
        "e__ppo__run-1",
        "e__ppo__run1.5",
        "e__run3",
        "e__run",
        "e____x__ppo",
        "e__pp o",
        "e__ppo__run 1",
        "e__ppo___run1",
        None,
        3,
    ],
)
def test_bad_stems_are_refused(name):
    with pytest.raises(ValueError, match="not a trained agent's file stem"):
        files.parse_stem(name)


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (("steamtemp__X-v0", "ppo"), "env id"),
        (("", "ppo"), "env id"),
        (("e/", "ppo"), "env id"),
        (("e", "ppo", -1), "run index"),
        (("e", "ppo", True), "run index"),
        (("e", "ppo", 1.0), "run index"),
        (("e", "ppo", "1"), "run index"),
        (("e", ""), "algo"),
        (("e", "a__b"), "algo"),
        (("e", "p o"), "algo"),
        (("e", "run2"), "algo"),
    ],
)
def test_bad_stem_parts_are_refused(args, match):
    with pytest.raises(ValueError, match=match):
        files.stem(*args)


# --------------------------------------------------------------------------- a zoo's runs
def _fake(d: Path, name: str) -> None:
    """A model .zip and .json pair (contents only hashed, never loaded)."""
    (d / f"{name}.zip").write_bytes(name.encode())
    (d / f"{name}.json").write_text("{}")


def test_a_file_without_run_index_is_run_0_unless_run0_is_there(tmp_path):
    for k in (None, 1, 2):
        _fake(tmp_path, files.stem(ENV, "ppo", k))
    (tmp_path / f"{files.stem(ENV, 'sac', 5)}.zip").write_bytes(b"no .json: not an agent")
    assert files.zoo_runs(tmp_path) == {(ENV, "ppo"): [0, 1, 2]}
    assert agents.runs(ENV, "ppo", zoo=tmp_path) == [0, 1, 2]
    assert files.steamtemp_files(tmp_path, ENV, "ppo").model.name == f"{files.stem(ENV, 'ppo')}.zip"
    assert files.steamtemp_files(tmp_path, ENV, "ppo", 2).model.stem == files.stem(ENV, "ppo", 2)
    with pytest.raises(ValueError, match="__run3.zip"):
        files.steamtemp_files(tmp_path, ENV, "ppo", 3)
    _fake(tmp_path, files.stem(ENV, "ppo", 0))
    assert files.zoo_runs(tmp_path) == {(ENV, "ppo"): [0, 1, 2]}
    assert files.steamtemp_files(tmp_path, ENV, "ppo", 0).model.stem == files.stem(ENV, "ppo", 0)


def test_a_zoo_file_with_a_bad_name_is_refused(tmp_path):
    _fake(tmp_path, "model")
    with pytest.raises(ValueError, match="'model' is not a trained agent's file stem"):
        files.zoo_runs(tmp_path)


def test_the_shipped_zoo_holds_runs_0_to_k_of_each_agent():
    """Every shipped agent has run 0 (the file without a run index) and runs 1..k-1 beside
    it; an agent with several runs is scored as one name per run, one with a single run
    under its own name."""
    assert agents.shipped()
    for env_id, algo in agents.shipped():
        ks = agents.runs(env_id, algo)
        assert ks == list(range(len(ks))), (env_id, algo, ks)
        assert files.steamtemp_files(agents.ZOO, env_id, algo).model.stem == files.stem(
            env_id, algo
        )
        names = specs.training_runs(f"sb3:{algo}", env_id)
        assert names == (
            [f"sb3:{algo}"] if ks == [0] else [specs.run_name(f"sb3:{algo}", k) for k in ks]
        )
    assert specs.parse("sb3:ppo@run0").run == 0


def test_a_zoo_with_one_run_scores_it_under_its_own_name(tmp_path, monkeypatch):
    """A zoo holding only run 0 of an agent (the file without a run index) scores it as
    ``sb3:<algo>`` and refuses another run by name."""
    stem = files.stem(ENV, "ppo")
    for suffix in (".zip", ".json"):
        shutil.copy(agents.ZOO / (stem + suffix), tmp_path / (stem + suffix))
    monkeypatch.setattr(agents, "ZOO", tmp_path)
    assert agents.runs(ENV, "ppo") == [0]
    assert specs.training_runs("sb3:ppo", ENV) == ["sb3:ppo"]
    with pytest.raises(ValueError, match="no trained agent 'ppo' run 1 shipped"):
        agents.load(ENV, "ppo", run=1)


def test_policy_names_of_runs(tmp_path, monkeypatch):
    for k in (0, 1, 2):  # the shipped runs' files (a policy name is checked against its model)
        shipped = files.steamtemp_files(agents.ZOO, ENV, "ppo", k)
        for f in (shipped.model, *shipped.meta):
            shutil.copy(f, tmp_path / (files.stem(ENV, "ppo", k) + f.suffix))
    _fake(tmp_path, files.stem(ENV, "sac"))
    monkeypatch.setattr(agents, "ZOO", tmp_path)
    assert specs.training_runs("sb3:ppo", ENV) == ["sb3:ppo@run0", "sb3:ppo@run1", "sb3:ppo@run2"]
    assert specs.training_runs("sb3:sac", ENV) == ["sb3:sac"]
    assert specs.training_runs("sb3:ppo@run1", ENV) == ["sb3:ppo@run1"]
    assert specs.training_runs("cascade_pi", ENV) == ["cascade_pi"]
    for name, want in (
        ("sb3:ppo@run2", ("sb3:ppo", 2)),
        ("sb3:ppo", ("sb3:ppo", None)),
        ("sb3:ppo@run02", ("sb3:ppo@run02", None)),
        ("cascade_pi", ("cascade_pi", None)),
    ):
        assert specs.split_run(name) == want
    assert specs.split_run(specs.run_name("sb3:sac_caps", 7)) == ("sb3:sac_caps", 7)
    spec = specs.parse("sb3:ppo@run2")
    assert (spec.kind, spec.target, spec.run, spec.envs) == (
        specs.SHIPPED,
        "ppo",
        2,
        frozenset({ENV}),
    )
    digests = {specs.parse(f"sb3:ppo@run{k}").digest(ENV).split(":", 2)[2] for k in (0, 1, 2)}
    assert len(digests) == 3  # each run's own files
    run0 = specs.parse("sb3:ppo@run0").digest(ENV).split(":", 2)[2]
    assert specs.parse("sb3:ppo").digest(ENV).endswith(run0)
    with pytest.raises(ValueError, match="no shipped trained agent 'sb3:ppo@run02'"):
        specs.parse("sb3:ppo@run02")


# --------------------------------------------------------------------------- the CLI
@pytest.mark.parametrize(
    ("value", "match"),
    [
        ("0", "from 1 to 100, got 0"),
        ("-1", "from 1 to 100, got -1"),
        ("101", "got 101"),
        ("x", "integer >= 1, got 'x'"),
        ("1.5", "integer >= 1, got '1.5'"),
        ("", "got ''"),
    ],
)
def test_bad_runs_are_argparse_errors(value, match, capsys):
    with pytest.raises(SystemExit) as exc:
        train.main(["--zoo", "--runs", value])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and "argument --runs" in err and match in err


@pytest.mark.parametrize(
    ("argv", "match"),
    [
        (["--env", ENV, "--algo", "ppo", "--runs", "2"], "argument --runs: only with --zoo"),
        (
            ["--env", ENV, "--algo", "ppo", "--backend", "ray"],
            "argument --backend: only with --zoo",
        ),
        (["--zoo", "--address", "auto"], "argument --address: only with --backend ray"),
        (["--zoo", "--backend", "ray", "--jobs", "0"], "argument --jobs: must be >= 1"),
        (["--zoo", "--jobs", "2"], "argument --jobs: only with --backend ray"),
        (["--zoo", "--backend", "dask"], "invalid choice: 'dask'"),
        (["--zoo", "--max-minutes", "0"], "--max-minutes must be > 0"),
        (["--env", ENV, "--algo", "ppo", "--resume"], "argument --resume: only with --zoo"),
        (["--zoo", "--algo", "ppo", "--hyperparams", "/no/such.yml"], "/no/such.yml: no such file"),
        (
            ["--zoo", "--algo", "nope", "--hyperparams", str(train_config.HYPERPARAMS / "ppo.yml")],
            "unknown algo 'nope'",
        ),
    ],
)
def test_zoo_flags_are_checked_before_training(argv, match, argparse_error):
    assert match in argparse_error(train.main, argv)


def test_every_entry_is_checked_before_the_first_run(tmp_path, argparse_error):
    yml = tmp_path / "ppo.yml"
    other = "steamtemp/Cascade300MW-v0"
    yml.write_text(yaml.safe_dump({ENV: TINY_PPO[ENV], other: {**TINY_PPO[ENV], "speed": 3}}))
    argv = [
        "--zoo",
        "--algo",
        "ppo",
        "--runs",
        "2",
        "--hyperparams",
        str(yml),
        "--out",
        str(tmp_path / "zoo"),
    ]
    assert "unknown key(s) ['speed']" in argparse_error(train.main, argv)
    assert not (tmp_path / "zoo").exists()


def test_a_file_given_with_its_algo_trains_its_own_entries(tmp_path):
    """--hyperparams with --algo: the entries of that file, shipped entry or not."""
    yml = tmp_path / "recurrentppo.yml"
    yml.write_text(yaml.safe_dump({ENV: {}, "steamtemp/Cascade300MW-v0": {}}))
    assert train_runs.entries_of(yml) == [ENV, "steamtemp/Cascade300MW-v0"]
    assert train_runs.entries_of(tmp_path / "none.yml") == []
    yml.write_text("a: [")
    with pytest.raises(train_config.ConfigError, match="cannot read it as YAML"):
        train_runs.entries_of(yml)


def test_run_seeds_never_share_a_training_env_seed(tmp_path):
    assert [train_runs.run_seed(5, k) for k in range(3)] == [5, 1005, 2005]
    jobs = train_runs.zoo_jobs([(ENV, "ppo"), (ENV, "sac")], tmp_path, 7, 3, 2.0, timesteps=None)
    assert [(j["algo"], j["run"], j["seed"]) for j in jobs] == [
        ("ppo", 0, 7),
        ("ppo", 1, 1007),
        ("ppo", 2, 2007),
        ("sac", 0, 7),
        ("sac", 1, 1007),
        ("sac", 2, 2007),
    ]
    assert all(j["max_minutes"] == 2.0 and "timesteps" not in j for j in jobs)
    (one,) = train_runs.zoo_jobs([(ENV, "ppo")], tmp_path, 7, None, 2.0, timesteps=300)
    assert (one["run"], one["seed"], one["timesteps"]) == (None, 7, 300)
    n_envs = [
        hp.get("n_envs", 1)
        for f in train_config.HYPERPARAMS.glob("*.yml")
        for hp in (yaml.safe_load(f.read_text()) or {}).values()
    ]
    assert n_envs and max(n_envs) < train_runs.RUN_SEED_STRIDE
    assert train_runs.run_seed(0, train_runs.MAX_RUNS) < validation.VALIDATION_SEED


# --------------------------------------------------------------------------- tiny runs
def _zoo_args(tmp: Path, out: Path) -> list[str]:
    yml = tmp / "ppo.yml"
    yml.write_text(yaml.safe_dump(TINY_PPO))
    return [
        "--zoo",
        "--env",
        ENV,
        "--algo",
        "ppo",
        "--runs",
        "2",
        "--timesteps",
        "256",
        "--hyperparams",
        str(yml),
        "--out",
        str(out),
        "--max-minutes",
        "30",
    ]
    # the cap is passed on to every run but never binds: a run stopped by the wall clock on
    # a busy machine would train fewer steps than its twin


@pytest.fixture(scope="module")
def local_zoo(tmp_path_factory) -> Path:
    """Two tiny runs of PPO trained one after the other."""
    tmp = tmp_path_factory.mktemp("local")
    train.main(_zoo_args(tmp, tmp / "zoo"))
    return tmp / "zoo"


def _meta(zoo: Path, run: int) -> dict:
    return json.loads(files.steamtemp_paths(zoo, ENV, "ppo", run)[1].read_text())


def _outcome(meta: dict) -> dict:
    """What a run's result is, without its times."""
    curve = [
        {k: v for k, v in c.items() if k not in ("wall_s", "cpu_s")}
        for c in meta["validation"]["curve"]
    ]
    return {
        "seed": meta["seed"],
        "run": meta["run"],
        "steps": meta["timesteps_trained"],
        "curve": curve,
        "normalization": meta["normalization"],
    }


def test_local_runs_write_run_indexed_files_with_their_seeds(local_zoo, tmp_path):
    assert sorted(f.name for f in local_zoo.iterdir()) == [
        f"{files.stem(ENV, 'ppo', k)}{ext}" for k in (0, 1) for ext in (".json", ".zip")
    ]
    m0, m1 = _meta(local_zoo, 0), _meta(local_zoo, 1)
    assert (m0["run"], m0["seed"], m1["run"], m1["seed"]) == (0, 0, 1, train_runs.RUN_SEED_STRIDE)
    assert m0["validation"]["curve"] != m1["validation"]["curve"]  # independent runs
    assert agents.runs(ENV, "ppo", zoo=local_zoo) == [0, 1]
    pol = agents.load(ENV, "ppo", zoo=local_zoo, run=1)
    assert pol.predict(np.zeros(pol.n_obs))[0].shape == (2,)
    again = training.train(
        training.checked_run(
            ENV,
            "ppo",
            local_zoo.parent / "ppo.yml",
            timesteps=256,
            seed=1000,
            out=tmp_path,
            max_minutes=30,
            quiet=True,
            run=1,
        )
    )
    assert _outcome(again) == _outcome(m1)  # same seed, same run
    assert files.steamtemp_paths(tmp_path, ENV, "ppo", 1)[0].is_file()


def test_a_resumed_rebuild_trains_only_the_runs_not_there(local_zoo, tmp_path):
    import shutil

    zoo = tmp_path / "zoo"
    shutil.copytree(local_zoo, zoo)
    before = {f.name: f.stat().st_mtime_ns for f in zoo.iterdir()}
    argv = _zoo_args(local_zoo.parent, zoo)
    argv[argv.index("--runs") + 1] = "3"
    train.main([*argv, "--resume"])
    after = {f.name: f.stat().st_mtime_ns for f in zoo.iterdir()}
    assert {k: after[k] for k in before} == before  # runs 0 and 1 untouched
    assert sorted(set(after) - set(before)) == [
        f"{files.stem(ENV, 'ppo', 2)}{ext}" for ext in (".json", ".zip")
    ]
    assert _meta(zoo, 2)["seed"] == 2 * train_runs.RUN_SEED_STRIDE


def test_ray_runs_equal_local_runs(local_zoo, tmp_path):
    """--backend ray on a new local Ray of one CPU: each run a task, the same results."""
    pytest.importorskip("ray", reason="the ray extra is not installed")
    import ray

    try:
        train.main([*_zoo_args(tmp_path, tmp_path / "zoo"), "--backend", "ray", "--jobs", "1"])
    finally:
        ray.shutdown()
    for k in (0, 1):
        assert _outcome(_meta(tmp_path / "zoo", k)) == _outcome(_meta(local_zoo, k))


def test_the_leaderboard_scores_each_run_and_reports_the_agent(local_zoo, tmp_path, monkeypatch):
    monkeypatch.setattr(agents, "ZOO", local_zoo)
    tiny = tmp_path / "tiny.yaml"
    tiny.write_text(TINY_SCENARIO)
    lb.main(
        [
            "--envs",
            ENV,
            "--policies",
            "cascade_pi,sb3:ppo",
            "--scenarios",
            str(tiny),
            "--seeds",
            "0-2",
            "--jobs",
            "1",
            "--out",
            str(tmp_path / "lb"),
        ]
    )
    doc = json.loads((tmp_path / "lb" / "leaderboard.json").read_text())
    assert doc["run"]["policies"][ENV][:3] == ["cascade_pi", "sb3:ppo@run0", "sb3:ppo@run1"]
    by_run = {
        k: [r["metrics"]["return"] for r in doc["episodes"] if r["policy"] == f"sb3:ppo@run{k}"]
        for k in (0, 1)
    }
    assert [len(v) for v in by_run.values()] == [3, 3]
    e = doc["plants"][ENV]["policies"]["sb3:ppo"]
    assert "sb3:ppo@run0" not in doc["plants"][ENV]["policies"]
    assert e["training_runs"] == [0, 1] and e["episodes"] == 6
    assert len(e["normalized_score"]["iqm"]["per_run"]) == 2
    assert e["return"]["iqm"]["per_run"] == pytest.approx(
        [stats.iqm(np.array(v)) for v in by_run.values()]
    )
    md = (tmp_path / "lb" / "leaderboard.md").read_text()
    assert "| sb3:ppo |" in md and "(2 runs)" in md
    # the agents' table and learning curves of docs/agents/plant_scale.md, from this run and its zoo
    tables = _script("agent_tables").tables(tmp_path / "lb", ["cascade_pi"])
    (row,) = [line for line in tables.splitlines() if line.startswith("| `sb3:ppo` |")]
    per_run = " / ".join(f"{v:.2f}" for v in e["normalized_score"]["iqm"]["per_run"])
    assert f"| {per_run} |" in row
    steps = [_meta(local_zoo, k)["timesteps_trained"] for k in (0, 1)]
    assert " / ".join(f"{n / 1e6:.1f}M" for n in steps) in row
    page = tmp_path / "page.md"
    start, end = "<!-- agent-tables:start -->", "<!-- agent-tables:end -->"
    page.write_text(f"intro\n{start}\nold\n{end}\nend\n")
    _script("agent_tables").write(page, tables)
    assert page.read_text() == f"intro\n{start}\n{tables}{end}\nend\n"
    curves = _script("learning_curves")
    assert curves.main([str(local_zoo), "--out", str(tmp_path / "img")]) == 0
    assert (tmp_path / "img" / f"learning_{ENV.split('/')[1]}.png").stat().st_size > 10_000


def _script(name: str):
    """A script of scripts/ as a module."""
    import importlib.util

    path = Path(__file__).resolve().parents[1] / "scripts" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_an_entrys_max_minutes_bounds_its_runs_where_the_command_does_not(tmp_path):
    """``max_minutes`` in a YAML entry stops its runs (here at once: after the first
    rollout) where --max-minutes is not given; --max-minutes wins where it is."""
    yml = tmp_path / "ppo.yml"
    yml.write_text(yaml.safe_dump({ENV: {**TINY_PPO[ENV], "max_minutes": 1e-4}}))
    meta = training.train(
        training.checked_run(ENV, "ppo", yml, timesteps=100_000, seed=0, out=tmp_path, quiet=True)
    )
    assert meta["timesteps_trained"] < 100_000
    (job,) = train_runs.zoo_jobs([(ENV, "ppo")], tmp_path, 0, None, None)
    assert job["max_minutes"] is None and job["default_minutes"] == train_runs.ZOO_MINUTES
    meta = training.train(
        training.checked_run(
            ENV, "ppo", yml, timesteps=128, seed=0, out=tmp_path, quiet=True, max_minutes=5.0
        )
    )
    assert meta["timesteps_trained"] == 128
    # a run under a time budget is validated at its marks of that budget and at the end of
    # the step budget, not also at the marks of the step budget
    assert [c["timesteps"] for c in meta["validation"]["curve"]] == [128]


def test_a_runs_budget_is_minutes_of_one_core_not_of_the_wall():
    """A run's clock counts its process's CPU time: waiting (a machine busy with other
    work) does not spend its budget; the metadata records both."""
    import time

    from agents.run_clock import RunClock

    clock = RunClock()
    time.sleep(0.3)
    assert clock.wall() >= 0.3 and clock.cpu() < 0.1
    sum(i * i for i in range(2_000_000))
    assert clock.cpu() > 0.05
    assert set(clock.stamp()) == {"cpu_s", "wall_s"}


@pytest.mark.parametrize("bad", [0, -1, 21, "ten", True])
def test_bad_max_minutes_in_an_entry_is_refused(tmp_path, bad):
    refused_entry(tmp_path, ENV, "ppo", {**TINY_PPO[ENV], "max_minutes": bad}, "max_minutes")
