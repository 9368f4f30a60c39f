"""steamtemp_gym._prewarm: the compile helper that builds a plant's step path from types."""

from __future__ import annotations

import fcntl
import json
import os
import signal
import subprocess
import sys
import types

import gymnasium as gym
import numpy as np
import pytest
from numba import typeof
from numba.core import types as types_nb

import steamtemp_gym
from steamtemp_gym import _cache, _prewarm, plants
from steamtemp_gym.envs.core import Core
from steamtemp_gym.rewards import RewardConfig

_POPEN = subprocess.Popen


def _types(core: Core) -> list[tuple]:
    return [(kernel, tuple(typeof(a) for a in args)) for kernel, args in core.compile_calls()]


@pytest.mark.parametrize("env_id", steamtemp_gym.ENV_IDS)
def test_skeleton_compiles_what_the_env_calls(env_id):
    """The helper compiles, from a skeleton plant, each kernel with exactly the argument
    types a real env calls it with: after a real reset and steps with float32 and float64
    actions, every (kernel, types) of the skeleton is among the kernel's signatures."""
    cls = plants.plant_class(env_id)
    skeleton = _types(Core(cls.skeleton(), 1, RewardConfig()))
    env = gym.make(env_id)
    env.reset(seed=0)
    env.step(env.action_space.sample())  # float32
    env.step(np.zeros(env.action_space.shape))  # float64
    real = _types(env.unwrapped.core)
    assert [k for k, _ in skeleton] == [k for k, _ in real]
    for (kernel, sig), (_, real_sig) in zip(skeleton, real, strict=True):
        assert sig == real_sig, kernel.py_func.__qualname__
        assert sig in kernel.signatures, (kernel.py_func.__qualname__, sig, kernel.signatures)


def test_skeleton_has_placeholders_and_no_calibration():
    cls = plants.plant_class("steamtemp/SupercriticalFSH-v0")
    sk = cls.skeleton()
    assert type(sk) is cls and sk.P.shape == (1,) and not sk.P.flags.writeable
    assert sk.params == cls.Params() and sk.n_u == len(cls.actions)


_USE = """
import json, sys
import gymnasium as gym, numpy as np
import steamtemp_gym
env = gym.make(sys.argv[1])
env.reset(seed=0)
env.step(env.action_space.sample())
env.step(np.zeros(env.action_space.shape))
out = {}
for kernel, _ in env.unwrapped.core.compile_calls():
    s = kernel.stats
    out[kernel.py_func.__qualname__] = [sum(s.cache_hits.values()), sum(s.cache_misses.values())]
print(json.dumps(out))
"""


def test_helper_leaves_the_step_path_in_the_cache(tmp_path):
    """End to end on an empty cache: the helper process alone compiles Cascade300MW's step
    path (the shared kernels too, nobody claiming them); a later process (helper off) then
    loads every kernel of it from the cache, compiling none; the helper's marker is left,
    its lock and claims removed."""
    env = dict(os.environ, STEAMTEMP_GYM_CACHE_DIR=str(tmp_path), STEAMTEMP_GYM_PREWARM="0")
    env.pop("NUMBA_CACHE_DIR", None)
    path = plants.PLANTS["steamtemp/Cascade300MW-v0"]
    subprocess.run([sys.executable, "-m", "steamtemp_gym._prewarm", path], env=env, check=True)
    (folder,) = tmp_path.glob("numba-*/prewarm")
    assert sorted(f.name for f in folder.iterdir()) == ["Cascade300MW"]
    out = subprocess.run([sys.executable, "-c", _USE, "steamtemp/Cascade300MW-v0"], env=env,
                         check=True, capture_output=True, text=True).stdout  # fmt: skip
    stats = json.loads(out.strip().splitlines()[-1])
    assert len(stats) == 7  # to_commands twice (float32, float64 actions)
    for name, (hits, misses) in stats.items():
        assert misses == 0 and hits >= 1 + (name == "to_commands"), (name, hits, misses)


