"""A policy that is not shipped cannot cheat, hang or kill the leaderboard
(agents/leaderboard/isolated.py): it acts from a process of its own, commissioned on an
env of its own; its SystemExit, KeyboardInterrupt or hang fails its episodes and the run
ends with every row written; Ctrl-C still stops the run; and it scores exactly as the same
controller run in the leaderboard's own process.

One plant (Cascade300MW, the cheapest), a 60 s scenario, one or two seeds.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from processes import alive, children

from agents import leaderboard as lb
from agents import specs
from agents.evaluation import run_batch
from agents.leaderboard import episodes, isolated, records, sandbox
from agents.leaderboard.plan import EPISODE_TIMEOUT_S

ROOT = Path(__file__).parents[1]
ENV = "steamtemp/Cascade300MW-v0"
TINY = "name: tiny\nduration_s: 60\nload: [[0, 1.0], [30, 0.95]]\n"
POLICIES = """
import os
import sys
import time

import numpy as np

import baselines


class Scripted:
    '''Valves held at mid-stroke; ``predict`` does ``what`` first.'''

    def __init__(self, env, what=None):
        self.what = what

    def reset(self):
        pass

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        if self.what is not None:
            self.what()
        return np.zeros(np.shape(observation)[:-1] + (1,), dtype=np.float32), None


def _exit():
    sys.exit(3)


def _interrupt():
    raise KeyboardInterrupt


def _sleep():
    if os.environ.get("POLICY_SLEEPS"):
        time.sleep(1000)


def sys_exit(env):
    return Scripted(env, _exit)


def interrupt(env):
    return Scripted(env, _interrupt)


def ends_its_process(env):
    return Scripted(env, lambda: os._exit(5))


def sleeper(env):
    return Scripted(env, _sleep)


def exit_when_built(env):
    sys.exit(4)


def cheat(env):
    '''Zero the reward weights of the env it is handed and move it to another scenario.'''
    env.unwrapped.core.cfg[[6, 9, 10, 11]] = 0
    env.reset(options={"scenario": "setpoint_step"})
    return baselines.make("cascade_pi", env)


def my_lqi(env):
    return baselines.make("lqi", env)


class _Exits:
    def __reduce__(self):  # unpickled where it is received: sys.exit(7) there
        return (sys.exit, (7,))


class Smuggler(Scripted):
    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        return super().predict(observation)[0], _Exits()


def smuggler(env):
    '''Answers predict with a state that would end the process unpickling it.'''
    return Smuggler(env)
