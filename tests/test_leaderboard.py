"""The leaderboard CLI (agents/leaderboard/): flags checked before anything runs, the
per-episode record, --resume after a crash, failed episodes, strict JSON that follows
docs/leaderboard_schema.json, batched and parallel runs identical to serial ones.

Tiny scenarios (60 s) on Cascade300MW (the cheapest plant to build) with a frozen-valve
policy keep these in seconds; one test runs the real baseline on the README's scenario.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import yaml
from processes import alive, children

import agents
import baselines
import steamtemp_gym
from agents import leaderboard as lb
from agents import specs
from agents.difficulty import FrozenValves
from agents.evaluation import run_batch, run_episode
from agents.leaderboard import backends, cli, episodes, mismatch, records, trends
from agents.leaderboard.plan import DEFAULT_SCENARIOS, REFERENCE, build_plan
from agents.leaderboard.summary import REFERENCES, SCHEMA_VERSION, ZERO
from steamtemp_gym import catalog, scenarios

SCHEMA = Path(__file__).parents[1] / "docs" / "leaderboard_schema.json"

IDS = steamtemp_gym.ENV_IDS
ENV = "steamtemp/Cascade300MW-v0"
ENV2 = "steamtemp/DrumBoilerSH-v0"
TINY = """name: tiny
duration_s: 60
load: [[0, 1.0], [30, 0.95]]
"""


class Scripted(FrozenValves):
    """Frozen valves that raise ``FAIL[(name, seed)]`` at the first step of that episode.

    In a vector env (a batch of seeds, whose seeds it cannot see) it raises the first
    exception listed for its name: the leaderboard then runs each seed alone.
    """

    FAIL: dict[tuple[str, int], BaseException] = {}

    def __init__(self, env, name: str) -> None:
        super().__init__(env)
        self.env, self.name = env, name

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        if hasattr(self.env, "num_envs"):
            exc = next((e for (n, _), e in self.FAIL.items() if n == self.name), None)
        else:
            exc = self.FAIL.get((self.name, self.env.unwrapped.np_random_seed))
        if exc is not None:
            raise exc
        return super().predict(observation, state, episode_start, deterministic)


@pytest.fixture
def fake_policies(monkeypatch):
    """Policies ``frozen`` and ``flaky`` (Scripted) next to the baselines, run in this process
    as the shipped ones are."""
    for name in ("frozen", "flaky"):
        monkeypatch.setitem(baselines.REGISTRY, name, lambda env, name=name: Scripted(env, name))
    monkeypatch.setattr(baselines, "NAMES", (*baselines.NAMES, "frozen", "flaky"))
    monkeypatch.setattr(baselines, "SHIPPED", (*baselines.SHIPPED, "frozen", "flaky"))
    real = specs.Spec.make

    def make(spec, env_id, env, *rest):
        if spec.name in ("frozen", "flaky"):
            return Scripted(env, spec.name)
        return real(spec, env_id, env, *rest)

    monkeypatch.setattr(specs.Spec, "make", make)
    monkeypatch.setattr(Scripted, "FAIL", {})
    return Scripted.FAIL


@pytest.fixture
def tiny(tmp_path) -> Path:
    path = tmp_path / "tiny.yaml"
    path.write_text(TINY)
    return path


def _args(tiny: Path, out: Path, **flags: str) -> list[str]:
    base = {
        "--envs": ENV,
        "--policies": "frozen",
        "--scenarios": str(tiny),
        "--seeds": "0",
        "--out": str(out),
        "--jobs": "1",
    }
    base.update(flags)
    oracle = base.pop("oracle", None)  # the oracle (the slowest policy) only where a test asks
    return [f"{k}={v}" for k, v in base.items()] + ([] if oracle else ["--no-oracle"])


def _strict_load(path: Path):
    def reject(token):
        raise AssertionError(f"non-strict JSON token {token} in {path}")

    return json.loads(path.read_text(), parse_constant=reject)


def _jsonl(path: Path) -> list[dict]:
    text = path.read_text()
    assert text.endswith("\n")
    return [_strict_load_line(line) for line in text.splitlines()]


def _strict_load_line(line: str) -> dict:
    def reject(token):
        raise AssertionError(f"non-strict JSON token {token}")

    return json.loads(line, parse_constant=reject)


# --------------------------------------------------------------------------- bad flags
BAD_FLAGS = [
    ({"--envs": "steamtemp/Nope-v0"}, ["--envs", "Nope-v0", "Cascade300MW-v0"]),
    ({"--envs": ""}, ["--envs", "empty"]),
    ({"--envs": " , "}, ["--envs", "empty"]),
    ({"--envs": f"{ENV},nope"}, ["--envs", "nope"]),
    ({"--policies": "nope"}, ["--policies", "nope", "cascade_pi"]),
    ({"--policies": ""}, ["--policies", "empty"]),
    ({"--policies": "frozen,sb3:nope"}, ["--policies", "sb3:nope"]),
    ({"--scenarios": "nope"}, ["--scenarios", "nope", "setpoint_step"]),
    ({"--scenarios": ""}, ["--scenarios", "empty"]),
    ({"--scenarios": "setpoint_step,nope"}, ["--scenarios", "nope"]),
    ({"--scenarios": "missing.yaml"}, ["--scenarios", "missing.yaml"]),
    ({"--seeds": ""}, ["--seeds", "empty"]),
    ({"--seeds": ","}, ["--seeds", "empty"]),
    ({"--seeds": "a,b"}, ["--seeds", "'a'"]),
    ({"--seeds": "-1"}, ["--seeds", "'-1'", ">= 0"]),
    ({"--seeds": "0,-1"}, ["--seeds", "'-1'"]),
    ({"--seeds": "1.5"}, ["--seeds", "'1.5'"]),
    ({"--seeds": "1 2"}, ["--seeds", "'1 2'"]),
    ({"--seeds": "0x10"}, ["--seeds", "'0x10'"]),
    ({"--seeds": "4-2"}, ["--seeds", "4-2"]),
    ({"--seeds": "0-99999999"}, ["--seeds", "10000"]),
    ({"--seeds": "9" * 30}, ["--seeds", "larger than"]),
    ({"--out": ""}, ["--out", "empty"]),
    ({"--out": " "}, ["--out", "empty"]),
    ({"--travel-budget": "0"}, ["--travel-budget", "> 0", "'0'"]),
    ({"--travel-budget": "nan"}, ["--travel-budget", "finite"]),
    ({"--travel-budget": "two"}, ["--travel-budget", "'two'"]),
    ({"--oracle": "mpc"}, ["--oracle", "'mpc'", "optimum", "cem"]),
]


@pytest.mark.parametrize(("flags", "words"), BAD_FLAGS, ids=[repr(f) for f, _ in BAD_FLAGS])
def test_bad_flag_is_an_argparse_error_and_writes_nothing(
    flags, words, tiny, tmp_path, fake_policies, capsys
):
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as exc:
        lb.main(_args(tiny, out, **flags))
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: steamtemp-leaderboard")
    assert "Traceback" not in err
    for w in words:
        assert w in err, (w, err)
    assert not out.exists()


def test_bad_scenario_files_name_the_file_and_field(tiny, tmp_path, fake_policies, capsys):
    """Unreadable or invalid YAML, after a good scenario: exit 2, nothing written."""
    cases = {
        "neg.yaml": ("name: n\nduration_s: -1\nload: 1.0\n", "duration_s"),
        "range.yaml": ("name: r\nduration_s: 60\nload: [[0, 3.0]]\n", "load"),
        "bad.yaml": ("name: [unclosed\n", "bad.yaml"),
        "field.yaml": ("name: f\nduration_s: 60\nload: 1.0\nloud: 2\n", "loud"),
    }
    out = tmp_path / "out"
    for fname, (text, word) in cases.items():
        path = tmp_path / fname
        path.write_text(text)
        with pytest.raises(SystemExit) as exc:
            lb.main(_args(tiny, out, **{"--scenarios": f"{tiny},{path}"}))
        assert exc.value.code == 2
        err = capsys.readouterr().err
        assert "--scenarios" in err and fname in err and word in err, err
        assert "Traceback" not in err
        assert not out.exists()


def test_bad_out_is_an_argparse_error(tiny, tmp_path, fake_policies, capsys):
    afile = tmp_path / "afile"
    afile.write_text("x")
    record_dir = tmp_path / "recdir"
    (record_dir / records.EPISODES).mkdir(parents=True)
    cases = [
        (afile, "not a directory"),
        (afile / "sub", "not a directory"),
        (Path("/proc/steamtemp_leaderboard_test/out"), "--out"),  # unwritable even for root
        (record_dir, "is not a file"),
    ]
    for out, word in cases:
        with pytest.raises(SystemExit) as exc:
            lb.main(_args(tiny, out))
        assert exc.value.code == 2
        err = capsys.readouterr().err
        assert "--out" in err and word in err and "Traceback" not in err, err
    assert afile.read_text() == "x"
    assert not Path("/proc/steamtemp_leaderboard_test").exists()


def test_existing_record_needs_resume(tiny, tmp_path, fake_policies, capsys):
    out = tmp_path / "out"
    lb.main(_args(tiny, out))
    before = (out / records.EPISODES).read_text()
    with pytest.raises(SystemExit) as exc:
        lb.main(_args(tiny, out))
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "--resume" in err and "--out" in err
    assert (out / records.EPISODES).read_text() == before


def test_corrupt_record_line_is_an_error_on_resume(tiny, tmp_path, fake_policies, capsys):
    out = tmp_path / "out"
    lb.main(_args(tiny, out, **{"--seeds": "0,1"}))
    lines = (out / records.EPISODES).read_text().splitlines()
    (out / records.EPISODES).write_text("\n".join(["{not json", *lines]) + "\n")
    with pytest.raises(SystemExit) as exc:
        lb.main([*_args(tiny, out, **{"--seeds": "0,1"}), "--resume"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "line 1" in err and "--resume" in err and "Traceback" not in err


@pytest.mark.parametrize("value", ["1e308", "true", "-2e15"])
def test_a_row_with_a_return_no_episode_gives_is_an_error_on_resume(
    tiny, tmp_path, fake_policies, capsys, value
):
    """A row appended to the record with a return of 1e308 or true was taken by --resume,
    and the run then crashed in matplotlib; now it is an argparse error naming the line and
    the file is left as it was."""
    out = tmp_path / "out"
    lb.main(_args(tiny, out, **{"--seeds": "0"}))
    lines = (out / records.EPISODES).read_text().splitlines()
    row = json.loads(lines[0])
    forged = json.dumps({**row, "metrics": {**row["metrics"]}})
    forged = forged.replace(
        f'"return": {json.dumps(row["metrics"]["return"])}', f'"return": {value}'
    )
    text = "\n".join([*lines, forged, lines[0]]) + "\n"
    (out / records.EPISODES).write_text(text)
    with pytest.raises(SystemExit) as exc:
        lb.main([*_args(tiny, out, **{"--seeds": "0"}), "--resume"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert f"line {len(lines) + 1}" in err and "return" in err and "Traceback" not in err, err
    assert (out / records.EPISODES).read_text() == text


def test_duplicates_are_dropped_in_order(tiny, tmp_path, fake_policies, capsys):
    ap = cli.make_parser()
    flags = {
        "--envs": f"{ENV}, {ENV}",
        "--policies": "frozen,frozen, flaky",
        "--scenarios": f"{tiny},{tiny.parent}/./tiny.yaml",
        "--seeds": " 3, 0-2,1,,2 ",
    }
    args = ap.parse_args(_args(tiny, tmp_path / "out", **flags))
    plan = build_plan(ap, args)
    assert plan.envs == [ENV]
    assert plan.policies == {ENV: ["frozen", "flaky", "cascade_pi_ff", REFERENCE]}
    assert plan.scenarios == [str(tiny)]
    assert plan.seeds == [3, 0, 1, 2]
    assert "duplicates dropped" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_default_run_is_valid_without_running(monkeypatch, tmp_path):
    """The README's main job: every default env, policy, scenario and seed resolves."""
    monkeypatch.chdir(tmp_path)
    ap = cli.make_parser()
    plan = build_plan(ap, ap.parse_args([]))
    assert plan.envs == list(IDS) and plan.seeds == [0, 1, 2, 3, 4]
    assert plan.scenarios == list(DEFAULT_SCENARIOS)
    assert {f"heldout:{n}" for n in steamtemp_gym.scenarios.heldout.NAMES} <= set(plan.scenarios)
    for env_id in IDS:  # every baseline, every shipped agent, the references
        shipped = [
            n
            for e, a in agents.shipped()
            if e == env_id  # one name per training run
            for n in specs.training_runs(f"sb3:{a}", env_id)
        ]
        assert plan.policies[env_id] == [*baselines.NAMES, *shipped, "oracle", REFERENCE]
    n = sum(len(p) for p in plan.policies.values())
    variants = {e: len(mismatch.labels(e)) for e in IDS}  # but the two references
    m = sum((len(plan.policies[e]) - 2) * variants[e] for e in IDS)
    assert {v for e, v in variants.items() if catalog.packaged(e)} == {4}
    assert len(list(plan.grid())) == (n * len(DEFAULT_SCENARIOS) + m) * 5
    assert not (tmp_path / "leaderboard_out").exists()


