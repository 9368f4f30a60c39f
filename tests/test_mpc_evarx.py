"""EV-ARX model (baselines/evarx.py) and its MPC (baselines/mpc_evarx.py): identification
and QP unit tests, the safety layer, and the claim check of Toyoda and Wada (Kyushu Univ.
1999) on steamtemp/BoilerTurbineMIMO-v0. Registry-wide contracts (every plant, batched ==
single, every named scenario) are in tests/test_baselines.py."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import baselines
import steamtemp_gym  # noqa: F401  (registers the ids)
from agents.evaluation import run_episode
from baselines.evarx import W0, evarx_predict, fit_evarx, identify, prbs
from baselines.mpc_evarx import _QP, BIAS_WEIGHT, MOVE_STEPS, MOVE_WEIGHT

BTM = "steamtemp/BoilerTurbineMIMO-v0"
CLAIM_SCENARIOS = ("load_ramp_100_50", "load_ramp_50_100", "load_following")
METRICS = ("iae_K_s", "max_abs_dev_K", "reheat_temp_C_iae_K_s", "reheat_temp_C_max_abs_dev_K")


def test_prbs_is_a_maximal_length_sequence():
    s = prbs(511, 1, 0)
    assert (s == 1).sum() == 256 and (s == -1).sum() == 255  # m-sequence balance
    np.testing.assert_array_equal(prbs(1022, 1, 0)[511:], s)  # period 511
    assert np.all(prbs(30, 3, 0).reshape(10, 3).std(1) == 0)  # each bit held `clock`


def test_gauss_newton_recovers_gamma_and_matches_scipy_least_squares():
    """Eq. (15)-(20) on data from a known EV-ARX: gamma recovered, and scipy's
    least_squares on the same residual (eq. 16) reaches the same cost J."""
    from scipy.optimize import least_squares

    rng = np.random.default_rng(0)
    T, p = 3000, 3
    w = 0.3 + 0.9 * rng.random(T)  # data around every centre: gamma identifiable
    phi = np.column_stack([rng.standard_normal((T, p - 1)), np.ones(T)])
    theta = rng.standard_normal((len(W0) + 1, p))
    gamma = np.array([30.0, 20.0, 40.0])
    y = evarx_predict(theta, gamma, phi, w) + 0.01 * rng.standard_normal(T)
    th, ga, info = fit_evarx(phi, w, y, iters=100, gamma0=25.0)
    np.testing.assert_allclose(ga, gamma, rtol=0.02)
    assert np.all(np.diff(info["cost"]) < 0)

    def resid(x: np.ndarray) -> np.ndarray:
        return y - evarx_predict(x[:-3].reshape(th.shape), x[-3:], phi, w)

    sol = least_squares(resid, np.concatenate([th.ravel(), ga]) + 1e-3, method="lm")
    assert float(np.sum(sol.fun**2)) == pytest.approx(info["cost"][-1], rel=1e-4)


def _toy_qp(rate: float) -> tuple[_QP, dict, int]:
    N, no, na = 30, 2, 2
    t = np.arange(1, N + 1)[:, None, None]
    G = (1.0 - np.exp(-t / np.array([[5.0, 9.0], [7.0, 4.0]]))) * np.array(
        [[-2.0, 0.5], [0.3, 3.0]]
    )
    qp = _QP(no, na, N, rates=np.full(na, rate))
    return qp, qp.matrices(G), na


def test_unconstrained_qp_equals_least_squares():
    """No bound active: the QP's moves are the normal-equation solution of its cost."""
    qp, mats, na = _toy_qp(10.0)
    e = 0.02 * np.random.default_rng(1).standard_normal((qp.N, qp.n_out))
    b0 = np.array([0.01, -0.02])
    warm = (np.zeros(qp.nz), np.zeros(qp.nc))
    ok, moves, _, _ = qp.solve(mats, e, b0, np.full(na, -0.2), np.full(na, 0.2), warm)
    assert ok and moves.shape == (len(MOVE_STEPS), na)
    # the cost's Hessian, assembled independently of the QP's own P
    S, nv = mats["S"], qp.nv
    g2 = np.abs(np.reshape(S[:, :na], (qp.N, qp.n_out, na))).max((0, 1)) ** 2 + 1e-9
    R = np.diag(np.tile(MOVE_WEIGHT * qp.N * g2, qp.M))
    Rabs = np.tile(BIAS_WEIGHT * g2, qp.N)
    H = S.T @ S + R + qp.Cb.T @ (Rabs[:, None] * qp.Cb)
    rhs = S.T @ e.ravel() - qp.Cb.T @ (Rabs * np.tile(b0, qp.N))
    np.testing.assert_allclose(moves.ravel(), np.linalg.solve(H, rhs), atol=1e-5)
    assert nv == len(MOVE_STEPS) * na


def test_qp_respects_bias_and_rate_bounds():
    qp, mats, na = _toy_qp(0.05)
    warm = (np.zeros(qp.nz), np.zeros(qp.nc))
    lo, hi = np.array([-0.2, -0.1]), np.array([0.15, 0.2])
    ok, moves, _, _ = qp.solve(mats, np.full((qp.N, qp.n_out), 50.0), np.zeros(na), lo, hi,
                               warm)  # fmt: skip
    assert ok
    assert np.all(np.abs(moves) <= 0.05 + 1e-4)
    b = np.cumsum(moves, 0)
    assert np.all((b >= lo - 1e-4) & (b <= hi + 1e-4))
    assert np.abs(b).max() > 0.09  # a large error drives the bias to its bounds


