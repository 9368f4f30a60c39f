"""Offset-free linear MPC on the plant's own linearized physics (``mpc_linear``).

Sources: offset-free estimation and target calculation as in Pannocchia and Rawlings 2003
and Muske and Badgwell 2002 (docs/references.md): the model is augmented with integrating
disturbance states, as many as measured outputs, estimated by a Kalman filter; a steady
target is computed from the estimated disturbances and the regulator tracks it, so a
constant disturbance leaves no offset. The QP is solved by OSQP (Stellato et al. 2020),
the model reduced by square-root balanced truncation (Moore 1981; Laub et al. 1987).

Model and estimation (baselines/mpc_linear_design.py): ``Plant.linearize`` and
``Plant.linearize_disturbances`` at ``GRID_LOADS`` = 40, 60, 80, 100 % load, reduced by
balanced truncation to one basis and augmented with integrating disturbances (the
heat-absorption bias and an output disturbance on every observed signal but the
main-steam thermocouple) estimated by a steady-state Kalman filter. The local model at
load L is the linear interpolation of the neighbouring grid models at L rounded to
``LOAD_QUANTUM`` (held outside the grid), its QP matrices built once per rounded load;
the operating point is interpolated at the exact load, and the state estimate is
shifted by its change when the load moves. Bumpless start: at an episode start the
plant is taken as steady and its disturbances solved from the first observation and
valve openings.

Prediction and target (the horizon's constants in baselines/mpc_linear_design.py). Over a
horizon of HORIZON_T63 times the slowest 63 % time of an actuator's effect on a scored
temperature (clipped to [HORIZON_MIN_S, HORIZON_MAX_S]), read at N_POINTS points; the
measured load rate is assumed to continue RATE_HOLD_S (inside [lowest op load, rated
load]), then the load holds. Target: the steady commands that hold every scored
temperature at its setpoint with the estimated disturbances at the end of that load path,
the least change from the scheduled openings weighted by each actuator's steady effect (on
Benson and MIMO, with more actuators than scored temperatures, the steady split between
the sprays is that of the schedules).

QP (condensed; decision variables: command moves at ``MOVE_T63`` fractions of the 63 %
time, one slack per scored temperature)::

    min sum_j |y_j - r|^2 + sum_i R |du_i|^2 + sum_j S |u_j - u_s|^2 + RHO_SLACK |s|^2
        + RHO_SLACK_L 1's
    s.t. 0 <= u_i <= 1 (valve openings), |du_i| <= rate x interval (the plant's actuator
         rate limits, read from its params; none where the plant has no valve dynamics),
         |y_j - r| <= BAND_K + s at every SOFT_EVERY-th point, s >= 0 (soft bounds)

with weights per K^2 of every scored temperature (the reward weights them alike), R =
MOVE_WEIGHT N_POINTS g^2 and S = U_WEIGHT g^2, g the actuator's steady effect (K per
stroke) at that load. MOVE_WEIGHT is the move suppression, per plant (declared on the plant
class, ``commissioning["mpc_linear"]["move_weight"]``): the smallest of
``MOVE_WEIGHT_LADDER`` = 0.01, 0.003, 0.001 whose valve travel stays within
``TRAVEL_RATIO_MAX`` = 1.7 times that of ``cascade_pi_ff`` on two
commissioning tests (a -5 % heat-absorption step and cascade_pi's feed-forward ramp, both
with the named scenarios' noise; not evaluation scenarios; benchmarks/mpc_linear_tuning.py
measures them: 0.01 on the drum unit, whose travel at 0.003 is 1.79 times the reference's
on the heat step, 0.003 on the FSH, whose travel at 0.001 is 2.08 times, 0.001 on the
others, at 0.5-1.3 times).

Robustness: the filter's assumed thermocouple noise (``filter_noise_K``, by default the
named scenarios' 0.25 K) and heat-absorption variability (``heat_std``) are knobs. A filter
that follows each reading closely makes the loop of estimate and target oscillate on a
unit faster or of higher gain than its model; a detuned one trusts the model's prediction
more. The design rule (baselines/mpc_linear_robustness.py, ``robust=True``): the smallest
assumed noise at or above the given one with which every mode of the linear closed loop
keeps a damping ratio of 0.02 on every vertex of the documented parameter ranges, at
35-100 % load. The benchmark's tuner chooses the knobs, the rule applied, under its
robustness check on the corner plants (docs/baseline_tuning.md).

OSQP, one solver per row (set up at its episode start, so a row acts the same alone or in
a batch and a reset forgets everything), warm-started from the row's last solution and
started from the same rho each solve (adaptive rho on a fixed iteration count), matrices
updated only when the rounded load changes. The first move is applied (rate-limited and
clipped); a solve that does not succeed within 400 iterations holds the valves
(``stats["failures"]``). A call whose estimate comes out non-finite (a non-finite
observation) raises ValueError and leaves the policy's state as it was.

Measured: docs/baselines/mpc_linear.md and docs/robustness.md. Offset after a constant +5 %
heat-absorption step (tests/test_mpc_linear.py): <= 5e-4 K on every plant, 1-5 K with
``disturbance_model=False``.
"""

