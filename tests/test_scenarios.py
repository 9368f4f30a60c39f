"""Scenarios: named ones, the random training distribution, schedule evaluation in the kernel."""

import numpy as np
import pytest

from steamtemp_gym import scenarios
from steamtemp_gym.envs.kernels import schedules
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
        schedules(0, 0, t, bp_t, bp_v, bp_n, 500.0, ou, D, sp)
        if t != 30.0:
            assert D[0, 0] == pytest.approx(s.value("load", t))
        assert D[0, 3] == pytest.approx(s.value("fouling", t))
        assert sp[0] == pytest.approx(500.0 + (5.0 if t >= 50 else 0.0))
    schedules(0, 0, 20.0, bp_t, bp_v, bp_n, 500.0, ou, D, sp)
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
    sc = Scenario(
        name="ou",
        duration_s=4000.0,
        load=1.0,
        heat_absorption_bias=0.01,
        heat_absorption_noise_std=std,
        heat_absorption_noise_tau_s=tau,
    )
    venv = gym.make_vec(
        "steamtemp/Cascade300MW-v0",
        num_envs=64,
        vectorization_mode="vector_entry_point",
        scenario=sc,
    )
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


# --------------------------------------------------------------------------------- hardening
GOOD = "name: x\nduration_s: 60\nload: [[0, 1.0], [30, 0.9]]\n"


def _laughs(depth: int, field: str) -> str:
    """A ~470-byte billion-laughs document: 9**depth strings ``lol`` under ``field``.

    The anchors are defined in a list under ``description``; ``field`` (if another)
    refers to the last one.
    """
    levels = ["&a0 [" + ",".join(["lol"] * 9) + "]"]
    levels += [f"&a{k} [" + ",".join([f"*a{k - 1}"] * 9) + "]" for k in range(1, depth)]
    head = {"name": "x", "duration_s": "60", "load": "1.0"}
    head.pop(field, None)
    text = "".join(f"{k}: {v}\n" for k, v in head.items())
    text += "description: [" + ", ".join(levels) + "]\n"
    return text + (f"{field}: *a{depth - 1}\n" if field != "description" else "")


