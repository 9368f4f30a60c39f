"""Scenarios: the world outside the plant.

A :class:`Scenario` is a set of piecewise-linear schedules over time (breakpoint
lists ``[[t_s, value], ...]``, linear interpolation, held constant after the
last breakpoint; two breakpoints at the same time are a step) in the common
vocabulary of the suite (``docs/architecture.md``):

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
The load-ramp test ``load_ramp_100_50`` (100 -> 50 % at 5 %/min from minute 20 to
30) is the test of Sagara et al., JSME International Journal, Series C, 1998
(``docs/references.md``, key 000).

Validation and limits (every violation is a ValueError naming the field or file and
quoting at most a short excerpt of the input):

- a scenario file is UTF-8 YAML of at most :data:`MAX_FILE_BYTES` (1 MiB) holding one
  mapping of the fields below; anchors and aliases (``&a`` / ``*a``, hence merge keys
  ``<<``), duplicate keys and unknown fields are rejected;
- ``name``: a printable string of 1-:data:`MAX_NAME_CHARS` (200) characters;
  ``description``: a string of at most :data:`MAX_DESCRIPTION_CHARS` (2000);
- ``duration_s``: a number in [1 s, 7 days] (:data:`DURATION_LIMITS_S`);
- a channel: a number (a constant) or a list of 1-:data:`MAX_BREAKPOINTS_PER_CHANNEL`
  (10,000) ``[t_s, value]`` pairs, times finite in [0, 30 days] and non-decreasing,
  values finite and inside the channel's physical range;
- numbers are int or float, numpy integer and floating scalars included; bool, strings,
  complex numbers and containers are not numbers (in a file, ``1e3`` and ``3.6e3`` are
  numbers, as in YAML 1.2; a quoted ``"60"`` is a string).

``resolve`` takes a name, ``heldout:<name>``, ``"random"``, a :class:`Scenario` or a file: any
``os.PathLike`` is a file (it must end in ``.yaml`` or ``.yml``), and so is a ``str``
ending in ``.yaml`` / ``.yml``.
"""

from __future__ import annotations

import math
import os
import re
import reprlib
import stat
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from steamtemp_gym.checks import head, is_real, tail

__all__ = [
    "CHANNELS",
    "Scenario",
    "forms",
    "get",
    "names",
    "register",
    "resolve",
    "load_yaml",
    "random_scenario",
    "pack",
    "RANDOM",
    "HELDOUT_PREFIX",
    "NAMED_DISTURBANCES",
    "MAX_FILE_BYTES",
    "MAX_BREAKPOINTS_PER_CHANNEL",
    "MAX_NAME_CHARS",
    "MAX_DESCRIPTION_CHARS",
    "DURATION_LIMITS_S",
]

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
RANDOM = "random"
#: How a held-out scenario is named: ``heldout:mill_trip`` (steamtemp_gym/scenarios/heldout).
HELDOUT_PREFIX = "heldout:"

#: Scalar fields with their inclusive ranges (units: K, fraction, s).
_SCALAR_LIMITS = {
    "noise_std_C": (0.0, 10.0),
    "heat_absorption_noise_std": (0.0, 0.2),
    "heat_absorption_noise_tau_s": (1.0, 86400.0),
}
#: Largest scenario file read, in bytes.
MAX_FILE_BYTES = 1 << 20
#: Most breakpoints one channel may have (the env's tables grow with it).
MAX_BREAKPOINTS_PER_CHANNEL = 10_000
#: Longest scenario name and description, in characters.
MAX_NAME_CHARS = 200
MAX_DESCRIPTION_CHARS = 2000
#: Inclusive range of an episode's length, s (1 s to 7 days).
DURATION_LIMITS_S = (1.0, 7 * 86400.0)
#: Inclusive range of breakpoint times, s (up to 30 days: a schedule may run past the end).
_TIME_LIMITS_S = (0.0, 30 * 86400.0)
#: Most YAML nodes in one file (five full channels of pairs, with room to spare).
_MAX_YAML_NODES = 4 * len(CHANNELS) * MAX_BREAKPOINTS_PER_CHANNEL

