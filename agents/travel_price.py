"""The valve-travel budget as a constraint in training: a price on travel that a Lagrange
multiplier sets, instead of a fixed charge.

The leaderboard admits a policy whose valve travel is at most ``TRAVEL_BUDGET`` (2x) the
industrial reference's (agents/stats.py). A fixed charge on travel either leaves the
agent over budget or teaches it to leave the valves alone (measured: tenfold the default
charge ended at 0.7-1.4x). Here the training reward is the scored reward less
``price * travel`` of each step, and after every rollout the price follows the travel
rate of the policy that will be scored, against ``target`` times the reference's (dual
ascent on the constraint ``travel <= target * reference``, in log space so that the price
stays positive)::

    price <- clip(price * exp(rate * (ratio / target - 1)), PRICE_MIN, PRICE_MAX)

``ratio`` is the travel per second over the reference's of the policy's deterministic
action along the rollout's states (for PPO, read from its rollout buffer): the scored
policy acts deterministically, and the rollout's own travel is mostly exploration
(measured on the FSH: 8x the reference's before training against 0.2-1.8x for the
deterministic policy; a price on it rose to its bound and the agent froze the valve).
Off-policy algorithms (SAC, TD3) collect a step at a time: their price moves every
:data:`OFF_POLICY_EVERY` transitions, on the travel of the scored policy in closed loop
(:func:`travel_probe`: :data:`PROBE_EPISODES` episodes of the ``random`` scenario, new
seeds each time). Read along the states of their exploring rollouts instead, as for PPO,
it was 10 to 20 times what the same policy moved in closed loop on the four boilers
(TD3 with position actions: 2.7-4 times the reference's along the replay buffer's
states against 0.17-0.27 times on the validation episodes, SupercriticalFSH and
DrumBoilerSH): an actor that acts on the valve openings it observes follows the noise
that moved them. An on-policy entry may read its travel in closed loop too
(``price_probe_every``: the price then moves at the first rollout's end after every that
many transitions). Their replay buffer holds the scored reward and charges the
price as it is when a batch is sampled (:class:`PricedReplayBuffer`): a charge made at
collection would stay in the buffer long after the price moved, so that the critic would
learn a mixture of old prices and the price would overshoot (measured with TD3 on
Cascade300MW: it rose to its bound of 100 while the agent's travel stayed 2-4x the
reference's, then the agent froze the valve). ``target``
is below the budget (:data:`TARGET`, the tuner's margin, agents/tuning_terms.py) because
travel on unseen scenarios spreads about the training travel.

:class:`VecTravelPrice` (an SB3 ``VecEnvWrapper`` directly over the env, where actions are
valve positions) charges the price and measures the rollout's travel;
:func:`price_callback` updates the price at the end of each rollout. The price is in
units of the reward per full valve stroke; the scored reward's own charge (``w_move``)
stays in the reward.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from stable_baselines3.common.buffers import ReplayBuffer
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvWrapper

from agents.tuning_terms import TUNING_TRAVEL_BUDGET
from agents.validation import validate
from baselines.loops import observation_layout

#: Training travel target (multiple of the reference's travel rate): the tuner's.
TARGET = TUNING_TRAVEL_BUDGET
#: Bounds and step (per rollout, log space) of the price.
PRICE_MIN, PRICE_MAX = 0.01, 100.0
RATE = 0.1


class VecTravelPrice(VecEnvWrapper):
    """Charges ``price`` per unit of valve travel and measures the travel rate (module
    docstring).

    Args:
        venv: The VecEnv to wrap: its observations must be the env's raw ones.
        env: The native vector env under it (observation layout and valves).
        reference_rate: The reference's travel per second (the budget's unit).
        price: The starting price.
    """

    def __init__(self, venv: VecEnv, env: Any, reference_rate: float, price: float) -> None:
        #: Whether the rewards it returns carry the charge (False: a replay buffer charges
        #: them when it samples, :func:`price_replay`).
        self.charge = True
        if not (np.isfinite(reference_rate) and reference_rate > 0):
            raise ValueError(f"reference travel rate must be > 0, got {reference_rate!r}")
        if not (np.isfinite(price) and PRICE_MIN <= price <= PRICE_MAX):
            raise ValueError(f"travel price must be in [{PRICE_MIN}, {PRICE_MAX}], got {price!r}")
        super().__init__(venv)
        names, scale, center = observation_layout(env)
        self.i_valve = np.array([names.index(v) for v in env.unwrapped.plant.valves])
        self.v_scale, self.v_center = scale[self.i_valve], center[self.i_valve]
        self.dt = float(env.unwrapped.plant.dt_s)
        self.reference_rate = float(reference_rate)
        self.price = float(price)
        self._last: np.ndarray | None = None
        self._travel, self._steps = 0.0, 0

    def opening(self, obs: np.ndarray) -> np.ndarray:
        """The valves' openings in (raw, possibly memory-extended) observations ``obs``."""
        return np.asarray(obs)[..., self.i_valve] * self.v_scale + self.v_center

    def reset(self) -> np.ndarray:
        obs = self.venv.reset()
        self._last = self.opening(obs)
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self.venv.step_async(actions)

    def step_wait(self):
        obs, rew, dones, infos = self.venv.step_wait()
        now = self.opening(obs)
        end = now.copy()
        for b in np.flatnonzero(dones):  # an ended row's move is to its final opening
            end[b] = self.opening(infos[b]["terminal_observation"])
        move = np.abs(end - self._last).sum(axis=1)
        self._last = now
        self._travel += float(move.sum())
        self._steps += move.size
        if self.charge:
            rew = rew - self.price * move
        return obs, np.asarray(rew, dtype=np.float32), dones, infos

    def ratio(self) -> float:
        """Travel per second since the last call over the reference's (then restarts)."""
        rate = self._travel / max(self._steps * self.dt, 1e-9)
        self._travel, self._steps = 0.0, 0
        return rate / self.reference_rate

    def update(self, ratio: float | None = None, target: float = TARGET) -> tuple[float, float]:
        """Move the price on ``ratio`` (default: the rollout's own travel since the last
        update, :meth:`ratio`); (ratio, new price)."""
        r = self.ratio() if ratio is None else float(ratio)
        self.price = float(
            np.clip(self.price * np.exp(RATE * (r / target - 1.0)), PRICE_MIN, PRICE_MAX)
        )
        return r, self.price