from __future__ import annotations

import json
from types import SimpleNamespace
from typing import Any

import numpy as np
import scipy.sparse as sp

from baselines import tuning
from baselines.loops import observation_layout, restart_rows
from baselines.mpc_linear_design import (
    GRID_LOADS,
    HEAT_STD,
    NOISE_K,
    design,
    rule_move_weight,
)
from baselines.mpc_linear_robustness import robust_filter_noise
from baselines.tuning import Knob

#: The local model and its QP are those of the load rounded to this (fraction of rated).
LOAD_QUANTUM = 0.01
#: The travel bound the commissioning rule keeps (x cascade_pi_ff).
TRAVEL_RATIO_MAX = 1.7  # the 2x budget less the tuner's margin (docs/baseline_tuning.md)
U_WEIGHT = 0.01


#: Soft output bounds |y - r| <= BAND_K + s (the reward's inner band), their costs.
BAND_K = 5.0
RHO_SLACK, RHO_SLACK_L = 1e2, 1e1
SOFT_EVERY = 4
OSQP_SETTINGS = {
    "verbose": False,
    "adaptive_rho": True,
    "adaptive_rho_interval": 25,
    "rho": 0.1,
    "eps_abs": 1e-6,
    "eps_rel": 1e-6,
    "max_iter": 400,
    "polishing": False,
    "warm_starting": True,
}


