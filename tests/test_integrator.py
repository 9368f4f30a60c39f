"""The ROS2 integrator at the control interval against a fine Radau solution of the same rhs.

Over the 100 -> 50 % ramp (Sagara et al. 1998's test), max outlet error <= 0.05 K, both at
the FSH outlet and at the turbine inlet after the main-steam line.
The inputs are the same zero-order-hold sequences for both: disturbances from the scenario at
the start of each interval, a valve command that moves every interval.
"""

import numpy as np
from scipy.integrate import solve_ivp

from steamtemp_gym import scenarios
from steamtemp_gym.envs.kernels import schedules
from steamtemp_gym.plants import supercritical_fsh as fsh
from steamtemp_gym.plants.valve import valve_rhs
from steamtemp_gym.steam import T_ph


def radau_reference(plant, x0, commands, D_of_k):
    """Radau (rtol 1e-8) on the continuous model: the valve ODE of valve.py feeds the rhs."""
    P, dt = plant.P, plant.dt_s
    f, jd, ju = np.empty(plant.n_x), np.empty(plant.n_x), np.zeros(plant.n_x)
    jl = np.empty(len(plant.jrow))
    n = int(P[fsh.IP.N])
    x_ref, out = x0.copy(), []
    for k, cmd in enumerate(commands):
        d = D_of_k(k)

        def rhs(_t, x, cmd=cmd, d=d):
            vdot = valve_rhs(x[fsh.IX.V], cmd, P[fsh.IP.TAUV], P[fsh.IP.RATEV])[0]
            fsh.rhs(x, np.array([vdot]), d, P, f, jd, ju, jl, False)
            return f.copy()

        atol = 1e-6 * np.maximum(1.0, np.abs(x_ref))
        sol = solve_ivp(rhs, (0.0, dt), x_ref, method="Radau", rtol=1e-8, atol=atol)
        assert sol.success
        x_ref = sol.y[:, -1]
        p = fsh.pressure(P, x_ref[fsh.IX.LW])
        # (FSH outlet, turbine inlet after the main-steam line) in C
        out.append(
            (
                T_ph(p, x_ref[fsh.IX.CHAIN + 2 * n - 1]) - 273.15,
                T_ph(p, x_ref[fsh.s_line(n) + int(P[fsh.IP.NL]) - 1]) - 273.15,
            )
        )
    return np.array(out)


def run_kernel(plant, X, commands, D_of_k):
    Z = np.zeros((1, plant.n_z))
    out = []
    for k, cmd in enumerate(commands):
        plant.step(X, np.array([[cmd]]), D_of_k(k)[None, :], Z)
        out.append((Z[0, fsh.IZ.fsh_outlet_temp_C], Z[0, fsh.IZ.outlet_temp_C]))
    return np.array(out)


def test_ros2_matches_radau_over_the_load_ramp():
    plant = fsh.SupercriticalFSH()
    dt = plant.dt_s
    sc = scenarios.get("load_ramp_100_50")
    bp_t, bp_v, bp_n = np.zeros((1, 5, 8)), np.zeros((1, 5, 8)), np.ones((1, 5), np.int64)
    scenarios.pack(sc, bp_t[0], bp_v[0], bp_n[0])
    t0, t1 = 1100.0, 2600.0  # the ramp (1200-1800 s) and the recovery after it

    def D_of_k(k):
        D, sp = np.zeros((1, 5)), np.zeros(1)
        schedules(0, 0, t0 + k * dt, bp_t, bp_v, bp_n, 593.0, np.zeros(1), D, sp)
        return D[0]

    X = np.zeros((1, plant.n_x))
    plant.steady_state(D_of_k(0)[None, :], np.array([593.0]), X)
    v0 = X[0, fsh.IX.V]
    steps = int((t1 - t0) / dt)
    commands = v0 + 0.04 * np.sin(2 * np.pi * (t0 + dt * np.arange(steps)) / 300.0)
    ref = radau_reference(plant, X[0], commands, D_of_k)
    got = run_kernel(plant, X, commands, D_of_k)
    err_fsh, err = np.max(np.abs(got - ref), axis=0)
    assert err <= 0.05 and err_fsh <= 0.05, f"max outlet error {err:.4f} K (FSH {err_fsh:.4f} K)"
    print(
        f"ROS2 dt={dt} s, {plant.n_sub} substeps: max outlet error {err * 1e3:.2f} mK "
        f"(FSH outlet {err_fsh * 1e3:.2f} mK)"
    )


def test_random_valve_steps_are_integrated_accurately():
    """Jumpy, rate-limited commands (an RL agent's) at rated load against Radau."""
    plant = fsh.SupercriticalFSH()
    D = np.zeros(5)
    D[0], D[3] = 1.0, 1.0
    X = np.zeros((1, plant.n_x))
    plant.steady_state(D[None, :], np.array([593.0]), X)
    rng = np.random.default_rng(0)
    commands = np.clip(X[0, fsh.IX.V] + rng.uniform(-0.3, 0.3, size=150), 0.0, 1.0)
    ref = radau_reference(plant, X[0], commands, lambda k: D)
    got = run_kernel(plant, X, commands, lambda k: D)
    err_fsh, err = np.max(np.abs(got - ref), axis=0)
    assert err <= 0.1 and err_fsh <= 0.1, f"max outlet error {err:.4f} K (FSH {err_fsh:.4f} K)"
    print(f"random valve steps: max outlet error {err * 1e3:.1f} mK (FSH {err_fsh * 1e3:.1f} mK)")


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
