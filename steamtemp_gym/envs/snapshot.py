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
episodes). Restoring into an env whose reward options differ is allowed (the state is the
same; the rewards are that env's).

``restore`` checks the whole snapshot (:func:`check`) before it writes anything: a
snapshot of another plant or parameter set, a field of the wrong type, length or shape
for its ``rows``, arrays of another dtype or with NaN or infinite values in a running row,
a scenario that is not a Scenario, generator states of another kind, target rows out of
range or a row count that matches neither the snapshot nor 1 raise ``ValueError`` naming
the field, and change nothing.

Planners that copy rows often use :func:`planning_core` and :func:`copy_rows` (no
Snapshot in between): the copied rows take their scenario and their plant along, a
``plant_randomization`` row its drawn one. :func:`env_core` gives the core of an env to
copy from; what a planner reads of a core's rows is listed in envs/core.py: Core.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from typing import Any

import numpy as np

from steamtemp_gym import scenarios as sc
from steamtemp_gym.envs.core import Core
from steamtemp_gym.envs.plant_rows import PlantRowsCore
from steamtemp_gym.envs.state import ROW_FIELDS
from steamtemp_gym.rewards import RewardConfig

#: The bit generator of the envs' per-row episode generators (gymnasium.utils.seeding).
GENERATOR = np.random.PCG64
#: The per-row arrays of envs/core.py:Core that make a row's state (first axis: the row;
#: the schedule-table slot follows the row's scenario).
ROW_ARRAYS = tuple(name for name in ROW_FIELDS if name != "slot")
#: The arrays a restored row hands out (its observation and reward): finite in every row,
#: a waiting one included (a row that tripped on a non-finite state holds NaN in its plant
#: state and outputs only).
HANDED_OUT = ("obs", "reward")


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


def row_indices(rows: Any, n_rows: int, what: str = "rows", distinct: bool = True) -> np.ndarray:
    """``rows`` (None: all, an int, or an iterable of ints) as an index array of rows in
    [0, n_rows), distinct unless ``distinct`` is False; ValueError naming the problem
    otherwise."""
    if rows is None:
        return np.arange(n_rows)
    if isinstance(rows, np.ndarray) and rows.ndim == 1 and rows.dtype.kind in "iu":
        rows = rows.tolist()  # Python integers, checked below
    if isinstance(rows, (int, np.integer)) and not isinstance(rows, (bool, np.bool_)):
        rows = [rows]
    if isinstance(rows, (str, bytes)) or not isinstance(rows, (Iterable, np.ndarray)):
        raise ValueError(
            f"{what} must be None, an integer or a sequence of integers, got {type(rows).__name__}"
        )
    items = list(rows)
    if not items:
        raise ValueError(f"{what} is empty")
    bad = [
        r for r in items if not isinstance(r, (int, np.integer)) or isinstance(r, (bool, np.bool_))
    ]
    if bad:
        raise ValueError(f"{what} must be integers, got {str(bad[:3])[:80]}")
    ints = [int(r) for r in items]  # Python integers: any size compares
    outside = [r for r in ints if not 0 <= r < n_rows]
    if outside:
        raise ValueError(f"{what} {outside[:5]} out of range for {n_rows} row(s)")
    out = np.array(ints, dtype=np.int64)
    if distinct and np.unique(out).size != out.size:
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


@dataclasses.dataclass(frozen=True)
class Restore:
    """A checked restore (:func:`check`): what :func:`put` writes, where.

    Attributes:
        target: The rows written.
        source: The snapshot row written into each target row.
        rngs: A fresh generator per target row, in its snapshot row's state.
    """

    target: np.ndarray
    source: np.ndarray
    rngs: tuple[np.random.Generator, ...]


def check(core: Any, snap: Any, rows: Any) -> Restore:
    """Check a restore of ``snap`` into ``rows`` of ``core`` entirely: the snapshot's type,
    plant and parameters, every field's type, its length or shape against the snapshot's
    ``rows``, the arrays' dtypes and finiteness (of running rows), the scenarios, the
    generators' kind and states; then the target rows.

    Raises:
        ValueError: naming the field and the problem. Nothing is written (:func:`put`
            writes a checked restore and cannot fail).
    """
    if not isinstance(snap, Snapshot):
        raise ValueError(f"expected a Snapshot (env.snapshot()), got {type(snap).__name__}")
    if snap.plant_id != core.plant.id:
        raise ValueError(f"snapshot of {snap.plant_id!r} cannot be restored into {core.plant.id}")
    n = _check_fields(core, snap)
    target = row_indices(snap.rows if rows is None else rows, core.B)
    if n == len(target):
        source = np.arange(n)
    elif n == 1:
        source = np.zeros(len(target), dtype=np.int64)
    else:
        raise ValueError(
            f"snapshot holds {n} rows; restoring into {len(target)} row(s) needs "
            "a snapshot of as many rows or a one-row snapshot"
        )
    fresh = []
    for i in source.tolist():
        rng = np.random.Generator(GENERATOR())
        try:
            rng.bit_generator.state = snap.rng_states[i]
        except Exception as exc:  # noqa: BLE001 - the setter's ValueError, TypeError, KeyError
            raise ValueError(
                f"snapshot's rng_states[{i}] cannot set this env's "
                f"{type(rng.bit_generator).__name__} generator: "
                f"{type(exc).__name__}: {exc}"
            ) from None
        fresh.append(rng)
    return Restore(target, source, tuple(fresh))


def _check_fields(core: Any, snap: Snapshot) -> int:
    """The number of rows of ``snap`` after checking its fields against ``core``."""
    own = core.plant.params
    if type(snap.params) is not type(own):
        raise ValueError(
            f"snapshot's params must be a {type(own).__name__}, got {type(snap.params).__name__}"
        )
    if not isinstance(snap.rows, (tuple, list)):
        raise ValueError(
            f"snapshot's rows must be a tuple of row indices, got {type(snap.rows).__name__}"
        )
    n = len(row_indices(snap.rows, 2**63, "snapshot's rows"))

    def sequence(name: str) -> tuple:
        value = getattr(snap, name)
        if not isinstance(value, (tuple, list)) or len(value) != n:
            got = (
                f"{len(value)} entries"
                if isinstance(value, (tuple, list))
                else type(value).__name__
            )
            raise ValueError(
                f"snapshot's {name} must be a tuple of one entry per row of "
                f"its rows ({n}), got {got}"
            )
        return tuple(value)

    empty = isinstance(snap.plants, (tuple, list)) and not snap.plants
    plants = () if empty else sequence("plants")
    _check_plants(core, snap, plants)
    waiting = snap.waiting
    if not (
        isinstance(waiting, np.ndarray) and waiting.dtype == np.bool_ and waiting.shape == (n,)
    ):
        got = (
            f"{waiting.dtype} {waiting.shape}"
            if isinstance(waiting, np.ndarray)
            else type(waiting).__name__
        )
        raise ValueError(
            f"snapshot's waiting must be a bool array of shape ({n},) (an entry "
            f"per entry of its rows), got {got}"
        )
    _check_arrays(core, snap.arrays, n, waiting)
    _check_scenarios(sequence("scenarios"))
    for i, state in enumerate(sequence("rng_states")):
        if not isinstance(state, dict):
            raise ValueError(
                f"snapshot's rng_states[{i}] must be a dict "
                f"(bit_generator.state), got {type(state).__name__}"
            )
    return n


def _check_plants(core: Any, snap: Snapshot, plants: tuple) -> None:
    """Check the snapshot's per-row ``plants`` (empty where the rows keep the env's): each of
    the core's plant class, on the plant parameters the env runs, of its sizes and time step."""
    own = core.plant.params
    kind = type(core.plant)
    for i, p in enumerate(plants):
        if not isinstance(p, kind) or type(p.params) is not type(own):
            raise ValueError(
                f"snapshot's plants[{i}] must be a {kind.__name__}, got {type(p).__name__}"
            )
    # an env drawing its rows' plants takes the snapshot's; any other needs its own in each
    wanted = [snap.params] if own_rows(core) else [p.params for p in plants] or [snap.params]
    for params in wanted:
        if params != own:
            diff = [
                f.name
                for f in dataclasses.fields(params)
                if getattr(params, f.name) != getattr(own, f.name)
            ]
            raise ValueError(
                f"snapshot of {snap.plant_id} with other plant parameters "
                f"(differing: {diff}) cannot be restored into this env"
            )
    sizes = core.plant.n_x, core.plant.P.shape, core.plant.dt_s
    for i, p in enumerate(plants):
        if (p.n_x, p.P.shape, p.dt_s) != sizes:
            raise ValueError(
                f"snapshot's plants[{i}] differs from this env's plant in its "
                "state or parameter sizes or its time step"
            )


def _check_scenarios(scenarios: tuple) -> None:
    """Check the snapshot's per-row scenarios: each a valid Scenario (its rows were reset)."""
    for i, s in enumerate(scenarios):
        if s is None:
            raise ValueError("snapshot of rows that were never reset")
        if not isinstance(s, sc.Scenario):
            raise ValueError(
                f"snapshot's scenarios[{i}] must be a Scenario, got "
                f"{type(s).__name__} {str(s)[:60]!r}"
            )
        try:  # its fields as construction checks them (a frozen one can be forged)
            valid = dataclasses.replace(s) == s
        except (ValueError, TypeError) as exc:
            raise ValueError(f"snapshot's scenarios[{i}] is not a valid Scenario: {exc}") from None
        if not valid:
            raise ValueError(
                f"snapshot's scenarios[{i}] holds fields of other types than a Scenario's"
            )


def _check_arrays(core: Any, arrays: Any, n: int, waiting: np.ndarray) -> None:
    """Check the snapshot's ``arrays`` of ``n`` rows: every name of :data:`ROW_ARRAYS` and
    no other, each of the core's dtype and shape (n, ...), counters non-negative, the
    float arrays finite in every row that does not wait for its reset (a row that tripped
    on a non-finite state holds NaN until then)."""
    if not isinstance(arrays, dict) or set(arrays) != set(ROW_ARRAYS):
        keys = sorted(map(str, arrays)) if isinstance(arrays, dict) else type(arrays).__name__
        raise ValueError(f"snapshot's arrays must be a dict of {list(ROW_ARRAYS)}, got {keys}")
    running = ~waiting
    for name in ROW_ARRAYS:
        a, own = arrays[name], getattr(core, name)
        want = (n, *own.shape[1:])
        if not isinstance(a, np.ndarray) or a.dtype != own.dtype or a.shape != want:
            got = f"{a.dtype} {a.shape}" if isinstance(a, np.ndarray) else type(a).__name__
            raise ValueError(
                f"snapshot's arrays[{name!r}] must be a {own.dtype} array of "
                f"shape {want} (a row per entry of its rows), got {got}"
            )
        if a.dtype.kind == "f" and not np.isfinite(a[running]).all():
            raise ValueError(
                f"snapshot's arrays[{name!r}] holds NaN or infinite values in a running row"
            )
        if name in HANDED_OUT and not np.isfinite(a).all():  # the env never hands these out
            raise ValueError(
                f"snapshot's arrays[{name!r}] holds NaN or infinite values (the "
                "env's observations and rewards are finite in every row)"
            )
        if name == "counter" and (a < 0).any():
            raise ValueError(f"snapshot's arrays['counter'] must be >= 0, got {a.tolist()[:5]}")


def put(core: Any, snap: Snapshot, plan: Restore, rngs: list, waiting: np.ndarray) -> None:
    """Write the checked restore ``plan`` (:func:`check`) of ``snap``: the rows' arrays,
    scenarios, plants (into a core whose rows have their own), generators (into ``rngs``)
    and waiting flags."""
    target, source = plan.target, plan.source
    for name in ROW_ARRAYS:
        getattr(core, name)[target] = snap.arrays[name][source]
    for b, i, rng in zip(target.tolist(), source.tolist(), plan.rngs, strict=True):
        core.assign_scenario(b, snap.scenarios[i])
        if own_rows(core) and snap.plants:
            core.set_plant(b, snap.plants[i])
        rngs[b] = rng
        waiting[b] = snap.waiting[i]


def own_rows(core: Any) -> bool:
    """Whether ``core``'s rows each simulate a plant of their own (plant_randomization)."""
    return isinstance(core, PlantRowsCore)


def env_core(env: Any) -> Core:
    """The batched core of a steamtemp_gym env (SteamTempEnv or the native vector env,
    wrapped or not), whose rows a planner copies (:func:`copy_rows`) and reads (Core).

    Raises:
        ValueError: any other env.
    """
    u = getattr(env, "unwrapped", env)
    core = getattr(u, "core", None)
    if not isinstance(core, Core):
        raise ValueError(
            "expected a steamtemp_gym env (SteamTempEnv or the native vector "
            f"env), got {type(u).__name__}"
        )
    return core


def planning_core(src: Any, batch: int) -> Core:
    """A core of ``batch`` rows to plan from rows of ``src`` (:func:`copy_rows`): of its
    plant object and reward weights; where ``src``'s rows simulate plants of their own
    (plant_randomization), one whose rows take the plants of the rows copied into them.

    Raises:
        ValueError: ``src`` is not a Core or ``batch`` not a positive integer.
    """
    if not isinstance(src, Core):
        raise ValueError(
            f"planning_core plans from a Core (env_core(env)), got {type(src).__name__}"
        )
    if (
        not isinstance(batch, (int, np.integer))
        or isinstance(batch, (bool, np.bool_))
        or (batch < 1)
    ):
        raise ValueError(f"planning_core: batch must be a positive integer, got {batch!r}")
    if own_rows(src):
        core = PlantRowsCore(src.plant, int(batch), RewardConfig(), src.ranges, src.base)
    else:
        core = Core(src.plant, int(batch), RewardConfig())
    core.cfg[:] = src.cfg  # the env's own reward weights
    return core


def copy_rows(src: Any, src_rows: Any, dst: Any, dst_rows: Any) -> None:
    """Copy the state of ``src_rows`` of one core into ``dst_rows`` of another, each row
    with its scenario and its plant: a planner's fan-out without a Snapshot in between
    (the caller owns both cores; make ``dst`` with :func:`planning_core`). A source row
    may be copied into several rows.

    Raises:
        ValueError: nothing is copied if either core is not a Core or the two simulate
            different plants, the rows are not integer rows of their core (``dst_rows``
            distinct) of equal numbers, a source row was never reset, or ``dst`` simulates
            one plant and a copied row another (a row of a plant_randomization env into a
            plain Core).
    """
    _check_copy(src, dst)
    src_rows = row_indices(src_rows, src.B, "copy_rows: source rows", distinct=False).tolist()
    dst_rows = row_indices(dst_rows, dst.B, "copy_rows: destination rows").tolist()
    if len(src_rows) != len(dst_rows):
        raise ValueError(
            f"copy_rows: {len(src_rows)} source row(s) into {len(dst_rows)} destination row(s)"
        )
    never = sorted({i for i in src_rows if src.scenario[i] is None})
    if never:
        raise ValueError(f"copy_rows: source rows {never[:5]} were never reset")
    drawn, per_row = own_rows(src), own_rows(dst)
    if not per_row:
        copied = map(src.row_plant, set(src_rows)) if drawn else (src.plant,)
        if any(p is not dst.plant and p.params != dst.plant.params for p in copied):
            raise ValueError(
                "copy_rows: the copied rows simulate other plants than the "
                "destination core's; make it with planning_core(src, n)"
            )
    for name in ROW_ARRAYS:
        getattr(dst, name)[dst_rows] = getattr(src, name)[src_rows]
    for b, i in zip(dst_rows, src_rows, strict=True):
        if dst.scenario[b] is not src.scenario[i]:
            dst.assign_scenario(b, src.scenario[i])
        if per_row:
            plant = src.row_plant(i)
            if dst.plants[b] is not plant:
                dst.set_plant(b, plant, src.factors[i] if drawn else None)


def _check_copy(src: Any, dst: Any) -> None:
    """Raise ValueError unless ``src`` and ``dst`` are cores of one plant's kind and sizes."""
    for name, core in (("source", src), ("destination", dst)):
        if not isinstance(core, Core):
            raise ValueError(f"copy_rows: the {name} must be a Core, got {type(core).__name__}")
    if src.plant.id != dst.plant.id or src.X.shape[1:] != dst.X.shape[1:]:
        raise ValueError(
            f"copy_rows: rows of {src.plant.id} cannot be copied into a core of {dst.plant.id}"
        )