def test_help_documents_failures_and_resume(capsys):
    with pytest.raises(SystemExit) as exc:
        lb.main(["--help"])
    assert exc.value.code == 0
    text = capsys.readouterr().out
    for word in (
        "--resume",
        "episodes.jsonl",
        "exit code is 1",
        "0-4",
        "duplicates",
        "--jobs",
        "heldout:",
        "frozen_valve",
        "oracle",
        "--no-oracle",
        "default:",
    ):
        assert word in text


# --------------------------------------------------------------------------- running
def _board(out: Path) -> list[dict]:
    return _strict_load(out / "leaderboard.json")["episodes"]


def test_resume_after_a_crash_completes_without_duplicates(tiny, tmp_path, fake_policies):
    """Killed in the 2nd of 6 batches, plus a half-written line: --resume runs the rest."""
    out = tmp_path / "out"
    argv = _args(
        tiny, out, **{"--envs": f"{ENV},{ENV2}", "--seeds": "0,1", "--policies": "frozen,flaky"}
    )
    fake_policies[("flaky", 1)] = KeyboardInterrupt()  # ENV: frozen 0, 1, [flaky 0, 1]
    with pytest.raises(SystemExit) as exc:
        lb.main(argv)
    assert exc.value.code == 130
    rows = _jsonl(out / records.EPISODES)
    assert [(r["env"], r["policy"], r["seed"]) for r in rows] == [
        (ENV, "frozen", 0),
        (ENV, "frozen", 1),
    ]
    assert len(_board(out)) == 2  # what finished, rebuilt
    with (out / records.EPISODES).open("a") as f:  # a crash in the middle of a write
        f.write(json.dumps(rows[-1])[:25])
    fake_policies.clear()
    lb.main([*argv, "--resume"])
    rows = _jsonl(out / records.EPISODES)
    keys = [(r["env"], r["scenario"], r["policy"], r["seed"]) for r in rows]
    assert len(keys) == len(set(keys)) == 16
    board = _board(out)
    assert [(r["env"], r["policy"], r["seed"]) for r in board] == [
        (e, p, s)
        for e in (ENV, ENV2)
        for p in ("frozen", "flaky", "cascade_pi_ff", REFERENCE)
        for s in (0, 1)
    ]
    assert all(r["metrics"] is not None and "error" not in r for r in board)
    assert {p.name for p in (out / "plots").glob("*__*.png")} == {
        "Cascade300MW-v0__tiny.png",
        "DrumBoilerSH-v0__tiny.png",
    }
    # a finished run resumed again runs nothing and rebuilds the same board
    lb.main([*argv, "--resume"])
    assert len(_jsonl(out / records.EPISODES)) == 16
    assert _board(out) == board


