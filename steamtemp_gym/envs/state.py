"""The state of an env core (envs/core.py) as one typed value: the arrays of its B rows and
the constant tables of its plant, in the :class:`EnvState` named tuple that the compiled
step (envs/kernels.py: :func:`~steamtemp_gym.envs.kernels.advance`) and the reset's kernels
take as one argument (numba compiles a named tuple of arrays as a struct of them).

Its per-row fields (:data:`ROW_FIELDS`) have the row as their first axis: a block of rows
of each, with the shared tables as they are, is the state of those rows alone
(:data:`ROW_POSITIONS`, the threaded row split of plants/threads.py).
"""

from __future__ import annotations

from operator import attrgetter
from typing import Any, NamedTuple

import numpy as np

from steamtemp_gym.envs.cost import COST_KEYS
from steamtemp_gym.envs.kernels import MIN_BREAKPOINTS, N_CH, OU_CHANNEL, H
from steamtemp_gym.plants.base import N_DIST, Plant
from steamtemp_gym.rewards import RewardConfig


class EnvState(NamedTuple):
    """The arrays of the rows of an env core and the tables they share.

    Per row (first axis: the row, B rows):
        X: (B, n_x) plant states. Z: (B, n_z) plant outputs.
        U: (B, n_u) the commands of the step (valve openings in [0, 1]).
        U_prev: (B, n_u) the commands of the previous step (the reward's move penalty).
        D: (B, N_DIST) disturbances of the step. sp: (B,) setpoint (C).
        slot: (B,) int64 schedule-table slot of each row (rows of one scenario share one).
        ep: (B, 5) episode values [time_s, duration_s, noise_std_C, ou_a, ou_b]
            (kernels.E_TIME ...).
        ou: (B,) coloured heat-absorption disturbance.
        key: (B,) uint64 noise key. counter: (B,) int64 steps since the row's reset.
        obs: (B, n_obs) normalized observation. meas: (B,) the outlet thermocouple's reading.
        info: (B, n_info) info values (kernels.fill_info).
        reward: (B,) the last step's reward.
        trip: (B,) int64 the last step's trip code (kernels.TRIP_REASONS index; 0: none).
        truncated: (B,) bool, whether the last step reached the scenario's end.

    Shared by every row:
        bp_t, bp_v: (n_slots, N_CH, k) breakpoint times and values of the schedule tables.
        bp_n: (n_slots, N_CH) int64 their numbers of breakpoints.
        ints: int64 output indices, laid out as kernels.H says.
        cfg: the scalars of kernels.CFG, the reward weights, the secondary setpoints.
        obs_cs: (n_obs, 3) centre, scale and noisiness of each observed signal.
    """

    X: np.ndarray
    Z: np.ndarray
    U: np.ndarray
    U_prev: np.ndarray
    D: np.ndarray
    sp: np.ndarray
    slot: np.ndarray
    ep: np.ndarray
    ou: np.ndarray
    key: np.ndarray
    counter: np.ndarray
    obs: np.ndarray
    meas: np.ndarray
    info: np.ndarray
    reward: np.ndarray
    trip: np.ndarray
    truncated: np.ndarray
    bp_t: np.ndarray
    bp_v: np.ndarray
    bp_n: np.ndarray
    ints: np.ndarray
    cfg: np.ndarray
    obs_cs: np.ndarray


#: The fields of :class:`EnvState` whose first axis is the row, and their positions.
ROW_FIELDS = EnvState._fields[: EnvState._fields.index("truncated") + 1]
ROW_POSITIONS = tuple(range(len(ROW_FIELDS)))
#: The values every info carries after the plant's own outputs (EnvState.info's last columns).
INFO_TAIL = ("measured_temp_C", "time_s", "setpoint_C", "load", "spray_flow_kg_s", *COST_KEYS)


class Outputs(NamedTuple):
    """Output indices of a plant's signals that the env reads (lists of ints)."""

    observed: list[int]
    valves: list[int]
    sprays: list[int]
    secondary: list[int]
    info: list[int]


