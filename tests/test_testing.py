"""steamtemp_gym.testing itself: its checks catch what they claim to, their failures say
how to reproduce them, the CLI, the pytest decorator, register_variant and the worked
example of docs/checking.md."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import steamtemp_gym
from steamtemp_gym.envs import register_variant
from steamtemp_gym.testing import (
    CheckSkipped,
    check_actions_in_bounds,
    check_bad_observations_rejected,
    check_batched_equals_unbatched,
    check_determinism,
    check_reset_clears_state,
    check_sb3_env,
    parametrize_with_checks,
)
from steamtemp_gym.testing.cli import main
from steamtemp_gym.testing.runner import bound_checks
from steamtemp_gym.testing.subjects import resolve_env
from steamtemp_gym.testing.vector_checks import (
    compare_vector_envs,
    reference_vector_env,
    short_scenario,
)

pytest_plugins = ["pytester"]
FSH = "steamtemp/SupercriticalFSH-v0"
CASCADE = "steamtemp/Cascade300MW-v0"  # the cheapest plant
DOCS = Path(__file__).resolve().parents[1] / "docs" / "checking.md"


# --------------------------------------------------------------- checks catch breakage
class _UnseededNoise(gym.ObservationWrapper):
    """Adds noise from an unseeded generator: not reproducible."""

    def observation(self, obs):
        return obs + np.random.default_rng().normal(0.0, 1e-6, obs.shape)


def test_a_nondeterministic_env_fails_with_a_reproducing_message():
    def make(**options):
        return _UnseededNoise(gym.make(CASCADE, **options))

    with pytest.raises(AssertionError) as err:
        check_determinism(make, quick=True)
    msg = str(err.value)
    assert "check_determinism failed on make" in msg
    assert "differs from the first at step 0" in msg and "seed 3" in msg
    assert "reproduce: from steamtemp_gym.testing import check_determinism" in msg


@pytest.mark.parametrize("mode", list(AutoresetMode))
def test_vector_comparison_accepts_gymnasium_semantics(mode):
    """Gymnasium's SyncVectorEnv against itself, every mode: the comparison follows its
    autoresets, final_obs / final_info and DISABLED resets, and sees every episode end."""
    target = resolve_env(CASCADE)
    sc = {"scenario": short_scenario(1.0)}
    endings = compare_vector_envs(
        reference_vector_env(target, 3, mode, **sc),
        reference_vector_env(target, 3, mode, **sc),
        mode,
    )
    assert endings >= 3


@pytest.mark.parametrize(
    "mode, other",
    [
        (AutoresetMode.SAME_STEP, AutoresetMode.NEXT_STEP),
        (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP),
    ],
)
def test_vector_comparison_catches_another_autoreset_semantics(mode, other):
    target = resolve_env(CASCADE)
    sc = {"scenario": short_scenario(1.0)}
    with pytest.raises(AssertionError, match=rf"mode {mode.name}, seed 11, .*step 12"):
        compare_vector_envs(
            reference_vector_env(target, 3, other, **sc),
            reference_vector_env(target, 3, mode, **sc),
            mode,
        )


class _Forgetful:
    """A PI-like stateful policy whose reset() and episode_start forget nothing."""

    def __init__(self, env, gain=0.05, bound=1.0, batched_bug=False):
        self.acc, self.gain, self.bound, self.batched_bug = 0.0, gain, bound, batched_bug
        vector = hasattr(env, "single_action_space")
        space = env.single_action_space if vector else env.action_space
        self.n_u = space.shape[0]

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        obs = np.atleast_2d(observation)
        self.acc = self.acc + self.gain * obs[:, -2:-1]  # the error entry
        a = np.clip(self.acc, -self.bound, self.bound) * np.ones((1, self.n_u))
        if self.batched_bug and obs.shape[0] > 1:
            a = a[::-1]
        return (a if np.ndim(observation) == 2 else a[0]), None

    def reset(self):
        pass


def test_policy_checks_catch_broken_policies():
    with pytest.raises(AssertionError, match="after reset\\(\\) the policy acts differently"):
        check_reset_clears_state(_Forgetful, CASCADE, quick=True)
    with pytest.raises(AssertionError, match="check_actions_in_bounds failed on _wild"):

        def _wild(env):
            return _Forgetful(env, gain=1e3, bound=2.0)

        check_actions_in_bounds(_wild, CASCADE, quick=True)
    with pytest.raises(AssertionError, match="batched .* != unbatched"):
        check_batched_equals_unbatched(
            lambda env: _Forgetful(env, batched_bug=True), CASCADE, quick=True
        )


def test_bad_observation_check_holds_user_policies_to_it():
    """A controller that takes a NaN observation into its state fails the check; the same
    controller through baselines.policy.checked passes it."""
    from baselines.policy import checked

    with pytest.raises(AssertionError, match="predict accepted an observation all NaN"):
        check_bad_observations_rejected(_Forgetful, CASCADE, quick=True)
    check_bad_observations_rejected(lambda env: checked(_Forgetful(env), env), CASCADE, quick=True)


class _Refuses(_Forgetful):
    """Refuses bad observations with a ValueError, but only after counting the call in its
    state."""

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        from baselines.policy import check_predict_args

        self.acc = self.acc + 0.01
        check_predict_args(observation, episode_start, 9)
        return super().predict(observation, state, episode_start, deterministic)


def test_bad_observation_check_catches_a_state_changed_by_a_refused_call():
    with pytest.raises(AssertionError, match="a copy that never saw them"):
        check_bad_observations_rejected(_Refuses, CASCADE, quick=True)


def test_sb3_check_is_skipped_visibly_without_sb3(monkeypatch):
    monkeypatch.setitem(sys.modules, "stable_baselines3.common.env_checker", None)
    with pytest.raises(CheckSkipped, match=r"stable_baselines3 is not installed.*\[agents\]"):
        check_sb3_env(CASCADE)


def test_bad_subjects_are_refused_with_the_valid_choices():
    with pytest.raises(ValueError, match="valid ids: .*steamtemp/Cascade300MW-v0"):
        check_determinism("steamtemp/NoSuch-v0")
    with pytest.raises(ValueError, match="valid names: .*cascade_pi"):
        check_reset_clears_state("no_such_controller", CASCADE)
    with pytest.raises(ValueError, match="valid names: .*check_determinism"):
        bound_checks(only=["check_nothing"])


# ------------------------------------------------------------------- pytest decorator
def test_parametrize_with_checks_ids_and_marks():
    mark = parametrize_with_checks(ids=[FSH], policies=["cascade_pi"]).mark
    assert mark.args[0] == ("env_id", "check")
    params = {p.id: p for p in mark.args[1]}
    assert "SupercriticalFSH-v0-check_determinism" in params
    assert "SupercriticalFSH-v0-cascade_pi-check_reset_clears_state" in params
    assert len(params) == 11 + 8
    slow = [i for i, p in params.items() if any(m.name == "slow" for m in p.marks)]
    assert slow == ["SupercriticalFSH-v0-cascade_pi-check_completes_every_scenario"]
    quick = parametrize_with_checks(ids=[FSH], policies=["cascade_pi"], env=False, quick=True)
    assert len(quick.mark.args[1]) == 7  # the slow check is left out


# ------------------------------------------------------------------------------ CLI
def test_cli_rejects_bad_arguments_listing_the_choices(capsys):
    for argv, needle in (
        (["steamtemp/NoSuch-v0"], "valid ids: steamtemp/SupercriticalFSH-v0"),
        (["--policy", "nope"], "valid names: cascade_pi"),
        (["--check", "nope"], "valid: check_gymnasium_env"),
    ):
        with pytest.raises(SystemExit) as exc:
            main(argv)
        assert exc.value.code == 2
        assert needle in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        main(["--help"])
    assert exc.value.code == 0 and "--quick" in capsys.readouterr().out


class _SmallFrames(gym.Wrapper):
    def render(self):
        frame = self.env.render()
        return None if frame is None else frame[::2]


def test_cli_table_and_exit_status(capsys):
    gym.register(
        "testing/SmallFrames-v0", entry_point=lambda **kw: _SmallFrames(gym.make(CASCADE, **kw))
    )
    try:
        code = main(
            [
                "testing/SmallFrames-v0",
                CASCADE,
                "--check",
                "check_render_frame",
                "--check",
                "check_predict_signature",
                "--policy",
                "cascade_pi",
            ]
        )
    finally:
        del gym.registry["testing/SmallFrames-v0"]
    out = capsys.readouterr().out
    assert code == 1
    assert re.search(r"SmallFrames-v0\s+-\s+check_render_frame\s+FAIL", out)
    assert re.search(r"Cascade300MW-v0\s+-\s+check_render_frame\s+PASS", out)
    assert re.search(r"Cascade300MW-v0\s+cascade_pi\s+check_predict_signature\s+PASS", out)
    assert "frame shape (240, 640, 3) != (480, 640, 3)" in out
    assert "3 passed, 1 failed, 0 skipped" in out


# -------------------------------------------------------------------- register_variant
def test_register_variant_validates_merges_and_is_idempotent():
    register_variant("testing/Cascade2-v0", CASCADE, params={"lead_order": 3})
    register_variant("testing/Cascade2-v0", CASCADE, params={"lead_order": 3})  # no-op
    try:
        register_variant("testing/Cascade2b-v0", "testing/Cascade2-v0", params={"dt_s": 2.0})
        env = gym.make("testing/Cascade2b-v0")
        assert env.unwrapped.plant.params.lead_order == 3 and env.unwrapped.plant.dt_s == 2.0
        venv = gym.make_vec(
            "testing/Cascade2b-v0", num_envs=2, vectorization_mode="vector_entry_point"
        )
        assert venv.unwrapped.plant.params.lead_order == 3
        with pytest.raises(ValueError, match="already registered"):
            register_variant("testing/Cascade2-v0", CASCADE, params={"lead_order": 4})
        with pytest.raises(ValueError, match="lead_order"):
            register_variant("testing/Bad-v0", CASCADE, params={"lead_order": "three"})
        with pytest.raises(ValueError, match="valid ids"):
            register_variant("testing/Bad-v0", "steamtemp/NoSuch-v0")
        assert "testing/Bad-v0" not in gym.registry
    finally:
        for i in ("testing/Cascade2-v0", "testing/Cascade2b-v0"):
            gym.registry.pop(i, None)


# ------------------------------------------------------------- the documented example
def _examples() -> dict[str, str]:
    """Code blocks of docs/checking.md marked ``<!-- example: NAME -->``."""
    text = DOCS.read_text()
    return dict(re.findall(r"<!-- example: (\S+) -->\n```\w+\n(.*?)```", text, re.S))


def _variant_files(tmp_path: Path) -> dict[str, str]:
    ex = _examples()
    assert set(ex) == {"my_plants.py", "shell", "test_my_plants.py"}
    for name in ("my_plants.py", "test_my_plants.py"):
        (tmp_path / name).write_text(ex[name])
    return ex


def _unregister():
    gym.registry.pop("my/FSH12Fouled-v0", None)
    sys.modules.pop("my_plants", None)


def test_documented_example_command_line(tmp_path, monkeypatch, capsys):
    """The docs' shell line, run in-process: the variant passes every quick check."""
    ex = _variant_files(tmp_path)
    argv = ex["shell"].split()
    assert argv[:2] == ["PYTHONPATH=.", "steamtemp-check"]
    monkeypatch.syspath_prepend(str(tmp_path))
    try:
        code = main(argv[2:])
        env = gym.make("my/FSH12Fouled-v0")
    finally:
        _unregister()
    out = capsys.readouterr().out
    assert code == 0, out
    assert env.unwrapped.plant.params.n_segments == 12
    assert env.unwrapped._scenario_spec.name == "fouled_load_ramp"
    assert "18 passed, 0 failed, 1 skipped" in out  # the slow check, skipped by --quick