@pytest.mark.parametrize("every", [False, True])
def test_trend_plots_name_the_scenario_and_show_the_selection(
    tmp_path, fake_policies, monkeypatch, every
):
    """A trend plot's title names the scenario (the YAML's name, not its path); by default it
    shows the reference and the best of the others (the frozen valve only with --trend-all),
    each plant drawn once all its episodes have finished."""
    path = tmp_path / "some_file.yaml"
    path.write_text(TINY)
    calls = []
    monkeypatch.setattr(
        trends,
        "trend",
        lambda p, env, env_id, sc, traces, seed, **kw: calls.append(
            (p.name, env_id, sc, list(traces), kw["colors"])
        ),
    )
    argv = _args(
        path, tmp_path / "out", **{"--policies": "frozen,flaky", "--envs": f"{ENV},{ENV2}"}
    )
    lb.main(argv + (["--trend-all"] if every else []))
    assert [c[:3] for c in calls] == [
        ("Cascade300MW-v0__some_file.png", ENV, "tiny"),
        ("DrumBoilerSH-v0__some_file.png", ENV2, "tiny"),
    ]
    shown = ["cascade_pi_ff", "flaky", "frozen"] + (["frozen_valve"] if every else [])
    assert all(sorted(c[3]) == sorted(shown) and c[3][0] == "cascade_pi_ff" for c in calls)
    assert all(len(set(c[4].values())) == len(c[4]) for c in calls)


