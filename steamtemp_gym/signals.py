"""Names, units and scaling of observation and action entries.

``env.unwrapped.signals`` is a :class:`Signals`: ``observation`` and ``action``
tuples of :class:`~steamtemp_gym.plants.base.Signal` (name, unit, center,
scale). An observation entry is ``(value - center) / scale``, clipped to
``[-OBS_LIMIT, OBS_LIMIT]`` (a transmitter's range); an action entry a in
[-1, 1] commands the actuator to opening (a + 1) / 2.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from steamtemp_gym.plants.base import Plant, Signal

OBS_LIMIT = 5.0
T0_K = 20.0  # normalizing temperature of Sagara et al. 1998


@dataclass(frozen=True)
class Signals:
    """Description of every observation and action entry."""

    observation: tuple[Signal, ...]
    action: tuple[Signal, ...]

    def decode(self, obs: np.ndarray) -> dict[str, np.ndarray | float]:
        """Physical values (engineering units) of an observation (or a batch of them)."""
        obs = np.asarray(obs, dtype=np.float64)
        out = {}
        for j, s in enumerate(self.observation):
            v = obs[..., j] * s.scale + s.center
            out[s.name] = float(v) if v.ndim == 0 else v
        return out

    def decode_action(self, action: np.ndarray) -> dict[str, np.ndarray | float]:
        """Actuator commands (openings in [0, 1]) of an action."""
        a = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)
        return {s.name: (a[..., j] + 1.0) * 0.5 for j, s in enumerate(self.action)}


def for_plant(plant: Plant) -> Signals:
    """Signals of a plant: its observed outputs, then setpoint, control error and load demand."""
    sp = plant.setpoint_C
    obs = tuple(s for s in plant.outputs if s.observed) + (
        Signal("setpoint_C", "C", sp, T0_K, description="main-steam temperature setpoint"),
        Signal("error_K", "K", 0.0, T0_K, description="setpoint minus measured outlet temperature"),
        Signal("load_demand", "1", 0.75, 0.25, description="unit load demand, fraction of rated"),
    )
    return Signals(observation=obs, action=plant.actions)
