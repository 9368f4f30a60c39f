"""Stand-ins the agent tests share."""

from __future__ import annotations

import numpy as np


class Model:
    """A stand-in model: a fixed pseudo-random action sequence, whatever it observes, for
    ``n_rows`` rows at a time; ``calls`` counts its decisions."""

    def __init__(self, n_act: int, n_rows: int, seed: int = 0) -> None:
        self.rng = np.random.default_rng(seed)
        self.shape = (n_rows, n_act)
        self.calls = 0

    def predict(self, x, deterministic=True):
        assert len(x) == self.shape[0]
        self.calls += 1
        return self.rng.uniform(-1.5, 1.5, self.shape).astype(np.float32), None
