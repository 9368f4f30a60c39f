"""The held-out evaluation scenarios: YAML files in this folder, never trained or tuned on.

Each file is an ordinary scenario file (format: ``steamtemp_gym.scenarios.yaml_loader``), read by
:func:`load`; the leaderboard names them ``heldout:<name>`` (:data:`PREFIX`). They are not
in the scenario registry, so nothing that iterates ``scenarios.names()`` (training
curricula, the difficulty table) sees them.

============================== ===============================================================
name                           what happens (and why ``random`` cannot draw it)
============================== ===============================================================
``deep_fast_ramp``             load 100 -> 35 % at 8 %/min (random: loads >= 50 %, ramps
                               <= 5 %/min)
``mill_trip``                  heat absorption -12 % within 10 s at rated load (random: bias
                               steps of at most 8 %, always rising over 60 s)
``sootblowing``                heat-transfer multiplier 0.80 -> 1.00 over 3 min at 85 % load
                               (random: a constant multiplier in 0.85-1.15)
``hp_heater_out``              spray water 40 K colder over 2 min (random: a constant offset
                               within +-15 K)
``setpoint_ramp_during_load_ramp`` setpoint slides -15 K at 3 K/min during a 4 %/min load
                               ramp (random: single setpoint steps of at most 10 K)
``high_noise``                 1.0 K thermocouple noise during a load ramp (random: 0.2-0.3 K)
============================== ===============================================================

Every file also carries the disturbances of the named scenarios (0.25 K noise, except
``high_noise``; a 2 % coloured heat-absorption disturbance), so seeds differ.

Exclusion by construction: :func:`outside_training` lists the features of a scenario that
``random_scenario`` cannot produce, read from ``RANDOM_DISTRIBUTION`` and the shapes of
its schedules (load: holds and ramps at 1-5 %/min within 50-100 %; setpoint: at most one
step of at most 10 K; heat-absorption bias: at most one 60 s rise of at most 8 %; fouling,
spray-water offset: one constant each; the three noise scalars in their ranges). Every
held-out file has at least one such feature, and every draw of ``random`` has none
(tests/test_scenarios_heldout.py checks both).

Magnitudes: chosen so that a frozen valve leaves the +-8 K band (most trip) while the
conventional cascade PI holds every plant without a trip on three seeds (the same test
file checks the latter); they are not tuned per plant.
"""

from __future__ import annotations

from pathlib import Path

from steamtemp_gym.scenarios import HELDOUT_PREFIX, RANDOM_DISTRIBUTION, Scenario, load_yaml

__all__ = ["DIR", "NAMES", "PREFIX", "is_heldout", "load", "outside_training", "path"]

DIR = Path(__file__).parent
#: Names of the held-out scenarios (the YAML file stems), sorted.
NAMES: tuple[str, ...] = tuple(sorted(p.stem for p in DIR.glob("*.yaml")))
#: How the leaderboard spells a held-out scenario: ``heldout:mill_trip``.
PREFIX = HELDOUT_PREFIX
_TOL = 1e-9


def is_heldout(spec: object) -> bool:
    """True for a ``heldout:<name>`` spec string."""
    return isinstance(spec, str) and spec.startswith(PREFIX)


def path(name: str) -> Path:
    """The YAML file of held-out scenario ``name`` (with or without the prefix)."""
    bare = name[len(PREFIX) :] if is_heldout(name) else name
    if bare not in NAMES:
        raise ValueError(
            f"unknown held-out scenario {name!r}; valid names: {[PREFIX + n for n in NAMES]}"
        )
    return DIR / f"{bare}.yaml"


def load(name: str) -> Scenario:
    """Held-out scenario ``name`` as a Scenario."""
    return load_yaml(path(name))


def _pieces(points) -> list[tuple[float, float, float, float]]:
    """Consecutive breakpoint pairs (t0, v0, t1, v1)."""
    return [(*a, *b) for a, b in zip(points[:-1], points[1:], strict=True)]


def _load_violations(points) -> list[str]:
    d = RANDOM_DISTRIBUTION
    lo, hi = d["load_range"]
    r_lo, r_hi = (r / 60.0 for r in d["ramp_rate_per_min"])
    out = []
    values = [v for _, v in points]
    if min(values) < lo - _TOL or max(values) > hi + _TOL:
        out.append(f"load {min(values):g}-{max(values):g} outside {lo:g}-{hi:g}")
    for t0, v0, t1, v1 in _pieces(points):
        if v0 == v1:
            continue
        rate = abs(v1 - v0) / (t1 - t0) if t1 > t0 else float("inf")
        if not r_lo * (1 - 1e-6) <= rate <= r_hi * (1 + 1e-6):
            out.append(f"load ramp {rate * 6000:.3g} %/min outside {r_lo * 6000:g}-{r_hi * 6000:g}")
            break
    return out


def _single_step(name: str, points, limit: float, rise_s: float) -> list[str]:
    """A schedule ``random`` draws: 0, or 0 then one change of |size| <= limit over rise_s."""
    changes = [(t0, v0, t1, v1) for t0, v0, t1, v1 in _pieces(points) if v0 != v1]
    if abs(points[0][1]) > _TOL:
        return [f"{name} starts at {points[0][1]:g}, not 0"]
    if len(changes) > 1:
        return [f"{name} changes {len(changes)} times (random: at most once)"]
    if not changes:
        return [] if abs(points[-1][1]) <= _TOL else [f"{name} jumps at t = 0"]
    t0, v0, t1, v1 = changes[0]
    out = []
    if abs(v1 - v0) > limit + _TOL:
        out.append(f"{name} change {v1 - v0:g} larger than {limit:g}")
    if abs((t1 - t0) - rise_s) > 1e-6:
        out.append(f"{name} changes over {t1 - t0:g} s (random: {rise_s:g} s)")
    return out


def _constant(name: str, points, lo: float, hi: float) -> list[str]:
    values = {v for _, v in points}
    if len(values) > 1:
        return [f"{name} varies in time (random: constant)"]
    (v,) = values
    return [] if lo - _TOL <= v <= hi + _TOL else [f"{name} {v:g} outside {lo:g}-{hi:g}"]


def outside_training(scenario: Scenario) -> list[str]:
    """Why ``random`` could not have drawn ``scenario`` (empty: it could have).

    Checks the support of ``random_scenario`` (see the module docstring); the episode
    length is not checked (``random`` takes any).
    """
    d = RANDOM_DISTRIBUTION
    out = _load_violations(scenario.load)
    out += _single_step(
        "setpoint_offset_C", scenario.setpoint_offset_C, max(map(abs, d["setpoint_step_K"])), 0.0
    )
    out += _single_step(
        "heat_absorption_bias",
        scenario.heat_absorption_bias,
        max(map(abs, d["heat_bias_step"])),
        60.0,
    )
    fouling = scenario.fouling if scenario.fouling else ((0.0, 1.0),)
    spray = scenario.spray_water_temp_offset_C or ((0.0, 0.0),)
    out += _constant("fouling", fouling, *d["fouling"])
    out += _constant("spray_water_temp_offset_C", spray, *d["spray_water_temp_offset_C"])
    for key in ("noise_std_C", "heat_absorption_noise_std", "heat_absorption_noise_tau_s"):
        lo, hi = d[key]
        v = getattr(scenario, key)
        if not lo - _TOL <= v <= hi + _TOL:
            out.append(f"{key} {v:g} outside {lo:g}-{hi:g}")
    return out