def test_failed_episode_is_recorded_and_the_run_goes_on(tiny, tmp_path, fake_policies, capsys):
    """A batch that raises runs its seeds alone: only the failing seed is a failed row."""
    out = tmp_path / "out"
    argv = _args(tiny, out, **{"--seeds": "0,1", "--policies": "frozen,flaky"})
    fake_policies[("flaky", 0)] = RuntimeError("controller diverged")
    with pytest.raises(SystemExit) as exc:
        lb.main(argv)
    assert exc.value.code == 1
    err = capsys.readouterr().err
    assert "1 of 8 episodes failed" in err and "controller diverged" in err and "--resume" in err
    rows = _jsonl(out / records.EPISODES)
    assert len(rows) == 8
    (bad,) = [r for r in rows if "error" in r]
    assert (bad["policy"], bad["seed"], bad["metrics"]) == ("flaky", 0, None)
    assert "RuntimeError: controller diverged" in bad["error"] and "Traceback" in bad["traceback"]
    board = _board(out)
    assert len(board) == 8 and sum("error" in r for r in board) == 1
    assert all("traceback" not in r for r in board)
    md = (out / "leaderboard.md").read_text()
    assert "Failed episodes" in md and "controller diverged" in md and "| flaky |" in md
    # the cause fixed, --resume runs only the failed episode
    fake_policies.clear()
    lb.main([*argv, "--resume"])
    rows = _jsonl(out / records.EPISODES)
    assert len(rows) == 9 and (rows[-1]["policy"], rows[-1]["seed"]) == ("flaky", 0)
    board = _board(out)
    assert len(board) == 8 and not any("error" in r for r in board)
    assert "Failed episodes" not in (out / "leaderboard.md").read_text()