def test_the_two_parts_cover_the_step_path_once():
    core = Core(plants.plant_class("steamtemp/DrumBoilerSH-v0").skeleton(), 1, RewardConfig())
    calls = core.compile_calls()
    shared, helper = _prewarm.part(calls, True), _prewarm.part(calls, False)
    assert [k.py_func.__name__ for k, _ in shared] == ["observe", "to_commands", "to_commands",
                                                       "advance"]  # fmt: skip
    assert len(shared) + len(helper) == len(calls) and helper[-1][0] is core.plant.kernel()


class _Kernel:
    """Stand-in for a dispatcher: records what it is asked to compile."""

    def __init__(self, name):
        self.py_func = types.SimpleNamespace(__name__=name)
        self.sigs = []

    def compile(self, sig):
        self.sigs.append(sig)


def test_shared_kernels_go_to_whoever_claims_first(fake_helpers):
    """wait() compiles the shared kernels the helper has not claimed, each group once (both
    action dtypes of to_commands together), and only while a helper was running."""
    fake_helpers.mkdir()
    obs, cmd, adv = _Kernel("observe"), _Kernel("to_commands"), _Kernel("advance")
    calls = [(obs, (1.0,)), (cmd, (np.zeros(1, np.float32),)), (cmd, (np.zeros(1),)),
             (adv, (2,))]  # fmt: skip
    plant_cls = type("Plant", (), {"__module__": "somewhere"})
    assert _prewarm._claim("Plant", "advance")  # the helper got there first
    assert not _prewarm._claim("Plant", "advance")
    _prewarm._shared["Plant"] = calls
    _prewarm.wait(plant_cls)
    assert obs.sigs == [(types_nb.float64,)] and len(cmd.sigs) == 2 and adv.sigs == []
    assert not _prewarm._shared
    core = types.SimpleNamespace(plant=plant_cls(), compile_calls=lambda: calls)
    _prewarm.share(core)
    assert not _prewarm._shared  # no helper of that class running: nothing noted
    _prewarm.pending["somewhere:Plant"] = _FakeProc([])
    _prewarm.share(core)
    assert [k for k, _ in _prewarm._shared["Plant"]] == [obs, cmd, cmd, adv]


class _FakeProc:
    def __init__(self, args, **kwargs):
        self.args, self.kwargs, self.returncode = args, kwargs, None
        _FakeProc.made.append(self)

    def wait(self, timeout=None):
        self.returncode = 0
        return 0


@pytest.fixture
def fake_helpers(tmp_path, monkeypatch):
    """_prewarm with a temporary cache folder, two CPUs and a recording Popen."""
    _FakeProc.made = []
    monkeypatch.setattr(_cache, "_FOLDER", _cache.Folder(tmp_path, True, tmp_path))
    monkeypatch.setattr(_prewarm.subprocess, "Popen", _FakeProc)
    monkeypatch.setattr(_prewarm, "_cpus", lambda: 2)
    monkeypatch.setattr(_prewarm, "_started", set())
    monkeypatch.setattr(_prewarm, "pending", {})
    monkeypatch.setattr(_prewarm, "_shared", {})
    monkeypatch.delenv("STEAMTEMP_GYM_PREWARM", raising=False)
    return tmp_path / "prewarm"


def test_start_runs_one_helper_per_class_on_a_cold_cache(fake_helpers):
    cls = plants.plant_class("steamtemp/Cascade300MW-v0")
    _prewarm.start(cls)
    _prewarm.start(cls)
    assert len(_FakeProc.made) == 1 and list(_prewarm.pending) == [plants.PLANTS[cls.id]]
    proc = _FakeProc.made[0]
    assert proc.args[1:4] == ["-m", "steamtemp_gym._prewarm", plants.PLANTS[cls.id]]
    assert proc.kwargs["env"]["STEAMTEMP_GYM_PREWARM"] == "0"  # no helpers of helpers
    assert (fake_helpers / "Cascade300MW.lock").exists()
    assert proc.kwargs["pass_fds"] == (int(proc.args[-1]),)  # the helper inherits its lock
    _prewarm.wait(plants.plant_class("steamtemp/DrumBoilerSH-v0"))  # another plant's step
    assert _prewarm.pending and proc.returncode is None  # does not wait for this helper
    _prewarm.wait(cls)
    assert not _prewarm.pending and proc.returncode == 0


