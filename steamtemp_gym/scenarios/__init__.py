"""Scenarios: the world outside the plant.

A :class:`Scenario` is a set of piecewise-linear schedules over time (breakpoint
lists ``[[t_s, value], ...]``, linear interpolation, held constant after the
last breakpoint) in the common vocabulary of ``../shared/DESIGN.md``:

========================== ========= ==========================================
channel                    unit      meaning
========================== ========= ==========================================
``load``                   fraction  unit load demand, fraction of rated
``setpoint_offset_C``      K         offset added to the plant's nominal setpoint
``heat_absorption_bias``   fraction  relative error of the superheater heat
                                     absorption (coal quality, mills, soot)
``fouling``                factor    gas-side heat-transfer multiplier (1 clean)
``spray_water_temp_offset_C`` K      spray-water temperature offset
========================== ========= ==========================================

plus three scalars:

- ``noise_std_C`` (K): standard deviation of the white noise on the measured
  temperatures (thermocouples of real units: 0.2-0.3 K);
- ``heat_absorption_noise_std`` (fraction) and ``heat_absorption_noise_tau_s`` (s):
  a coloured heat-absorption disturbance (slagging, coal quality, soot blowing,
  mill changes), an Ornstein-Uhlenbeck process with that stationary standard
  deviation and correlation time, added by the env to ``heat_absorption_bias``
  (exact discretization at the control interval, counter-based random numbers,
  started from its stationary distribution so that a reset is a steady state).

A field left out of a scenario means none of that disturbance (a file without
``noise_std_C`` is noise-free, so deterministic step tests stay possible). The
named scenarios (``library.py``) have sensor noise and the coloured heat-absorption
disturbance on (:data:`NAMED_DISTURBANCES`). Every plant maps this vocabulary onto
its own inputs.

Scenarios are deterministic; ``"random"`` is the seeded training distribution
drawn afresh at every reset (:func:`random_scenario`). Named scenarios live in
a registry (:func:`get`, :func:`names`); plants may register their own.
The load-ramp test ``load_ramp_100_50`` is the test of 000_f43a9a359eb2e47e.txt
(100 -> 50 % at 5 %/min from minute 20 to 30); the operating-practice figures
used for the random distribution are from ../shared/REFERENCE_DATA.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np
import yaml

__all__ = [
    "CHANNELS",
    "Scenario",
    "get",
    "names",
    "register",
    "resolve",
    "load_yaml",
    "random_scenario",
    "pack",
    "RANDOM",
    "NAMED_DISTURBANCES",
]

#: Schedule channels in the order the compiled kernels read them.
CHANNELS: tuple[str, ...] = (
    "load",
    "setpoint_offset_C",
    "heat_absorption_bias",
    "fouling",
    "spray_water_temp_offset_C",
)
_DEFAULTS = {
    "load": 1.0,
    "setpoint_offset_C": 0.0,
    "heat_absorption_bias": 0.0,
    "fouling": 1.0,
    "spray_water_temp_offset_C": 0.0,
}
#: Ranges of each channel (inclusive) accepted by every plant: loads from minimum stable
#: firing to 110 % overload; setpoint offsets of sliding-temperature operation; heat-absorption
#: errors and gas-side fouling factors beyond those of coal switching and heavy slagging
#: (plausible, unverified); spray water from HP heaters out of service to their overshoot.
#: Within them a plant may still be unable to hold a combination at t = 0: such a scenario is
#: rejected at reset with the values that make it impossible (envs/core.py:Core.check_start).
_LIMITS = {
    "load": (0.2, 1.1),
    "setpoint_offset_C": (-30.0, 30.0),
    "heat_absorption_bias": (-0.25, 0.25),
    "fouling": (0.6, 1.6),
    "spray_water_temp_offset_C": (-60.0, 60.0),
}
RANDOM = "random"

#: Scalar fields with their inclusive ranges (units: K, fraction, s).
_SCALAR_LIMITS = {
    "noise_std_C": (0.0, 10.0),
    "heat_absorption_noise_std": (0.0, 0.2),
    "heat_absorption_noise_tau_s": (1.0, 86400.0),
}
#: Disturbances on in every named scenario: thermocouple noise 0.25 K (real units:
#: 0.2-0.3 K) and a coloured heat-absorption disturbance of 2 % std with a 5 min
#: correlation time (slagging, coal quality and mill changes; plausible default, unverified).
NAMED_DISTURBANCES = {
    "noise_std_C": 0.25,
    "heat_absorption_noise_std": 0.02,
    "heat_absorption_noise_tau_s": 300.0,
}
Schedule = tuple[tuple[float, float], ...]


def _as_scalar(name: str, value: Any, lo: float, hi: float) -> float:
    """Validate a scalar scenario field (finite, inside [lo, hi])."""
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"scenario {name!r} must be a number, got {value!r}") from exc
    if isinstance(value, bool) or not (math.isfinite(v) and lo <= v <= hi):
        raise ValueError(f"scenario {name!r} must be in [{lo}, {hi}], got {value!r}")
    return v


def _as_schedule(name: str, value: Any) -> Schedule:
    """Validate and normalize a breakpoint list (or a constant) into a tuple of pairs."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        value = [[0.0, float(value)]]
    if not isinstance(value, (list, tuple)) or len(value) == 0:
        raise ValueError(
            f"scenario field {name!r} must be a number or a non-empty list of [t_s, value] "
            f"breakpoints, got {value!r}"
        )
    pts = []
    for item in value:
        if not isinstance(item, (list, tuple)) or len(item) != 2:
            raise ValueError(
                f"scenario field {name!r}: breakpoint {item!r} is not a [t_s, value] pair"
            )
        try:
            t, v = float(item[0]), float(item[1])
        except (TypeError, ValueError) as exc:
            raise ValueError(
                f"scenario field {name!r}: breakpoint {item!r} is not numeric"
            ) from exc
        if not (math.isfinite(t) and math.isfinite(v)):
            raise ValueError(f"scenario field {name!r}: breakpoint {item!r} is not finite")
        pts.append((t, v))
    times = [p[0] for p in pts]
    if times[0] < 0.0:
        raise ValueError(f"scenario field {name!r}: breakpoint times must be >= 0, got {times[0]}")
    if any(b < a for a, b in zip(times[:-1], times[1:], strict=True)):
        raise ValueError(f"scenario field {name!r}: breakpoint times must be non-decreasing")
    lo, hi = _LIMITS[name]
    for _, v in pts:
        if not lo <= v <= hi:
            raise ValueError(
                f"scenario field {name!r}: value {v} is outside the physical range [{lo}, {hi}]"
            )
    return tuple(pts)


