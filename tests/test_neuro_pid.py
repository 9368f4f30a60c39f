"""Neuro-PID by MEE / MSE (baselines/neuro_pid.py): the mechanism against independent
references, the batched contract, and the claim check of Zhang et al. (ISA Trans. 2012) on
steamtemp/Cascade300MW-v0, scenario ``setpoint_step_535_545``."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from scipy import stats

import baselines
from agents.evaluation import run_episode
from baselines import neuro_pid as npid

ID = "steamtemp/Cascade300MW-v0"
LAM, SIG = npid.LAMBDA, npid.SIGMA_K


def _net(w, x, scale):
    """Reference forward pass of eq. (5)-(8) in plain numpy: gains s_l g(net_l)."""
    W2 = w[: npid.N_W2].reshape(npid.N_HIDDEN, npid.N_IN + 1)
    W3 = w[npid.N_W2 :].reshape(3, npid.N_HIDDEN + 1)
    h = np.tanh(W2 @ np.r_[1.0, x])
    net = W3 @ np.r_[1.0, h]
    return scale * np.exp(net) / (np.exp(net) + np.exp(-net))


def _sens(w, x, E, scale):
    h, g, s = np.empty(npid.N_HIDDEN), np.empty(3), np.empty(npid.N_W)
    du = np.array([E[0] - E[1], E[0], E[0] - 2 * E[1] + E[2]])
    npid._forward(w, x, h, g)
    npid._sensitivity(w, x, h, g, du, scale, s)
    return s, du


def test_sensitivity_is_minus_du_dw_by_finite_differences():
    """Eq. (11), (15) with the Jacobian sign +1: de_k/dw = -d(sum_l dU_l k_l)/dw."""
    rng = np.random.default_rng(1)
    w = rng.uniform(-1, 1, npid.N_W)
    x, E, scale = rng.normal(size=npid.N_IN), rng.normal(size=3), np.array([1.2, 1.0, 1.0])
    s, du = _sens(w, x, E, scale)
    fd = np.empty(npid.N_W)
    for j in range(npid.N_W):
        dw = np.zeros(npid.N_W)
        dw[j] = 1e-6
        fd[j] = -(du @ (_net(w + dw, x, scale) - _net(w - dw, x, scale))) / 2e-6
    np.testing.assert_allclose(s, fd, rtol=1e-6, atol=1e-9)


def _run_kernel(mee, es, xs, w, L, eta=0.0):
    n = 1
    W, G, V = w[None].copy(), np.zeros((n, npid.N_W)), np.zeros(n)
    Eb, Sb = np.zeros((n, L)), np.zeros((n, L, npid.N_W))
    nb, hd, gains = np.zeros(n, np.int64), np.zeros(n, np.int64), np.zeros((n, 3))
    scale = np.ones((n, 3))
    Gs, Vs = [], []
    for k in range(len(es)):
        E = np.array([[es[k], es[k - 1] if k else es[0], es[k - 2] if k > 1 else es[0]]])
        npid.npid_step(xs[k][None], E, W, G, V, Eb, Sb, nb, hd, scale, mee, SIG, LAM, L, eta,
                       gains)  # fmt: skip
        Gs.append(G[0].copy())
        Vs.append(V[0])
    return np.array(Gs), np.array(Vs)


def test_mee_gradient_is_eq_10_over_the_receding_window():
    """Kernel (ring buffer of L = 5, wrapped several times) vs eq. (3) and (10) summed
    directly over the stored errors and sensitivities, weights frozen (eta = 0)."""
    rng = np.random.default_rng(2)
    L, K = 5, 23
    w = rng.uniform(-0.5, 0.5, npid.N_W)
    es, xs = rng.normal(0, 2, K), rng.normal(size=(K, npid.N_IN))
    G_k, V_k = _run_kernel(True, es, xs, w, L)
    S = []
    G, V = np.zeros(npid.N_W), 0.0
    kap = lambda d: np.exp(-d * d / (4 * SIG**2)) / (math.sqrt(2 * math.pi) * math.sqrt(2) * SIG)  # noqa: E731
    for k in range(K):
        E = [es[k], es[k - 1] if k else es[0], es[k - 2] if k > 1 else es[0]]
        s, _ = _sens(w, xs[k], np.array(E), np.ones(3))
        win = range(max(0, k - L), k)
        G = (1 - LAM) * G - LAM / (2 * L * SIG**2) * sum(
            (es[i] - es[k]) * kap(es[i] - es[k]) * (S[i] - s) for i in win
        )
        V = (1 - LAM) * V + LAM / L * sum(kap(es[i] - es[k]) for i in win)
        S.append(s)
        np.testing.assert_allclose(G_k[k], G, rtol=1e-10, atol=1e-15)
        assert V_k[k] == pytest.approx(V, rel=1e-12, abs=1e-15)


def test_mse_gradient_is_the_forgotten_mean_of_e_de_dw():
    rng = np.random.default_rng(3)
    K = 30
    w = rng.uniform(-0.5, 0.5, npid.N_W)
    es, xs = rng.normal(0, 2, K), rng.normal(size=(K, npid.N_IN))
    G_k, V_k = _run_kernel(False, es, xs, w, 5)
    G, M = np.zeros(npid.N_W), 0.0
    for k in range(K):
        E = [es[k], es[k - 1] if k else es[0], es[k - 2] if k > 1 else es[0]]
        s, _ = _sens(w, xs[k], np.array(E), np.ones(3))
        G, M = (1 - LAM) * G + LAM * es[k] * s, (1 - LAM) * M + LAM * es[k] ** 2
    np.testing.assert_allclose(G_k[-1], G, rtol=1e-10)
    assert V_k[-1] == pytest.approx(M, rel=1e-12)


def test_update_directions():
    """MEE ascends V (eq. (9)): a tiny step along eta G raises the window's information
    potential with the stored sensitivities; MSE descends e^2."""
    rng = np.random.default_rng(4)
    w = rng.uniform(-0.5, 0.5, npid.N_W)
    es, xs = rng.normal(0, 2, 40), rng.normal(size=(40, npid.N_IN))
    G_mee, _ = _run_kernel(True, es, xs, w, 200)
    G_mse, _ = _run_kernel(False, es, xs, w, 200)
    assert np.linalg.norm(G_mee[-1]) > 0 and np.linalg.norm(G_mse[-1]) > 0
    # with the paper's constants the MEE gradient is far smaller than the MSE one
    assert np.linalg.norm(G_mee[-1]) < 0.2 * np.linalg.norm(G_mse[-1])


def test_initial_net_gives_the_commissioning_gains():
    k0 = npid.commissioning_gains(ID, "{}")[0]
    w, scale = npid.initial_weights(k0[:3])
    np.testing.assert_allclose(_net(w, np.zeros(npid.N_IN), scale), k0[:3], rtol=1e-12)
    assert np.all(scale >= 1.0) and k0[3] == 1.0
    # SIMC PI on the identified outer process (inner P loop closed): K ~ 2.09 * 16/17
    m = npid.outer_models(ID, "{}")[0]
    assert m.K == pytest.approx(2.09 * 16.08 / 17.08, rel=0.01)
    w2, _ = npid.initial_weights(k0[:3])
    np.testing.assert_array_equal(w, w2)  # reproducible


@pytest.mark.parametrize("name", ["neuro_pid_mee", "neuro_pid_mse"])
def test_batched_equals_single_while_learning_and_restart_restores_weights(name):
    envs = [gym.make(ID, scenario="setpoint_step_535_545") for _ in range(3)]
    batch = baselines.make(name, envs[0])
    singles = [baselines.make(name, e) for e in envs]
    obs = [e.reset(seed=s)[0] for s, e in enumerate(envs)]
    start = np.ones(3, bool)
    for _ in range(700):
        a_b, _ = batch.predict(np.stack(obs), episode_start=start)
        for i, e in enumerate(envs):
            a_i, _ = singles[i].predict(obs[i], episode_start=start[i : i + 1])
            np.testing.assert_allclose(a_b[i], a_i, rtol=0, atol=1e-12)
            obs[i] = e.step(a_i)[0]
        start[:] = False
    W = batch._st["W"]
    assert np.all(np.abs(W - batch.w0).max(axis=1) > 0)  # it learned something
    restart = np.array([False, True, False])
    batch.predict(np.stack(obs), episode_start=restart)
    assert np.abs(W[1] - batch.w0[0]).max() < 1e-6  # one update from the initial weights
    assert np.abs(W[0] - batch.w0[0]).max() > 1e-6
    batch.reset()
    assert batch._st is None


# ---------------------------------------------------------------------- claim check
def claim_stats(seeds: int) -> dict[str, np.ndarray]:
    """Per policy, per seed: (mean, std) of e = setpoint - true outlet over the episode and
    (mean, std) after 800 s (the transient of the 500 s step excluded)."""
    env = gym.make(ID, scenario="setpoint_step_535_545")
    out = {}
    for name in ("neuro_pid_mee", "neuro_pid_mse", "cascade_pi"):
        pol, rows = baselines.make(name, env), []
        for seed in range(seeds):
            tr = run_episode(env, pol, seed)["trace"]
            e = tr["setpoint_C"] - tr["outlet_temp_C"]
            late = tr["time_s"] >= 800.0
            rows.append((e.mean(), e.std(), e[late].mean(), e[late].std()))
        out[name] = np.array(rows)
    return out


def ci95(x: np.ndarray) -> tuple[float, float, float]:
    """Mean and its two-sided 95 % Student-t confidence interval."""
    m = float(np.mean(x))
    h = float(stats.t.ppf(0.975, len(x) - 1) * np.std(x, ddof=1) / np.sqrt(len(x)))
    return m, m - h, m + h


def _check_claim(seeds: int, tol: float) -> None:
    """What we measure (20 seeds, 95 % CI; whole episode mean / std, K):
    MEE 1.449 [1.315, 1.583] / 2.757 [2.619, 2.896], MSE 1.421 [1.289, 1.553] / 2.759
    [2.620, 2.897], cascade_pi 0.575 / 3.033; after 800 s std MEE 1.702 [1.537, 1.868],
    MSE 1.709 [1.542, 1.875], cascade_pi 2.233 [2.028, 2.437]. Paper: MEE 0.4452 / 1.7049,
    MSE 0.5093 / 1.7153. Paired MEE - MSE (same seeds, same disturbances): std -0.0013
    [-0.0037, 0.0010] K (p = 0.25), late std -0.0063 [-0.0109, -0.0016] K (p = 0.01),
    mean +0.028 [0.024, 0.032] K: no practical benefit of MEE (the paper: -0.0104 K std).
    ``tol`` covers the seed-to-seed spread of the smaller default sample."""
    r = claim_stats(seeds)
    mee, mse, pi = r["neuro_pid_mee"], r["neuro_pid_mse"], r["cascade_pi"]
    # the step is tracked and the late error std is of the paper's order (1.7 K)
    for x in (mee, mse):
        assert ci95(x[:, 3])[0] == pytest.approx(1.70, abs=tol)
        assert abs(ci95(x[:, 2])[0]) < 1.5
        assert ci95(x[:, 1])[0] == pytest.approx(2.76, abs=tol)
    # the claim (MEE narrows the error distribution vs MSE) reproduces at most as a
    # difference of no engineering weight: within 0.01 K (whole) and 0.02 K (late)
    d = mee - mse
    assert abs(ci95(d[:, 1])[0]) < 0.01 and abs(ci95(d[:, 3])[0]) < 0.02
    if seeds >= 20:  # as measured: late std MEE below MSE, mean error MEE above MSE
        assert -0.02 < ci95(d[:, 3])[2] < 0.0 and ci95(d[:, 0])[1] > 0.0
    # the neuro-PID cascade (paper's P inner loop) holds the outlet tighter than cascade_pi
    # after the step, but tracks the step more slowly (larger whole-episode mean error)
    assert ci95(mee[:, 3] - pi[:, 3])[2] < 0.0
    assert ci95(mee[:, 0] - pi[:, 0])[1] > 0.0


def test_claim_setpoint_step_5_seeds():
    _check_claim(5, tol=0.35)


@pytest.mark.slow
def test_claim_setpoint_step_20_seeds():
    _check_claim(20, tol=0.15)