# -- the QP of one row ---------------------------------------------------------------------
class QP:
    """OSQP on the condensed QP of one row: a dense pattern fixed at setup, values updated."""

    def __init__(self, H: np.ndarray, A: np.ndarray) -> None:
        import osqp

        nz, nc = H.shape[0], A.shape[0]
        self.P_rc = np.nonzero(np.triu(np.ones((nz, nz))).T)[::-1]  # (rows, cols), CSC order
        self.A_rc = np.nonzero(np.ones((nc, nz)).T)[::-1]
        self.solver = osqp.OSQP()
        self.solver.setup(
            P=sp.csc_matrix((H[self.P_rc], self.P_rc), (nz, nz)),
            q=np.zeros(nz),
            A=sp.csc_matrix((A[self.A_rc], self.A_rc), (nc, nz)),
            l=np.full(nc, -np.inf),
            u=np.full(nc, np.inf),
            **OSQP_SETTINGS,
        )
        self.key: int | None = None
        self.rho_moved = False  # whether the last solve adapted rho away from the setting's
        # the compiled solver behind osqp's wrapper (osqp >= 1.0), called directly: the
        # wrapper's bookkeeping per call (caches for derivatives, a namespace of the info)
        # cost about a tenth of the controller's time; the calls are the wrapper's own
        self.core = getattr(self.solver, "_solver", None)
        self.infty = float(self.solver.constant("OSQP_INFTY"))

    def solve(
        self,
        key: int,
        H: np.ndarray,
        A: np.ndarray,
        g: np.ndarray,
        lo: np.ndarray,
        hi: np.ndarray,
        warm: tuple | None,
    ) -> Any:
        """Solve with the matrices of local model ``key`` (sent only when the key changes),
        from rho and the given warm start: the result depends on the row's data only."""
        c = self.core
        if c is None:  # an osqp without the compiled solver at hand: through the wrapper
            return self._solve_wrapped(key, H, A, g, lo, hi, warm)
        c.update_data_vec(q=g, l=np.maximum(lo, -self.infty), u=np.minimum(hi, self.infty))
        if key != self.key:
            c.update_data_mat(P_x=H[self.P_rc], P_i=None, A_x=A[self.A_rc], A_i=None)
            self.key = key
        if self.rho_moved:  # back to the setting's rho (a new factorization)
            c.update_rho(OSQP_SETTINGS["rho"])
        if warm is not None:
            c.warm_start(warm[0], warm[1])
        c.solve()
        info, sol = c.info, c.solution
        self.rho_moved = info.rho_updates > 0
        return SimpleNamespace(x=sol.x, y=sol.y, info=info)

    def _solve_wrapped(
        self,
        key: int,
        H: np.ndarray,
        A: np.ndarray,
        g: np.ndarray,
        lo: np.ndarray,
        hi: np.ndarray,
        warm: tuple | None,
    ) -> Any:
        """:meth:`solve` through osqp's public wrapper (the same calls)."""
        s = self.solver
        if key != self.key:
            s.update(q=g, l=lo, u=hi, Px=H[self.P_rc], Ax=A[self.A_rc])
            self.key = key
        else:
            s.update(q=g, l=lo, u=hi)
        if self.rho_moved:
            s.update_settings(rho=OSQP_SETTINGS["rho"])
        if warm is not None:
            s.warm_start(x=warm[0], y=warm[1])
        res = s.solve(raise_error=False)
        self.rho_moved = getattr(res.info, "rho_updates", 1) > 0
        return res


