"""The batched simulation core shared by SteamTempEnv (a batch of one) and the vector env:
the state of B rows of one plant (envs/state.py), each under its own scenario, their
schedule tables, reset to a steady start, the step (the plant's kernel, then
:func:`envs.kernels.advance`), the info values and what a planner reads of each row.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from steamtemp_gym import scenarios as sc
from steamtemp_gym._jit import entry_point
from steamtemp_gym.checks import is_real
from steamtemp_gym.envs.cost import COST_DOC
from steamtemp_gym.envs.kernels import (
    E_DUR,
    E_TIME,
    N_CH,
    OU_CHANNEL,
    TRIP_REASONS,
    advance,
    fill_info,
    info_indices,
    obs_indices,
    observe,
    ou_coefficients,
    schedules,
    to_commands,
)
from steamtemp_gym.envs.state import (
    INFO_TAIL,
    ROW_POSITIONS,
    EnvState,
    StateFields,
    info_sources,
    new_state,
    outputs,
    with_tables,
)
from steamtemp_gym.plants.base import N_DIST, Plant
from steamtemp_gym.plants.threads import MIN_SPLIT_ROWS, run_rows
from steamtemp_gym.rewards import RewardConfig
from steamtemp_gym.rng import gauss
from steamtemp_gym.signals import for_plant

_TRIP_NAMES = np.array(TRIP_REASONS)
#: A scenario must start within this many K of its setpoint in steady state (the +-5 K band
#: plant engineers read): further away the valves are saturated at t = 0 and the episode
#: starts as a disturbance nobody can correct.
START_BAND_K = 5.0
#: Unit and meaning of the info values every plant has (the others are plant outputs).
INFO_DOC = {
    "outlet_temp_C": ("C", "true main-steam temperature (the trip band applies to it)"),
    "measured_temp_noise_free_C": ("C", "the outlet thermocouple's own temperature (its lag, "
                                        "without the noise)"),
    "measured_temp_C": ("C", "what the outlet thermocouple reported, noise included (as "
                             "observed)"),
    "time_s": ("s", "time since the episode started (steps x control interval)"),
    "setpoint_C": ("C", "main-steam temperature setpoint (the scenario's offset included)"),
    "load": ("1", "load demand, fraction of rated"),
    "spray_flow_kg_s": ("kg/s", "total spray-water flow of every attemperator"),
    "trip_reason": ("", "why the episode terminated: '' or one of "
                        + ", ".join(repr(r) for r in TRIP_REASONS[1:])),
    **COST_DOC,
}  # fmt: skip


class Core(StateFields):
    """Batched state of B copies of one plant under per-row scenarios.

    Its arrays are those of ``state`` (:class:`~steamtemp_gym.envs.state.EnvState`), each
    also an attribute of the same name. A planner reads a row's position and the last
    step's outcome through :meth:`time_left`, :meth:`ended`, :meth:`held_commands`,
    :meth:`noise_keys` and :meth:`steps` and the arrays ``reward``, ``trip`` (the trip code,
    :data:`TRIP_REASONS` index; 0: none) and ``truncated`` of the last step (read them, do
    not write them); envs/snapshot.py makes its planning cores and copies rows into them.

    Args:
        plant: The plant instance (parameters fixed).
        batch: Number of rows.
        reward_cfg: Reward weights.
    """

    def __init__(self, plant: Plant, batch: int, reward_cfg: RewardConfig) -> None:
        self.plant = plant
        self.B = batch
        self.signals = for_plant(plant)
        obs_cs = np.array([[s.center, s.scale, float(s.noisy)] for s in self.signals.observation],
                          dtype=np.float64)  # fmt: skip
        out = outputs(plant)
        self.state: EnvState = new_state(plant, batch, reward_cfg, obs_cs, out)
        # schedule tables: one slot per distinct scenario in use (rows share identical ones)
        self._slots: dict[sc.Scenario, list[int]] = {}  # scenario -> [slot, rows using it]
        self._free: list[int] = list(range(self.bp_t.shape[0]))
        self._feasible: set[sc.Scenario] = set()  # scenarios whose start check passed
        self.i_out = plant.index[plant.outlet]
        self.valve_idx, self.spray_idx = out.valves, out.sprays
        self.scenario: list[sc.Scenario | None] = [None] * batch
        #: the names of the info columns
        self._info_columns = [name for name, _ in info_sources(plant)] + list(INFO_TAIL)
        self._make_info = dict_maker(self._info_columns)
        #: the valve openings' columns of Z for info (several valves): a slice when they are
        #: adjacent (a copy of a slice costs a third of fancy indexing), else an index array
        v = self.valve_idx
        adjacent = v == list(range(v[0], v[0] + len(v)))
        self._valves = (None if len(v) < 2
                        else slice(v[0], v[0] + len(v)) if adjacent else np.array(v))  # fmt: skip
        #: the plant kernel's arguments, built once (the arrays keep their identity)
        self._plant_args = (plant.step_args(self.X, self.U, self.D, self.Z)
                            if type(plant).step is Plant.step else None)  # fmt: skip
        #: compiled entry points of (plant kernel or None, advance) for those arguments
        self._entries: tuple | None = None
        self._no_trips = np.full(batch, TRIP_REASONS[0], dtype=_TRIP_NAMES.dtype)

    def _alloc_schedules(self, n_slots: int, k: int) -> None:
        """Reallocate the schedule tables for n_slots scenarios of k breakpoints, keeping
        the slots in use."""
        self._free += list(range(self.bp_t.shape[0], n_slots))
        self.state = with_tables(self.state, n_slots, k)

    def assign_scenario(self, b: int, scenario: sc.Scenario) -> None:
        """Make row b run ``scenario`` (its schedules packed into a table slot); the row's
        state is not touched."""
        self._assign_slot(b, scenario)
        self.scenario[b] = scenario

    def _assign_slot(self, b: int, scenario: sc.Scenario) -> None:
        """Point row b at the table slot of ``scenario``, packing it if no row uses it yet."""
        prev = self.scenario[b]
        if prev is not None:
            entry = self._slots[prev]
            entry[1] -= 1
            if entry[1] == 0:
                del self._slots[prev]
                self._free.append(entry[0])
        entry = self._slots.get(scenario)
        if entry is None:
            need = sc.max_breakpoints([scenario])
            if not self._free or need > self.bp_t.shape[2]:
                n_slots = self.bp_t.shape[0]
                grow = n_slots if self._free else min(2 * n_slots, self.B)
                self._alloc_schedules(max(grow, n_slots), max(need, self.bp_t.shape[2]))
            entry = self._slots[scenario] = [min(self._free), 0]
            self._free.remove(entry[0])
            sc.pack(scenario, self.bp_t[entry[0]], self.bp_v[entry[0]], self.bp_n[entry[0]])
        entry[1] += 1
        self.slot[b] = entry[0]

    def _start_error(self, scenario: sc.Scenario,
                     plant: Plant | None = None) -> tuple[float, np.ndarray, float]:  # fmt: skip
        """(setpoint - outlet, Z, setpoint) of ``scenario``'s steady start on ``plant``
        (default: the core's) with its coloured disturbance at the mean; the error is NaN if
        the steady state is not finite."""
        plant = self.plant if plant is None else plant
        k = sc.max_breakpoints([scenario])
        tables = (np.zeros((1, N_CH, k)), np.zeros((1, N_CH, k)), np.ones((1, N_CH), np.int64))
        sc.pack(scenario, tables[0][0], tables[1][0], tables[2][0])
        D, sp = np.zeros((1, N_DIST)), np.zeros(1)
        schedules(0, 0, 0.0, *tables, plant.setpoint_C, np.zeros(1), D, sp)
        _, z = plant.steady_outputs(D[0], sp[0])
        e = sp[0] - z[self.i_out] if np.all(np.isfinite(z)) else float("nan")
        return e, z, float(sp[0])

    def start_fits(self, scenario: sc.Scenario, plant: Plant) -> bool:
        """Whether ``plant`` (of the core's class and setpoint) holds ``scenario``'s start in
        steady state within :data:`START_BAND_K` of the setpoint (:meth:`check_start`)."""
        return bool(abs(self._start_error(scenario, plant)[0]) <= START_BAND_K)

    def row_plant(self, b: int) -> Plant:
        """The plant row b simulates (every row's is the core's plant)."""
        return self.plant

    def check_start(self, scenario: sc.Scenario) -> None:
        """Raise ValueError unless the plant can hold ``scenario``'s start in steady state.

        The steady state at t = 0 (the coloured heat-absorption disturbance at its mean)
        must bring the true outlet within :data:`START_BAND_K` of the setpoint. The error
        names the initial values that make it impossible (those whose return to their
        default alone would make it possible).
        """
        if scenario in self._feasible:
            return
        e, z, sp = self._start_error(scenario)
        if abs(e) <= START_BAND_K:
            self._feasible.add(scenario)
            return
        at0 = {ch: scenario.value(ch, 0.0) for ch in sc.CHANNELS}
        culprits = []
        for ch in sc.CHANNELS:
            default = sc.Scenario.__dataclass_fields__[ch].default
            if at0[ch] != default[0][1]:
                nominal = dataclasses.replace(scenario, **{ch: default})
                if abs(self._start_error(nominal)[0]) <= START_BAND_K:
                    culprits.append(f"{ch} = {at0[ch]:g}")
        openings = ", ".join(f"{v:.2f}" for v in z[self.valve_idx])
        state = "no finite steady state" if not np.isfinite(e) else (
            f"the steady outlet is {abs(e):.1f} K {'below' if e > 0 else 'above'} the setpoint "
            f"{sp:.1f} C with the valve openings at [{openings}]")  # fmt: skip
        why = (f"; it could with {' or '.join('nominal ' + c.split(' =')[0] for c in culprits)} "
               f"(here {', '.join(culprits)})") if culprits else ""  # fmt: skip
        values = ", ".join(f"{ch} {v:g}" for ch, v in at0.items())
        raise ValueError(
            f"scenario {scenario.name!r} cannot start in a steady state {self.plant.id} can "
            f"hold (within {START_BAND_K:g} K of the setpoint): at t = 0 ({values}) {state}{why}"
        )

    def reset_row(self, b: int, scenario: sc.Scenario, key: int) -> None:
        """Start row b at t = 0 of ``scenario`` in steady state, with noise key ``key``
        (:meth:`reset_rows` of one row)."""
        self.reset_rows([b], [(scenario, key)])

    def reset_rows(self, rows: Any, episodes: list[tuple[sc.Scenario, int]]) -> None:
        """Start each row of ``rows`` at t = 0 of its (scenario, noise key) of ``episodes``
        in steady state, all or none: every row's start is checked (:meth:`episode_plant`)
        before any row changes.

        Raises:
            ValueError: a scenario that is not a Scenario or that a row's plant cannot
                hold at its start (:meth:`check_start`); no row is changed.
        """
        drawn = [self.episode_plant(scenario, key) for scenario, key in episodes]
        for b, (scenario, key), plant in zip(rows, episodes, drawn, strict=True):
            self._start_row(int(b), scenario, key, plant)

    def episode_plant(self, scenario: sc.Scenario, key: int) -> tuple[Plant, dict[str, float]]:
        """(plant, its parameter groups' factors) of an episode of ``scenario`` with noise
        key ``key``, checked to hold its start: the core's plant and no factors here
        (envs/plant_rows.py draws one from the key).

        Raises:
            ValueError: ``scenario`` is not a Scenario, or the plant cannot hold its start.
        """
        if not isinstance(scenario, sc.Scenario):
            raise ValueError(f"a row starts on a Scenario, got {type(scenario).__name__}")
        self.check_start(scenario)
        return self.plant, {}

    def _start_row(self, b: int, scenario: sc.Scenario, key: int,
                   drawn: tuple[Plant, dict[str, float]]) -> None:  # fmt: skip
        """Start row b on ``scenario`` and ``key`` with the plant ``drawn`` for them by
        :meth:`episode_plant` (nothing here can fail)."""
        self.assign_scenario(b, scenario)
        ou_ab = ou_coefficients(scenario.heat_absorption_noise_std,
                                scenario.heat_absorption_noise_tau_s, self.plant.dt_s)  # fmt: skip
        self.ep[b] = (0.0, scenario.duration_s, scenario.noise_std_C, *ou_ab)
        self.ou[b] = scenario.heat_absorption_noise_std * gauss(np.uint64(key), 0, OU_CHANNEL)
        self.key[b] = np.uint64(key)
        self.counter[b] = 0
        self.reward[b], self.trip[b], self.truncated[b] = 0.0, 0, False
        schedules(b, self.slot[b], 0.0, self.bp_t, self.bp_v, self.bp_n, self.plant.setpoint_C,
                  self.ou, self.D, self.sp)  # fmt: skip
        r = slice(b, b + 1)
        plant = self.row_plant(b)
        plant.seed_rows(self.X[r], self.key[r])
        plant.steady_state(self.D[r], self.sp[r], self.X[r])
        plant.step(self.X[r], self.U[r], self.D[r], self.Z[r], dt=0.0)  # outputs of it
        self.U[b] = self.Z[b, self.valve_idx]
        self.U_prev[b] = self.U[b]
        observe_args, info_args = self._output_args(b)
        observe(*observe_args)
        fill_info(*info_args)

    def _output_args(self, b: int) -> tuple[tuple, tuple]:
        """The arguments of :func:`observe` and :func:`fill_info` for row b at its start
        (cost 0: the info of a reset closes no interval)."""
        s = self.state
        obs_idx, i_meas = obs_indices(s.ints)
        cols, sprays = info_indices(s.ints)
        return ((b, s.Z, s.D, s.sp, s.ep, s.key, s.counter, s.obs_cs, obs_idx, i_meas, s.obs,
                 s.meas), (b, s.Z, s.D, s.sp, s.ep, s.meas, cols, sprays, 0.0, s.info))  # fmt: skip

    def compile_calls(self) -> list[tuple[Any, tuple]]:
        """(kernel, arguments) of the compiled calls of a reset and a step but the plant's
        steady state, with arguments of the types they really get (actions: float32 or
        float64), the env's kernels first and the plant's step last: what an episode
        compiles or loads from the cache (tests/test_precompile.py checks it loads them all).
        """
        actions = [np.zeros((self.B, self.plant.n_u), dtype=t) for t in (np.float32, np.float64)]
        s = self.state
        return [(schedules, (0, s.slot[0], 0.0, s.bp_t, s.bp_v, s.bp_n, self.plant.setpoint_C,
                             s.ou, s.D, s.sp)),
                (gauss, (np.uint64(0), 0, OU_CHANNEL)),
                (obs_indices, (s.ints,)),
                (info_indices, (s.ints,)),
                *zip((observe, fill_info), self._output_args(0), strict=True),
                *[(to_commands, (a, self.U)) for a in actions],
                (advance, (s,)),
                (self.plant.kernel(), self.plant.step_args(self.X, self.U, self.D, self.Z))]

    def step(self, A: np.ndarray) -> None:
        """Advance every row by one control interval with actions A (shape checked) in [-1, 1].

        Raises:
            ValueError: A holds NaN or infinite values (nothing is changed).
        """
        s = self.state  # its fields read directly: a property per field costs 25 ns
        if not to_commands(A, s.U):
            raise non_finite_action(A)
        # the compiled entry points directly, with arguments built once (saves 1.3 us of a
        # 10 us step at B=1, and numba's type dispatch 0.6 us more), unless the plant's class
        # has a step of its own. The arguments are this core's own arrays, whose types never
        # change, so the entry points fixed at the first step stay right.
        entries = self._entries
        if entries is None:
            entries = self._entries = self._entry_points()
        if self.B >= MIN_SPLIT_ROWS:  # blocks of rows on several threads
            self.plant.step(s.X, s.U, s.D, s.Z)
            run_rows(self._advance_rows, s, per_row=ROW_POSITIONS)
        elif entries[0] is None:
            self.plant.step(s.X, s.U, s.D, s.Z)
            entries[1](s)
        else:
            entries[0](*self._plant_args)
            entries[1](s)

    def _advance_rows(self, *fields: np.ndarray) -> None:
        """``advance`` on the state of the fields of an EnvState (of a block of rows)."""
        self._entries[1](EnvState(*fields))  # type: ignore[index]

    def __getstate__(self) -> dict:
        """Pickle and deepcopy without the compiled entry points (made again at a step) and
        the info dict maker (made again by __setstate__)."""
        return {**self.__dict__, "_entries": None, "_make_info": None}

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._make_info = dict_maker(self._info_columns)

    def _entry_points(self) -> tuple:
        """(plant kernel or None, advance): their compiled entry points (_jit.entry_point)."""
        kernel = (None if self._plant_args is None
                  else entry_point(self.plant.kernel(), self._plant_args))  # fmt: skip
        return kernel, entry_point(advance, (self.state,))

    def info_row(self, b: int) -> dict[str, float | np.ndarray]:
        """Physical values of row b in engineering units (floats; an array for several valves).

        ``measured_temp_C`` is what the outlet thermocouple reported (noise included, as in
        the observation), ``measured_temp_noise_free_C`` the thermocouple's own temperature
        (its lag, without the noise); ``trip_reason`` is "" or one of :data:`TRIP_REASONS`.
        """
        s = self.state
        info = self._make_info(s.info[b].tolist())
        info["trip_reason"] = TRIP_REASONS[s.trip.item(b)]
        if self._valves is not None:
            info["spray_valve"] = s.Z[b, self._valves].copy()
        return info

    def info_columns(self) -> dict[str, np.ndarray]:
        """Physical values of every row, in engineering units (arrays of shape (B,) or (B, k))."""
        s = self.state
        info = self._make_info(s.info.T.copy())  # views of one fresh array
        codes = s.trip
        info["trip_reason"] = (_TRIP_NAMES[codes] if np.count_nonzero(codes)
                               else self._no_trips.copy())  # fmt: skip
        if self._valves is not None:
            info["spray_valve"] = s.Z[:, self._valves].copy()
        return info


    def time_left(self) -> np.ndarray:
        """(B,) seconds from each row's time to the end of its scenario (0 or less: ended)."""
        return self.ep[:, E_DUR] - self.ep[:, E_TIME]

    def ended(self) -> np.ndarray:
        """(B,) bool: whether each row's last step ended its episode (a trip or the end of
        its scenario)."""
        return (self.trip != 0) | self.truncated

    def held_commands(self) -> np.ndarray:
        """(B, n_u) copy of the commands each row holds (openings in [0, 1]: those of its
        last step, or of its steady start after a reset)."""
        return self.U_prev.copy()

    def noise_keys(self) -> np.ndarray:
        """(B,) copy of each row's noise key (uint64; it names the row's episode)."""
        return self.key.copy()

    def steps(self) -> np.ndarray:
        """(B,) copy of each row's number of steps since its reset (int64)."""
        return self.counter.copy()


def non_finite_action(A: np.ndarray) -> ValueError:
    """The error of an action batch holding NaN or infinite values."""
    return ValueError(f"action contains NaN or infinite values: {A.tolist()!r}")


def dict_maker(keys: list[str]) -> Any:
    """The function ``v -> {keys[0]: v[0], keys[1]: v[1], ...}`` (the info dict of a step).

    It is a dict display with the keys as constants, which Python builds in one instruction:
    half the time of ``dict(zip(keys, v))`` for the 14-20 values of an info (0.3 us a step).
    """
    if not all(isinstance(k, str) for k in keys):
        raise ValueError(f"info keys must be strings, got {keys!r}")
    items = ", ".join(f"{k!r}: v[{i}]" for i, k in enumerate(keys))
    return eval(f"lambda v: {{{items}}}")  # noqa: S307 - a display of repr()'d strings


def check_action(action: Any, shape: tuple[int, ...], single: bool = False) -> np.ndarray:
    """An action batch of ``shape`` (n_rows, n_actuators) as a native float32 or float64 array.

    Accepted: any array-like of real numbers (every float dtype and byte order, integers,
    Python integers beyond int64, a masked array without masked entries; not bool,
    complex, strings or other objects) of exactly ``shape`` (vector env) or, for the
    single env (``single``, one row), of shape (n_actuators,) or, with one actuator, a
    scalar. Finiteness is checked by :meth:`Core.step` (compiled, before anything changes).

    Raises:
        ValueError: anything else, naming the expected shape.
    """
    if type(action) is np.ndarray and action.dtype.char in "fd" and action.dtype.isnative and (
            action.shape == (shape[1:] if single else shape)):  # fmt: skip
        return action.reshape(shape)  # the common case, checked in a fraction of a µs
    expected = f"({shape[1]},)" if single else str(shape)
    if isinstance(action, np.ma.MaskedArray):
        masked = int(np.ma.count_masked(action))
        if masked:
            raise ValueError(f"action has {masked} masked entries; every command must be given")
        action = np.ma.getdata(action)
    try:
        a = np.asarray(action)
    except Exception as exc:  # noqa: BLE001 - TypeError, ValueError, a tensor's RuntimeError
        raise ValueError(
            f"action must be an array of shape {expected}: {type(exc).__name__}: {exc}"
        ) from None
    if a.dtype.kind == "O" and a.size and all(is_real(v) for v in a.flat):
        try:  # Python integers beyond int64
            a = a.astype(np.float64)
        except OverflowError:
            raise ValueError(f"action holds a number beyond the float range "
                             f"({str(action)[:80]})") from None  # fmt: skip
    if a.dtype.kind not in "fiu":
        raise ValueError(
            f"action must hold real numbers (float or integer), got dtype {a.dtype} "
            f"({str(action)[:80]})"
        )
    ok = (a.shape == shape[1:] or (a.shape == () and shape[1] == 1)) if single else (
        a.shape == shape)  # fmt: skip
    if not ok:
        raise ValueError(f"action has shape {a.shape}, expected {expected}")
    if a.dtype != np.float64 and a.dtype != np.float32:  # the dtypes the kernels take
        a = a.astype(np.float64)
    return a.reshape(shape)