def policy_travel(
    model: Any, max_move: float | None, alpha: float | None = None, expand: np.ndarray | None = None
) -> float | None:
    """Valve travel per decision of ``model``'s deterministic action along the states of its
    last rollout (PPO's rollout buffer; None without one). Position actions move
    the valves by half the change of the action (actions in [-1, 1]), incremental ones by
    ``max_move`` times the action, filtered ones (``alpha``: the output filter's gain per
    decision, agents/moves.py ``LowPassState``) by the change of the filtered position,
    restarted at each episode's first action; a row's first step of an episode does not
    count. ``expand``: the action index of each valve where valves are tied
    (agents/moves.py ``tie_map``), None for one action per valve."""
    import torch

    buf = getattr(model, "rollout_buffer", None)
    if buf is None or not getattr(buf, "full", False):
        return None
    obs, starts = buf.observations, buf.episode_starts  # (steps, rows, n); (steps, rows)
    with torch.no_grad():
        x = torch.as_tensor(
            obs.reshape(-1, obs.shape[-1]), dtype=torch.float32, device=model.device
        )
        a = model.policy._predict(x, deterministic=True).cpu().numpy()
    a = np.clip(a.reshape(*obs.shape[:2], -1), -1.0, 1.0)
    if expand is not None:
        a = a[..., expand]
    if max_move is not None:
        return float(max_move * np.abs(a).sum(axis=-1).mean())
    if alpha is not None:  # the filter's output along each row, from its first position
        p, u = 0.5 * (a + 1.0), np.empty_like(a)
        u[0] = p[0]
        for k in range(1, len(p)):
            fresh = starts[k].astype(bool)
            u[k] = np.where(fresh[:, None], p[k], u[k - 1] + alpha * (p[k] - u[k - 1]))
        a = 2.0 * u - 1.0
    move = 0.5 * np.abs(np.diff(a, axis=0)).sum(axis=-1)  # (steps - 1, rows)
    counts = starts[1:] == 0  # a move into a new episode is not a move
    return float(move[counts].mean()) if counts.any() else 0.0