#: Disturbances on in every named scenario: thermocouple noise 0.25 K (real units:
#: 0.2-0.3 K) and a coloured heat-absorption disturbance of 2 % std with a 5 min
#: correlation time (slagging, coal quality and mill changes; plausible default, unverified).
NAMED_DISTURBANCES = {
    "noise_std_C": 0.25,
    "heat_absorption_noise_std": 0.02,
    "heat_absorption_noise_tau_s": 300.0,
}
Schedule = tuple[tuple[float, float], ...]

# --------------------------------------------------------------------------- checks
_REPR = reprlib.Repr()
_REPR.maxlevel, _REPR.maxlist, _REPR.maxtuple, _REPR.maxdict = 2, 4, 4, 4
_REPR.maxstring, _REPR.maxother, _REPR.maxlong = 60, 60, 40


def _excerpt(value: Any, limit: int = 120) -> str:
    """A short, bounded repr of a (possibly huge) user input for error messages."""
    try:
        text = _REPR.repr(value)
    except Exception:  # noqa: BLE001  (a broken __repr__ must not hide the real error)
        text = f"<{type(value).__name__}>"
    return head(text, limit)


def _clip(text: str, limit: int = 300) -> str:
    """``text`` cut to ``limit`` characters (its end kept: the file name of a path)."""
    return tail(text, limit)


def _describe(value: Any) -> str:
    """``type excerpt`` of a bad value, e.g. ``bool True`` or ``str '60'``."""
    return f"{type(value).__name__} {_excerpt(value)}"


def _as_float(name: str, value: Any) -> float:
    """A finite float from a number (bool, str, containers and complex rejected)."""
    if not is_real(value):
        raise ValueError(f"scenario {name!r} must be a number, got {_describe(value)}")
    try:
        v = float(value)
    except (OverflowError, ValueError, TypeError):
        v = math.inf
    if not math.isfinite(v):
        raise ValueError(f"scenario {name!r} must be finite, got {_excerpt(value)}")
    return v


def _as_scalar(name: str, value: Any, lo: float, hi: float) -> float:
    """Validate a scalar scenario field (a finite number inside [lo, hi])."""
    v = _as_float(name, value)
    if not lo <= v <= hi:
        raise ValueError(f"scenario {name!r} must be in [{lo}, {hi}], got {_excerpt(value)}")
    return v


def _as_string(name: str, value: Any, min_len: int, max_len: int, printable: bool) -> str:
    """Validate a string field (type, length, optionally printable characters)."""
    if not isinstance(value, str):
        raise ValueError(f"scenario {name!r} must be a string, got {_describe(value)}")
    if not min_len <= len(value) <= max_len:
        raise ValueError(
            f"scenario {name!r} must have {min_len} to {max_len} characters, "
            f"got {len(value)}: {_excerpt(value)}"
        )
    if printable and not value.isprintable():
        raise ValueError(
            f"scenario {name!r} must be printable (no newlines or control characters), "
            f"got {_excerpt(value)}"
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
            f"breakpoints, got {_describe(value)}"
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
        where = f"scenario field {name!r}: breakpoint {k} ({_excerpt(item)})"
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


def _as_duration(value: Any) -> float:
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
        object.__setattr__(self, "duration_s", _as_duration(self.duration_s))
        for ch in CHANNELS:
            object.__setattr__(self, ch, _as_schedule(ch, getattr(self, ch)))
        for name, (lo, hi) in _SCALAR_LIMITS.items():
            object.__setattr__(self, name, _as_scalar(name, getattr(self, name), lo, hi))

    def value(self, channel: str, t: float) -> float:
        """Value of one channel at time ``t`` (linear interpolation, held at the ends)."""
        if channel not in CHANNELS:
            raise ValueError(f"unknown channel {_excerpt(channel)}; valid: {list(CHANNELS)}")
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
                f"{source}: scenario field names must be strings, got {_describe(bad_keys[0])}"
            )
        unknown = sorted(set(data) - set(valid))
        if unknown:
            raise ValueError(
                f"{source}: unknown scenario field(s) {_excerpt(unknown, 200)}; "
                f"valid fields: {valid}"
            )
        for key in ("name", "duration_s", "load"):
            if key not in data:
                raise ValueError(f"{source}: missing required field {key!r}")
        try:
            return cls(**dict(data))
        except ValueError as exc:
            raise ValueError(f"{source}: {exc}") from None


