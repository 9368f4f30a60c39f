"""The Scenario dataclass: its channels, their limits and the validation of every field.

Validation and limits (every violation is a ValueError naming the field and quoting at most
a short excerpt of the input):

- ``name``: a printable string of 1-:data:`MAX_NAME_CHARS` (200) characters;
  ``description``: a string of at most :data:`MAX_DESCRIPTION_CHARS` (2000);
- ``duration_s``: a number in [1 s, 7 days] (:data:`DURATION_LIMITS_S`);
- a channel: a number (a constant) or a list of 1-:data:`MAX_BREAKPOINTS_PER_CHANNEL`
  (10,000) ``[t_s, value]`` pairs, times finite in [0, 30 days] and non-decreasing,
  values finite and inside the channel's physical range (:data:`LIMITS`);
- numbers are int or float, numpy integer and floating scalars included; bool, strings,
  complex numbers and containers are not numbers.
"""

from __future__ import annotations

import math
import reprlib
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from steamtemp_gym.checks import head, is_real, tail

#: Schedule channels in the order the compiled kernels read them.
CHANNELS: tuple[str, ...] = (
    "load",
    "setpoint_offset_C",
    "heat_absorption_bias",
    "fouling",
    "spray_water_temp_offset_C",
)
#: Ranges of each channel (inclusive) accepted by every plant: loads from minimum stable
#: firing to 110 % overload; setpoint offsets of sliding-temperature operation; heat-absorption
#: errors and gas-side fouling factors beyond those of coal switching and heavy slagging
#: (plausible, unverified); spray water from HP heaters out of service to their overshoot.
#: Within them a plant may still be unable to hold a combination at t = 0: such a scenario is
#: rejected at reset with the values that make it impossible (envs/core.py:Core.check_start).
LIMITS = {
    "load": (0.2, 1.1),
    "setpoint_offset_C": (-30.0, 30.0),
    "heat_absorption_bias": (-0.25, 0.25),
    "fouling": (0.6, 1.6),
    "spray_water_temp_offset_C": (-60.0, 60.0),
}

#: Scalar fields with their inclusive ranges (units: K, fraction, s).
_SCALAR_LIMITS = {
    "noise_std_C": (0.0, 10.0),
    "heat_absorption_noise_std": (0.0, 0.2),
    "heat_absorption_noise_tau_s": (1.0, 86400.0),
}
#: Most breakpoints one channel may have (the env's tables grow with it).
MAX_BREAKPOINTS_PER_CHANNEL = 10_000
#: Longest scenario name and description, in characters.
MAX_NAME_CHARS = 200
MAX_DESCRIPTION_CHARS = 2000
#: Inclusive range of an episode's length, s (1 s to 7 days).
DURATION_LIMITS_S = (1.0, 7 * 86400.0)
#: Inclusive range of breakpoint times, s (up to 30 days: a schedule may run past the end).
_TIME_LIMITS_S = (0.0, 30 * 86400.0)
Schedule = tuple[tuple[float, float], ...]

# --------------------------------------------------------------------------- checks
_REPR = reprlib.Repr()
_REPR.maxlevel, _REPR.maxlist, _REPR.maxtuple, _REPR.maxdict = 2, 4, 4, 4
_REPR.maxstring, _REPR.maxother, _REPR.maxlong = 60, 60, 40


def excerpt(value: Any, limit: int = 120) -> str:
    """A short, bounded repr of a (possibly huge) user input for error messages."""
    try:
        text = _REPR.repr(value)
    except Exception:  # noqa: BLE001  (a broken __repr__ must not hide the real error)
        text = f"<{type(value).__name__}>"
    return head(text, limit)


def clip(text: str, limit: int = 300) -> str:
    """``text`` cut to ``limit`` characters (its end kept: the file name of a path)."""
    return tail(text, limit)


def describe(value: Any) -> str:
    """``type excerpt`` of a bad value, e.g. ``bool True`` or ``str '60'``."""
    return f"{type(value).__name__} {excerpt(value)}"


def _as_float(name: str, value: Any) -> float:
    """A finite float from a number (bool, str, containers and complex rejected)."""
    if not is_real(value):
        raise ValueError(f"scenario {name!r} must be a number, got {describe(value)}")
    try:
        v = float(value)
    except (OverflowError, ValueError, TypeError):
        v = math.inf
    if not math.isfinite(v):
        raise ValueError(f"scenario {name!r} must be finite, got {excerpt(value)}")
    return v


def _as_scalar(name: str, value: Any, lo: float, hi: float) -> float:
    """Validate a scalar scenario field (a finite number inside [lo, hi])."""
    v = _as_float(name, value)
    if not lo <= v <= hi:
        raise ValueError(f"scenario {name!r} must be in [{lo}, {hi}], got {excerpt(value)}")
    return v


def _as_string(name: str, value: Any, min_len: int, max_len: int, printable: bool) -> str:
    """Validate a string field (type, length, optionally printable characters)."""
    if not isinstance(value, str):
        raise ValueError(f"scenario {name!r} must be a string, got {describe(value)}")
    if not min_len <= len(value) <= max_len:
        raise ValueError(
            f"scenario {name!r} must have {min_len} to {max_len} characters, "
            f"got {len(value)}: {excerpt(value)}"
        )
    if printable and not value.isprintable():
        raise ValueError(
            f"scenario {name!r} must be printable (no newlines or control characters), "
            f"got {excerpt(value)}"
        )
    return value


