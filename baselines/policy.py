"""The Policy protocol: what every baseline (and every trained agent) offers, and the
checks of what ``predict`` is given.

The signature is Stable-Baselines3's ``predict`` (``PolicyPredictor`` in
``stable_baselines3/common/type_aliases.py``): a policy sees exactly the
observation an RL agent sees and returns actions in [-1, 1]. ``reset()`` clears
internal controller state at the start of an episode (it is also done automatically
where ``episode_start`` is True).

``predict`` refuses an observation that is not a finite real array of shape (n_obs,) or
(n_envs, n_obs) with n_envs >= 1, and an ``episode_start`` that is not one flag or one per
row, with a ``ValueError`` naming the problem, before the policy's state changes
(:func:`check_predict_args`). :func:`checked` gives any policy that guarantee;
``baselines.make`` returns every baseline through it, and the trained agents
(agents/policy.py) check their arguments with the same function.
"""

from __future__ import annotations

import math
from typing import Any, Protocol, runtime_checkable

import numpy as np

#: Observations of at most this many entries are checked for finiteness in Python.
_FEW = 64


@runtime_checkable
class Policy(Protocol):
    """A controller or agent acting on normalized observations."""

    def predict(
        self,
        observation: np.ndarray,
        state: Any = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        """Action(s) for one observation (n_obs,) or a batch (n_envs, n_obs)."""
        ...

    def reset(self) -> None:
        """Forget the episode (integrators, estimators, histories)."""
        ...


def observation_size(env: Any) -> int:
    """The number of entries of one observation of ``env`` (a single or a vector env)."""
    space = getattr(env, "single_observation_space", None) or env.observation_space
    return int(space.shape[-1])


def check_predict_args(observation: Any, episode_start: Any, n_obs: int) -> np.ndarray:
    """``observation`` as an array of shape (n_obs,) or (n_envs, n_obs), after checking it
    and ``episode_start`` (module docstring).

    Raises:
        ValueError: None, not real numbers, a masked entry, another shape, an empty batch,
            a NaN or an infinity in the observation; an ``episode_start`` of another shape
            than (), (1,) or (n_envs,), or not flags.
    """
    obs = observation
    if type(obs) is not np.ndarray or obs.dtype.kind != "f":  # the common case skips this
        if obs is None:
            raise ValueError(f"observation is None; expected an array of shape {_shapes(n_obs)}")
        if isinstance(obs, np.ma.MaskedArray) and np.ma.count_masked(obs):
            raise ValueError(f"observation has {np.ma.count_masked(obs)} masked entries")
        try:
            obs = np.asarray(obs)
        except Exception as exc:  # noqa: BLE001 - TypeError, ValueError, a tensor's RuntimeError
            raise ValueError(
                f"observation must be an array of shape {_shapes(n_obs)}: "
                f"{type(exc).__name__}: {exc}"
            ) from None
        if obs.dtype.kind not in "fiu":
            raise ValueError(
                f"observation must hold real numbers, got dtype {obs.dtype} "
                f"({str(observation)[:80]})"
            )
    if obs.ndim not in (1, 2) or obs.shape[-1] != n_obs:
        raise ValueError(f"observation has shape {obs.shape}, expected {_shapes(n_obs)}")
    n = 1 if obs.ndim == 1 else obs.shape[0]
    if n == 0:
        raise ValueError(f"observation is an empty batch of shape {obs.shape}; give >= 1 row")
    # a few entries: Python's isfinite over a list is several times faster than the ufunc
    ok = (
        all(map(math.isfinite, obs.ravel().tolist()))
        if obs.size <= _FEW
        else bool(np.isfinite(obs).all())
    )
    if not ok:
        rows, cols = np.nonzero(~np.isfinite(np.atleast_2d(obs)))
        raise ValueError(
            f"observation has {rows.size} NaN or infinite entries (first: row {rows[0]}, "
            f"entry {cols[0]} = {np.atleast_2d(obs)[rows[0], cols[0]]}); a policy acts on "
            "finite observations only"
        )
    if episode_start is not None:
        try:
            start = np.asarray(episode_start)
        except Exception as exc:  # noqa: BLE001
            raise ValueError(f"episode_start must be an array of flags: {exc}") from None
        if start.dtype.kind not in "biu" or start.shape not in ((), (1,), (n,)):
            raise ValueError(
                f"episode_start must be flags of shape (), (1,) or ({n},) for {n} "
                f"observation row(s), got dtype {start.dtype} shape {start.shape}"
            )
    return obs


def _shapes(n_obs: int) -> str:
    return f"({n_obs},) or (n_envs, {n_obs})"


class CheckedPolicy:
    """``policy`` whose ``predict`` checks its arguments first (:func:`check_predict_args`);
    every other attribute is the wrapped policy's (read and written through)."""

    def __init__(self, policy: Any, n_obs: int) -> None:
        object.__setattr__(self, "policy", policy)
        object.__setattr__(self, "n_obs", int(n_obs))

    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        """The wrapped policy's ``predict`` of arguments that passed the checks."""
        check_predict_args(observation, episode_start, self.n_obs)
        return self.policy.predict(observation, state, episode_start, deterministic)

    def reset(self) -> None:
        self.policy.reset()

    def __getattr__(self, name: str) -> Any:
        if name in ("policy", "n_obs"):  # not set yet (unpickling)
            raise AttributeError(name)
        return getattr(self.policy, name)

    def __setattr__(self, name: str, value: Any) -> None:
        setattr(self.policy, name, value)

    def __reduce__(self) -> tuple:
        return type(self), (self.policy, self.n_obs)

    def __repr__(self) -> str:
        return f"checked({self.policy!r})"


def checked(policy: Any, env: Any) -> CheckedPolicy:
    """``policy`` (acting on ``env``'s observations) with its ``predict`` arguments checked."""
    return (
        policy
        if isinstance(policy, CheckedPolicy)
        else CheckedPolicy(policy, observation_size(env))
    )