"""


@pytest.fixture
def files(tmp_path) -> tuple[Path, Path]:
    (tmp_path / "pols.py").write_text(POLICIES)
    (tmp_path / "tiny.yaml").write_text(TINY)
    return tmp_path / "pols.py", tmp_path / "tiny.yaml"


def _argv(
    files, out: Path, policies: list[str], seeds: str = "0,1", jobs: int = 1, *extra: str
) -> list[str]:
    pols, tiny = files
    names = ",".join(
        p if p in ("cascade_pi", "lqi", "cascade_pi_ff") else f"{pols}:{p}" for p in policies
    )
    return [
        "--envs",
        ENV,
        "--policies",
        names,
        "--scenarios",
        str(tiny),
        "--seeds",
        seeds,
        "--jobs",
        str(jobs),
        "--no-oracle",
        "--out",
        str(out),
        *extra,
    ]


def _rows(out: Path) -> dict[tuple[str, int], dict]:
    rows = [json.loads(line) for line in (out / records.EPISODES).read_text().splitlines()]
    return {(r["policy"].rsplit(":", 1)[-1], r["seed"]): r for r in rows}


@pytest.mark.parametrize("jobs", [1, 2])
def test_a_policy_ending_its_process_fails_its_episodes_and_the_run_goes_on(
    files, tmp_path, capsys, jobs
):
    """SystemExit, KeyboardInterrupt and os._exit in predict fail that policy's episodes;
    every other row is written, the outputs are built, the exit status is 1 with a message
    (SystemExit ended the run with status 3, nothing printed and no leaderboard.json)."""
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as exc:
        lb.main(
            _argv(
                files, out, ["cascade_pi", "sys_exit", "interrupt", "ends_its_process"], jobs=jobs
            )
        )
    assert exc.value.code == 1
    rows = _rows(out)
    assert len(rows) == 6 * 2  # the four, cascade_pi_ff, frozen_valve x 2 seeds
    for seed in (0, 1):
        assert rows["cascade_pi", seed]["metrics"] is not None
        assert "SystemExit: 3" in rows["sys_exit", seed]["error"]
        assert "KeyboardInterrupt" in rows["interrupt", seed]["error"]
        assert "ended (exit code 5)" in rows["ends_its_process", seed]["error"]
        assert "in its predict" in rows["sys_exit", seed]["error"]
    assert "sys.exit(3)" in rows["sys_exit", 0]["traceback"]  # the policy's own traceback
    doc = json.loads((out / "leaderboard.json").read_text())
    assert len(doc["episodes"]) == 12 and (out / "leaderboard.md").is_file()
    err = capsys.readouterr().err
    assert "6 of 12 episodes failed" in err and "--resume" in err


def test_a_factory_ending_the_process_is_a_bad_policy(files, tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        lb.main(_argv(files, tmp_path / "out", ["exit_when_built"]))
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "argument --policies" in err and "SystemExit: 4" in err and "in its factory" in err


def test_a_hanging_policy_times_out_and_resumes(files, tmp_path, monkeypatch, capsys):
    """--jobs 1: a predict that sleeps fails its episodes after --episode-timeout (the run
    hung at 1/4 episodes); --resume runs only those again."""
    out = tmp_path / "out"
    argv = _argv(files, out, ["sleeper"], "0,1", 1)
    monkeypatch.setenv("POLICY_SLEEPS", "1")
    t0 = time.monotonic()
    with pytest.raises(SystemExit) as exc:
        lb.main([*argv, "--episode-timeout", "10"])
    assert exc.value.code == 1 and time.monotonic() - t0 < 180
    rows = _rows(out)
    for seed in (0, 1):
        assert "timed out" in rows["sleeper", seed]["error"]
        assert "--episode-timeout 10" in rows["sleeper", seed]["error"]
    assert rows["cascade_pi_ff", 0]["metrics"] is not None
    monkeypatch.delenv("POLICY_SLEEPS")
    lb.main([*argv, "--resume"])  # the timeout is not part of the fingerprint
    lines = (out / records.EPISODES).read_text().splitlines()
    assert len(lines) == 6 + 2 and all('"sleeper' not in x or "error" not in x for x in lines[6:])
    assert [json.loads(x)["policy"].endswith(":sleeper") for x in lines[6:]] == [True, True]


def test_episode_timeout_flag_is_checked(files, tmp_path, capsys):
    for bad in ("-1", "nan", "soon"):
        with pytest.raises(SystemExit) as exc:
            lb.main(
                _argv(files, tmp_path / "out", ["cascade_pi"], "0", 1, "--episode-timeout", bad)
            )
        assert exc.value.code == 2 and "--episode-timeout" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
    assert EPISODE_TIMEOUT_S >= 10 * 28  # the longest shipped episode measured: 28 s


def test_a_factory_cannot_change_how_it_is_scored(files, tmp_path):
    """A factory that zeroes the reward weights of the env it is handed and resets it into
    another scenario changes only its own commissioning env: it scores as cascade_pi, the
    controller it builds (it scored a return of 0 before)."""
    out = tmp_path / "out"
    lb.main(_argv(files, out, ["cascade_pi", "cheat"]))
    rows = _rows(out)
    for seed in (0, 1):
        assert rows["cheat", seed]["metrics"] == rows["cascade_pi", seed]["metrics"]
        assert rows["cheat", seed]["metrics"]["return"] < 0


def test_a_policy_in_its_own_process_scores_as_in_the_leaderboards(files, tmp_path):
    """The same baselines from a factory file (a process of their own, commissioned on an
    env of their own) give the rows of the shipped ones, bit for bit, alone and in a pool."""
    for jobs in (1, 2):
        out = tmp_path / f"out{jobs}"
        lb.main(_argv(files, out, ["lqi", "my_lqi"], "0,1", jobs))
        lines = [json.loads(x) for x in (out / records.EPISODES).read_text().splitlines()]
        mine = {r["seed"]: r["metrics"] for r in lines if r["policy"].endswith(":my_lqi")}
        shipped = {r["seed"]: r["metrics"] for r in lines if r["policy"] == "lqi"}
        assert mine == shipped and len(mine) == 2


@pytest.mark.parametrize("name", ["cascade_pi_ff", "lqi", "mpc_linear"])
def test_baselines_commission_alike_on_an_env_of_their_own(name):
    """A shipped baseline commissioned on a separate env made as the evaluation env is (the
    same id, scenario and rows) acts as one commissioned on the evaluation env: the traces
    of run_batch are identical bit for bit."""
    from steamtemp_gym import scenarios

    sc = scenarios.resolve("setpoint_step", ENV)
    traces = []
    for separate in (False, True):
        venv = isolated.make_env(ENV, sc, 2)
        model = isolated.make_env(ENV, sc, 2) if separate else venv
        out = run_batch(venv, specs.parse(name, references=True).make(ENV, model), [0, 1])
        traces.append(out)
    for a, b in zip(*traces, strict=True):
        assert a["metrics"] == b["metrics"]
        for k in a["trace"]:
            np.testing.assert_array_equal(a["trace"][k], b["trace"][k], err_msg=f"{name} {k}")


def test_an_answer_that_would_run_code_when_unpickled_fails_the_policy(files, tmp_path, capsys):
    """An answer whose unpickling would call sys.exit in the leaderboard's process (ended
    the run with status 7, silently, without the other rows) fails that policy's episodes."""
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as exc:
        lb.main(_argv(files, out, ["cascade_pi", "smuggler"], "0"))
    assert exc.value.code == 1
    rows = _rows(out)
    assert len(rows) == 4 and rows["cascade_pi", 0]["metrics"] is not None
    assert "it names sys.exit (in its predict)" in rows["smuggler", 0]["error"]
    assert "1 of 4 episodes failed" in capsys.readouterr().err


