"""EV-ARX MPC (baselines/mpc_evarx.py): identification and QP unit tests, and the claim
check of Toyoda and Wada (Kyushu Univ. 1999) on steamtemp/BoilerTurbineMIMO-v0."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import baselines
import steamtemp_gym  # noqa: F401  (registers the ids)
from agents.evaluation import run_episode
from baselines.mpc_evarx import (
    _QP,
    MOVE_STEPS,
    W0,
    evarx_predict,
    fit_evarx,
    identify,
    prbs,
)

BTM = "steamtemp/BoilerTurbineMIMO-v0"
STATS: dict = {}
CLAIM_SCENARIOS = ("load_ramp_100_50", "load_ramp_50_100", "load_following")


def test_prbs_is_a_maximal_length_sequence():
    s = prbs(511, 1, 0)
    assert (s == 1).sum() == 256 and (s == -1).sum() == 255  # m-sequence balance
    np.testing.assert_array_equal(prbs(1022, 1, 0)[511:], s)  # period 511
    assert np.all(prbs(30, 3, 0).reshape(10, 3).std(1) == 0)  # each bit held `clock`


def test_gauss_newton_recovers_gamma_and_matches_scipy_least_squares():
    """Eq. (15)-(20) on data from a known EV-ARX: gamma recovered (with broad bases over
    only 50-100 % load the valley is flat and GN crawls: a limit of the model), and scipy's
    least_squares on the same residual (eq. 16) from the same start reaches the same J."""
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
    J_gn = info["cost"][-1]

    def resid(x: np.ndarray) -> np.ndarray:
        return y - evarx_predict(x[:-3].reshape(th.shape), x[-3:], phi, w)

    x0 = np.concatenate([th.ravel(), ga]) + 1e-3
    sol = least_squares(resid, x0, method="lm")
    assert float(np.sum(sol.fun**2)) == pytest.approx(J_gn, rel=1e-4)


def test_unconstrained_qp_equals_least_squares():
    rng = np.random.default_rng(1)
    N, no, nf = 30, 2, 2
    t = np.arange(1, N + 1)[:, None, None]
    G = (1.0 - np.exp(-t / np.array([[5.0, 9.0], [7.0, 4.0]]))) * np.array([[-2.0, 0.5],
                                                                               [0.3, 3.0]])
    qp = _QP(no, nf, N, rates=np.full(nf, 10.0))
    S, Px, Ax, R = qp.matrices(0, G, [0, 1])
    e = 0.05 * rng.standard_normal((N, no))  # small: no bound active
    ok, moves, _, info = qp.solve(S, Px, Ax, e, np.full(nf, 0.5),
                                  (np.zeros(qp.nz), np.zeros(qp.nc)))  # fmt: skip
    assert ok and moves.shape == (len(MOVE_STEPS), nf)
    ref = np.linalg.solve(S.T @ S + np.diag(R), S.T @ e.ravel())
    np.testing.assert_allclose(moves.ravel(), ref, atol=1e-4)
    # a large error saturates the moves at the rate and opening bounds
    qp2 = _QP(no, nf, N, rates=np.full(nf, 0.05))
    ok, moves, _, _ = qp2.solve(*qp2.matrices(0, G, [0, 1])[:3], np.full((N, no), 50.0),
                                np.full(nf, 0.5), (np.zeros(qp2.nz), np.zeros(qp2.nc)))
    assert ok
    assert np.all(np.abs(moves) <= 0.05 + 1e-4)
    assert np.all((0.5 + np.cumsum(moves, 0) >= -1e-4) & (0.5 + np.cumsum(moves, 0) <= 1 + 1e-4))


def test_evarx_fits_better_than_interpolated_arx_under_ramped_load():
    """Section 7.1 / Fig. 8: validation on a separate ramp (simulation, eq. 14).
    Measured (fit %): EV-ARX STE 37.9, RTE 45.9; interpolated ARX 35.3, 13.7."""
    fit = identify(BTM, "{}")["fit_pct"]
    assert np.all(fit["evarx"] > fit["arx"])
    np.testing.assert_allclose(fit["evarx"], [37.9, 45.9], atol=3.0)
    np.testing.assert_allclose(fit["arx"], [35.3, 13.7], atol=3.0)


def test_batched_predict_equals_single_rows_over_steps():
    envs = [gym.make(BTM, scenario="load_ramp_100_50") for _ in range(3)]
    pol = baselines.make("mpc_evarx", envs[0])
    singles = [baselines.make("mpc_evarx", envs[0]) for _ in range(3)]
    obs = np.stack([e.reset(seed=s)[0] for s, e in enumerate(envs)])
    start = np.ones(3, bool)
    for _ in range(40):
        a_b, _ = pol.predict(obs, episode_start=start)
        for i in range(3):
            a_i, _ = singles[i].predict(obs[i], episode_start=start[i : i + 1])
            np.testing.assert_allclose(a_b[i], a_i, atol=1e-12)
        obs = np.stack([e.step(a)[0] for e, a in zip(envs, a_b, strict=True)])
        start[:] = False


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
                rows.append([m["iae_K_s"], m["max_abs_dev_K"], m["reheat_temp_C_iae_K_s"],
                             m["reheat_temp_C_max_abs_dev_K"]])  # fmt: skip
            if name != "cascade_pi":  # failed solves (max_iter) are rare and counted
                assert pol.stats["fallbacks"] <= 0.03 * pol.stats["solves"]  # measured 1.3 %
                STATS[name, sc] = dict(pol.stats)
            out[name, sc] = np.array(rows)
    return out


def _check_claim(res: dict) -> None:
    """The paper (Fig. 9): the MPC beats the conventional PI on STE and RTE. It does NOT
    reproduce here: on every scenario the MPC's mean STE IAE is more than twice
    cascade_pi's (measured 3 seeds: about 3-6x), its STE peak larger. Asserted as
    measured; the tolerance (factor 2) covers seeds, not a change of verdict."""
    for sc in CLAIM_SCENARIOS:
        pi = res["cascade_pi", sc].mean(0)
        for name in ("mpc_evarx", "mpc_arx"):
            m = res[name, sc].mean(0)
            assert m[0] > 2.0 * pi[0], (name, sc)
            assert m[1] > pi[1], (name, sc)


def test_claim_check_three_seeds():
    _check_claim(_claim(range(3)))


@pytest.mark.slow
def test_claim_check_five_seeds():
    _check_claim(_claim(range(5)))