@dataclass(frozen=True)
class Scenario:
    """Schedules of the disturbances and setpoint over one episode.

    Attributes:
        name: Identifier shown in tables and plots.
        duration_s: Episode length in seconds (``truncated`` after it).
        load: Load demand breakpoints ``((t_s, fraction), ...)``.
        setpoint_offset_C: Setpoint offset breakpoints in K.
        heat_absorption_bias: Heat-absorption relative bias breakpoints.
        fouling: Gas-side heat-transfer multiplier breakpoints.
        spray_water_temp_offset_C: Spray-water temperature offset breakpoints in K.
        noise_std_C: Standard deviation of measured-temperature noise in K.
        heat_absorption_noise_std: Stationary standard deviation (fraction) of the coloured
            heat-absorption disturbance added to ``heat_absorption_bias``.
        heat_absorption_noise_tau_s: Its correlation time in s.
        description: One line for humans.
    """

    name: str
    duration_s: float
    load: Schedule = ((0.0, 1.0),)
    setpoint_offset_C: Schedule = ((0.0, 0.0),)
    heat_absorption_bias: Schedule = ((0.0, 0.0),)
    fouling: Schedule = ((0.0, 1.0),)
    spray_water_temp_offset_C: Schedule = ((0.0, 0.0),)
    noise_std_C: float = 0.0
    heat_absorption_noise_std: float = 0.0
    heat_absorption_noise_tau_s: float = 600.0
    description: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError("scenario 'name' must be a non-empty string")
        try:
            duration = float(self.duration_s)
        except (TypeError, ValueError) as exc:
            raise ValueError(
                f"scenario 'duration_s' must be a number, got {self.duration_s!r}"
            ) from exc
        if not (math.isfinite(duration) and duration > 0.0):
            raise ValueError(
                f"scenario 'duration_s' must be finite and > 0, got {self.duration_s!r}"
            )
        object.__setattr__(self, "duration_s", duration)
        for ch in CHANNELS:
            object.__setattr__(self, ch, _as_schedule(ch, getattr(self, ch)))
        for name, (lo, hi) in _SCALAR_LIMITS.items():
            object.__setattr__(self, name, _as_scalar(name, getattr(self, name), lo, hi))

    def value(self, channel: str, t: float) -> float:
        """Value of one channel at time ``t`` (linear interpolation, held at the ends)."""
        pts = np.asarray(getattr(self, channel))
        return float(np.interp(t, pts[:, 0], pts[:, 1]))

    def to_dict(self) -> dict[str, Any]:
        """The YAML-ready form of this scenario."""
        out: dict[str, Any] = {"name": self.name, "duration_s": self.duration_s}
        for ch in CHANNELS:
            out[ch] = [list(p) for p in getattr(self, ch)]
        for name in _SCALAR_LIMITS:
            out[name] = getattr(self, name)
        if self.description:
            out["description"] = self.description
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "scenario") -> Scenario:
        """Build from a mapping (as read from YAML), rejecting unknown keys."""
        if not isinstance(data, Mapping):
            raise ValueError(
                f"{source}: expected a mapping of scenario fields, got {type(data).__name__}"
            )
        valid = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - valid)
        if unknown:
            raise ValueError(
                f"{source}: unknown scenario field(s) {unknown}; valid fields: {sorted(valid)}"
            )
        for key in ("name", "duration_s", "load"):
            if key not in data:
                raise ValueError(f"{source}: missing required field {key!r}")
        return cls(**dict(data))