# --------------------------------------------------------------------------- YAML
_YamlLoader: type = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
_MERGE_TAG = "tag:yaml.org,2002:merge"


class _ScenarioLoader(_YamlLoader):  # type: ignore[misc,valid-type]
    """Safe YAML loader that refuses duplicate mapping keys (PyYAML keeps the last)."""

    def construct_mapping(self, node: yaml.Node, deep: bool = False) -> dict[Any, Any]:
        if isinstance(node, yaml.MappingNode):
            seen: set[Any] = set()
            for key_node, _ in node.value:
                key = self.construct_object(key_node, deep=True)
                try:
                    duplicate = key in seen
                    seen.add(key)
                except TypeError:  # unhashable: the base class reports it
                    continue
                if duplicate:
                    raise yaml.constructor.ConstructorError(
                        None, None, f"duplicate key {_excerpt(key)}", key_node.start_mark
                    )
        return super().construct_mapping(node, deep)


# YAML 1.1 reads 1e3 or 3.6e3 (no dot or no exponent sign) as strings; 1.2 and users: floats.
_ScenarioLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?[0-9][0-9_]*(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"),
)


def _check_nodes(root: yaml.Node) -> None:
    """Reject aliases, merge keys and too many nodes before anything is constructed.

    An alias makes one node appear twice in the composed graph, so a node seen twice
    is an alias: the graph of a billion-laughs file is small, its expansion is not.
    """
    seen: set[int] = set()
    stack: list[yaml.Node] = [root]
    while stack:
        node = stack.pop()
        if id(node) in seen:
            raise ValueError(
                f"YAML anchors and aliases (&name / *name) are not supported (line "
                f"{node.start_mark.line + 1}): write each value out"
            )
        seen.add(id(node))
        if len(seen) > _MAX_YAML_NODES:
            raise ValueError(f"more than {_MAX_YAML_NODES} YAML nodes")
        if isinstance(node, yaml.SequenceNode):
            stack.extend(node.value)
        elif isinstance(node, yaml.MappingNode):
            for key, val in node.value:
                if key.tag == _MERGE_TAG:
                    raise ValueError(
                        f"YAML merge keys (<<) are not supported (line {key.start_mark.line + 1})"
                    )
                stack.extend((key, val))


def _parse_yaml(text: str) -> Any:
    """Parse one YAML document safely (see ``_ScenarioLoader`` and ``_check_nodes``).

    Raises:
        ValueError: aliases, merge keys, too many nodes (message without
            the file name); yaml.YAMLError: malformed YAML, duplicate keys.
    """
    loader = _ScenarioLoader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        _check_nodes(node)
        return loader.construct_document(node)
    finally:
        loader.dispose()


def _as_path(spec: Any) -> Path:
    """A Path from a str or os.PathLike (bytes paths decoded with the file-system codec)."""
    try:
        return Path(os.fsdecode(os.fspath(spec)))
    except TypeError as exc:
        raise ValueError(
            f"a scenario file must be a str or os.PathLike, got {_describe(spec)}"
        ) from exc