def _run_documented_pytest_file(tmp_path, pytester, *args, subprocess=False):
    _variant_files(tmp_path)
    for name in ("my_plants.py", "test_my_plants.py"):
        pytester.makepyfile(**{name[:-3]: (tmp_path / name).read_text()})
    pytester.syspathinsert()
    args = ("-p", "no:xdist", "-p", "no:cacheprovider", *args)
    if subprocess:  # a clean interpreter: an in-process run re-imports numba modules
        return pytester.runpytest_subprocess(*args)
    gym.make(FSH)  # its modules imported before the in-process run's sys.modules snapshot
    try:
        return pytester.runpytest_inprocess(*args)
    finally:
        _unregister()


def test_documented_example_pytest_form_collects(tmp_path, pytester):
    """The docs' pytest file collects one test per check, with the documented ids."""
    result = _run_documented_pytest_file(tmp_path, pytester, "--collect-only", "-q")
    result.stdout.fnmatch_lines(
        [
            "*test_contract[[]FSH12Fouled-v0-check_determinism[]]",
            "*FSH12Fouled-v0-cascade_pi-check_reset_clears_state*",
            "19 tests collected*",
        ]
    )


@pytest.mark.slow
def test_documented_example_pytest_form(tmp_path, pytester, monkeypatch):
    """The docs' pytest file, run by pytest: every check passes (the slow one too)."""
    monkeypatch.setenv("PYTHONPATH", str(DOCS.parents[1]))  # this source tree
    result = _run_documented_pytest_file(tmp_path, pytester, subprocess=True)
    result.assert_outcomes(passed=18)