@pytest.mark.parametrize("why", ["marker", "lock", "off", "one_cpu", "frozen"])
def test_start_does_nothing_when_not_needed(fake_helpers, monkeypatch, why):
    cls = plants.plant_class("steamtemp/Cascade300MW-v0")
    fake_helpers.mkdir()
    if why == "marker":  # an earlier helper finished
        (fake_helpers / "Cascade300MW").touch()
    elif why == "lock":  # another helper holds the lock
        held = os.open(fake_helpers / "Cascade300MW.lock", os.O_CREAT | os.O_RDWR)
        fcntl.flock(held, fcntl.LOCK_EX)
    elif why == "off":
        monkeypatch.setenv("STEAMTEMP_GYM_PREWARM", "0")
    elif why == "frozen":  # e.g. PyInstaller: sys.executable is the application
        monkeypatch.setattr(sys, "frozen", True, raising=False)
    else:
        monkeypatch.setattr(_prewarm, "_cpus", lambda: 1)
    _prewarm.start(cls)
    assert _FakeProc.made == [] and not _prewarm.pending


def test_a_lock_left_by_a_killed_helper_does_not_block(fake_helpers):
    """A process holding the helper's lock is killed with SIGKILL: the lock file is left
    behind, fresh, and the next start() runs a helper at once."""
    cls = plants.plant_class("steamtemp/Cascade300MW-v0")
    fake_helpers.mkdir()
    lock = fake_helpers / "Cascade300MW.lock"
    holder = _POPEN([sys.executable, "-c", "import fcntl, os, sys, time; "
                     f"fd = os.open({str(lock)!r}, os.O_CREAT | os.O_RDWR); "
                     "fcntl.flock(fd, fcntl.LOCK_EX); print('held', flush=True); time.sleep(60)"],
                    stdout=subprocess.PIPE, text=True)  # fmt: skip
    assert holder.stdout.readline().strip() == "held"
    _prewarm.start(cls)
    assert _FakeProc.made == []  # a helper holds the lock
    holder.send_signal(signal.SIGKILL)
    holder.wait()
    assert lock.exists()
    _prewarm._started.clear()
    _prewarm.start(cls)
    assert len(_FakeProc.made) == 1


def test_wait_stops_a_helper_that_hangs(fake_helpers, monkeypatch):
    proc = _POPEN([sys.executable, "-c", "import time; time.sleep(60)"])
    monkeypatch.setattr(_prewarm, "pending", {"x:Y": proc})
    monkeypatch.setattr(_prewarm, "TIMEOUT_S", 0.2)
    _prewarm.wait(type("Y", (), {"__module__": "x"}))
    assert proc.returncode is not None and not _prewarm.pending


def test_read_only_cache_folder_starts_nothing(fake_helpers, monkeypatch):
    cls = plants.plant_class("steamtemp/Cascade300MW-v0")
    monkeypatch.setattr(_cache, "_FOLDER", _cache.Folder(fake_helpers.parent, False, None))
    _prewarm.start(cls)
    assert _FakeProc.made == [] and not fake_helpers.exists()


def test_no_interpreter_to_start_is_not_an_error(fake_helpers, monkeypatch):
    def fail(*a, **k):
        raise FileNotFoundError("no python")

    monkeypatch.setattr(_prewarm.subprocess, "Popen", fail)
    _prewarm.start(plants.plant_class("steamtemp/Cascade300MW-v0"))
    assert not _prewarm.pending
    lock = os.open(fake_helpers / "Cascade300MW.lock", os.O_RDWR)
    fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)  # not held: the next start may run one
    os.close(lock)