def test_policy_that_cannot_be_built_fails_its_episodes_only(
    tiny, tmp_path, fake_policies, monkeypatch
):
    make = specs.Spec.make

    def broken(spec, env_id, env, *rest):
        if spec.name == "flaky":
            raise ValueError("no such tuning")
        return make(spec, env_id, env, *rest)

    monkeypatch.setattr(specs.Spec, "make", broken)
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as exc:
        lb.main(_args(tiny, out, **{"--seeds": "0,1", "--policies": "flaky,frozen"}))
    assert exc.value.code == 1
    board = _board(out)
    assert [("error" in r, r["policy"]) for r in board] == [
        (True, "flaky"),
        (True, "flaky"),
        (False, "frozen"),
        (False, "frozen"),
        (False, "cascade_pi_ff"),
        (False, "cascade_pi_ff"),
        (False, REFERENCE),
        (False, REFERENCE),
    ]
    assert list((out / "plots").glob("*.png"))


def test_changed_scenario_runs_again_on_resume(tiny, tmp_path, fake_policies):
    out = tmp_path / "out"
    argv = _args(tiny, out)
    lb.main(argv)
    fps = {r["fingerprint"] for r in _jsonl(out / records.EPISODES)}
    tiny.write_text(TINY.replace("0.95", "0.9"))
    lb.main([*argv, "--resume"])
    rows = _jsonl(out / records.EPISODES)
    assert len(rows) == 6 and not {r["fingerprint"] for r in rows[3:]} & fps
    assert [r["fingerprint"] for r in _board(out)] == [r["fingerprint"] for r in rows[3:]]


def test_outputs_are_strict_json_that_follows_the_schema(tiny, tmp_path, fake_policies):
    """Metrics that do not apply (no setpoint step: no settling time) are null in the rows
    and left out of the summary and the markdown (never NaN)."""
    jsonschema = pytest.importorskip("jsonschema")
    out = tmp_path / "out"
    lb.main(_args(tiny, out, **{"--seeds": "0-1"}))
    doc = _strict_load(out / "leaderboard.json")
    jsonschema.validate(doc, json.loads(SCHEMA.read_text()))
    assert doc["schema_version"] == SCHEMA_VERSION
    board = doc["episodes"]
    assert len(board) == 6
    for r in board:
        assert r["metrics"]["settling_time_s"] is None
        assert set(r) == {"env", "scenario", "policy", "seed", "fingerprint", "metrics"}
        assert all(v is None or np.isfinite(v) for v in r["metrics"].values())
    assert _jsonl(out / records.EPISODES) == board
    cells = doc["plants"][ENV]["scenarios"][str(tiny)]
    assert all("settling_time_s" not in c for c in cells.values())
    md = (out / "leaderboard.md").read_text()
    assert "nan" not in md.lower().replace("tanh", "")
    assert records.dumps({"a": float("inf"), "b": np.float32("nan"), "c": [np.int64(3)]}) == (
        '{"a": null, "b": null, "c": [3]}'
    )
    with pytest.raises(jsonschema.ValidationError):  # the schema is not vacuous
        bad = dict(doc, schema_version=1)
        jsonschema.validate(bad, json.loads(SCHEMA.read_text()))


@pytest.mark.parametrize("engine", ["optimum", "cem"])
def test_every_output_names_the_oracles_engine(tiny, tmp_path, fake_policies, engine):
    """``--oracle optimum`` scores against the whole-episode optimum (solved here: the tiny
    episodes are not stored), ``--oracle cem`` against the CEM search, and leaderboard.json
    and leaderboard.md say which; the oracle's return is above the frozen valves'."""
    out = tmp_path / engine
    lb.main([*_args(tiny, out, oracle="1"), f"--oracle={engine}"])
    doc = _strict_load(out / "leaderboard.json")
    assert doc["run"]["oracle"] == engine
    md = (out / "leaderboard.md").read_text()
    assert ("a lower bound of the clairvoyant optimum" in md) == (engine == "cem")
    assert ("the clairvoyant optimum of each episode" in md) == (engine == "optimum")
    ret = {r["policy"]: r["metrics"]["return"] for r in _jsonl(out / records.EPISODES)}
    assert ret["oracle"] > ret["frozen"]


def test_run_batch_is_identical_to_run_episode():
    """Seeds side by side in the vector env give the single env's traces bit for bit, for
    every baseline and the reference (a trip ends a row early: frozen valve, deep ramp)."""
    sc = steamtemp_gym.scenarios.heldout.load("deep_fast_ramp")
    env_id = "steamtemp/SupercriticalFSH-v0"
    env = gym.make(env_id, scenario=sc)
    venv = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point", scenario=sc)
    for name in (*baselines.NAMES, REFERENCE):
        serial = [
            run_episode(env, specs.parse(name, references=True).make(env_id, env), s)
            for s in (3, 7)
        ]
        batch = run_batch(venv, specs.parse(name, references=True).make(env_id, venv), [3, 7])
        for a, b in zip(serial, batch, strict=True):
            assert a["metrics"] == b["metrics"], name
            for k in a["trace"]:
                np.testing.assert_array_equal(a["trace"][k], b["trace"][k], err_msg=name)
    assert serial[0]["metrics"]["tripped"] == 1.0  # the frozen valve trips on it