def load_yaml(path: str | Path) -> Scenario:
    """Read a scenario YAML file (format in ../shared/DESIGN.md)."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise ValueError(f"cannot read scenario file {str(path)!r}: {exc}") from exc
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise ValueError(f"malformed scenario YAML {str(path)!r}: {exc}") from exc
    return Scenario.from_dict(data, source=str(path))


# --------------------------------------------------------------------------- registry
_REGISTRY: dict[str, tuple[Scenario, tuple[str, ...] | None]] = {}


def register(scenario: Scenario, plants: Sequence[str] | None = None) -> Scenario:
    """Register a named scenario, for every plant or only for the given plant ids."""
    if scenario.name == RANDOM:
        raise ValueError(f"{RANDOM!r} is reserved for the seeded training distribution")
    _REGISTRY[scenario.name] = (scenario, tuple(plants) if plants is not None else None)
    return scenario


def _load_plant(plant_id: str | None) -> None:
    """Import the plant's module so its own named scenarios are registered."""
    if plant_id is not None:
        from steamtemp_gym import plants

        plants.plant_class(plant_id)


def names(plant_id: str | None = None) -> list[str]:
    """Names of the registered scenarios valid for ``plant_id`` (all if None), plus ``random``."""
    _load_plant(plant_id)
    out = [
        n for n, (_, pl) in _REGISTRY.items() if pl is None or plant_id is None or plant_id in pl
    ]
    return sorted(out) + [RANDOM]


def get(name: str, plant_id: str | None = None) -> Scenario:
    """A registered scenario by name; ValueError listing the valid names otherwise."""
    _load_plant(plant_id)
    entry = _REGISTRY.get(name)
    if entry is None or (
        plant_id is not None and entry[1] is not None and plant_id not in entry[1]
    ):
        raise ValueError(
            f"unknown scenario {name!r}; valid names: {names(plant_id)} or a YAML path"
        )
    return entry[0]


def resolve(spec: str | Path | Scenario, plant_id: str | None = None) -> Scenario | str:
    """Turn a scenario argument (name, YAML path or Scenario) into a Scenario or ``"random"``."""
    if isinstance(spec, Scenario):
        return spec
    if isinstance(spec, Path) or (isinstance(spec, str) and spec.endswith((".yaml", ".yml"))):
        return load_yaml(spec)
    if isinstance(spec, str):
        if spec == RANDOM:
            return RANDOM
        return get(spec, plant_id)
    raise ValueError(
        f"scenario must be a name, a YAML path or a Scenario, got {type(spec).__name__}"
    )