class PricedReplayBuffer(ReplayBuffer):
    """SB3's replay buffer, holding the scored reward of each transition, whose samples are
    charged the travel price of ``price`` at the time they are drawn: the reward less
    ``price`` times the valves' travel from the observation to the next (a decision's,
    when actions repeat: a held position, move or filter target moves each valve one way
    within it, so that is its travel). SB3's sampling otherwise (uniform over the stored
    transitions and the rows, normalization by the VecNormalize it is given).

    Args:
        *args, **kwargs: SB3's ``ReplayBuffer`` arguments (``optimize_memory_usage``
            refused: next observations are read from their own array).
        price: The wrapper whose price and observation layout count.
    """

    def __init__(self, *args: Any, price: VecTravelPrice, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        if self.optimize_memory_usage:
            raise ValueError("a priced replay buffer needs optimize_memory_usage=False")
        self.price = price

    def _get_samples(self, batch_inds: np.ndarray, env: Any = None) -> Any:
        from stable_baselines3.common.type_aliases import ReplayBufferSamples

        # the global generator, as SB3 samples (seeded by the model's set_random_seed)
        rows = np.random.randint(0, high=self.n_envs, size=(len(batch_inds),))  # noqa: NPY002
        obs = self.observations[batch_inds, rows, :]
        nxt = self.next_observations[batch_inds, rows, :]
        travel = np.abs(self.price.opening(nxt) - self.price.opening(obs)).sum(axis=-1)
        reward = self.rewards[batch_inds, rows] - self.price.price * travel
        done = self.dones[batch_inds, rows] * (1.0 - self.timeouts[batch_inds, rows])
        data = (
            self._normalize_obs(obs, env),
            self.actions[batch_inds, rows, :],
            self._normalize_obs(nxt, env),
            done.reshape(-1, 1),
            self._normalize_reward(reward.reshape(-1, 1), env),
        )
        return ReplayBufferSamples(*tuple(map(self.to_torch, data)))


def price_replay(model: Any, price: VecTravelPrice) -> None:
    """Give the off-policy ``model`` (before it learns) a :class:`PricedReplayBuffer` of its
    buffer's size and spaces, and make ``price`` return the scored reward."""
    if model.replay_buffer.size():
        raise ValueError("price_replay: the model's replay buffer holds transitions already")
    model.replay_buffer = PricedReplayBuffer(
        model.buffer_size,
        model.observation_space,
        model.action_space,
        device=model.device,
        n_envs=model.n_envs,
        optimize_memory_usage=model.optimize_memory_usage,
        price=price,
        **(model.replay_buffer_kwargs or {}),
    )
    price.charge = False


#: Transitions between two price updates of an off-policy algorithm, whose rollouts are a
#: step or a few: a PPO rollout's (512 steps of 8 envs).
OFF_POLICY_EVERY = 4096
#: Episodes of each closed-loop travel probe (:func:`travel_probe`), and the first seed of
#: the probes (probe k runs seeds PROBE_SEED + PROBE_EPISODES k + i, apart from the
#: validation's and the training's).
PROBE_EPISODES = 4
PROBE_SEED = 2_000_000


def travel_probe(env_id: str, policy: Any, k: int, reference_rate: float) -> float:
    """The travel per second of ``policy`` (the scored one) over ``reference_rate`` (the
    reference's), in closed loop on :data:`PROBE_EPISODES` episodes of the ``random``
    scenario, the k-th probe's seeds (a measurement cost of about 0.1 CPU s per episode
    and 4,096 transitions)."""
    seed = PROBE_SEED + PROBE_EPISODES * k
    return validate(env_id, policy, n=PROBE_EPISODES, seed=seed)["travel_per_s"] / reference_rate


def price_callback(
    wrapper: VecTravelPrice,
    log: list,
    max_move: float | None = None,
    alpha: float | None = None,
    expand: np.ndarray | None = None,
    repeat: int = 1,
    probe: Any = None,
    every: int = OFF_POLICY_EVERY,
) -> Any:
    """SB3 callback: at each rollout's end, :meth:`VecTravelPrice.update` on the travel of
    the policy's deterministic action (:func:`policy_travel`, per decision of ``repeat``
    control intervals, agents/repeat.py; ``alpha``: the filter's gain per decision; the
    rollout's own travel where the algorithm keeps no rollout buffer), appending
    ``(timesteps, ratio of the policy, ratio of the rollout, price)`` to ``log``. With
    ``probe`` (update k -> the scored policy's travel ratio in closed loop,
    :func:`travel_probe`: an off-policy algorithm's, or an on-policy entry's with
    ``price_probe_every``) the price moves at the first rollout's end after every
    ``every`` transitions, on that."""
    from stable_baselines3.common.callbacks import BaseCallback

    class Price(BaseCallback):
        last = 0

        def _on_step(self) -> bool:
            return True

        def _on_rollout_end(self) -> None:
            if probe is not None:
                if self.num_timesteps - self.last < every:
                    return
                self.last = self.num_timesteps
            rollout = wrapper.ratio()
            if probe is not None:
                own = probe(len(log))
            else:
                per_step = policy_travel(self.model, max_move, alpha, expand)
                own = (
                    rollout
                    if per_step is None
                    else per_step / (wrapper.dt * repeat) / wrapper.reference_rate
                )
            r, p = wrapper.update(own)
            log.append((self.num_timesteps, r, rollout, p))

    return Price()


__all__ = [
    "OFF_POLICY_EVERY",
    "PROBE_EPISODES",
    "PROBE_SEED",
    "TARGET",
    "PricedReplayBuffer",
    "VecTravelPrice",
    "policy_travel",
    "price_callback",
    "price_replay",
    "travel_probe",
]