#: (file text or bytes, substrings the error message must contain besides the file name)
BAD_YAML = {
    "laughs7_load": (_laughs(7, "load"), ["alias"]),
    "laughs8_load": (_laughs(8, "load"), ["alias"]),
    "laughs7_description": (_laughs(7, "description"), ["alias"]),
    "laughs8_description": (_laughs(8, "description"), ["alias"]),
    "laughs7_duration": (_laughs(7, "duration_s"), ["alias"]),
    "alias_scalar": ("name: &n x\nduration_s: 60\nload: 1.0\ndescription: *n\n", ["alias"]),
    "merge_key": ("name: x\nduration_s: 60\n<<: {load: 1.0}\n", ["merge"]),
    "too_big": (GOOD + "#" * (2 << 20) + "\n", ["bytes"]),
    "too_many_breakpoints": (
        "name: x\nduration_s: 60\nload: [" + ",".join(["[0, 1]"] * 10_001) + "]\n",
        ["load", "10000"],
    ),
    "long_name": (f"name: {'n' * 201}\nduration_s: 60\nload: 1.0\n", ["name", "200"]),
    "long_description": (GOOD + f"description: {'d' * 2001}\n", ["description", "2000"]),
    "duplicate_load": (GOOD + "load: 0.5\n", ["duplicate", "load"]),
    "duplicate_name": ("name: x\nname: y\nduration_s: 60\nload: 1.0\n", ["duplicate", "name"]),
    "duration_bool": ("name: x\nduration_s: true\nload: 1.0\n", ["duration_s", "bool"]),
    "duration_str": ("name: x\nduration_s: '60'\nload: 1.0\n", ["duration_s", "str"]),
    "duration_list": ("name: x\nduration_s: [60]\nload: 1.0\n", ["duration_s", "list"]),
    "duration_map": ("name: x\nduration_s: {a: 1}\nload: 1.0\n", ["duration_s"]),
    "duration_date": ("name: x\nduration_s: 2024-01-01\nload: 1.0\n", ["duration_s"]),
    "duration_null": ("name: x\nduration_s:\nload: 1.0\n", ["duration_s"]),
    "duration_nan": ("name: x\nduration_s: .nan\nload: 1.0\n", ["duration_s"]),
    "duration_inf": ("name: x\nduration_s: .inf\nload: 1.0\n", ["duration_s"]),
    "duration_short": ("name: x\nduration_s: 0.5\nload: 1.0\n", ["duration_s", "1"]),
    "duration_long": ("name: x\nduration_s: 700000\nload: 1.0\n", ["duration_s", "604800"]),
    "duration_huge_int": ("name: x\nduration_s: " + "9" * 400 + "\nload: 1.0\n", ["duration_s"]),
    "noise_str": (GOOD + "noise_std_C: '0.2'\n", ["noise_std_C", "str"]),
    "noise_bool": (GOOD + "noise_std_C: true\n", ["noise_std_C", "bool"]),
    "noise_list": (GOOD + "noise_std_C: [0.2]\n", ["noise_std_C"]),
    "tau_negative": (GOOD + "heat_absorption_noise_tau_s: -5\n", ["heat_absorption_noise_tau_s"]),
    "load_str": ("name: x\nduration_s: 60\nload: '1.0'\n", ["load", "str"]),
    "load_bool": ("name: x\nduration_s: 60\nload: true\n", ["load", "bool"]),
    "load_map": ("name: x\nduration_s: 60\nload: {0: 1.0}\n", ["load"]),
    "load_empty": ("name: x\nduration_s: 60\nload: []\n", ["load"]),
    "load_null": ("name: x\nduration_s: 60\nload:\n", ["load"]),
    "load_flat": ("name: x\nduration_s: 60\nload: [1.0, 0.9]\n", ["load", "pair"]),
    "load_triple": ("name: x\nduration_s: 60\nload: [[0, 1.0, 2]]\n", ["load", "pair"]),
    "load_str_value": ("name: x\nduration_s: 60\nload: [[0, '1']]\n", ["load", "number"]),
    "load_nested_value": ("name: x\nduration_s: 60\nload: [[0, [1]]]\n", ["load", "number"]),
    "load_nested_deep": ("name: x\nduration_s: 60\nload: [[0, [[[[1]]]]]]\n", ["load"]),
    "load_bool_time": ("name: x\nduration_s: 60\nload: [[true, 1.0]]\n", ["load", "number"]),
    "load_nan_time": ("name: x\nduration_s: 60\nload: [[.nan, 1.0]]\n", ["load", "finite"]),
    "load_inf_value": ("name: x\nduration_s: 60\nload: [[0, .inf]]\n", ["load", "finite"]),
    "load_overflow": ("name: x\nduration_s: 60\nload: [[0, 1.0e+400]]\n", ["load", "finite"]),
    "load_exp_overflow": ("name: x\nduration_s: 60\nload: [[0, 1e400]]\n", ["load", "finite"]),
    "load_negative_time": ("name: x\nduration_s: 60\nload: [[-1, 1.0]]\n", ["load", ">= 0"]),
    "load_far_time": ("name: x\nduration_s: 60\nload: [[1e12, 1.0]]\n", ["load", "time"]),
    "load_decreasing": ("name: x\nduration_s: 60\nload: [[10, 1.0], [5, 0.9]]\n", ["load"]),
    "load_range": ("name: x\nduration_s: 60\nload: [[0, 5.0]]\n", ["load", "physical range"]),
    "load_deep": ("name: x\nduration_s: 60\nload: " + "[" * 5000 + "]" * 5000 + "\n", []),
    "fouling_garbage": (GOOD + "fouling: [[0, {a: [1, 2]}]]\n", ["fouling"]),
    "name_int": ("name: 5\nduration_s: 60\nload: 1.0\n", ["name", "int"]),
    "name_empty": ("name: ''\nduration_s: 60\nload: 1.0\n", ["name"]),
    "name_list": ("name: [a]\nduration_s: 60\nload: 1.0\n", ["name", "list"]),
    "name_control": ('name: "a\\ab"\nduration_s: 60\nload: 1.0\n', ["name", "printable"]),
    "name_binary": ("name: !!binary aGVsbG8=\nduration_s: 60\nload: 1.0\n", ["name", "bytes"]),
    "description_int": (GOOD + "description: 5\n", ["description", "int"]),
    "description_map": (GOOD + "description: {a: b}\n", ["description", "dict"]),
    "unknown_key": (GOOD + "wind: 3\n", ["unknown scenario field", "wind"]),
    "int_key": (GOOD + "1: 2\n", ["field names must be strings"]),
    "missing_load": ("name: x\nduration_s: 60\n", ["load"]),
    "python_tag": (GOOD + "description: !!python/object:os.system x\n", ["malformed"]),
    "not_mapping": ("- 1\n- 2\n", ["mapping"]),
    "scalar_doc": ("just a string\n", ["mapping"]),
    "empty_file": ("", ["mapping"]),
    "two_documents": (GOOD + "---\n" + GOOD, ["malformed"]),
    "malformed": ("name: x\nduration_s: [60\n", ["malformed"]),
    "control_char": ("name: x\x01\nduration_s: 60\nload: 1.0\n", ["malformed"]),
    "not_utf8": (b"name: caf\xe9\nduration_s: 60\nload: 1.0\n", ["UTF-8"]),
}