def _as_schedule(name: str, value: Any) -> Schedule:
    """Validate and normalize a breakpoint list (or a constant) into a tuple of pairs."""
    if isinstance(value, np.ndarray):  # a 0-d array gives its number, a 2-d one its rows
        value = value.tolist() if value.size <= 2 * MAX_BREAKPOINTS_PER_CHANNEL else list(value)
    if is_real(value):
        value = [[0.0, value]]
    if not isinstance(value, (list, tuple)) or len(value) == 0:
        raise ValueError(
            f"scenario field {name!r} must be a number or a non-empty list of [t_s, value] "
            f"breakpoints, got {describe(value)}"
        )
    if len(value) > MAX_BREAKPOINTS_PER_CHANNEL:
        raise ValueError(
            f"scenario field {name!r} has {len(value)} breakpoints, more than the "
            f"{MAX_BREAKPOINTS_PER_CHANNEL} allowed"
        )
    lo, hi = LIMITS[name]
    t_lo, t_hi = _TIME_LIMITS_S
    pts: list[tuple[float, float]] = []
    for k, item in enumerate(value):
        where = f"scenario field {name!r}: breakpoint {k} ({excerpt(item)})"
        if not isinstance(item, (list, tuple)) or len(item) != 2:
            raise ValueError(f"{where} is not a [t_s, value] pair")
        if not (is_real(item[0]) and is_real(item[1])):
            raise ValueError(f"{where}: t_s and value must each be a number")
        try:
            t, v = float(item[0]), float(item[1])
        except (OverflowError, ValueError, TypeError):
            t = v = math.inf
        if not (math.isfinite(t) and math.isfinite(v)):
            raise ValueError(f"{where} is not finite")
        if not t_lo <= t:
            raise ValueError(f"{where}: breakpoint times must be >= 0")
        if not t <= t_hi:
            raise ValueError(f"{where}: breakpoint time must be <= {t_hi} s (30 days)")
        if pts and t < pts[-1][0]:
            raise ValueError(
                f"{where}: breakpoint times must be non-decreasing (equal times are a step), "
                f"previous {pts[-1][0]}"
            )
        if not lo <= v <= hi:
            raise ValueError(
                f"scenario field {name!r}: value {v} is outside the physical range [{lo}, {hi}]"
            )
        pts.append((t, v))
    return tuple(pts)


def as_duration(value: Any) -> float:
    """Validate an episode length (a number in DURATION_LIMITS_S)."""
    return _as_scalar("duration_s", value, *DURATION_LIMITS_S)


@dataclass(frozen=True)
class Scenario:
    """Schedules of the disturbances and setpoint over one episode.

    Every field is validated on construction (limits in the module docstring); numbers
    are stored as Python floats and schedules as tuples of ``(t_s, value)`` pairs.

    Attributes:
        name: Identifier shown in tables and plots (printable, 1-200 characters).
        duration_s: Episode length in seconds (``truncated`` after it), 1 s to 7 days.
        load: Load demand breakpoints ``((t_s, fraction), ...)``.
        setpoint_offset_C: Setpoint offset breakpoints in K.
        heat_absorption_bias: Heat-absorption relative bias breakpoints.
        fouling: Gas-side heat-transfer multiplier breakpoints.
        spray_water_temp_offset_C: Spray-water temperature offset breakpoints in K.
        noise_std_C: Standard deviation of measured-temperature noise in K.
        heat_absorption_noise_std: Stationary standard deviation (fraction) of the coloured
            heat-absorption disturbance added to ``heat_absorption_bias``.
        heat_absorption_noise_tau_s: Its correlation time in s.
        description: For humans (at most 2000 characters).
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
        _as_string("name", self.name, 1, MAX_NAME_CHARS, printable=True)
        _as_string("description", self.description, 0, MAX_DESCRIPTION_CHARS, printable=False)
        object.__setattr__(self, "duration_s", as_duration(self.duration_s))
        for ch in CHANNELS:
            object.__setattr__(self, ch, _as_schedule(ch, getattr(self, ch)))
        for name, (lo, hi) in _SCALAR_LIMITS.items():
            object.__setattr__(self, name, _as_scalar(name, getattr(self, name), lo, hi))

    def value(self, channel: str, t: float) -> float:
        """Value of one channel at time ``t`` (linear interpolation, held at the ends)."""
        if channel not in CHANNELS:
            raise ValueError(f"unknown channel {excerpt(channel)}; valid: {list(CHANNELS)}")
        pts = np.asarray(getattr(self, channel))
        return float(np.interp(t, pts[:, 0], pts[:, 1]))

    def last_change_s(self) -> float:
        """Time (s) at which the last scheduled change of any channel ends (0 if none):
        the end of the last ramp or step of load, setpoint, heat absorption, fouling or
        spray-water temperature."""
        last = 0.0
        for ch in CHANNELS:
            pts = getattr(self, ch)
            for (_, v0), (t1, v1) in zip(pts[:-1], pts[1:], strict=True):
                if v1 != v0:
                    last = max(last, t1)
        return last

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
        """Build from a mapping (as read from YAML), rejecting unknown keys.

        Every error message starts with ``source`` (the file, for a YAML file).
        """
        if not isinstance(data, Mapping):
            raise ValueError(
                f"{source}: expected a mapping of scenario fields, got {type(data).__name__}"
            )
        valid = [f.name for f in fields(cls)]
        bad_keys = [k for k in data if not isinstance(k, str)]
        if bad_keys:
            raise ValueError(
                f"{source}: scenario field names must be strings, got {describe(bad_keys[0])}"
            )
        unknown = sorted(set(data) - set(valid))
        if unknown:
            raise ValueError(
                f"{source}: unknown scenario field(s) {excerpt(unknown, 200)}; "
                f"valid fields: {valid}"
            )
        for key in ("name", "duration_s", "load"):
            if key not in data:
                raise ValueError(f"{source}: missing required field {key!r}")
        try:
            return cls(**dict(data))
        except ValueError as exc:
            raise ValueError(f"{source}: {exc}") from None