def info_sources(plant: Any) -> list[tuple[str, str]]:
    """(info key, the plant output it reads) of the info values taken from the plant's
    outputs, in order; :data:`INFO_TAIL` and ``trip_reason`` follow them. With several
    valves, ``spray_valve`` holds every valve's opening."""
    return [
        ("outlet_temp_C", plant.outlet),
        ("measured_temp_noise_free_C", plant.outlet_measured),
        ("spray_valve", plant.valves[0]),
    ] + [(name, name) for name in plant.extra_info]


def outputs(plant: Plant) -> Outputs:
    """The output indices of ``plant``'s observed signals, valves, sprays, secondary
    temperatures and info values (:func:`info_sources`).

    Raises:
        ValueError: the plant observes more outputs than the noise has channels.
    """
    idx = plant.index
    observed = [i for i, s in enumerate(plant.outputs) if s.observed]
    if len(observed) >= OU_CHANNEL:
        raise ValueError(f"{plant.id}: at most {OU_CHANNEL - 1} observed outputs")
    return Outputs(
        observed,
        [idx[v] for v in plant.valves],
        [idx[s] for s in plant.sprays],
        [idx[name] for name, _ in plant.secondary],
        [idx[source] for _, source in info_sources(plant)],
    )


def new_state(
    plant: Plant, batch: int, reward_cfg: RewardConfig, obs_cs: np.ndarray, out: Outputs
) -> EnvState:
    """The zeroed state of ``batch`` rows of ``plant`` with one schedule-table slot: its
    tables from the plant's outputs ``out`` (:func:`outputs`), the reward weights and the
    observed signals' ``obs_cs``."""
    B, idx = batch, plant.index
    starts = np.cumsum([len(H)] + [len(v) for v in out]).tolist()
    ints = np.array(
        [
            idx[plant.outlet],
            idx[plant.outlet_measured],
            idx[plant.design_spray] if plant.design_spray else -1,
            *starts,
        ]
        + [i for v in out for i in v],
        dtype=np.int64,
    )
    spray_scale = plant.outputs[out.sprays[0]].scale if out.sprays else 1.0
    # the scalars in the order of kernels.CFG
    cfg = np.concatenate(
        [
            [plant.dt_s, plant.setpoint_C, *plant.trip_band_K, spray_scale],
            reward_cfg.to_array(),
            [sp for _, sp in plant.secondary],
        ]
    )
    zeros = dict(
        X=(B, plant.n_x),
        Z=(B, plant.n_z),
        U=(B, plant.n_u),
        U_prev=(B, plant.n_u),
        D=(B, N_DIST),
        sp=B,
        ep=(B, 5),
        ou=B,
        obs=(B, len(out.observed) + 3),
        meas=B,
        info=(B, len(out.info) + len(INFO_TAIL)),
        reward=B,
    )
    state = EnvState(
        **{k: np.zeros(shape) for k, shape in zeros.items()},
        slot=np.zeros(B, np.int64),
        key=np.zeros(B, np.uint64),
        counter=np.zeros(B, np.int64),
        trip=np.zeros(B, np.int64),
        truncated=np.zeros(B, np.bool_),
        bp_t=None,
        bp_v=None,
        bp_n=None,
        ints=ints,
        cfg=cfg,
        obs_cs=obs_cs,
    )
    return with_tables(state, 1, MIN_BREAKPOINTS)


def with_tables(state: EnvState, n_slots: int, k: int) -> EnvState:
    """``state`` with schedule tables of ``n_slots`` slots of ``k`` breakpoints, holding the
    old tables' slots (none: every slot empty)."""
    bp_t, bp_v = np.zeros((n_slots, N_CH, k)), np.zeros((n_slots, N_CH, k))
    bp_n = np.ones((n_slots, N_CH), dtype=np.int64)
    if state.bp_t is not None:
        n0, k0 = state.bp_t.shape[0], state.bp_t.shape[2]
        bp_t[:n0, :, :k0], bp_v[:n0, :, :k0], bp_n[:n0] = state.bp_t, state.bp_v, state.bp_n
    return state._replace(bp_t=bp_t, bp_v=bp_v, bp_n=bp_n)


class StateFields:
    """Each field of an :class:`EnvState` ``state`` as an attribute of the same name (the
    same array: ``core.X is core.state.X``)."""

    state: EnvState


for _name in EnvState._fields:
    setattr(
        StateFields,
        _name,
        property(attrgetter(f"state.{_name}"), doc=f"``state.{_name}`` (:class:`EnvState`)"),
    )