# -- the controller ------------------------------------------------------------------------
class MPCLinear:
    """Offset-free linear MPC (see module docstring).

    Args:
        env: The env (or vector env) the policy will act on.
        disturbance_model: Estimate the heat-absorption and output disturbances (the
            offset-free design); False holds them at zero (no offset-free estimation).
        move_weight: Move suppression; u_weight: weight of the steady target;
            filter_noise_K: the thermocouple noise (K) the Kalman filter assumes; heat_std:
            the heat-absorption variability it assumes (the ``KNOBS``; default: the
            benchmark's stored tuning, baselines/tuned/mpc_linear.json, where the plant has
            one, else the commissioning rule's move suppression, U_WEIGHT and the named
            scenarios' noise and disturbance, baselines/mpc_linear_design.py NOISE_K and
            HEAT_STD). A larger filter noise or smaller variability detunes the estimator:
            it trusts the model's prediction more than each new measurement, which keeps the
            loop stable on a unit faster or of higher gain than its model.
        robust: Raise ``filter_noise_K`` to the design rule's (module docstring);
            ``robustness`` holds (the noise used, the least damping ratio, where).
    """

    #: Searched by agents.baseline_tuning from the commissioning rule's values.
    KNOBS = (
        Knob("move_weight", 1e-4, 0.1),
        Knob("u_weight", 1e-3, 1.0),
        Knob("filter_noise_K", NOISE_K, 100 * NOISE_K),
        Knob("heat_std", 1e-3, 0.05),
    )

    @staticmethod
    def knob_defaults(env_id: str) -> dict[str, float]:
        """The commissioning rule's move suppression and U_WEIGHT, and the filter of the
        named scenarios' noise and disturbance."""
        return {
            "move_weight": rule_move_weight(env_id),
            "u_weight": U_WEIGHT,
            "filter_noise_K": NOISE_K,
            "heat_std": HEAT_STD,
        }

    @staticmethod
    def knob_alternatives(env_id: str) -> list[dict[str, float]]:
        """The robust designs the tuner also starts from: the filter detuned to ten times the
        thermocouple noise with a quarter of the heat-absorption variability; the filter
        detuned to twenty times with the least move suppression and steady-target weight
        of the knobs' boxes (a slow estimator with a fast regulator: the estimate no
        longer follows each reading, so the moves need little suppression); and three
        times the commissioning rule's move suppression."""
        rule = rule_move_weight(env_id)
        lo = {k.name: k.lo for k in MPCLinear.KNOBS}
        return [
            {"filter_noise_K": 10.0 * NOISE_K, "heat_std": HEAT_STD / 4.0},
            {
                "filter_noise_K": 20.0 * NOISE_K,
                "heat_std": HEAT_STD / 4.0,
                "move_weight": lo["move_weight"],
                "u_weight": lo["u_weight"],
            },
            {"move_weight": 3.0 * rule},
        ]

    def __init__(
        self,
        env: Any,
        disturbance_model: bool = True,
        move_weight: float | None = None,
        u_weight: float | None = None,
        filter_noise_K: float | None = None,
        heat_std: float | None = None,
        robust: bool = True,
    ) -> None:
        u = env.unwrapped
        plant = u.plant
        base = tuning.stored_or("mpc_linear", plant.id, self.knob_defaults(plant.id))
        given = {
            "move_weight": move_weight,
            "u_weight": u_weight,
            "filter_noise_K": filter_noise_K,
            "heat_std": heat_std,
        }
        k = {name: base[name] if v is None else v for name, v in given.items()}
        for name, v in k.items():
            if not (
                isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v) and v > 0
            ):
                raise ValueError(f"{name} must be a positive finite number, got {v!r}")
        move_weight, u_weight = k["move_weight"], k["u_weight"]
        params = json.dumps(getattr(u, "params_overrides", {}) or {}, sort_keys=True)
        if not isinstance(robust, bool):
            raise ValueError(f"robust must be True or False, got {robust!r}")
        #: (filter noise used, least damping ratio over the vertices, where) of the rule
        self.robustness: tuple[float, float, str] | None = None
        if robust:
            self.robustness = robust_filter_noise(
                type(self), plant.id, params, *(float(k[n]) for n in given)
            )
            k["filter_noise_K"] = self.robustness[0]
        self.d = d = design(plant.id, params, float(k["filter_noise_K"]), float(k["heat_std"]))
        self.estimate_disturbances = bool(disturbance_model)
        self._weights = (float(move_weight), float(u_weight))
        names, self._scale, self._center = observation_layout(env)
        self.n_u = n_u = plant.n_u
        self.i_sp = names.index("setpoint_C")
        self.i_load = names.index("load_demand")
        self.i_valve = [names.index(v) for v in plant.valves]
        self.dt = plant.dt_s
        n_pts, n_mv, n_c = len(d["pts"]), len(d["moves"]), d["n_c"]
        nv = n_mv * n_u
        self.soft = np.arange(SOFT_EVERY - 1, n_pts, SOFT_EVERY)
        n_s = len(self.soft) * n_c
        on = (d["pts"][:, None] > d["moves"][None, :]).astype(float)  # move i acts at point j
        self._Cb = np.kron(on, np.eye(n_u))  # commands at the points per move
        # constraint rows: openings at the moves, moves, soft bounds (two sides), slacks
        self._A0 = np.zeros((2 * nv + 2 * n_s + n_c, nv + n_c))
        self._A0[:nv, :nv] = np.kron(np.tril(np.ones((n_mv, n_mv))), np.eye(n_u))
        self._A0[nv : 2 * nv, :nv] = np.eye(nv)
        Es = np.tile(np.eye(n_c), (len(self.soft), 1))
        self._A0[2 * nv : 2 * nv + n_s, nv:] = -Es
        self._A0[2 * nv + n_s : 2 * nv + 2 * n_s, nv:] = Es
        self._A0[2 * nv + 2 * n_s :, nv:] = np.eye(n_c)
        seg = np.diff(np.append(d["moves"], d["Nh"]))
        seg[0] = 1  # the first move happens in one interval, later ones over their block
        self.max_move = np.kron(seg, d["rates"] * self.dt)
        inf = np.full(n_s, np.inf)
        self._lo0 = np.concatenate(
            [np.zeros(nv), -self.max_move, -inf, np.full(n_s, -BAND_K), np.zeros(n_c)]
        )
        self._hi0 = np.concatenate(
            [np.zeros(nv), self.max_move, np.full(n_s, BAND_K), inf, np.full(n_c, np.inf)]
        )
        self._g0 = np.concatenate([np.zeros(nv), np.full(n_c, RHO_SLACK_L)])
        self._local: dict[int, dict[str, Any]] = {}
        self.stats = {"solves": 0, "iterations": 0, "failures": 0}
        self._rows: list[dict[str, Any] | None] | None = None

    def reset(self) -> None:
        self._rows = None

    def applied(self, action: Any) -> None:
        """Tell the estimator the commands the valves received after this call's
        ``predict`` (env action units, one row per row of that call), when something
        downstream changed them (a residual agent adds its correction): the next time
        update and output prediction use these, so that the disturbance estimates do not
        absorb the correction (a row told its own action is left as it is). The regulator
        still plans from its own last command."""
        if self._rows is None:
            raise ValueError("mpc_linear.applied: no predict call to apply commands to")
        u = np.atleast_2d(np.asarray(action, dtype=np.float64))
        if u.shape != (len(self._rows), self.n_u) or not np.all(np.isfinite(u)):
            raise ValueError(
                f"mpc_linear.applied: expected finite commands of shape "
                f"({len(self._rows)}, {self.n_u}), got shape {u.shape}"
            )
        for st, ab in zip(self._rows, u, strict=True):
            own = (2.0 * st["u"] - 1.0).astype(np.float32)  # the action predict gave
            if not np.array_equal(own, ab.astype(np.float32)):
                st["applied"] = np.clip(0.5 * (ab + 1.0), 0.0, 1.0)

    # -- scheduling ----------------------------------------------------------------------
    def _model(self, L: float) -> tuple[int, dict[str, Any]]:
        """(key, local model): the grid models interpolated at L rounded to LOAD_QUANTUM
        (held outside the grid) and the QP matrices of that model, built once per key."""
        xp = GRID_LOADS
        key = int(round(min(max(L, xp[0]), xp[-1]) / LOAD_QUANTUM))
        m = self._local.get(key)
        if m is not None:
            return key, m
        Lq = key * LOAD_QUANTUM
        i = min(max(int(np.searchsorted(xp, Lq)) - 1, 0), len(xp) - 2)
        a = min(max((Lq - xp[i]) / (xp[i + 1] - xp[i]), 0.0), 1.0)
        g0, g1 = self.d["grid"][i], self.d["grid"][i + 1]
        m = {k: (1.0 - a) * g0[k] + a * g1[k] for k in g0 if k != "f"}
        m["f"] = (g0["f"], g1["f"], a)
        d, Sd = self.d, m["Sd"]
        nv, n_c, n_pts, n_mv = Sd.shape[1], d["n_c"], len(d["pts"]), len(d["moves"])
        gu2 = np.abs(m["Gu"]).max(axis=0) ** 2 + 1e-12  # (K per stroke)^2 at this load
        mw, uw = self._weights
        CbS = 2.0 * self._Cb.T * np.tile(uw * gu2, n_pts)[None, :]
        H = np.zeros((nv + n_c, nv + n_c))
        H[:nv, :nv] = 2.0 * (Sd.T @ Sd + np.diag(np.tile(mw * n_pts * gu2, n_mv))) + CbS @ self._Cb
        H[nv:, nv:] = 2.0 * RHO_SLACK * np.eye(n_c)
        n_s = len(self.soft) * n_c
        Ssoft = Sd.reshape(n_pts, n_c, nv)[self.soft].reshape(n_s, nv)
        A = self._A0.copy()
        A[2 * nv : 2 * nv + n_s, :nv] = Ssoft
        A[2 * nv + n_s : 2 * nv + 2 * n_s, :nv] = Ssoft
        G, Wi = m["Gu"], 1.0 / gu2  # target: least change, weighted by the steady effects
        m.update(
            H=H,
            A=A,
            SdT2=2.0 * Sd.T,
            CbS=CbS,
            Gpinv=Wi[:, None] * (G.T @ np.linalg.inv((G * Wi) @ G.T)),
        )
        self._local[key] = m
        return key, m

    def _op(self, L: float) -> list[np.ndarray]:
        """[xi_op, u_op, ym_op, yc_op] interpolated at load L (held outside the table)."""
        xp, table, c = self.d["op_loads"], self.d["op"], self.d["op_cols"]
        i = min(max(int(np.searchsorted(xp, L)) - 1, 0), len(xp) - 2)
        a = min(max((L - xp[i]) / (xp[i + 1] - xp[i]), 0.0), 1.0)
        row = (1.0 - a) * table[i] + a * table[i + 1]
        return [row[c[k] : c[k + 1]] for k in range(4)]

    def _md(self, y: np.ndarray, ym_op: np.ndarray) -> np.ndarray:
        """The measured disturbance states' deviations from the operating point."""
        rows = self.d["md_rows"]
        return (y[rows] - ym_op[rows]) / self.d["md_gain"]

    # -- one row ---------------------------------------------------------------------------
    def _start(self, y: np.ndarray, L: float, m: dict[str, Any], op: list) -> dict[str, Any]:
        """Row state at an episode start: the plant taken as steady, its disturbances solved
        from the first observation (bumpless)."""
        _, u_op, ym_op, _ = op
        u0 = np.clip(y[self.i_valve], 0.0, 1.0)
        md = self._md(y, ym_op)
        if self.estimate_disturbances:
            rhs = y[: self.d["n_y"]] - ym_op - m["InitU"] @ (u0 - u_op) - m["InitM"] @ md
            qp = np.linalg.solve(m["Init"], rhs)
        else:
            qp = np.zeros(1 + self.d["n_p"])
        xi = m["inv"] @ (m["Bu"] @ (u0 - u_op) + m["bq"] * qp[0] + m["Bmd"] @ md)
        return {
            "z": np.concatenate([xi, qp]),
            "u": u0,
            "L": L,
            "op": op,
            "md": md,
            "warm": None,
            "qp": None,
        }

    def _row(self, st: dict[str, Any] | None, y: np.ndarray) -> dict[str, Any]:
        """The next state of one row (``st`` None: an episode start); ``st`` is not changed."""
        d = self.d
        L = min(max(float(y[self.i_load]), d["op_loads"][0]), d["op_loads"][-1])
        key, m = self._model(L)
        op = self._op(L)
        xi_op, u_op, ym_op, yc_op = op
        r = d["r"]
        if st is None:
            st, rate = self._start(y, L, m, op), 0.0
            z = st["z"]
        else:  # time update over the last interval, the frame moved to this load's op
            rate = (L - st["L"]) / self.dt
            u_in = st.get("applied", st["u"])  # what the valves were commanded (applied())
            known = np.concatenate([u_in - st["op"][1], [rate], st["md"]])
            z = m["Az"] @ st["z"] + m["Bz"] @ known
            z[:r] -= xi_op - st["op"][0]
            feed = m["Dm"] @ (u_in - u_op) + m["DdL"] * (st["L"] - L) + m["Ddr"] * rate
            z = z + m["M"] @ (y[: d["n_y"]] - ym_op - feed - m["Cmz"] @ z)
            if not self.estimate_disturbances:
                z[r:] = 0.0
        md = self._md(y, ym_op)
        # the assumed load path: the measured rate for n_eff steps, then held
        n_eff = d["n_hold"]
        if rate > 0.0:
            n_eff = min(n_eff, int(max(1.0 - L, 0.0) / (rate * self.dt)))
        elif rate < 0.0:
            n_eff = min(n_eff, int(max(L - d["op_loads"][0], 0.0) / (-rate * self.dt)))
        dL_end = rate * self.dt * n_eff
        # target: the steady commands holding the references at the end of the load path
        ref = np.concatenate([[y[self.i_sp]], d["secondary_sp"]])
        b = ref - yc_op - m["Gq"] * z[r] - d["Ec"] @ z[r + 1 :] - m["GL"] * dL_end
        du_ref = self._op(L + dL_end)[1] - u_op
        du_s = du_ref + m["Gpinv"] @ (b - m["Gu"] @ du_ref)
        # free response and the QP
        u_prev = st["u"]
        f0, f1, a = m["f"]
        free = (
            yc_op
            + m["Phi"] @ z
            + m["Gam"] @ (u_prev - u_op)
            + m["Pm"] @ md
            + ((1.0 - a) * f0[n_eff] + a * f1[n_eff]) * rate
        )
        e0 = (free - ref).reshape(-1)
        n_pts, n_c, n_mv = len(d["pts"]), d["n_c"], len(d["moves"])
        nv, n_s = n_mv * self.n_u, len(self.soft) * n_c
        g = self._g0.copy()
        g[:nv] = m["SdT2"] @ e0 + m["CbS"] @ np.tile(u_prev - u_op - du_s, n_pts)
        esoft = e0.reshape(n_pts, n_c)[self.soft].reshape(n_s)
        lo, hi = self._lo0.copy(), self._hi0.copy()
        lo[:nv], hi[:nv] = np.tile(-u_prev, n_mv), np.tile(1.0 - u_prev, n_mv)
        lo[2 * nv + n_s : 2 * nv + 2 * n_s] -= esoft
        hi[2 * nv : 2 * nv + n_s] -= esoft
        qp = st["qp"] or QP(m["H"], m["A"])
        res = qp.solve(key, m["H"], m["A"], g, lo, hi, st["warm"])
        self.stats["solves"] += 1
        self.stats["iterations"] += int(res.info.iter)
        warm = st["warm"]
        if res.info.status in ("solved", "solved inaccurate") and np.all(np.isfinite(res.x)):
            du0, warm = res.x[: self.n_u], (res.x.copy(), res.y.copy())
        else:
            self.stats["failures"] += 1
            du0 = np.zeros(self.n_u)
        lim = self.max_move[: self.n_u]
        u_new = np.clip(u_prev + np.clip(du0, -lim, lim), 0.0, 1.0)
        return {"z": z, "u": u_new, "L": L, "op": op, "md": md, "warm": warm, "qp": qp}

    def predict(self, observation, state=None, episode_start=None, deterministic=True):
        obs = np.atleast_2d(np.asarray(observation, dtype=np.float64))
        y = obs * self._scale + self._center
        n = obs.shape[0]
        fresh = self._rows is None or len(self._rows) != n
        restart = restart_rows(fresh, n, episode_start)
        rows = [None if fresh or restart[b] else self._rows[b] for b in range(n)]
        with np.errstate(invalid="ignore", over="ignore"):  # non-finite rows are refused below
            new = [self._row(rows[b], y[b]) for b in range(n)]
        bad = [
            b
            for b, s in enumerate(new)
            if not (np.all(np.isfinite(s["z"])) and np.all(np.isfinite(s["u"])))
        ]
        if bad:
            raise ValueError(
                f"mpc_linear: non-finite estimate for rows {bad} of the "
                f"observation; the policy's state is unchanged"
            )
        self._rows = new
        u = np.array([s["u"] for s in new])
        action = (2.0 * u - 1.0).astype(np.float32)
        return (action[0] if np.ndim(observation) == 1 else action), None