def test_rows_of_their_own_scenarios_equal_run_episode():
    """Rows of different scenarios side by side in one vector env (the leaderboard's
    batches: episodes.RowScenarios) give each scenario's single-env traces bit for bit."""
    sc = [
        scenarios.Scenario.from_dict(yaml.safe_load(TINY)),
        scenarios.Scenario.from_dict(yaml.safe_load(TINY.replace("0.95", "0.9"))),
    ]
    rows, seeds = [sc[1], sc[0], sc[1]], [3, 7, 7]
    venv = gym.make_vec(ENV, num_envs=3, vectorization_mode="vector_entry_point", scenario=sc[0])
    venv = episodes.RowScenarios(venv, rows)
    for name in ("cascade_pi_ff", "lqi", "mpc_linear"):
        batch = run_batch(venv, specs.parse(name, references=True).make(ENV, venv), seeds)
        for s, row, b in zip(seeds, rows, batch, strict=True):
            env = gym.make(ENV, scenario=row)
            a = run_episode(env, specs.parse(name, references=True).make(ENV, env), s)
            assert a["metrics"] == b["metrics"], name
            for k in a["trace"]:
                np.testing.assert_array_equal(a["trace"][k], b["trace"][k], err_msg=name)
    assert batch[1]["metrics"] != batch[2]["metrics"]  # the scenario, not the seed, differs
    with pytest.raises(ValueError, match="2 scenarios for 3 sub-envs"):
        episodes.RowScenarios(venv.env, rows[:2])


OWN = str(Path(__file__).parents[1] / "examples" / "my_controller.py") + ":make_controller"


def _unit(spec, sc, policy="lqi", params=None):
    return episodes.Unit(ENV, spec, sc, policy, [0, 1], "fp", 0, params=params)


def test_batches_group_a_shipped_policy_s_scenarios_of_equal_length():
    """A batch: one shipped policy's units on one env's nominal plant whose scenarios last
    as long; the oracle, the EV-ARX MPCs (episodes.ALONE), a mismatch variant, a policy of
    a process of its own and the drawn scenario ``random`` run alone."""
    short = scenarios.Scenario.from_dict(yaml.safe_load(TINY))
    other = scenarios.Scenario.from_dict(yaml.safe_load(TINY.replace("0.95", "0.9")))
    long = scenarios.Scenario.from_dict(yaml.safe_load(TINY.replace("60", "120")))
    units = [
        _unit("a", short),
        _unit("b", long),
        _unit("c", other),
        _unit("a", short, "fao_sf"),
        _unit("c", other, "fao_sf"),
        _unit("a", short, "oracle"),
        _unit("c", other, "oracle"),
        _unit("a", short, "mpc_arx"),
        _unit("c", other, "mpc_arx"),
        _unit("m", short, params={"k": 1}),
        _unit("n", other, params={"k": 1}),
        _unit("a", short, OWN),
        _unit("c", other, OWN),
        _unit("r", "random"),
        _unit("s", "random"),
    ]
    got = [[(u.spec, u.policy) for u in b] for b in episodes.batches(units)]
    assert got == [
        [("a", "lqi"), ("c", "lqi")],
        [("b", "lqi")],
        [("a", "fao_sf"), ("c", "fao_sf")],
        [("a", "oracle")],
        [("c", "oracle")],
        [("a", "mpc_arx")],
        [("c", "mpc_arx")],
        [("m", "lqi")],
        [("n", "lqi")],
        [("a", OWN)],
        [("c", OWN)],
        [("r", "lqi")],
        [("s", "lqi")],
    ]


def test_a_batch_that_raises_runs_its_units_then_seeds_alone(tmp_path, fake_policies):
    """Two scenarios of one length run as one batch; when it raises, only the failing
    episode is a failed row, and the others equal a run without the failure."""
    paths = []
    for i, text in enumerate((TINY, TINY.replace("0.95", "0.9"))):
        paths.append(tmp_path / f"tiny{i}.yaml")
        paths[-1].write_text(text)
    flags = {"--seeds": "0,1", "--policies": "flaky", "--scenarios": f"{paths[0]},{paths[1]}"}
    lb.main(_args(paths[0], tmp_path / "ok", **flags))
    fake_policies[("flaky", 1)] = RuntimeError("controller diverged")
    with pytest.raises(SystemExit):
        lb.main(_args(paths[0], tmp_path / "bad", **flags))
    ok, bad = _board(tmp_path / "ok"), _board(tmp_path / "bad")
    failed = [(r["scenario"], r["seed"]) for r in bad if "error" in r]
    assert failed == [(str(paths[0]), 1), (str(paths[1]), 1)]
    assert [r for r in bad if "error" not in r] == [
        r for r in ok if r["seed"] == 0 or r["policy"] != "flaky"
    ]