def load_yaml(path: str | os.PathLike[str]) -> Scenario:
    """Read a scenario YAML file (format and limits in the module docstring).

    Raises:
        ValueError: naming the file: missing, a directory or not a regular file,
            unreadable, larger than MAX_FILE_BYTES, not UTF-8, malformed YAML, or an
            invalid scenario (the message then also names the field).
    """
    p = _as_path(path)
    shown = repr(_clip(str(p), 200))
    try:
        st = p.stat()
    except OSError as exc:
        raise ValueError(f"cannot read scenario file {shown}: {exc.strerror or exc}") from None
    if stat.S_ISDIR(st.st_mode):
        raise ValueError(f"cannot read scenario file {shown}: it is a directory")
    if not stat.S_ISREG(st.st_mode):
        raise ValueError(f"cannot read scenario file {shown}: not a regular file")
    if st.st_size > MAX_FILE_BYTES:
        raise ValueError(
            f"scenario file {shown} has {st.st_size} bytes, more than the {MAX_FILE_BYTES} allowed"
        )
    try:
        with open(p, "rb") as f:
            raw = f.read(MAX_FILE_BYTES + 1)
    except OSError as exc:
        raise ValueError(f"cannot read scenario file {shown}: {exc.strerror or exc}") from None
    if len(raw) > MAX_FILE_BYTES:  # grew since stat
        raise ValueError(f"scenario file {shown} has more than the {MAX_FILE_BYTES} bytes allowed")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        bad = raw[exc.start : exc.start + 1]
        raise ValueError(
            f"scenario file {shown} is not valid UTF-8 (byte {exc.start}: {bad!r})"
        ) from None
    try:
        data = _parse_yaml(text)
    except yaml.YAMLError as exc:
        where = str(exc).replace('in "<unicode string>", ', "at ")
        raise ValueError(f"malformed scenario YAML {shown}: {_clip(where)}") from None
    except RecursionError:
        raise ValueError(f"malformed scenario YAML {shown}: nested too deeply") from None
    except ValueError as exc:
        raise ValueError(f"scenario file {shown}: {exc}") from None
    return Scenario.from_dict(data, source=f"scenario file {shown}")


# --------------------------------------------------------------------------- registry
_REGISTRY: dict[str, tuple[Scenario, tuple[str, ...] | None]] = {}


def register(scenario: Scenario, plants: Sequence[str] | None = None) -> Scenario:
    """Register a named scenario, for every plant or only for the given plant ids.

    ``gym.make(id, scenario=name)``, ``reset(options={"scenario": name})``, the
    leaderboard's ``--scenarios`` and :func:`names` then know it (on the command line,
    ``--import MODULE`` imports the module that registers it). The scenario is used as
    given: the named scenarios' disturbances (:data:`NAMED_DISTURBANCES`) are not added.
    Registering the same scenario again does nothing.

    Raises:
        ValueError: not a Scenario, bad ``plants``, a name the command lines cannot spell
            (``random``, ``heldout:...``, a ``.yaml``/``.yml`` ending, a comma) or a name
            registered with another scenario; nothing is registered then.
    """
    if not isinstance(scenario, Scenario):
        raise ValueError(f"register() needs a Scenario, got {_describe(scenario)}")
    if plants is not None and (
        isinstance(plants, str)
        or not isinstance(plants, Sequence)
        or not all(isinstance(p, str) for p in plants)
    ):
        raise ValueError(
            f"register() 'plants' must be a list of plant ids, got {_describe(plants)}"
        )
    name = scenario.name
    if name == RANDOM:
        raise ValueError(f"{RANDOM!r} is reserved for the seeded training distribution")
    if name.startswith(HELDOUT_PREFIX) or name.lower().endswith((".yaml", ".yml")) or "," in name:
        raise ValueError(f"scenario name {_excerpt(name)} would read as a held-out scenario, "
                         "a file or a list; choose another name")  # fmt: skip
    entry = (scenario, tuple(plants) if plants is not None else None)
    old = _REGISTRY.get(name)
    if old is not None and (old[0].to_dict() != scenario.to_dict() or old[1] != entry[1]):
        raise ValueError(f"scenario {_excerpt(name)} is already registered (with another "
                         "schedule or other plants); choose another name")  # fmt: skip
    _REGISTRY[name] = entry
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
    entry = _REGISTRY.get(name) if isinstance(name, str) else None
    if entry is None or (
        plant_id is not None and entry[1] is not None and plant_id not in entry[1]
    ):
        raise ValueError(f"unknown scenario {_excerpt(name)}; {forms(plant_id)}")
    return entry[0]