def test_answers_read_numbers_strings_containers_and_arrays_only(tmp_path):
    """read_answer builds what actions, states and failures are made of, bit for bit, and
    refuses any other global before anything of the policy's choosing runs."""
    import pickle
    from multiprocessing.reduction import ForkingPickler

    def dumps(obj):
        return bytes(ForkingPickler.dumps(obj))

    a = np.array([[0.25], [-1.0]], dtype=np.float32)
    state = (np.zeros((1, 2, 3)), {"h": [np.float64(1.5), 2, "x", None]})
    kind, (got, got_state) = isolated.read_answer(dumps(("ok", (a, state))))
    assert kind == "ok" and got.dtype == a.dtype and np.array_equal(got, a)
    assert np.array_equal(got_state[0], state[0]) and got_state[1] == state[1]
    assert isolated.read_answer(dumps(("error", ("m", "tb")))) == ("error", ("m", "tb"))
    flag = tmp_path / "ran"
    payload = (exec, (f"open({str(flag)!r}, 'w').close()",))

    class Runs:
        def __reduce__(self):
            return payload

    for bad, words in [
        (("ok", (a, Runs())), "names builtins.exec"),
        (("ok", np.array([Runs()], dtype=object)), "names builtins.exec"),
        (("ok", np.ma.masked_array([1.0])), "names numpy.ma"),
        (("error", 5), "another form"),
        (["ok", None], "another form"),
    ]:
        with pytest.raises(ValueError, match=words):
            isolated.read_answer(dumps(bad))
    with pytest.raises(ValueError, match="cannot cross"):
        isolated.read_answer(b"not a pickle")
    assert not flag.exists()
    assert pickle.loads(dumps(Runs())) is None and flag.exists()  # the payload does run


def test_answers_that_expand_past_the_item_bound_are_refused():
    """A pickle names an object once and refers to it again by a few bytes: an answer of
    450 kB standing for 5e7 floats is refused before the leaderboard converts it, quickly,
    and so is a cyclic one; an answer as large as a real one is read."""
    from multiprocessing.reduction import ForkingPickler

    def dumps(obj):
        return bytes(ForkingPickler.dumps(obj))

    row = [0.5] * 50_000
    data = dumps(("ok", [row] * 1000))
    assert len(data) < 500_000
    with pytest.raises(ValueError, match="more than 8,388,608 numbers"):
        isolated.read_answer(data)
    cyclic = []
    cyclic.append(cyclic)
    with pytest.raises(ValueError, match="more than"):
        isolated.read_answer(dumps(("ok", cyclic)))
    shared = np.zeros(1000)
    with pytest.raises(ValueError, match="more than"):  # arrays' elements count per reference
        isolated.read_answer(dumps(("ok", [shared] * 9000)))
    kind, got = isolated.read_answer(dumps(("ok", [shared] * 8000)))
    assert kind == "ok" and len(got) == 8000 and got[0] is got[1]


def test_policy_process_answers_bit_for_bit():
    """A PolicyProcess's actions are its policy's, bit for bit, and it ends on close."""
    env = gym.make(ENV)
    obs, _ = env.reset(seed=0)
    here = specs.parse("cascade_pi", references=True).make(ENV, gym.make(ENV))
    with isolated.PolicyProcess("cascade_pi", ENV, None, None) as there:
        for k in range(5):
            a = here.predict(obs, episode_start=np.array([k == 0]))[0]
            b = there.predict(obs, episode_start=np.array([k == 0]))[0]
            assert a.dtype == b.dtype and np.array_equal(a, b)
            obs, *_ = env.step(a)
        proc = there._proc
    assert not proc.is_alive()