def test_parallel_rows_equal_in_process_rows(tiny, tmp_path):
    """--jobs 2 (worker processes) writes the same rows as --jobs 1."""
    flags = {
        "--policies": "cascade_pi,lqi",
        "--seeds": "0-2",
        "--scenarios": f"{tiny},setpoint_step",
    }
    lb.main(_args(tiny, tmp_path / "a", **flags))
    lb.main(_args(tiny, tmp_path / "b", **flags, **{"--jobs": "2"}))
    a = _strict_load(tmp_path / "a" / "leaderboard.json")
    b = _strict_load(tmp_path / "b" / "leaderboard.json")
    assert a["episodes"] == b["episodes"] and a["plants"] == b["plants"]


def test_ray_backend_rows_equal_local_rows(tiny, tmp_path):
    """--backend ray on a local 2-CPU Ray writes the same rows as the local backend."""
    pytest.importorskip("ray")
    import ray

    flags = {
        "--policies": "cascade_pi,lqi",
        "--seeds": "0-1",
        "--scenarios": f"{tiny},setpoint_step",
    }
    lb.main(_args(tiny, tmp_path / "a", **flags))
    try:
        lb.main([*_args(tiny, tmp_path / "b", **flags, **{"--jobs": "2"}), "--backend=ray"])
    finally:
        ray.shutdown()
    a = _strict_load(tmp_path / "a" / "leaderboard.json")
    b = _strict_load(tmp_path / "b" / "leaderboard.json")
    assert len(a["episodes"]) == 2 * 2 * 4  # scenarios x seeds x (2 + cascade_pi_ff, frozen)
    assert a["episodes"] == b["episodes"] and a["plants"] == b["plants"]