# ------------------------------------------------ the checked code cannot end the run
_ENDING = """
import sys
import baselines


class Ending:
    def __init__(self, env, exc):
        self.inner, self.exc = baselines.make("cascade_pi", env), exc

    def reset(self):
        self.inner.reset()

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        raise self.exc


def sys_exit(env):
    return Ending(env, SystemExit(3))


def interrupt(env):
    return Ending(env, KeyboardInterrupt())


def exit_when_built(env):
    sys.exit(4)
"""


@pytest.fixture
def default_sigint():
    """Python's own SIGINT handler for the test, as ``steamtemp-check`` has it in its own
    process (the guard tells a policy's KeyboardInterrupt from Ctrl-C only there; a test
    run earlier in the same worker may leave another handler)."""
    import signal

    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


@pytest.mark.parametrize(
    ("factory", "raised"), [("sys_exit", "SystemExit: 3"), ("interrupt", "KeyboardInterrupt")]
)
def test_a_policy_ending_the_process_fails_its_checks_and_the_run_goes_on(
    tmp_path, capsys, factory, raised, default_sigint
):
    """A policy's SystemExit or KeyboardInterrupt fails each check it ends; the table, the
    messages and the exit status 1 follow (once they ended the checker, exit 3, silently)."""
    (tmp_path / "ending.py").write_text(_ENDING)
    code = main(
        [
            CASCADE,
            "--policy",
            f"{tmp_path / 'ending.py'}:{factory}",
            "--no-env-checks",
            "--quick",
            "--check",
            "check_predict_signature",
            "--check",
            "check_actions_in_bounds",
        ]
    )
    out = capsys.readouterr().out
    assert code == 1
    assert len(re.findall(r"check_\w+\s+FAIL", out)) == 2
    assert f"{raised} (raised by the code under check" in out and "0 passed, 2 failed" in out


