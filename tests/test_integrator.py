"""The ROS2 integrator at the control interval against a fine Radau solution of the same rhs.

Issue 2: over the 100 -> 50 % ramp (000_*.txt's test), max outlet temperature error <= 0.05 K.
The inputs are the same zero-order-hold sequences for both: disturbances from the scenario at
the start of each interval, a valve command that moves every interval.
"""

import numpy as np
from scipy.integrate import solve_ivp

from steamtemp_gym import scenarios
from steamtemp_gym.envs.core import eval_schedules
from steamtemp_gym.plants import supercritical_fsh as fsh
from steamtemp_gym.steam import T_ph


def test_ros2_matches_radau_over_the_load_ramp():
    plant = fsh.SupercriticalFSH()
    P, dt = plant.P, plant.dt_s
    sc = scenarios.get("load_ramp_100_50")
    bp_t = np.zeros((1, 5, 8))
    bp_v = np.zeros((1, 5, 8))
    bp_n = np.ones((1, 5), np.int64)  # noqa: E702
    scenarios.pack(sc, bp_t[0], bp_v[0], bp_n[0])
    D = np.zeros((1, 5))
    sp = np.zeros(1)  # noqa: E702
    t0, t1 = 1100.0, 2600.0  # the ramp (1200-1800 s) and the recovery after it
    eval_schedules(0, t0, bp_t, bp_v, bp_n, 593.0, D, sp)
    X = np.zeros((1, plant.n_x))
    plant.steady_state(D, sp, X)
    v0 = X[0, fsh.S_V]
    x_ref = X[0].copy()
    Z = np.zeros((1, plant.n_z))
    n = int(P[fsh.I_N])
    f, jd, ju = np.empty(plant.n_x), np.empty(plant.n_x), np.zeros(plant.n_x)
    jl = np.empty(len(plant.jrow))
    errs = []
    for k in range(int((t1 - t0) / dt)):
        t = t0 + k * dt
        eval_schedules(0, t, bp_t, bp_v, bp_n, 593.0, D, sp)
        U = np.array([[v0 + 0.04 * np.sin(2 * np.pi * t / 300.0)]])
        plant.step(X, U, D, Z)

        u, d = U[0], D[0].copy()

        def rhs(_t, x, u=u, d=d):
            fsh.rhs(x, u, d, P, f, jd, ju, jl, False)
            return f.copy()

        sol = solve_ivp(
            rhs,
            (0.0, dt),
            x_ref,
            method="Radau",
            rtol=1e-8,
            atol=1e-6 * np.maximum(1.0, np.abs(x_ref)),
        )
        assert sol.success
        x_ref = sol.y[:, -1]
        p = fsh._pressure(P, x_ref[fsh.S_LW])
        T_ref = T_ph(p, x_ref[fsh.S_CHAIN + 2 * n - 1]) - 273.15
        errs.append(abs(Z[0, fsh.Z_TOUT] - T_ref))
    assert max(errs) <= 0.05, f"max outlet error {max(errs):.4f} K"
    print(f"ROS2 dt={dt} s, {plant.n_sub} substeps: max outlet error {max(errs) * 1e3:.2f} mK")


def test_ros2_is_second_order_for_any_matrix():
    """The W-method property the plant integrator relies on: order 2 whatever A is."""
    from steamtemp_gym.plants.integrator import GAMMA

    def ros2(a, c, h, n):
        y = 1.0
        for _ in range(n):
            k1 = a * y / (1 - GAMMA * h * c)
            k2 = (a * (y + h * k1) - 2 * k1) / (1 - GAMMA * h * c)
            y += 1.5 * h * k1 + 0.5 * h * k2
        return y

    for c in (0.0, -1.0, -3.0, 2.0):
        e = [abs(ros2(-1.0, c, 1.0 / n, n) - np.exp(-1.0)) for n in (40, 80, 160)]
        assert 1.7 < np.log2(e[0] / e[1]) < 2.3 and 1.7 < np.log2(e[1] / e[2]) < 2.3