def test_ray_flags_are_checked(tiny, tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        lb.main([*_args(tiny, tmp_path / "c"), "--ray-address=auto"])
    assert exc.value.code == 2 and "only with --backend ray" in capsys.readouterr().err
    assert not (tmp_path / "c").exists()


def test_leaderboard_cli_with_the_baseline(tmp_path):
    """The real baselines, agents and references on two scenarios: rows, summary (0 =
    cascade_pi_ff, 1 = oracle), markdown and plots."""
    lb.main(
        [
            "--envs",
            IDS[0],
            "--scenarios",
            "setpoint_step,heldout:mill_trip",
            "--seeds",
            "0,1",
            "--out",
            str(tmp_path),
        ]
    )
    doc = _strict_load(tmp_path / "leaderboard.json")
    rows = doc["episodes"]
    trained = [f"sb3:{a}" for e, a in agents.shipped() if e == IDS[0]]  # shipped agents too
    runs = sum(len(agents.runs(IDS[0], t.removeprefix("sb3:"))) for t in trained)
    assert len(rows) == 2 * 2 * (len(baselines.NAMES) + runs + 2)  # a row per training run
    assert all(np.isfinite(r["metrics"]["iae_K_s"]) for r in rows)
    pols = doc["plants"][IDS[0]]["policies"]
    refs = REFERENCES
    ranks = sorted(e["rank"] for p, e in pols.items() if p not in refs)
    assert ranks[0] == 1 and len(ranks) == len(baselines.NAMES) + len(trained)
    assert all("rank" not in pols[r] for r in refs)
    zero = ZERO
    assert f"p_improvement_over_{zero}" not in pols[zero]
    assert all(
        0 <= e[f"p_improvement_over_{zero}"]["value"] <= 1 for p, e in pols.items() if p != zero
    )
    assert pols[zero]["normalized_score"]["mean"]["value"] == pytest.approx(0.0)
    for sc, ref in doc["plants"][IDS[0]]["reference"].items():  # the oracle at 1, or floored
        cell = doc["plants"][IDS[0]]["scenarios"][sc]["oracle"]
        assert cell["normalized_score"] == pytest.approx(ref["headroom"] / ref["span"])
        assert ref["span"] >= ref["headroom"]
    admissible = [*baselines.NAMES, *trained]
    best = max(pols[p]["normalized_score"]["mean"]["value"] for p in admissible)
    assert best <= pols["oracle"]["normalized_score"]["mean"]["value"]
    md = (tmp_path / "leaderboard.md").read_text()
    assert "cascade_pi_ff" in md and "setpoint_step" in md and "## Headline" in md
    assert "IQM of the normalized score over scenario × seed (2 seeds)" in md
    assert "| ref. | oracle |" in md and "margin" in md
    # the agents table: cascade_pi_ff, the best other baseline, every shipped agent, one bold
    part = md.split("## Trained agents against the baselines")[1].split("\n## ")[0]
    table = [line for line in part.splitlines() if line.startswith("| SupercriticalFSH")]
    others = [p for p in baselines.NAMES if p != zero]
    best_base = max(others, key=lambda p: pols[p]["normalized_score"]["iqm"]["value"])
    assert [r.split(" | ")[1] for r in table] == [
        zero,
        f"{best_base} (best baseline)",
        *sorted(trained),
    ]
    assert [r.split(" | ")[2] for r in table] == [
        "baseline",
        "baseline",
        *(agents.kind(t[4:]) for t in sorted(trained)),
    ]
    assert sum(r.split(" | ")[3].startswith("**") for r in table) == 1
    names = {p.name for p in (tmp_path / "plots").glob("*.png")}
    assert {
        "scores.png",
        "profiles.png",
        "pareto.png",
        "SupercriticalFSH-v0__heldout_mill_trip.png",
    } <= names
    with pytest.raises(SystemExit):
        lb.main(["--envs", "steamtemp/Nope-v0", "--out", str(tmp_path / "x")])


# ------------------------------------------------------------- concurrency and signals
def test_resume_refuses_a_hand_edited_row_without_metrics(tiny, tmp_path, fake_policies, capsys):
    """A well-formed row of a finished episode whose metrics were emptied by hand is an
    argparse error naming the line and what it lacks, not a KeyError traceback."""
    out = tmp_path / "out"
    lb.main(_args(tiny, out, **{"--seeds": "0,1"}))
    rows = _jsonl(out / records.EPISODES)
    rows[0]["metrics"] = {}
    (out / records.EPISODES).write_text("".join(json.dumps(r) + "\n" for r in rows))
    with pytest.raises(SystemExit) as exc:
        lb.main([*_args(tiny, out, **{"--seeds": "0,1"}), "--resume"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "line 1" in err and "metrics lack" in err and "Traceback" not in err


def _start_cli(out: Path, *extra: str):
    """The leaderboard CLI in a process of its own (two workers, two policies of long
    units) once its workers run, with its worker processes' ids."""
    import subprocess
    import sys
    import time

    args = [
        sys.executable,
        "-m",
        "agents.leaderboard",
        "--envs",
        ENV,
        "--policies",
        "cascade_pi,lqi",
        "--scenarios",
        "load_ramp_100_50",
        "--seeds",
        "0-63",
        "--jobs",
        "2",
        "--no-oracle",
        "--out",
        str(out),
        *extra,
    ]
    proc = subprocess.Popen(
        args,
        cwd=Path(__file__).parents[1],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 60
    while len(workers := children(proc.pid)) < 2 and time.monotonic() < deadline:
        assert proc.poll() is None, proc.stderr.read()
        time.sleep(0.1)
    assert len(workers) >= 2, "no worker processes"
    return proc, workers


@pytest.mark.parametrize("sig", ["SIGTERM", "SIGKILL"])
def test_workers_end_with_the_leaderboard(tmp_path, sig):
    """SIGTERM (timeout, CI runners) stops the run as Ctrl-C does and its workers end with
    it; after a SIGKILL of it they end within a bounded time (a parent-death check)."""
    import signal
    import time

    proc, workers = _start_cli(tmp_path / "out")
    try:
        proc.send_signal(getattr(signal, sig))
        proc.communicate(timeout=60)  # drains stderr, which could otherwise block the child
        assert proc.returncode == (143 if sig == "SIGTERM" else -signal.SIGKILL)
        deadline = time.monotonic() + 5 * backends.PARENT_POLL_S + 3
        while any(alive(w) for w in workers) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not any(alive(w) for w in workers), f"workers {workers} outlived the run"
    finally:
        for w in workers:
            if alive(w):
                os.kill(w, signal.SIGKILL)
        if proc.poll() is None:
            proc.kill()


def test_a_second_run_on_the_same_out_is_refused(tmp_path, capsys):
    """While one run writes to --out, a second one started on it is an argparse error and
    writes nothing; the first is not disturbed."""
    import signal

    out = tmp_path / "out"
    proc, workers = _start_cli(out)
    try:
        before = (out / records.EPISODES).read_bytes()
        with pytest.raises(SystemExit) as exc:
            lb.main(
                [
                    "--envs",
                    ENV,
                    "--policies",
                    "cascade_pi",
                    "--scenarios",
                    "setpoint_step",
                    "--seeds",
                    "0",
                    "--jobs",
                    "1",
                    "--out",
                    str(out),
                    "--resume",
                ]
            )
        assert exc.value.code == 2
        assert "in use by another steamtemp-leaderboard run" in capsys.readouterr().err
        assert (out / records.EPISODES).read_bytes()[: len(before)] == before
        assert proc.poll() is None
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=30)


def test_library_log_writes_to_the_stderr_of_the_moment(monkeypatch):
    """The compile notice goes to the current stderr, not to one bound at the first run
    (which a caller may have closed since: 'Logging error ... closed file')."""
    import io
    import logging

    monkeypatch.setattr(logging.getLogger("steamtemp_gym"), "handlers", [])
    first = io.StringIO()
    monkeypatch.setattr("sys.stderr", first)
    cli.show_library_log()
    first.close()
    now = io.StringIO()
    monkeypatch.setattr("sys.stderr", now)
    logging.getLogger("steamtemp_gym").warning("steamtemp_gym: compiling")
    assert now.getvalue() == "steamtemp_gym: compiling\n"