# slow: under the full parallel suite (two workers, each plant compiling) the run did not
# exit within 60 s of the SIGINT in two of three runs here, and the xdist worker then
# crashed on its next test; alone or with its file it passes in seconds (runs with -m slow)
@pytest.mark.slow
def test_ctrl_c_still_stops_the_run_and_ends_the_policys_process(files, tmp_path):
    """Ctrl-C (SIGINT) while a policy of its own process acts stops the run as before (exit
    130, resumable), is not recorded as that policy's failure, and ends its process."""
    out = tmp_path / "out"
    env = dict(os.environ, POLICY_SLEEPS="1")
    argv = [sys.executable, "-m", "agents.leaderboard", *_argv(files, out, ["sleeper"], "0")]
    proc = subprocess.Popen(
        argv, cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
    )
    try:
        deadline = time.monotonic() + 60
        record = out / records.EPISODES  # opened once the plan is made: the run's process
        while not (record.exists() and (kids := children(proc.pid))):
            assert proc.poll() is None, proc.stderr.read()
            assert time.monotonic() < deadline, "no policy process"
            time.sleep(0.1)
        time.sleep(0.5)
        proc.send_signal(signal.SIGINT)
        # communicate, not wait: it drains stderr, which a run under load (compile notices,
        # warnings, progress) can fill past the pipe's buffer, blocking the child
        _, err = proc.communicate(timeout=60)
        assert proc.returncode == 130, err
        assert "--resume" in err
        deadline = time.monotonic() + 5
        while any(alive(c) for c in kids) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not any(alive(c) for c in kids), "the policy's process outlived the run"
        rows = [json.loads(x) for x in record.read_text().splitlines()]
        assert not any(r.get("error") for r in rows)
    finally:
        if proc.poll() is None:
            proc.kill()


# ------------------------------------------- a factory's module never runs in the leaderboard
PATCHER = """
import numpy as np

from agents.leaderboard import episodes

_real = episodes._ok_row


def _forged(u, seed, metrics):
    return _real(u, seed, dict(metrics, **{"return": 1e6}))


episodes._ok_row = _forged  # scores every row of the process that imports this module


class Shut:
    def __init__(self, env):
        pass

    def reset(self):
        pass

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        return -np.ones(np.shape(observation)[:-1] + (1,), dtype=np.float32), None


def make(env):
    return Shut(env)
"""


def test_a_factory_module_that_patches_the_scoring_at_import_changes_nothing(tmp_path):
    """A module that replaces the leaderboard's row builder when imported: the leaderboard
    never imports it (its name, checks and fingerprint come from its file), so every row,
    its own included, is scored as in a clean run (it forged 1.19 from -6.81 and ranked
    first when the leaderboard imported it)."""
    (tmp_path / "patcher.py").write_text(PATCHER)
    (tmp_path / "tiny.yaml").write_text(TINY)
    real = episodes._ok_row
    out = tmp_path / "out"

    def run(policies: str, to: Path) -> None:
        lb.main(
            ["--envs", ENV, "--policies", policies, "--scenarios", str(tmp_path / "tiny.yaml")]
            + ["--seeds", "0", "--jobs", "1", "--no-oracle", "--out", str(to)]
        )

    run(f"cascade_pi,{tmp_path / 'patcher.py'}:make", out)
    assert episodes._ok_row is real
    assert "patcher" not in sys.modules
    rows = _rows(out)
    assert rows["make", 0]["metrics"]["return"] < 0  # the valve held shut, scored as it is
    clean = tmp_path / "clean"
    run("cascade_pi", clean)
    for key, row in _rows(clean).items():
        assert rows[key]["metrics"] == row["metrics"], key