def forms(plant_id: str | None = None) -> str:
    """Every way to name a scenario (for error messages and help texts)."""
    from steamtemp_gym.scenarios import heldout

    named = [n for n in names(plant_id) if n != RANDOM]
    return (f"valid names: {named}, {HELDOUT_PREFIX}<name> of the held-out set "
            f"{[HELDOUT_PREFIX + n for n in heldout.NAMES]}, {RANDOM!r} (the seeded training "
            "distribution), or a YAML file (a path ending in .yaml or .yml)")


def resolve(spec: str | os.PathLike[str] | Scenario, plant_id: str | None = None) -> Scenario | str:
    """Turn a scenario argument into a Scenario or ``"random"``.

    ``spec`` is a Scenario; a file (any ``os.PathLike``, or a ``str`` ending in ``.yaml`` or
    ``.yml``, suffix case ignored), which must end in ``.yaml`` / ``.yml``; ``"random"``;
    ``heldout:<name>``, a held-out scenario (steamtemp_gym/scenarios/heldout); or the name
    of a registered scenario valid for ``plant_id``. The same names work in ``gym.make``,
    ``reset(options={"scenario": ...})``, the leaderboard's ``--scenarios`` and
    ``steamtemp-check --scenario``.

    Raises:
        ValueError: naming the file or listing the valid names.
    """
    if isinstance(spec, Scenario):
        return spec
    if isinstance(spec, os.PathLike):
        path = _as_path(spec)
        if path.suffix.lower() not in (".yaml", ".yml"):
            raise ValueError(
                f"scenario file {_clip(str(path), 200)!r} must end in .yaml or .yml "
                "(a path is always read as a file, never as a scenario name)"
            )
        return load_yaml(path)
    if isinstance(spec, str):
        if spec.lower().endswith((".yaml", ".yml")):
            return load_yaml(spec)
        if spec == RANDOM:
            return RANDOM
        if spec.startswith(HELDOUT_PREFIX):
            from steamtemp_gym.scenarios import heldout

            if spec[len(HELDOUT_PREFIX):] not in heldout.NAMES:
                raise ValueError(f"unknown held-out scenario {_excerpt(spec)}; {forms(plant_id)}")
            return heldout.load(spec)
        try:
            return get(spec, plant_id)
        except ValueError as exc:
            if len(spec) < 4096 and os.path.isfile(spec):
                raise ValueError(
                    f"{exc} (a file {_clip(spec, 200)!r} exists, but scenario files must end "
                    "in .yaml or .yml)"
                ) from None
            raise
    raise ValueError(
        "scenario must be a name, 'random', a YAML file (str or os.PathLike) or a Scenario, "
        f"got {_describe(spec)}"
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
    1-5 %/min (coal units: about 1.5 %/min typical, 4-6 %/min state of the art)
    to a new target in 50-100 %. With probability 0.3 a setpoint step of
    +-10 K at a random time; with probability 0.5 a heat-absorption bias step of
    +-8 %; a constant fouling factor 0.85-1.15; a constant spray-water
    temperature offset of +-15 K; thermocouple noise 0.2-0.3 K; a coloured
    heat-absorption disturbance of 0-4 % std with a 2-15 min correlation time.
    """
    dist = RANDOM_DISTRIBUTION
    duration = _as_duration(duration_s if duration_s is not None else dist["duration_s"])
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