@pytest.mark.parametrize("case", sorted(BAD_YAML))
def test_bad_yaml_is_rejected_with_a_short_error_naming_file_and_field(tmp_path, case):
    import tracemalloc

    text, needles = BAD_YAML[case]
    path = tmp_path / f"{case}.yaml"
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    tracemalloc.start()
    try:
        with pytest.raises(ValueError) as err:
            scenarios.resolve(path)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    msg = str(err.value)
    assert path.name in msg
    for needle in needles:
        assert needle in msg, (needle, msg)
    assert len(msg) < 1000, msg[:300]  # quotes at most a short excerpt of the input
    assert peak < 64 << 20  # bounded memory: no expansion of the input (the file is < 2 MB)


def test_good_yaml_loads_from_str_path_and_any_pathlike(tmp_path):
    class MyPath:  # an os.PathLike that is not a pathlib.Path
        def __init__(self, p):
            self.p = p

        def __fspath__(self):
            return str(self.p)

    path = tmp_path / "good.yaml"
    path.write_text(GOOD + "description: fine\n# comment\n")
    upper = tmp_path / "GOOD.YML"
    upper.write_text(GOOD)
    loaded = [scenarios.resolve(x) for x in (path, str(path), MyPath(path), upper, str(upper))]
    loaded.append(scenarios.load_yaml(path))
    for s in loaded:
        assert s.name == "x" and s.load == ((0.0, 1.0), (30.0, 0.9))
    exp = tmp_path / "exp.yml"  # YAML 1.2 floats (PyYAML's 1.1 reads them as strings)
    exp.write_text("name: x\nduration_s: 3.6e3\nload: [[0, 1.0], [1e3, 9e-1], [2E+3, 1]]\n")
    assert scenarios.resolve(exp).load == ((0.0, 1.0), (1000.0, 0.9), (2000.0, 1.0))
    assert scenarios.resolve(exp).duration_s == 3600.0
    # the limits themselves are accepted
    limit = scenarios.MAX_BREAKPOINTS_PER_CHANNEL
    big = tmp_path / "big.yaml"
    big.write_text(
        f"name: {'n' * 200}\nduration_s: 604800\nload: ["
        + ",".join(f"[{k}, 1.0]" for k in range(limit))
        + f"]\ndescription: {'d' * 2000}\n"
    )
    s = scenarios.resolve(big)
    assert len(s.load) == limit and len(s.name) == 200


BAD_PATHS = {
    "no_suffix": lambda d: _touch(d / "scenario.txt"),
    "no_suffix_named_like_a_scenario": lambda d: _touch(d / "load_cycle"),
    "directory": lambda d: _mkdir(d / "dir.yaml"),
    "directory_no_suffix": lambda d: _mkdir(d / "somedir"),
    "missing": lambda d: d / "absent.yaml",
    "missing_no_suffix": lambda d: d / "absent",
    "fifo": lambda d: _fifo(d / "pipe.yaml"),
}


def _touch(p):
    p.write_text(GOOD)
    return p


def _mkdir(p):
    p.mkdir()
    return p


def _fifo(p):
    import os

    if not hasattr(os, "mkfifo"):
        pytest.skip("no FIFOs here")
    os.mkfifo(p)
    return p


@pytest.mark.parametrize("as_str", [False, True])
@pytest.mark.parametrize("case", sorted(BAD_PATHS))
def test_bad_paths_give_an_error_naming_the_file(tmp_path, case, as_str):
    path = BAD_PATHS[case](tmp_path)
    if as_str and path.suffix != ".yaml":
        pytest.skip("a str without the suffix is a scenario name (tested below)")
    with pytest.raises(ValueError) as err:
        scenarios.resolve(str(path) if as_str else path)
    assert path.name in str(err.value)


