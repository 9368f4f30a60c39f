"""The condensed QP of the bias MPC of baselines/mpc_evarx.py (``mpc_evarx``, ``mpc_arx``):
eq. (21)-(22) of Toyoda and Wada 1999 (docs/references.md) over the bias moves, and its
OSQP solvers.

Solver: OSQP (Stellato et al. 2020), one solver per row, set up afresh at the row's episode
start. Sparse P and A have a fixed pattern and their values are updated per solve; each
solve is warm-started from the row's previous solution and starts from the same rho
(adaptive rho on, adapted every ``OSQP_SETTINGS['adaptive_rho_interval']`` iterations, a
count rather than OSQP's default time-based rule). An OSQP object carries state from solve
to solve beyond these (measured: the same inputs give moves 5e-18 apart after another
row's solve), so with a solver per row a row's result does not depend on the other rows or
on earlier episodes (batched == single, bit for bit). ``policy.stats``: solves, iterations
and solve times per solve, fallbacks by reason.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

MOVE_STEPS = (0, 1, 2, 4, 8, 16)
#: knob start values (all chosen: the paper gives the form of eq. 21-22, no values); the
#: default of each knob is the benchmark's stored tuning (baselines/tuned/mpc_<model>.json)
DEFAULTS = {
    "move_weight": 0.05,
    "bias_weight": 0.1,
    "secondary_weight": 1.0,
    "y_max_K": 10.0,
    "move_limit": 0.02,
    "b_max": 0.2,
}
RHO_SLACK, RHO_SLACK_L = 1e3, 1e2
OSQP_SETTINGS = {
    "verbose": False,
    "adaptive_rho": True,
    "adaptive_rho_interval": 25,
    "rho": 0.1,
    "eps_abs": 1e-5,
    "eps_rel": 1e-5,
    "max_iter": 4000,
    "polishing": True,
    "warm_starting": True,
}


def _pattern(M: sp.csc_matrix) -> tuple[np.ndarray, np.ndarray]:
    """(row, column) of every stored entry of M in CSC order."""
    M = M.tocsc()
    M.sort_indices()
    return M.indices.copy(), np.repeat(np.arange(M.shape[1]), np.diff(M.indptr))


class BiasQP:
    """The condensed MPC QP of one plant: sparsity fixed at construction, values updated.

    Args:
        n_out: Controlled outputs.
        n_act: Biased actuators.
        N: Horizon in model intervals.
        rates: Largest bias move per model interval, per actuator (stroke).
        weights: The knobs (``DEFAULTS``' keys).
    """

    def __init__(
        self,
        n_out: int,
        n_act: int,
        N: int,
        rates: np.ndarray,
        weights: dict[str, float] | None = None,
    ) -> None:
        import osqp

        self.w = {**DEFAULTS, **(weights or {})}
        self.N, self.n_out, self.n_act, self.M = N, n_out, n_act, len(MOVE_STEPS)
        self.q = np.array([1.0] + [self.w["secondary_weight"]] * (n_out - 1))
        self.nv = nv = self.M * n_act
        self.nz = nv + n_out
        self.pts = np.arange(4, N, 5)
        self.rates = np.asarray(rates, float)
        # the moves' cumulative sums: at the move instants (L) and at every point (Cb)
        self.L = np.kron(np.tril(np.ones((self.M, self.M))), np.eye(n_act))
        on = (np.arange(N)[:, None] >= np.array(MOVE_STEPS)[None]).astype(float)
        self.Cb = np.kron(on, np.eye(n_act))  # (N n_act, nv)
        self.ns = len(self.pts) * n_out
        self.E = np.kron(np.ones((len(self.pts), 1)), np.eye(n_out))
        P = np.zeros((self.nz, self.nz))
        P[:nv, :nv], P[nv:, nv:] = 1.0, np.eye(n_out)
        P = sp.triu(sp.csc_matrix(P), format="csc")
        A = sp.csc_matrix(self._A(np.ones((self.ns, nv))))
        self.P_idx, self.A_idx = _pattern(P), _pattern(A)
        self.nc = A.shape[0]
        self._setup = {
            "P": P,
            "q": np.zeros(self.nz),
            "A": A,
            "l": -np.ones(self.nc),
            "u": np.ones(self.nc),
            **OSQP_SETTINGS,
        }
        self._osqp = osqp.OSQP
        #: One solver per row, set up afresh when its episode starts (:meth:`restart`): an
        #: OSQP object carries state from solve to solve, so a shared one would make a
        #: row's result depend on the rows solved before it.
        self.solvers: dict[int, Any] = {}

    def restart(self, row: int) -> None:
        """Row ``row`` starts an episode: its next solve uses a new solver."""
        self.solvers.pop(row, None)

    def _solver(self, row: int) -> Any:
        if row not in self.solvers:
            s = self._osqp()
            s.setup(**self._setup)
            self.solvers[row] = s
        return self.solvers[row]

    def _A(self, Ssub: np.ndarray) -> np.ndarray:
        """Constraint matrix: bias bounds, move bounds, soft outputs (two sides), slacks."""
        nv, no = self.nv, self.n_out
        return np.vstack(
            [
                np.hstack([self.L, np.zeros((nv, no))]),
                np.hstack([np.eye(nv), np.zeros((nv, no))]),
                np.hstack([Ssub, -self.E]),
                np.hstack([Ssub, self.E]),
                np.hstack([np.zeros((no, nv)), np.eye(no)]),
            ]
        )

    def matrices(self, G: np.ndarray) -> dict[str, np.ndarray]:
        """Dynamic matrix S, the values of P and A, and the weights for step responses G."""
        N, no, nv = self.N, self.n_out, self.nv
        S = np.zeros((N, no, self.M, self.n_act))
        for i, t0 in enumerate(MOVE_STEPS):
            S[t0:, :, i, :] = G[: N - t0]
        S = S.reshape(N * no, nv)
        sq = np.tile(np.sqrt(self.q), N)[:, None]
        g2 = np.abs(G).max((0, 1)) ** 2 + 1e-9
        R = np.tile(self.w["move_weight"] * N * g2, self.M)
        Rabs = np.tile(self.w["bias_weight"] * g2, N)
        H = np.zeros((self.nz, self.nz))
        H[:nv, :nv] = 2.0 * (
            (sq * S).T @ (sq * S) + np.diag(R) + self.Cb.T @ (Rabs[:, None] * self.Cb)
        )
        H[nv:, nv:] = 2.0 * RHO_SLACK * np.eye(no)
        Ssub = S.reshape(N, no, nv)[self.pts].reshape(-1, nv)
        return {"S": S, "Rabs": Rabs, "Px": H[self.P_idx], "Ax": self._A(Ssub)[self.A_idx]}

    def solve(
        self,
        mats: dict[str, np.ndarray],
        e_free: np.ndarray,
        b_last: np.ndarray,
        lo_b: np.ndarray,
        hi_b: np.ndarray,
        warm: tuple,
        row: int = 0,
    ) -> tuple:
        """Bias moves (M, n_act) for the free tracking error e_free = r - y_free (N, n_out),
        the current bias b_last and its bounds [lo_b, hi_b] (b_last inside them), solved by
        row ``row``'s solver.

        Returns (solved, moves, (x, y) for the next warm start, OSQP info).
        """
        nv, no = self.nv, self.n_out
        qe = (e_free * self.q).reshape(-1)
        q = np.concatenate(
            [
                -2.0 * mats["S"].T @ qe
                + 2.0 * self.Cb.T @ (mats["Rabs"] * np.tile(b_last, self.N)),
                np.full(no, RHO_SLACK_L),
            ]
        )
        esub = e_free[self.pts].reshape(-1)
        inf = np.full(self.ns, np.inf)
        rate = np.tile(self.rates, self.M)
        ym = self.w["y_max_K"]
        lo = np.concatenate([np.tile(lo_b - b_last, self.M), -rate, -inf, esub - ym, np.zeros(no)])
        hi = np.concatenate(
            [np.tile(hi_b - b_last, self.M), rate, esub + ym, inf, np.full(no, np.inf)]
        )
        s = self._solver(row)
        s.update(q=q, l=lo, u=hi, Px=mats["Px"], Ax=mats["Ax"])
        s.update_settings(rho=OSQP_SETTINGS["rho"])
        s.warm_start(x=warm[0], y=warm[1])
        res = s.solve(raise_error=False)
        ok = res.info.status == "solved" and np.all(np.isfinite(res.x))
        return ok, res.x[:nv].reshape(self.M, -1), (res.x.copy(), res.y.copy()), res.info
