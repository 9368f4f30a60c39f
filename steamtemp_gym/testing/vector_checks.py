"""The vector env equals the single env, in every autoreset mode it supports.

The reference is Gymnasium's own ``SyncVectorEnv`` over single envs in the same autoreset
mode, seeded as Gymnasium seeds it (sub-env i gets ``seed + i``): observations, rewards,
flags and every ``info`` entry with its ``_key`` mask (``final_obs`` / ``final_info`` in
SAME_STEP) must be identical, bit for bit, through autoresets, a partial reset
(``reset(options={"reset_mask": ...})``) and, in DISABLED mode, the caller's resets.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, SyncVectorEnv, VectorEnv

from steamtemp_gym.envs import vector_env
from steamtemp_gym.scenarios import Scenario
from steamtemp_gym.testing.subjects import CheckSkipped, EnvTarget, env_check

N_ENVS, SEED, STEPS = 3, 11, 30
#: Steps of the short scenario (so every sub-env ends and restarts during the check).
EPISODE_STEPS = 12


def autoreset_modes() -> tuple[AutoresetMode, ...]:
    """The autoreset modes the native vector env declares (NEXT_STEP if it declares none)."""
    return tuple(getattr(vector_env, "AUTORESET_MODES", (AutoresetMode.NEXT_STEP,)))


def short_scenario(dt_s: float, steps: int = EPISODE_STEPS) -> Scenario:
    """A scenario of ``steps`` control intervals with a load ramp, a heat step and noise."""
    return Scenario(
        name="short",
        duration_s=steps * dt_s,
        load=((0.0, 0.9), (steps * dt_s, 0.85)),
        heat_absorption_bias=((0.0, 0.0), (3 * dt_s, 0.03)),
        noise_std_C=0.5,
        heat_absorption_noise_std=0.02,
        heat_absorption_noise_tau_s=60.0,
    )


def native_vector_env(target: EnvTarget, n: int, mode: AutoresetMode, **options: Any) -> VectorEnv:
    """The env's native vector env in ``mode`` (the mode is passed only where the vector env
    declares AUTORESET_MODES; before that it has NEXT_STEP only)."""
    if hasattr(vector_env, "AUTORESET_MODES"):
        options["autoreset_mode"] = mode
    return target.make_vec(n, **options)


def reference_vector_env(target: EnvTarget, n: int, mode: AutoresetMode, **options: Any):
    """Gymnasium's SyncVectorEnv over n single envs of ``target`` in ``mode``."""
    return SyncVectorEnv([functools.partial(target.make, **options)] * n, autoreset_mode=mode)


def _same(x: Any, y: Any) -> bool:
    if isinstance(x, dict) or isinstance(y, dict):
        return isinstance(x, dict) and isinstance(y, dict) and not _info_differences(x, y, "")
    return np.array_equal(np.asarray(x), np.asarray(y))


def _info_differences(got: dict, ref: dict, where: str) -> list[str]:
    """What differs between two vector infos: keys, masks, values of the masked rows."""
    keys = {k for k in ref if not k.startswith("_")}
    other = {k for k in got if not k.startswith("_")}
    if keys != other:
        return [f"info keys {sorted(other)} != reference {sorted(keys)} {where}"]
    out = []
    for k in sorted(keys):
        mask = np.asarray(ref["_" + k])
        if not np.array_equal(np.asarray(got.get("_" + k)), mask):
            out.append(f"info['_{k}'] {got.get('_' + k)} != reference {mask} {where}")
        elif isinstance(ref[k], dict):
            out += _info_differences(got[k], ref[k], f"{where} in info[{k!r}]")
        else:
            out += [
                f"info[{k!r}][{i}] = {got[k][i]!r} != reference {ref[k][i]!r} {where}"
                for i in np.flatnonzero(mask)
                if not _same(got[k][i], ref[k][i])
            ]
    return out


def compare_vector_envs(
    vec: VectorEnv, ref: VectorEnv, mode: AutoresetMode, steps: int = STEPS, seed: int = SEED
) -> int:
    """Step ``vec`` and ``ref`` with the same random actions and compare everything.

    A partial reset of sub-env 1 at step 3 puts the sub-envs' episodes out of phase. In
    DISABLED mode ended sub-envs are reset by ``reset(options={"reset_mask": ended})``.
    Returns the number of episode ends seen; raises AssertionError at the first difference.
    """
    name = getattr(mode, "name", mode)

    def compare(got: tuple, want: tuple, where: str) -> None:
        labels = ("observations", "rewards", "terminated", "truncated")
        for label, g, w in zip(labels, got[:-1], want[:-1], strict=False):
            assert np.array_equal(g, w), f"{label} {g} != reference {w} {where}"
        diffs = _info_differences(got[-1], want[-1], where)
        assert not diffs, "; ".join(diffs[:3])

    n = vec.num_envs
    compare(vec.reset(seed=seed), ref.reset(seed=seed), f"(mode {name}, reset(seed={seed}))")
    rng = np.random.default_rng(0)
    endings = 0
    for k in range(1, steps + 1):
        where = f"(mode {name}, seed {seed}, actions rng 0, step {k})"
        a = rng.uniform(-1, 1, size=vec.action_space.shape).astype(np.float32)
        got, want = vec.step(a), ref.step(a)
        compare(got, want, where)
        ended = np.logical_or(want[2], want[3])
        endings += int(ended.sum())
        mask = np.zeros(n, dtype=bool)
        if k == 3:
            mask[1] = True
        if mode == AutoresetMode.DISABLED:
            mask |= ended
        if mask.any():
            opts = {"reset_mask": mask}
            compare(
                vec.reset(options=dict(opts)),
                ref.reset(options=dict(opts)),
                f"{where}, reset(options={{'reset_mask': {mask.tolist()}}})",
            )
    return endings


@env_check
def check_vector_env_matches_single_env(target: EnvTarget, quick: bool = False) -> None:
    """The native vector env equals Gymnasium's SyncVectorEnv over single envs, bit for bit,
    in every autoreset mode it declares (module docstring)."""
    if not target.has_native_vector_env:
        raise CheckSkipped("no native vector env (register an id with a vector_entry_point)")
    options = {"scenario": short_scenario(target.make().unwrapped.plant.dt_s)}
    for mode in autoreset_modes():
        vec = native_vector_env(target, N_ENVS, mode, **options)
        declared = vec.metadata.get("autoreset_mode")
        assert declared == mode, f"asked for autoreset mode {mode}, the env declares {declared}"
        endings = compare_vector_envs(
            vec, reference_vector_env(target, N_ENVS, mode, **options), mode
        )
        assert endings >= N_ENVS, f"mode {mode.name}: only {endings} episode ends in {STEPS} steps"