def test_a_factory_ending_the_process_is_a_bad_policy(tmp_path, capsys):
    (tmp_path / "ending.py").write_text(_ENDING)
    with pytest.raises(SystemExit) as exc:
        main([CASCADE, "--policy", f"{tmp_path / 'ending.py'}:exit_when_built", "--quick"])
    assert exc.value.code == 2
    assert "SystemExit: 4 (raised by the factory" in capsys.readouterr().err


_EXITING = """
import os
import baselines


class Exiting:
    def __init__(self, env):
        self.inner = baselines.make("cascade_pi", env)

    def reset(self):
        self.inner.reset()

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        os._exit(0)


def make(env):
    return Exiting(env)
"""


@pytest.mark.parametrize("where", ["predict", "import"])
def test_code_that_ends_its_process_fails_the_command(tmp_path, where):
    """The command runs the checks in a child process: os._exit(0) in a policy's predict
    (it printed a FAIL row, then exit 0) or in an --import module (no output, exit 0) now
    fails the run, exit 1, saying so; a passing run keeps its status 0."""
    (tmp_path / "exiting.py").write_text(_EXITING)
    (tmp_path / "exit_on_import.py").write_text("import os\nos._exit(0)\n")
    extra = (
        ["--policy", f"{tmp_path / 'exiting.py'}:make"]
        if where == "predict"
        else ["--import", "exit_on_import", "--policy", "cascade_pi"]
    )
    argv = [
        sys.executable,
        "-m",
        "steamtemp_gym.testing.cli",
        CASCADE,
        "--no-env-checks",
        "--quick",
        "--check",
        "check_predict_signature",
    ]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), *sys.path])}
    run = subprocess.run(argv + extra, env=env, capture_output=True, text=True, timeout=300)
    assert run.returncode == 1, run.stderr
    assert "ended before they finished (exit status 0)" in run.stderr
    ok = subprocess.run(
        argv + ["--policy", "cascade_pi"], env=env, capture_output=True, text=True, timeout=300
    )
    assert ok.returncode == 0 and "1 passed, 0 failed" in ok.stdout, ok.stderr


def test_nothing_selected_is_an_error_not_a_pass(capsys):
    """--no-env-checks with no --policy checked 0 things and exited 0."""
    with pytest.raises(SystemExit) as exc:
        main([CASCADE, "--no-env-checks", "--quick"])
    assert exc.value.code == 2
    assert "nothing to check" in capsys.readouterr().err


def test_a_subject_whose_every_check_was_skipped_is_not_a_pass(capsys, monkeypatch):
    """A shipped agent checked on a plant it was not trained for checks nothing: exit 1,
    naming the subject and why (it printed '0 passed, 0 failed, 8 skipped' and exited 0)."""
    import agents
    from agents import specs

    where = {n: {e for e, a in agents.shipped() if f"sb3:{a}" == n} for n in specs.shipped_names()}
    other, env = next((n, e) for n in where for e in steamtemp_gym.ENV_IDS if e not in where[n])
    code = main([env, "--policy", other, "--no-env-checks", "--quick"])
    out = capsys.readouterr().out
    assert code == 1
    assert f"NOT CHECKED policy {other}: every check was skipped" in out
    assert f"{other} is not available for {env}" in out and "0 passed, 0 failed" in out
    # a subject with one check run and one skipped is checked
    monkeypatch.setitem(sys.modules, "stable_baselines3.common.env_checker", None)
    assert main([CASCADE, "--check", "check_render_frame", "--check", "check_sb3_env"]) == 0
    assert main([CASCADE, "--check", "check_sb3_env"]) == 1
    assert "NOT CHECKED env checks of steamtemp/Cascade300MW-v0" in capsys.readouterr().out
