"""SteamTempVectorEnv: the native batched env (``gym.make_vec(..., vectorization_mode=
"vector_entry_point")``), the same Core as SteamTempEnv over B rows.

Sub-env i behaves exactly as a SteamTempEnv seeded with ``seed + i``: its own
generator draws its scenarios and noise keys, the plant kernel and the reward
are the same compiled code. ``info`` holds arrays of shape (num_envs,) with ``_key``
masks.

Autoreset follows Gymnasium's modes (``autoreset_mode=`` of the constructor, hence of
``gym.make_vec(..., vectorization_mode="vector_entry_point", autoreset_mode=...)``;
reported in ``metadata["autoreset_mode"]``), with the semantics of
``gymnasium.vector.SyncVectorEnv`` (https://farama.org/Vector-Autoreset-Mode):

- NEXT_STEP (default): the step after an episode ends resets that sub-env (reward 0,
  not terminated or truncated, action ignored, the reset's info);
- SAME_STEP: the step that ends an episode resets it at once: the observation is the
  new episode's first, reward/terminated/truncated are the ending step's, and
  ``info["final_obs"]`` (object array, None elsewhere) and ``info["final_info"]`` (info
  columns with ``_key`` masks True for the ended sub-envs) hold what it ended with;
- DISABLED: no autoreset; the caller resets ended sub-envs with
  ``reset(options={"reset_mask": mask})`` before stepping them again (RuntimeError
  otherwise).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from steamtemp_gym.checks import is_integer
from steamtemp_gym.envs import options as opts
from steamtemp_gym.envs import snapshot as snap_
from steamtemp_gym.envs.actions import check_action
from steamtemp_gym.envs.cost import cost_limit
from steamtemp_gym.envs.steam_temp_env import draw_episode, scenario_option, spaces

#: No rows (the usual case of rows that ended last step).
_NONE = np.zeros(0, dtype=np.int64)

#: The autoreset modes the native vector env implements (every one of Gymnasium's).
AUTORESET_MODES: tuple[AutoresetMode, ...] = (
    AutoresetMode.NEXT_STEP,
    AutoresetMode.SAME_STEP,
    AutoresetMode.DISABLED,
)


def _autoreset_mode(mode: Any) -> AutoresetMode:
    """An AutoresetMode from itself or its value ("NextStep", "SameStep", "Disabled")."""
    for m in AUTORESET_MODES:
        if mode is m or (isinstance(mode, str) and mode == m.value):
            return m
    raise ValueError(
        f"unknown autoreset_mode {mode!r}; valid: {[m.value for m in AUTORESET_MODES]} "
        "or the gymnasium.vector.AutoresetMode members"
    )


class SteamTempVectorEnv(VectorEnv):
    """B copies of one plant stepped by one compiled kernel call.

    Args:
        plant_id: Registered id whose plant to simulate.
        num_envs: Number of sub-envs.
        autoreset_mode: A ``gymnasium.vector.AutoresetMode`` or its value (module
            docstring); default NEXT_STEP.
        **options: As for SteamTempEnv (``scenario``, ``reward``, ``params``,
            ``plant_randomization``: ``core.plants[i]`` is sub-env i's plant; no rendering).
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(
        self,
        plant_id: str,
        num_envs: int = 1,
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        **options: Any,
    ) -> None:
        if not is_integer(num_envs) or num_envs < 1:
            raise ValueError(f"num_envs must be a positive integer, got {num_envs!r}")
        self.autoreset_mode = _autoreset_mode(autoreset_mode)
        self.metadata = {**self.metadata, "autoreset_mode": self.autoreset_mode}
        if options.get("render_mode") is not None:
            raise ValueError("the native vector env does not render; use SteamTempEnv")
        plant, self._scenario_spec, reward_cfg, _ = opts.build(plant_id, options)
        #: The plant parameters given in the ``params`` option (the rest are the defaults).
        self.params_overrides = dict(options.get("params") or {})
        self.plant = plant
        self.num_envs = int(num_envs)
        self.core = opts.make_core(plant, self.num_envs, reward_cfg, options)
        self.signals = self.core.signals
        self.single_observation_space, self.single_action_space = spaces(self.core)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._rngs = [seeding.np_random(None)[0] for _ in range(self.num_envs)]
        self._autoreset = np.zeros(self.num_envs, dtype=bool)
        self._shape = (self.num_envs, plant.n_u)
        self._started = False
        #: (the info keys' mask keys, {mask key: the all-rows mask}), made at the first reset
        self._mask_keys: tuple[list[str], dict] | None = None

    def _reset_rows(self, rows, spec: Any = None, rngs: list | None = None) -> None:
        """Start new episodes in ``rows``, drawn from their generators ``rngs`` (default:
        the env's; on success they become the env's); all or nothing: if one cannot start,
        the ValueError leaves every row and generator as before."""
        spec = self._scenario_spec if spec is None else spec
        rngs = self._rngs if rngs is None else rngs
        states = [rngs[b].bit_generator.state for b in rows]
        try:
            episodes = [draw_episode(rngs[b], spec, self.plant.default_duration_s) for b in rows]
            self.core.reset_rows(rows, episodes)
        except Exception:
            for b, state in zip(rows, states, strict=True):
                rngs[b].bit_generator.state = state
            raise
        self._rngs = rngs

    def reset(self, *, seed: int | list[int | None] | None = None, options: dict | None = None):
        """Reset every sub-env, or those of ``options={"reset_mask": mask}`` (Gymnasium's
        partial reset: a bool array of shape (num_envs,); the others keep their state, and
        ``info`` masks are False for them).

        ``seed``: None, an integer (sub-env i gets seed + i) or a list of num_envs integers
        or None entries (the sub-envs not reset ignore theirs). ``options={"scenario":
        spec}`` starts the episodes of the sub-envs reset now under ``spec`` (as
        SteamTempEnv's reset does); their autoresets return to the env's own scenario.

        All or nothing: if a sub-env's episode cannot start (a ValueError: a scenario or
        drawn plant that cannot hold its start), every sub-env, plant and generator is as
        before.
        """
        spec = scenario_option(options, self._scenario_spec, self.plant.id, ("reset_mask",))
        mask = (options or {}).get("reset_mask")
        if mask is None:
            mask = np.ones(self.num_envs, dtype=bool)
        elif not (
            isinstance(mask, np.ndarray)
            and mask.dtype == np.bool_
            and mask.shape == (self.num_envs,)
        ):
            raise ValueError(
                f"options['reset_mask'] must be a numpy bool array of shape ({self.num_envs},), "
                f"got {type(mask).__name__} {getattr(mask, 'dtype', '')} {np.shape(mask)}"
            )
        elif not self._started and not mask.all():
            raise ValueError("the first reset() must reset every sub-env (no reset_mask)")
        rows = np.flatnonzero(mask)
        rngs = list(self._rngs)
        for b, s in zip(rows, self._seeds(seed)[rows], strict=True):
            if s is not None:
                rngs[b] = seeding.np_random(int(s))[0]
        self._reset_rows(rows, spec, rngs)
        self._autoreset[rows] = False
        self._started = True
        return self.core.obs.copy(), self._info(mask)

    def _seeds(self, seed: Any) -> np.ndarray:
        """Per-sub-env seeds (object array of int or None) of a reset() ``seed`` argument."""

        def valid(s: Any) -> bool:
            return s is None or (is_integer(s) and s >= 0)

        if seed is None or valid(seed):
            seeds = [None if seed is None else int(seed) + i for i in range(self.num_envs)]
        elif isinstance(seed, (list, tuple, np.ndarray)) and all(valid(s) for s in seed):
            seeds = [None if s is None else int(s) for s in seed]
            if len(seeds) != self.num_envs:
                raise ValueError(f"expected {self.num_envs} seeds, got {len(seeds)}")
        else:
            raise ValueError(
                "seed must be None, a non-negative integer or a list of num_envs of them, "
                f"got {str(seed)[:100]!r}"
            )
        out = np.empty(self.num_envs, dtype=object)
        out[:] = seeds
        return out

    def step(self, actions):
        if not self._started:
            raise RuntimeError("call reset() before step()")
        # count_nonzero: a C fast path, ~10x cheaper than .any() on a small bool array
        pending = np.count_nonzero(self._autoreset)
        done_before = np.flatnonzero(self._autoreset) if pending else _NONE
        if done_before.size and self.autoreset_mode == AutoresetMode.DISABLED:
            raise RuntimeError(
                f"sub-env(s) {done_before.tolist()} ended their episode; with autoreset_mode "
                "DISABLED reset them first: reset(options={'reset_mask': mask})"
            )
        self.core.step(check_action(actions, self._shape))
        s = self.core.state
        rewards = s.reward.copy()
        terminated = s.trip != 0  # a trip code
        truncated = s.truncated.copy()
        if done_before.size:  # NEXT_STEP: the rows that ended last step start afresh
            self._reset_rows(done_before)
            rewards[done_before] = 0.0
            terminated[done_before] = False
            truncated[done_before] = False
        done = terminated | truncated
        final = None
        if self.autoreset_mode == AutoresetMode.SAME_STEP and np.count_nonzero(done):
            final = self._final(done)
            self._reset_rows(np.flatnonzero(done))
        else:
            self._autoreset = done
        info = self._info()
        if final is not None:
            info.update(final)
        return s.obs.copy(), rewards, terminated, truncated, info

    def _final(self, done: np.ndarray) -> dict[str, Any]:
        """``final_obs`` and ``final_info`` (with masks) of the rows that just ended."""
        final_obs = np.full(self.num_envs, None, dtype=object)
        for b in np.flatnonzero(done):
            final_obs[b] = self.core.obs[b].copy()
        return {
            "final_obs": final_obs,
            "_final_obs": done.copy(),
            "final_info": self._info(done),
            "_final_info": done.copy(),
        }

    def _info(self, mask: np.ndarray | None = None) -> dict[str, Any]:
        """Info columns, each with its own ``_key`` mask array (True where the row reports)."""
        info = self.core.info_columns()
        if self._mask_keys is None:  # the core's info keys never change
            every = np.ones(self.num_envs, dtype=bool)  # one shared read-only all-rows mask
            every.flags.writeable = False
            mask_keys = ["_" + k for k in info]
            self._mask_keys = (mask_keys, dict.fromkeys(mask_keys, every))
        mask_keys, all_rows = self._mask_keys
        if mask is None:  # every row reports
            info.update(all_rows)
        else:
            masks = np.empty((len(mask_keys), self.num_envs), dtype=bool)  # one allocation
            masks[:] = mask
            info.update(zip(mask_keys, masks, strict=True))
        return info

    def snapshot(self, rows: Any = None) -> snap_.Snapshot:
        """Copies of the full state of ``rows`` (None: every sub-env; an int; a sequence),
        to :meth:`restore` later or into other rows (envs/snapshot.py).

        Raises:
            ValueError: rows out of range, repeated or not integers; no reset() yet.
        """
        if not self._started:
            raise ValueError("call reset() before snapshot()")
        rows = snap_.row_indices(rows, self.num_envs)
        return snap_.take(self.core, rows, self._rngs, self._autoreset)

    def restore(self, snapshot: snap_.Snapshot, rows: Any = None) -> None:
        """Write ``snapshot`` into ``rows`` (None: the rows it was taken from): as many rows
        as it holds, or any number of rows from a one-row snapshot. The rows then continue
        bit for bit as the snapshot's would (envs/snapshot.py); :attr:`observations` gives
        their observations.

        Raises:
            ValueError: a snapshot of another plant or parameter set, rows out of range or
                of the wrong count, or (before the first reset) rows that do not cover every
                sub-env; nothing is changed.
        """
        plan = snap_.check(self.core, snapshot, rows)
        if not self._started and plan.target.size != self.num_envs:
            raise ValueError("before the first reset() restore must cover every sub-env")
        snap_.put(self.core, snapshot, plan, self._rngs, self._autoreset)
        self._started = True

    @property
    def cost_limit(self) -> np.ndarray:
        """The default limit of each sub-env's current episode's summed ``info["cost"]``,
        shape (num_envs,) (envs/cost.py, docs/safe_rl.md).

        Raises:
            ValueError: no reset() yet.
        """
        if not self._started:
            raise ValueError("call reset() before cost_limit (it depends on the scenarios)")
        return np.array([cost_limit(s, self.plant.dt_s) for s in self.core.scenario])

    @property
    def observations(self) -> np.ndarray:
        """A copy of every sub-env's current observation."""
        return self.core.obs.copy()

    def close_extras(self, **kwargs: Any) -> None:
        pass
