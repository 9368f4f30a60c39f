"""The batched simulation core shared by SteamTempEnv (a batch of one) and the vector env:
the state of B rows of one plant (envs/state.py), each under its own scenario, their
schedule tables, reset to a steady start, the step (the plant's kernel, then
:func:`envs.kernels.advance`), the info values and what a planner reads of each row.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from steamtemp_gym import scenarios as sc
from steamtemp_gym._jit import entry_point
from steamtemp_gym.envs.actions import non_finite_action
from steamtemp_gym.envs.cost import COST_DOC
from steamtemp_gym.envs.kernels import (
    E_DUR,
    E_TIME,
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
from steamtemp_gym.envs.schedule_slots import ScheduleSlots
from steamtemp_gym.envs.start import start_fits, start_refusal
from steamtemp_gym.envs.state import (
    INFO_TAIL,
    ROW_POSITIONS,
    EnvState,
    StateFields,
    info_sources,
    new_state,
    outputs,
)
from steamtemp_gym.plants.base import Plant
from steamtemp_gym.plants.threads import MIN_SPLIT_ROWS, run_rows
from steamtemp_gym.rewards import RewardConfig
from steamtemp_gym.rng import gauss
from steamtemp_gym.signals import for_plant

_TRIP_NAMES = np.array(TRIP_REASONS)
#: Unit and meaning of the info values every plant has (the others are plant outputs).
INFO_DOC = {
    "outlet_temp_C": ("C", "true main-steam temperature (the trip band applies to it)"),
    "measured_temp_noise_free_C": (
        "C",
        "the outlet thermocouple's own temperature (its lag, without the noise)",
    ),
    "measured_temp_C": ("C", "what the outlet thermocouple reported, noise included (as observed)"),
    "time_s": ("s", "time since the episode started (steps x control interval)"),
    "setpoint_C": ("C", "main-steam temperature setpoint (the scenario's offset included)"),
    "load": ("1", "load demand, fraction of rated"),
    "spray_flow_kg_s": ("kg/s", "total spray-water flow of every attemperator"),
    "trip_reason": (
        "",
        "why the episode terminated: '' or one of " + ", ".join(repr(r) for r in TRIP_REASONS[1:]),
    ),
    **COST_DOC,
}


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
        obs_cs = np.array(
            [[s.center, s.scale, float(s.noisy)] for s in self.signals.observation],
            dtype=np.float64,
        )
        out = outputs(plant)
        self.state: EnvState = new_state(plant, batch, reward_cfg, obs_cs, out)
        self._slots = ScheduleSlots(self.bp_t.shape[0])
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
        self._valves = (
            None if len(v) < 2 else slice(v[0], v[0] + len(v)) if adjacent else np.array(v)
        )
        #: the plant kernel's arguments, built once (the arrays keep their identity)
        self._plant_args = (
            plant.step_args(self.X, self.U, self.D, self.Z)
            if type(plant).step is Plant.step
            else None
        )
        #: compiled entry points of (plant kernel or None, advance) for those arguments
        self._entries: tuple | None = None
        self._no_trips = np.full(batch, TRIP_REASONS[0], dtype=_TRIP_NAMES.dtype)

    def assign_scenario(self, b: int, scenario: sc.Scenario) -> None:
        """Make row b run ``scenario`` (its schedules packed into a table slot); the row's
        state is not touched."""
        self.state = self._slots.assign(self.state, b, self.scenario[b], scenario)
        self.scenario[b] = scenario

    def start_fits(self, scenario: sc.Scenario, plant: Plant) -> bool:
        """Whether ``plant`` (of the core's class and setpoint) holds ``scenario``'s start in
        steady state within :data:`START_BAND_K` of the setpoint (:meth:`check_start`)."""
        return start_fits(plant, scenario)

    def row_plant(self, b: int) -> Plant:
        """The plant row b simulates (every row's is the core's plant)."""
        return self.plant

    def check_start(self, scenario: sc.Scenario) -> None:
        """Raise ValueError unless the plant can hold ``scenario``'s start in steady state
        (envs/start.py: the error names the initial values that make it impossible)."""
        if scenario in self._feasible:
            return
        refusal = start_refusal(self.plant, scenario, self.valve_idx)
        if refusal is not None:
            raise refusal
        self._feasible.add(scenario)

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

    def _start_row(
        self, b: int, scenario: sc.Scenario, key: int, drawn: tuple[Plant, dict[str, float]]
    ) -> None:
        """Start row b on ``scenario`` and ``key`` with the plant ``drawn`` for them by
        :meth:`episode_plant` (nothing here can fail)."""
        self.assign_scenario(b, scenario)
        ou_ab = ou_coefficients(
            scenario.heat_absorption_noise_std,
            scenario.heat_absorption_noise_tau_s,
            self.plant.dt_s,
        )
        self.ep[b] = (0.0, scenario.duration_s, scenario.noise_std_C, *ou_ab)
        self.ou[b] = scenario.heat_absorption_noise_std * gauss(np.uint64(key), 0, OU_CHANNEL)
        self.key[b] = np.uint64(key)
        self.counter[b] = 0
        self.reward[b], self.trip[b], self.truncated[b] = 0.0, 0, False
        schedules(
            b,
            self.slot[b],
            0.0,
            self.bp_t,
            self.bp_v,
            self.bp_n,
            self.plant.setpoint_C,
            self.ou,
            self.D,
            self.sp,
        )
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
        return (
            (b, s.Z, s.D, s.sp, s.ep, s.key, s.counter, s.obs_cs, obs_idx, i_meas, s.obs, s.meas),
            (b, s.Z, s.D, s.sp, s.ep, s.meas, cols, sprays, 0.0, s.info),
        )

    def compile_calls(self) -> list[tuple[Any, tuple]]:
        """(kernel, arguments) of the compiled calls of a reset and a step but the plant's
        steady state, with arguments of the types they really get (actions: float32 or
        float64), the env's kernels first and the plant's step last: what an episode
        compiles or loads from the cache (tests/test_precompile.py checks it loads them all).
        """
        actions = [np.zeros((self.B, self.plant.n_u), dtype=t) for t in (np.float32, np.float64)]
        s = self.state
        return [
            (
                schedules,
                (0, s.slot[0], 0.0, s.bp_t, s.bp_v, s.bp_n, self.plant.setpoint_C, s.ou, s.D, s.sp),
            ),
            (gauss, (np.uint64(0), 0, OU_CHANNEL)),
            (obs_indices, (s.ints,)),
            (info_indices, (s.ints,)),
            *zip((observe, fill_info), self._output_args(0), strict=True),
            *[(to_commands, (a, self.U)) for a in actions],
            (advance, (s,)),
            (self.plant.kernel(), self.plant.step_args(self.X, self.U, self.D, self.Z)),
        ]

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
        kernel = (
            None if self._plant_args is None else entry_point(self.plant.kernel(), self._plant_args)
        )
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
        info["trip_reason"] = (
            _TRIP_NAMES[codes] if np.count_nonzero(codes) else self._no_trips.copy()
        )
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


def dict_maker(keys: list[str]) -> Any:
    """The function ``v -> {keys[0]: v[0], keys[1]: v[1], ...}`` (the info dict of a step).

    It is a dict display with the keys as constants, which Python builds in one instruction:
    half the time of ``dict(zip(keys, v))`` for the 14-20 values of an info (0.3 us a step).
    """
    if not all(isinstance(k, str) for k in keys):
        raise ValueError(f"info keys must be strings, got {keys!r}")
    items = ", ".join(f"{k!r}: v[{i}]" for i, k in enumerate(keys))
    return eval(f"lambda v: {{{items}}}")  # noqa: S307 - a display of repr()'d strings
