"""Snapshots of env rows: copy the full state of episodes, restore it, fan it out.

For planners, tree search and model-based RL: :meth:`SteamTempVectorEnv.snapshot` and
:meth:`SteamTempEnv.snapshot` copy everything a row's future depends on, and ``restore``
writes it back into the same or other rows of an env of the same plant and parameters,
a one-row snapshot into as many rows as wanted. A restored row then continues bit for bit
as the original would have, given the same actions: the state copied is

- the plant's state vector (temperatures, enthalpies, metal, valve and thermowell states,
  the plant's own random disturbance generators) and its outputs;
- the commands held and the last ones (the move cost), the disturbances, setpoint, time,
  step counter and noise key (sensor noise and the coloured heat-absorption disturbance
  are counter-based, steamtemp_gym/rng.py, so the same key and counter give the same
  future noise), the coloured disturbance's state, the last observation, reward, flags
  and info;
- the scenario each row runs (its whole future schedule);
- the env's per-row random generator (the scenario and key of the episodes after this
  one) and whether the row waits for its autoreset.

Example (one episode's state fanned out to 64 rows of a planning env)::

    venv = gym.make_vec(id, num_envs=64, vectorization_mode="vector_entry_point",
                        autoreset_mode="Disabled")
    venv.reset(seed=0)
    venv.unwrapped.restore(env.unwrapped.snapshot(), rows=range(64))

The episodes after the current one are drawn by the restored generator from the target
env's own ``scenario`` option (the same option as the source env's gives the same
episodes). Restoring into an env whose reward options differ is allowed (the state is the same; the
rewards are that env's). Bad input (a snapshot of another plant or parameter set, rows out
of range, a row count that matches neither the snapshot nor 1) raises ``ValueError``
naming the problem and changes nothing.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from typing import Any

import numpy as np

#: The per-row arrays of envs/core.py:Core that make a row's state (first axis: the row).
ROW_ARRAYS = ("X", "Z", "U", "U_prev", "D", "sp", "ep", "ou", "key", "counter", "out", "meas",
              "obs", "info")  # fmt: skip


@dataclasses.dataclass(frozen=True, eq=False)
class Snapshot:
    """Copies of the full state of some rows of an env (module docstring).

    Attributes:
        plant_id: The plant the rows simulate.
        params: The plant's parameters (its frozen dataclass); restore needs equal ones.
        plants: The plant of each row (with ``plant_randomization`` each row's drawn one:
            restore then needs equal parameters per row, or an env with the option, whose
            rows take these plants).
        rows: The rows it was taken from.
        arrays: Per-row copies of :data:`ROW_ARRAYS`, first axis ``len(rows)``.
        scenarios: The scenario of each row.
        rng_states: The state of each row's episode generator (``bit_generator.state``).
        waiting: Per row, True where the episode has ended and the row waits for its reset.
    """

    plant_id: str
    params: Any
    rows: tuple[int, ...]
    arrays: dict[str, np.ndarray]
    scenarios: tuple[Any, ...]
    rng_states: tuple[dict, ...]
    waiting: np.ndarray
    plants: tuple[Any, ...] = ()

    def __len__(self) -> int:
        return len(self.rows)


def row_indices(rows: Any, n_rows: int, what: str = "rows") -> np.ndarray:
    """``rows`` (None: all, an int, or an iterable of ints) as an index array of distinct
    rows in [0, n_rows); ValueError naming the problem otherwise."""
    if rows is None:
        return np.arange(n_rows)
    if isinstance(rows, (int, np.integer)) and not isinstance(rows, (bool, np.bool_)):
        rows = [rows]
    if isinstance(rows, (str, bytes)) or not isinstance(rows, (Iterable, np.ndarray)):
        raise ValueError(f"{what} must be None, an integer or a sequence of integers, "
                         f"got {type(rows).__name__}")  # fmt: skip
    items = list(rows)
    if not items:
        raise ValueError(f"{what} is empty")
    bad = [r for r in items if not isinstance(r, (int, np.integer)) or isinstance(
        r, (bool, np.bool_))]  # fmt: skip
    if bad:
        raise ValueError(f"{what} must be integers, got {str(bad[:3])[:80]}")
    out = np.array([int(r) for r in items], dtype=np.int64)
    outside = out[(out < 0) | (out >= n_rows)]
    if outside.size:
        raise ValueError(f"{what} {outside[:5].tolist()} out of range for {n_rows} row(s)")
    if np.unique(out).size != out.size:
        raise ValueError(f"{what} has duplicates: {out.tolist()[:20]}")
    return out


def take(core: Any, rows: np.ndarray, rngs: list, waiting: np.ndarray) -> Snapshot:
    """A snapshot of ``rows`` of ``core`` with their generators and waiting flags."""
    return Snapshot(
        plant_id=core.plant.id,
        params=core.plant.params,
        rows=tuple(int(r) for r in rows),
        arrays={name: getattr(core, name)[rows].copy() for name in ROW_ARRAYS},
        scenarios=tuple(core.scenario[r] for r in rows),
        rng_states=tuple(rngs[r].bit_generator.state for r in rows),
        waiting=np.asarray(waiting, dtype=bool)[rows].copy(),
        plants=tuple(core.row_plant(int(r)) for r in rows),
    )


def check(core: Any, snap: Any, rows: Any) -> tuple[np.ndarray, np.ndarray]:
    """(target rows, snapshot row for each) of a restore; ValueError if it cannot be done."""
    if not isinstance(snap, Snapshot):
        raise ValueError(f"expected a Snapshot (env.snapshot()), got {type(snap).__name__}")
    if snap.plant_id != core.plant.id:
        raise ValueError(f"snapshot of {snap.plant_id} cannot be restored into {core.plant.id}")
    own = core.plant.params
    # an env drawing its rows' plants takes the snapshot's; any other needs its own in each
    wanted = [snap.params] if own_rows(core) else [p.params for p in snap.plants] or [snap.params]
    for params in wanted:
        if params != own:
            diff = [f.name for f in dataclasses.fields(params)
                    if getattr(params, f.name) != getattr(own, f.name)]  # fmt: skip
            raise ValueError(f"snapshot of {snap.plant_id} with other plant parameters "
                             f"(differing: {diff}) cannot be restored into this env")  # fmt: skip
    if any(snap.scenarios[i] is None for i in range(len(snap))):
        raise ValueError("snapshot of rows that were never reset")
    n = core.B
    target = row_indices(snap.rows if rows is None else rows, n)
    if len(snap) == len(target):
        source = np.arange(len(snap))
    elif len(snap) == 1:
        source = np.zeros(len(target), dtype=np.int64)
    else:
        raise ValueError(f"snapshot holds {len(snap)} rows; restore needs as many target rows "
                         f"or a one-row snapshot, got {len(target)} rows")  # fmt: skip
    for name in ROW_ARRAYS:
        want, got = getattr(core, name).shape[1:], snap.arrays[name].shape[1:]
        if want != got:
            raise ValueError(f"snapshot's {name} has row shape {got}, this env's {want}")
    return target, source


def put(core: Any, snap: Snapshot, target: np.ndarray, source: np.ndarray, rngs: list,
        waiting: np.ndarray) -> None:  # fmt: skip
    """Write snapshot rows ``source`` into ``target`` rows (checked by :func:`check`)."""
    for name in ROW_ARRAYS:
        getattr(core, name)[target] = snap.arrays[name][source]
    for b, i in zip(target.tolist(), source.tolist(), strict=True):
        core.assign_scenario(b, snap.scenarios[i])
        if own_rows(core) and snap.plants:
            core.set_plant(b, snap.plants[i])
        rng = np.random.Generator(type(rngs[b].bit_generator)())
        rng.bit_generator.state = snap.rng_states[i]
        rngs[b] = rng
        waiting[b] = snap.waiting[i]


def own_rows(core: Any) -> bool:
    """Whether ``core``'s rows each simulate a plant of their own (plant_randomization)."""
    return hasattr(core, "plants")


def copy_rows(src: Any, src_rows: np.ndarray, dst: Any, dst_rows: np.ndarray) -> None:
    """Copy the state of ``src_rows`` of one core into ``dst_rows`` of another core of the
    same plant object (a planner's fan-out without a Snapshot in between; unchecked: the
    caller owns both cores)."""
    for name in ROW_ARRAYS:
        getattr(dst, name)[dst_rows] = getattr(src, name)[src_rows]
    for b, i in zip(np.asarray(dst_rows).tolist(), np.asarray(src_rows).tolist(), strict=True):
        if dst.scenario[b] is not src.scenario[i]:
            dst.assign_scenario(b, src.scenario[i])
