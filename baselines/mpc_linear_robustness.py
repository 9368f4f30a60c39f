"""Robust stability of ``mpc_linear`` over the documented plant spread: the linear closed
loop of the MPC (unconstrained), its Kalman filter and a perturbed plant, at the vertices of
the parameter ranges.

A plant engineer commissions the MPC on the model and runs it on a unit whose heat
transfer, metal, firing and thermowells (or, on Cascade300MW, section gains and time
constants) differ from the model's within the documented ranges
(steamtemp_gym/plants/perturb.py ``RANGES``). The estimator is what loses the loop there: at
the named scenarios' thermocouple noise the Kalman filter follows each reading, and on a
unit of higher gain or shorter time constants than its model the loop of estimate and
target oscillates (Cascade300MW, 35-50 % load: a mode of 250-340 s period growing by
0.02-0.2 % per second). The design rule (:func:`worst_damping`, applied by
``MPCLinear``): the filter's assumed noise is the smallest at or above the given one for
which every mode of the linear closed loop keeps a damping ratio of at least
:data:`ZETA_MIN` on every vertex of the ranges (every group at one end of its range; the
model's own parameters elsewhere) at each of :data:`LOADS`.

The loop, in deviations from the steady state of the perturbed plant at load L (constant
load and setpoint; the known load rate and measured disturbances zero)::

    y_k = C x_k + D u_{k-1}                       the plant's observed signals
    z_k = (I - M Cmz)(Az z_{k-1} + Bz u_{k-1}) + M (y_k - Dm u_{k-1})   the filter
    u_k = u_{k-1} + du_k,  du_k = first move of argmin of the QP without its bounds
    x_{k+1} = A x_k + B u_k

with (A, B, C, D) the perturbed plant's own linearization (``Plant.linearize``, the states
its commands reach) and the MPC's matrices those of its local model at L. Within the
bounds (valve strokes, rate limits, the soft temperature band) this is the MPC's own law;
a loop unstable here strokes the valves end to end on that unit.
"""

from __future__ import annotations

import json
from typing import Any

import gymnasium as gym
import numpy as np

from baselines.commissioned import commissioned
from baselines.linear_models import reachable
from steamtemp_gym import plants
from steamtemp_gym.plants import perturb

#: The least damping ratio of every closed-loop mode on every vertex (0.02: an oscillation
#: loses at least 12 % of its amplitude per period).
ZETA_MIN = 0.02
#: Loads of the check (fraction of rated): the bottom of the scenarios' load range to rated.
LOADS = (0.35, 0.5, 0.75, 1.0)
#: The filter's assumed noise is raised by this factor per try, at most ``MAX_STEPS`` times.
NOISE_STEP, MAX_STEPS = 2.0**0.125, 64


def closed_loop(ctrl: Any, plant: Any, load: float) -> np.ndarray:
    """The closed-loop matrix on [x, z, u] (module docstring) of ``ctrl`` (an ``MPCLinear``)
    on ``plant`` at ``load``."""
    d = ctrl.d
    _, m = ctrl._model(load)
    observed = [s.name for s in plant.outputs if s.observed]
    Ap, Bp, Cp, Dp = plant.linearize(load, outputs=observed)
    keep = reachable(Ap, Bp)
    A, B, C, D = Ap[np.ix_(keep, keep)], Bp[keep], Cp[:, keep], Dp
    n_z, n_u, r = m["Az"].shape[0], ctrl.n_u, d["r"]
    nv = len(d["moves"]) * n_u
    first = np.linalg.solve(m["H"][:nv, :nv], np.eye(nv))[:n_u]  # du_0 = -first @ g
    n_pts = len(d["pts"])
    tile = np.tile(np.eye(n_u), (n_pts, 1))
    # filter: z_k = Fz z + Fx x + Fu u
    K = np.eye(n_z) - m["M"] @ m["Cmz"]
    Fz, Fx = K @ m["Az"], m["M"] @ C
    Fu = K @ m["Bz"][:, :n_u] + m["M"] @ (D - m["Dm"])
    # target: du_s = T z_k;  regulator: du = -first (SdT2 (Phi z_k + Gam u) + CbS tile (u - du_s))
    T = np.zeros((n_u, n_z))
    T[:, r] = -m["Gpinv"] @ m["Gq"]
    T[:, r + 1 :] = -m["Gpinv"] @ d["Ec"]
    Rz = -first @ (m["SdT2"] @ m["Phi"].reshape(-1, n_z) - m["CbS"] @ tile @ T)
    Ru = -first @ (m["SdT2"] @ m["Gam"].reshape(-1, n_u) + m["CbS"] @ tile)
    # u_k = u + Rz z_k + Ru u
    Ux, Uz, Uu = Rz @ Fx, Rz @ Fz, np.eye(n_u) + Rz @ Fu + Ru
    return np.block(
        [
            [A + B @ Ux, B @ Uz, B @ Uu],
            [Fx, Fz, Fu],
            [Ux, Uz, Uu],
        ]
    )


def damping(matrix: np.ndarray, dt: float) -> float:
    """The least damping ratio of the modes of a discrete-time ``matrix`` (interval
    ``dt``): -Re(s)/|s| of s = log(lambda)/dt; below 0 for a growing mode, 1 for a mode that
    dies within one interval (lambda = 0, e.g. a pure delay's)."""
    ev = np.linalg.eigvals(matrix).astype(complex)
    ev = ev[np.abs(ev) > 1e-12]
    s = np.log(ev) / dt
    return float(np.min(-s.real / np.maximum(np.abs(s), 1e-300), initial=1.0))


def worst_damping(ctrl: Any, env_id: str, params_json: str) -> tuple[float, str]:
    """(least damping ratio, where) of ``ctrl``'s loop over the vertices of the plant's
    documented ranges (``perturb.corners``) x :data:`LOADS`,
    each vertex's plant the model (``params_json``) with its groups scaled."""
    base = json.loads(params_json)
    worst, where = np.inf, ""
    for factors in perturb.corners(env_id):
        plant = plants.make(env_id, **perturb.scaled(env_id, base, factors))
        for load in LOADS:
            z = damping(closed_loop(ctrl, plant, load), plant.dt_s)
            if z < worst:
                text = ", ".join(f"{g} x{f:g}" for g, f in factors.items())
                worst, where = z, f"{text} at {load:.0%} load"
    return worst, where


@commissioned(maxsize=64)
def robust_filter_noise(
    cls: type,
    env_id: str,
    params_json: str,
    move_weight: float,
    u_weight: float,
    filter_noise_K: float,
    heat_std: float,
) -> tuple[float, float, str]:
    """(filter noise, its least damping ratio, where) of the design rule (module
    docstring): the first of ``filter_noise_K`` x NOISE_STEP^k, k = 0..MAX_STEPS, whose
    loop keeps ZETA_MIN on every vertex, else the best damped of them. ``cls``: the MPC's
    class, built with ``robust=False`` on the env of ``env_id`` with ``params_json``."""
    env = gym.make(env_id, params=json.loads(params_json))
    best = (-np.inf, filter_noise_K, "")
    try:
        for k in range(MAX_STEPS + 1):
            noise = filter_noise_K * NOISE_STEP**k
            ctrl = cls(
                env,
                move_weight=move_weight,
                u_weight=u_weight,
                filter_noise_K=noise,
                heat_std=heat_std,
                robust=False,
            )
            zeta, where = worst_damping(ctrl, env_id, params_json)
            if zeta >= ZETA_MIN:
                return noise, zeta, where
            if zeta > best[0]:
                best = (zeta, noise, where)
    finally:
        env.close()
    return best[1], best[0], best[2]