def test_fallback_is_exactly_cascade_pi():
    """The safety layer: with the model monitor tripping at every check, the bias is zero
    from the second model interval on (the first has no prediction to check yet) and the
    policy acts as cascade_pi, bit for bit; the fallbacks are counted."""
    env = gym.make(BTM, scenario="load_ramp_100_50")
    mpc, pi = baselines.make("mpc_evarx", env), baselines.make("cascade_pi", env)
    mpc.monitor_K = np.zeros_like(mpc.monitor_K)
    obs, _ = env.reset(seed=0)
    differs = []
    for k in range(120):
        a, _ = mpc.predict(obs, episode_start=np.array([k == 0]))
        a_pi, _ = pi.predict(obs, episode_start=np.array([k == 0]))
        if k < mpc.n:
            differs.append(np.any(a != a_pi))
        else:
            np.testing.assert_array_equal(a, a_pi)
        obs, *_ = env.step(a)
    assert all(differs)  # the first interval's QP did move the biases
    assert mpc.stats["fallbacks"]["model"] == 120 // mpc.n - 1


def test_identification_fit_evarx_vs_interpolated_arx():
    """Section 7.1 / Fig. 8 on separate validation data (a ramp with other PRBS phases and
    noise seed), simulation fit % (eq. 14) per output (STE, RTE). The paper finds EV-ARX
    the better model under ramped load. Measured here: EV-ARX 28.1 / 43.5 %, interpolated
    ARX 37.6 / 47.5 %: it does NOT reproduce (the closed-loop STE is mostly driven by the
    unmeasured coloured heat-absorption noise, which neither model sees). Asserted as
    measured, +-3 points (the runs are deterministic; the tolerance covers numerics)."""
    fit = identify(BTM, "{}")["fit_pct"]
    np.testing.assert_allclose(fit["evarx"], [28.1, 43.5], atol=3.0)
    np.testing.assert_allclose(fit["arx"], [37.6, 47.5], atol=3.0)
    assert np.all(fit["evarx"] < fit["arx"])


def _claim(seeds: range) -> dict[tuple[str, str], np.ndarray]:
    """(policy, scenario) -> (seeds, 4): STE IAE, STE peak, RTE IAE, RTE peak."""
    out = {}
    for sc in CLAIM_SCENARIOS:
        env = gym.make(BTM, scenario=sc)
        for name in ("cascade_pi", "mpc_evarx", "mpc_arx"):
            pol = baselines.make(name, env)
            rows = []
            for s in seeds:
                m = run_episode(env, pol, seed=s)["metrics"]
                assert m["tripped"] == 0.0
                rows.append([m[k] for k in METRICS])
            if name != "cascade_pi":
                fb = pol.stats["fallbacks"]
                assert fb["qp"] <= 0.01 * pol.stats["solves"]
            out[name, sc] = np.array(rows)
    return out


#: Measured mean-IAE ratios over cascade_pi's (STE, RTE), by number of seeds (0..n-1).
CLAIM_RATIO = {
    2: {("mpc_evarx", "load_ramp_100_50"): (2.533, 1.481),
        ("mpc_arx", "load_ramp_100_50"): (0.693, 0.620),
        ("mpc_evarx", "load_ramp_50_100"): (1.538, 0.784),
        ("mpc_arx", "load_ramp_50_100"): (1.051, 0.658),
        ("mpc_evarx", "load_following"): (1.064, 0.694),
        ("mpc_arx", "load_following"): (1.014, 0.638)},
    5: {("mpc_evarx", "load_ramp_100_50"): (2.863, 1.554),
        ("mpc_arx", "load_ramp_100_50"): (0.796, 0.691),
        ("mpc_evarx", "load_ramp_50_100"): (1.887, 0.950),
        ("mpc_arx", "load_ramp_50_100"): (1.065, 0.683),
        ("mpc_evarx", "load_following"): (1.401, 0.739),
        ("mpc_arx", "load_following"): (1.110, 0.668)},
}  # fmt: skip


def _check_claim(res: dict, n_seeds: int) -> None:
    """The paper (Fig. 9): the MPC beats the conventional PI on STE and RTE. Measured ratio
    of mean IAE to cascade_pi's (5 seeds): ``mpc_arx`` beats it on RTE everywhere (0.67-0.69)
    and on STE on the 100 -> 50 % ramp (0.80), ties it on STE elsewhere (1.07, 1.11);
    ``mpc_evarx`` beats it on RTE on 50 -> 100 % and load_following (0.95, 0.74) and loses
    on STE everywhere (1.4-2.9): the claim holds for the RTE, not for the STE, and the
    EV-ARX model does not pay off in closed loop. Asserted as measured; the runs are
    deterministic, the tolerance 0.05 covers numerics, not a change of verdict."""
    for sc in CLAIM_SCENARIOS:
        pi = res["cascade_pi", sc].mean(0)
        for name in ("mpc_evarx", "mpc_arx"):
            ratio = res[name, sc].mean(0)[[0, 2]] / pi[[0, 2]]
            np.testing.assert_allclose(ratio, CLAIM_RATIO[n_seeds][name, sc], atol=0.05,
                                       err_msg=f"{name} {sc}")  # fmt: skip


def test_claim_check_two_seeds():
    _check_claim(_claim(range(2)), 2)


@pytest.mark.slow
def test_claim_check_five_seeds():
    _check_claim(_claim(range(5)), 5)