# --------------------------------------------------------------------------- random
#: The documented training distribution of ``random`` (see random_scenario).
RANDOM_DISTRIBUTION = {
    "duration_s": 3600.0,
    "initial_load": (0.5, 1.0),
    "hold_s": (120.0, 900.0),
    "ramp_rate_per_min": (0.01, 0.05),
    "load_range": (0.5, 1.0),
    "setpoint_step_probability": 0.3,
    "setpoint_step_K": (-10.0, 10.0),
    "heat_bias_step_probability": 0.5,
    "heat_bias_step": (-0.08, 0.08),
    "fouling": (0.85, 1.15),
    "spray_water_temp_offset_C": (-15.0, 15.0),
    "noise_std_C": (0.2, 0.3),
    "heat_absorption_noise_std": (0.0, 0.04),
    "heat_absorption_noise_tau_s": (120.0, 900.0),
}


def random_scenario(rng: np.random.Generator, duration_s: float | None = None) -> Scenario:
    """Draw one scenario from the training distribution ``RANDOM_DISTRIBUTION``.

    Load: start uniform in 50-100 %, then alternate holds (2-15 min) and ramps at
    1-5 %/min (REFERENCE_DATA.md: 1.5 %/min typical, 4-6 %/min state of the art)
    to a new target in 50-100 %. With probability 0.3 a setpoint step of
    +-10 K at a random time; with probability 0.5 a heat-absorption bias step of
    +-8 %; a constant fouling factor 0.85-1.15; a constant spray-water
    temperature offset of +-15 K; thermocouple noise 0.2-0.3 K; a coloured
    heat-absorption disturbance of 0-4 % std with a 2-15 min correlation time.
    """
    dist = RANDOM_DISTRIBUTION
    duration = float(duration_s if duration_s is not None else dist["duration_s"])
    u = rng.uniform
    load = u(*dist["initial_load"])
    t = 0.0
    load_pts = [(0.0, load)]
    while t < duration:
        t += u(*dist["hold_s"])
        target = u(*dist["load_range"])
        rate = u(*dist["ramp_rate_per_min"]) / 60.0
        t_end = t + abs(target - load) / rate
        load_pts += [(t, load), (t_end, target)]
        t, load = t_end, target
    sp = [(0.0, 0.0)]
    if u() < dist["setpoint_step_probability"]:
        ts, step = u(0.1, 0.8) * duration, u(*dist["setpoint_step_K"])
        sp = [(0.0, 0.0), (ts, 0.0), (ts, step)]
    bias = [(0.0, 0.0)]
    if u() < dist["heat_bias_step_probability"]:
        ts, step = u(0.1, 0.8) * duration, u(*dist["heat_bias_step"])
        bias = [(0.0, 0.0), (ts, 0.0), (ts + 60.0, step)]
    return Scenario(
        name=RANDOM,
        duration_s=duration,
        load=tuple(load_pts),
        setpoint_offset_C=tuple(sp),
        heat_absorption_bias=tuple(bias),
        fouling=((0.0, u(*dist["fouling"])),),
        spray_water_temp_offset_C=((0.0, u(*dist["spray_water_temp_offset_C"])),),
        noise_std_C=u(*dist["noise_std_C"]),
        heat_absorption_noise_std=u(*dist["heat_absorption_noise_std"]),
        heat_absorption_noise_tau_s=u(*dist["heat_absorption_noise_tau_s"]),
    )


# --------------------------------------------------------------------------- packing
def pack(scenario: Scenario, bp_t: np.ndarray, bp_v: np.ndarray, bp_n: np.ndarray) -> None:
    """Write one scenario's breakpoints into rows of the kernel's padded tables.

    Args:
        scenario: The scenario.
        bp_t: Breakpoint times, shape (n_channels, K), written in place.
        bp_v: Breakpoint values, shape (n_channels, K), written in place.
        bp_n: Breakpoint counts, shape (n_channels,), written in place.
    """
    for c, ch in enumerate(CHANNELS):
        pts = getattr(scenario, ch)
        if len(pts) > bp_t.shape[1]:
            raise ValueError(
                f"scenario {scenario.name!r}: channel {ch!r} has {len(pts)} breakpoints, "
                f"more than the {bp_t.shape[1]} supported"
            )
        bp_n[c] = len(pts)
        for k, (t, v) in enumerate(pts):
            bp_t[c, k] = t
            bp_v[c, k] = v


def max_breakpoints(scenarios: Sequence[Scenario]) -> int:
    """Largest breakpoint count over channels of the given scenarios."""
    return max(len(getattr(s, ch)) for s in scenarios for ch in CHANNELS)


ScenarioFactory = Callable[[np.random.Generator], Scenario]

from steamtemp_gym.scenarios import library as _library  # noqa: E402,F401  (registers names)