@pytest.mark.parametrize(
    ("body", "words"),
    [
        ("import os\nos._exit(0)\n", ["process ended (exit code 0) during its build"]),
        ("import time\ntime.sleep(1000)\n", ["did not answer its build within 3 s"]),
    ],
)
def test_a_factory_module_that_ends_or_hangs_at_import_is_a_bad_policies_value(
    tmp_path, capsys, body, words
):
    """os._exit at import ended the run with status 0, no output and no --out; a sleep at
    import hung it past --episode-timeout. Now the module is first imported in the policy's
    own process, at the run's check of its policies: an argparse error naming it, in about
    the timeout, and nothing is written."""
    (tmp_path / "hostile.py").write_text(body + "\ndef make(env):\n    return None\n")
    (tmp_path / "tiny.yaml").write_text(TINY)
    out = tmp_path / "out"
    t0 = time.monotonic()
    with pytest.raises(SystemExit) as exc:
        lb.main(
            [
                "--envs",
                ENV,
                "--policies",
                f"{tmp_path / 'hostile.py'}:make",
                "--scenarios",
                str(tmp_path / "tiny.yaml"),
                "--seeds",
                "0",
                "--no-oracle",
                "--episode-timeout",
                "3",
                "--out",
                str(out),
            ]
        )
    err = capsys.readouterr().err
    assert exc.value.code == 2 and "argument --policies" in err, err
    assert all(w in err for w in words), err
    assert not out.exists() and time.monotonic() - t0 < 60


# ------------------------------------ a policy cannot kill the run or rewrite its record
HOSTILE = (
    POLICIES
    + """

import signal


def _kill_the_run():
    os.kill(os.getppid(), signal.SIGKILL)  # the leaderboard, or the process that relays it


def _kill_everything():
    os.kill(-1, signal.SIGKILL)  # every process it may signal


def _rewrite_the_record():
    path = os.path.join(os.environ["STEAMTEMP_LEADERBOARD_OUT"], "episodes.jsonl")
    with open(path, "a") as f:
        f.write('{"env": "forged"}\\n')


def kills_the_run(env):
    return Scripted(env, _kill_the_run)


class Bulky(Scripted):
    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        return super().predict(observation)[0], np.zeros(10_000_000)  # 80 MB of state


def bulky(env):
    return Bulky(env)


def kills_everything(env):
    return Scripted(env, _kill_everything)


def rewrites_the_record(env):
    return Scripted(env, _rewrite_the_record)
"""
)


@pytest.mark.skipif(sandbox.available() is not None, reason=f"no sandbox: {sandbox.available()}")
@pytest.mark.parametrize(
    ("hostile", "fails"),
    [
        ("kills_the_run", None),
        ("kills_everything", "ProcessLookupError: [Errno 3] No such process"),
        ("rewrites_the_record", "Read-only file system"),
        ("bulky", "larger than 64 MiB: refused before it is read"),
    ],
)
def test_a_policy_can_neither_kill_the_run_nor_rewrite_its_record(tmp_path, hostile, fails):
    """A policy that signals its parent (SIGKILL ended the run with status 137, and --resume
    reran it forever), every process it may, or appends to the run's episodes.jsonl
    (found from its parent's command line, it multiplied cascade_pi_ff's returns by 10):
    in its walls (agents/leaderboard/sandbox.py) its signals reach no process but itself,
    which as its namespace's first process ignores them (kill(-1) finds no process at all),
    and the record is read-only to it. An answer of 80 MB (one of 400 MB raised the run's
    peak memory from 271 MB to 1,364 MB) is refused before it is read.
    Every other row equals a clean run's; the run ends as it would without the attack (0),
    or as with any failing policy (1) where the attack raised in its predict. The run is a
    process of its own here: without the walls the test's would be killed."""
    (tmp_path / "pols.py").write_text(HOSTILE)
    (tmp_path / "tiny.yaml").write_text(TINY)

    def run(out: Path, policies: str) -> subprocess.CompletedProcess:
        argv = [
            sys.executable,
            "-m",
            "agents.leaderboard",
            "--envs",
            ENV,
            "--policies",
            policies,
            "--scenarios",
            str(tmp_path / "tiny.yaml"),
            "--seeds",
            "0,1",
            "--jobs",
            "1",
            "--no-oracle",
            "--out",
            str(out),
        ]
        return subprocess.run(argv, cwd=ROOT, capture_output=True, text=True, timeout=600)

    attacked = run(tmp_path / "out", f"cascade_pi,{tmp_path / 'pols.py'}:{hostile}")
    assert attacked.returncode == (1 if fails else 0), attacked.stderr[-2000:]
    rows = _rows(tmp_path / "out")
    for s in (0, 1):
        if fails:
            assert fails in rows[hostile, s]["error"], rows[hostile, s]["error"]
        else:
            assert rows[hostile, s]["metrics"] is not None
    clean = run(tmp_path / "clean", "cascade_pi")
    assert clean.returncode == 0, clean.stderr[-2000:]
    for key, row in _rows(tmp_path / "clean").items():
        assert rows[key]["metrics"] == row["metrics"], key
    assert "forged" not in (tmp_path / "out" / records.EPISODES).read_text()