def test_unreadable_file_gives_an_error_naming_the_file(tmp_path, monkeypatch):
    import pathlib

    path = _touch(tmp_path / "locked.yaml")

    def refuse(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(pathlib.Path, "open", refuse)
    monkeypatch.setattr("builtins.open", refuse)
    with pytest.raises(ValueError, match="locked.yaml.*Permission denied"):
        scenarios.resolve(path)


def test_names_and_other_specs():
    with pytest.raises(ValueError, match="load_cycle") as err:
        scenarios.resolve("no_such_scenario")
    assert "no_such_scenario" in str(err.value)
    with pytest.raises(ValueError, match="load_cycle"):
        scenarios.resolve("x" * 100_000)
    for bad in (3, None, b"load_cycle.yaml", ["load_cycle"], 2.5):
        with pytest.raises(ValueError, match="scenario"):
            scenarios.resolve(bad)
    assert scenarios.resolve("random") == scenarios.RANDOM
    with pytest.raises(ValueError, match="must end in .yaml or .yml"):
        scenarios.resolve(__file__)  # an existing file without the suffix: a hint
    assert scenarios.resolve("load_cycle") is scenarios.get("load_cycle")


#: Scenario(...) keyword arguments that must be rejected, with the field the error names.
BAD_FIELDS = [
    ({"duration_s": True}, "duration_s"),
    ({"duration_s": np.bool_(True)}, "duration_s"),
    ({"duration_s": "60"}, "duration_s"),
    ({"duration_s": [60]}, "duration_s"),
    ({"duration_s": None}, "duration_s"),
    ({"duration_s": 60 + 0j}, "duration_s"),
    ({"duration_s": 0.0}, "duration_s"),
    ({"duration_s": 1e9}, "duration_s"),
    ({"name": None}, "name"),
    ({"name": b"x"}, "name"),
    ({"name": "x\ny"}, "name"),
    ({"name": "n" * 201}, "name"),
    ({"description": None}, "description"),
    ({"description": "d" * 2001}, "description"),
    ({"load": None}, "load"),
    ({"load": "1.0"}, "load"),
    ({"load": True}, "load"),
    ({"load": np.bool_(True)}, "load"),
    ({"load": 1 + 0j}, "load"),
    ({"load": ((0, 1.0), (10, "0.9"))}, "load"),
    ({"load": ((0, 1.0), (10,))}, "load"),
    ({"load": ((0, 1.0), 0.9)}, "load"),
    ({"load": {0: 1.0}}, "load"),
    ({"load": ((0, 1.0),) * 10_001}, "load"),
    ({"load": np.zeros((3, 3))}, "load"),
    ({"load": np.array([["0", "1"]])}, "load"),
    ({"load": ((0, True),)}, "load"),
    ({"fouling": ((0, float("nan")),)}, "fouling"),
    ({"fouling": ((float("inf"), 1.0),)}, "fouling"),
    ({"setpoint_offset_C": ((-5, 0.0),)}, "setpoint_offset_C"),
    ({"setpoint_offset_C": ((5, 0.0), (4, 1.0))}, "setpoint_offset_C"),
    ({"noise_std_C": True}, "noise_std_C"),
    ({"noise_std_C": "0.2"}, "noise_std_C"),
    ({"noise_std_C": [0.2]}, "noise_std_C"),
    ({"heat_absorption_noise_std": None}, "heat_absorption_noise_std"),
    ({"heat_absorption_noise_tau_s": np.float64("nan")}, "heat_absorption_noise_tau_s"),
]


@pytest.mark.parametrize(("kwargs", "field"), BAD_FIELDS, ids=[f for _, f in BAD_FIELDS])
def test_every_scenario_field_is_type_checked(kwargs, field):
    args = {"name": "x", "duration_s": 60.0, **kwargs}
    with pytest.raises(ValueError, match=field) as err:
        Scenario(**args)
    assert len(str(err.value)) < 1000
    with pytest.raises(ValueError, match=field):  # the same through the YAML-mapping path
        Scenario.from_dict({"load": 1.0, **args})


def test_numpy_numbers_are_numbers_and_equal_times_are_a_jump():
    s = Scenario(
        name="np",
        duration_s=np.float32(60.0),
        load=np.array([[0.0, 1.0], [10.0, 0.9]]),
        setpoint_offset_C=((np.int64(0), np.float16(0.0)), (np.int32(20), np.longdouble(5.0))),
        fouling=np.float64(1.1),
        noise_std_C=np.float32(0.25),
        heat_absorption_noise_tau_s=np.int64(60),
    )
    assert s.duration_s == 60.0 and type(s.duration_s) is float
    assert s.load == ((0.0, 1.0), (10.0, 0.9)) and type(s.load[0][0]) is float
    assert s.fouling == ((0.0, 1.1),) and type(s.noise_std_C) is float
    jump = Scenario(name="j", duration_s=60.0, load=((0, 1.0), (30, 1.0), (30, 0.8)))
    assert jump.value("load", 31.0) == pytest.approx(0.8)


def test_random_scenario_rejects_a_bad_duration_before_drawing():
    for bad in (True, "3600", float("inf"), 1e300, -1.0):
        with pytest.raises(ValueError, match="duration_s"):
            scenarios.random_scenario(np.random.default_rng(0), bad)


def test_last_change_is_the_end_of_the_last_ramp_or_step_of_any_channel():
    s = Scenario(
        name="x",
        duration_s=3600.0,
        load=((0.0, 1.0), (600.0, 1.0), (1200.0, 0.5)),
        fouling=((0.0, 1.0), (1500.0, 1.0), (1500.0, 0.9), (2000.0, 0.9)),
    )
    assert s.last_change_s() == 1500.0
    assert Scenario(name="flat", duration_s=60.0).last_change_s() == 0.0
    held = Scenario(name="held", duration_s=60.0, load=((0.0, 0.8), (30.0, 0.8)))
    assert held.last_change_s() == 0.0


# ----------------------------------------------------------------- plants' own scenarios
CASCADE = "steamtemp/Cascade300MW-v0"
ID_FSH = "steamtemp/SupercriticalFSH-v0"
CASCADE_OWN = ("load_ramp_100_50_100_2pct", "setpoint_step_535_545")


def test_scenarios_never_import_the_plants_or_the_envs():
    """The package is data and its checks: plants declare scenarios, never the reverse."""
    import ast
    from pathlib import Path

    root = Path(scenarios.__file__).parent
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                names = [f"{node.module}.{a.name}" for a in node.names]
            elif isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            else:
                continue
            for name in names:
                assert not name.startswith(("steamtemp_gym.plants", "steamtemp_gym.envs")), (
                    f"{path.name}:{node.lineno} imports {name}"
                )


def test_a_plant_declares_its_named_scenarios_as_data():
    from steamtemp_gym.plants import own_scenarios, plant_class

    own = plant_class(CASCADE).scenarios
    assert tuple(sorted(own)) == CASCADE_OWN and own is own_scenarios(CASCADE)
    with pytest.raises(TypeError):
        own["x"] = own[CASCADE_OWN[0]]  # read-only
    for name in CASCADE_OWN:
        s = scenarios.get(name, CASCADE)
        assert s is own[name] and scenarios.resolve(name, CASCADE) is s
        assert (s.noise_std_C, s.heat_absorption_noise_std) == (0.25, 0.02)
        assert name in scenarios.names(CASCADE)
        assert name not in scenarios.names() and name not in scenarios.names(ID_FSH)
        for plant_id in (None, ID_FSH):
            with pytest.raises(ValueError, match=f"unknown scenario '{name}'"):
                scenarios.resolve(name, plant_id)
    assert own_scenarios(ID_FSH) == {}
    assert scenarios.names(CASCADE) == sorted({*CASCADE_OWN, *scenarios.names()[:-1]}) + [
        scenarios.RANDOM
    ]
    with pytest.raises(ValueError, match="unknown plant id"):
        scenarios.names("steamtemp/NoSuchPlant-v0")


def test_declare_checks_names_and_switches_the_disturbances_on():
    s = Scenario(name="mine", duration_s=60.0)
    (declared,) = scenarios.declare(s).values()
    assert declared.noise_std_C == scenarios.NAMED_DISTURBANCES["noise_std_C"]
    for bad, word in [
        ((s, s), "twice"),
        (("mine",), "Scenario"),
        ((Scenario(name="random", duration_s=1.0),), "reserved"),
        ((Scenario(name="heldout:x", duration_s=1.0),), "held-out"),
        ((Scenario(name="a.yml", duration_s=1.0),), "file"),
    ]:
        with pytest.raises(ValueError, match=word):
            scenarios.declare(*bad)
