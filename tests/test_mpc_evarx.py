"""EV-ARX model (baselines/evarx.py) and its MPC (baselines/mpc_evarx.py): identification
(recovery of known systems, the simulation-error Jacobian), the model against step tests
of the real closed loop, the QP, the safety layer, the knobs, and the claims of Toyoda and
Wada 1999 on steamtemp/BoilerTurbineMIMO-v0. Registry-wide contracts (every plant, batched
== single, every named scenario) are in tests/test_baselines.py."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import numpy as np
import pytest

import baselines
import steamtemp_gym  # noqa: F401  (registers the ids)
from agents.evaluation import run_episode
from baselines import evarx as E
from baselines import evarx_identification as EI
from baselines import tuning
from baselines.mpc_evarx import MPCEVARX, expected_signs
from baselines.mpc_evarx_qp import DEFAULTS, MOVE_STEPS, BiasQP

BTM = "steamtemp/BoilerTurbineMIMO-v0"


def test_prbs_is_a_maximal_length_sequence():
    s = EI.prbs(511, 1, 0)
    assert (s == 1).sum() == 256 and (s == -1).sum() == 255  # m-sequence balance
    np.testing.assert_array_equal(EI.prbs(1022, 1, 0)[511:], s)  # period 511
    assert np.all(EI.prbs(30, 3, 0).reshape(10, 3).std(1) == 0)  # each bit held `clock`


def _synthetic(kind: str, noise: float, seed: int = 0) -> tuple:
    """Sequences (K, S) from a known 2-output EV-ARX (or ARX) driven by random inputs and
    load, with output noise (the regime where one-step fits are biased)."""
    rng = np.random.default_rng(seed)
    no, K, S = 2, 400, 2
    p = E.N_Y * no + 4
    n0 = len(E.W0) if kind == "evarx" else 0
    theta = np.zeros((no, 1 + n0, p))
    theta[0, 0, 0], theta[1, 0, 3] = 0.7, 0.5  # own lags, stable for every load
    theta[0, 0, E.N_Y * no :] = [1.0, -0.5, 0.3, 0.2]
    theta[1, 0, E.N_Y * no :] = [-0.4, 0.8, 0.1, 0.5]
    if n0:
        theta[0, 1, 0], theta[1, 2, 3], theta[0, 3, E.N_Y * no] = -0.3, 0.3, 1.0
    gamma = np.array([[20.0, 30.0, 25.0], [25.0, 20.0, 30.0]])[:, :n0]
    w = 0.45 + 0.6 * rng.random((K, S))
    phi = np.concatenate([np.zeros((K, S, E.N_Y * no)), rng.standard_normal((K, S, 4))], 2)
    C = np.einsum(
        "ksjb,jbp->ksjp", np.stack([E.gaussian_basis(w, gamma[j]) for j in range(no)], 2), theta
    )
    y = E.simulate_coef(C, phi)[0] + noise * rng.standard_normal((K, S, no))
    return theta, gamma, phi, w, y


def test_simulation_sensitivities_match_finite_differences():
    theta, gamma, phi, w, _ = _synthetic("evarx", 0.0)
    th = theta + 0.05
    _, D = E.simulation_sensitivities(th, gamma, phi[:60], w[:60])
    x = np.concatenate([th.ravel(), gamma.ravel()])
    for q in (0, 5, E.N_Y * 2 + 1, th.size + 1, th.size + 4):  # theta (lags, inputs), gamma
        h = np.zeros_like(x)
        h[q] = 1e-6
        yp = E.simulation_sensitivities(
            (x + h)[: th.size].reshape(th.shape),
            (x + h)[th.size :].reshape(gamma.shape),
            phi[:60],
            w[:60],
        )[0]
        ym = E.simulation_sensitivities(
            (x - h)[: th.size].reshape(th.shape),
            (x - h)[th.size :].reshape(gamma.shape),
            phi[:60],
            w[:60],
        )[0]
        np.testing.assert_allclose(D[..., q], (yp - ym) / 2e-6, rtol=1e-5, atol=1e-7)


@pytest.mark.parametrize("kind", ["evarx", "arx"])
def test_output_error_fit_recovers_a_known_system(kind):
    """Section 4.2: the simulation-error Gauss-Newton, started from a perturbed estimate,
    recovers a known EV-ARX or ARX from noisy outputs: its coefficients theta(w) at every
    load of 50-100 % within 0.02 and, on the EV-ARX, each gamma whose basis carries a
    non-zero theta (the others do not enter the model) within 10 %; the cost falls at every
    step and ends at or below that of the true parameters (the noise's)."""
    theta, gamma, phi, w, y = _synthetic(kind, 0.05)
    rng = np.random.default_rng(1)
    th0 = theta + 0.05 * rng.standard_normal(theta.shape)
    th, ga, info = E.fit_output_error(th0, gamma * 1.3, phi, w, y, iters=100)
    loads = np.linspace(0.5, 1.0, 11)
    true = E.Model("evarx", 2, 2, 1, theta=theta, gamma=gamma)  # no gamma columns: ARX
    est = E.Model("evarx", 2, 2, 1, theta=th, gamma=ga)
    np.testing.assert_allclose(est.coef(loads), true.coef(loads), atol=0.02)
    used = np.abs(theta[:, 1:]).max(-1) > 0  # (n_out, n_w0)
    np.testing.assert_allclose(ga[used], gamma[used], rtol=0.1)
    assert np.all(np.diff(info["cost"]) < 0)
    sy = y.reshape(-1, 2).std(0)
    c_true = np.sum(((y - E.simulation_sensitivities(theta, gamma, phi, w)[0]) / sy) ** 2)
    assert info["cost"][-1] <= c_true


def test_one_step_fit_is_biased_where_the_simulation_fit_is_not():
    """The reason for section 4.2's identification: with output noise the equation-error
    (one-step) estimate of the output lags is biased towards zero; the simulation-error
    estimate is not."""
    theta, gamma, phi, w, y = _synthetic("arx", 1.0)
    K, S, p = phi.shape
    x = phi[E.N_Y :].copy()  # the measured (noisy) output lags in the regressors
    for lag in range(E.N_Y):
        x[:, :, 2 * lag : 2 * lag + 2] = y[E.N_Y - 1 - lag : K - 1 - lag]
    ee = np.array([E.lstsq_scaled(x.reshape(-1, p), y[E.N_Y :, :, j].ravel()) for j in (0, 1)])
    oe = E.fit_output_error(ee[:, None], gamma, phi, w, y)[0][:, 0]
    assert abs(ee[0, 0] - 0.7) > 0.15 and abs(ee[1, 3] - 0.5) > 0.15  # biased to zero
    assert abs(oe[0, 0] - 0.7) < 0.05 and abs(oe[1, 3] - 0.5) < 0.05


@pytest.fixture(scope="module")
def ident():
    return EI.identify(BTM, "{}")


@pytest.fixture(scope="module")
def steps():
    return EI.closed_loop_steps(BTM, "{}")


@pytest.mark.parametrize(
    "kind",
    [
        pytest.param(
            "evarx",
            marks=pytest.mark.xfail(
                strict=True,
                reason="measured: EV-ARX at 100 % load, RGD -> STE first lobe -5.59 against "
                "the closed loop's +5.39 (50 and 75 % match); the sign monitor falls back there",
            ),
        ),
        "arx",
    ],
)
def test_model_gains_match_closed_loop_step_tests_at_three_loads(ident, steps, kind):
    """The identified model against step tests of the real closed loop at 50, 75 and 100 %
    load: zero steady gains (the loops integrate every bias out; the closed loop ends within
    0.5 K per stroke of zero) and, on every channel whose first lobe physics fixes (the sign
    the same at every load, expected_signs), the model's first lobe of that sign and within
    a factor 2.5 of the closed loop's."""
    model = ident[kind]
    exp = expected_signs(steps)
    assert np.count_nonzero(exp) >= 3  # SP2 -> STE, RGD -> STE and RGD -> RTE at least
    for li, L in enumerate(EI.STEP_LOADS):
        assert np.all(np.abs(steps[li, -1]) < 0.5)
        np.testing.assert_allclose(E.steady_gains(model, L), 0.0, atol=1e-9)
        cl = E.first_lobe(steps[li])
        mo = E.first_lobe(model.step_response(L, steps.shape[1]))
        chk = exp != 0
        assert np.all(np.sign(mo[chk]) == exp[chk]), (L, mo, cl)
        ratio = mo[chk] / cl[chk]
        assert np.all((ratio > 1 / 2.5) & (ratio < 2.5)), (L, np.round(ratio, 2))


def _toy_qp(rate: float, **weights: float) -> tuple[BiasQP, dict, int]:
    N, no, na = 30, 2, 2
    t = np.arange(1, N + 1)[:, None, None]
    G = (1.0 - np.exp(-t / np.array([[5.0, 9.0], [7.0, 4.0]]))) * np.array(
        [[-2.0, 0.5], [0.3, 3.0]]
    )
    qp = BiasQP(no, na, N, rates=np.full(na, rate), weights=weights)
    return qp, qp.matrices(G), na


def test_unconstrained_qp_equals_least_squares():
    """No bound active: the QP's moves are the normal-equation solution of its cost."""
    qp, mats, na = _toy_qp(10.0, secondary_weight=2.0)
    e = 0.02 * np.random.default_rng(1).standard_normal((qp.N, qp.n_out))
    b0 = np.array([0.01, -0.02])
    warm = (np.zeros(qp.nz), np.zeros(qp.nc))
    ok, moves, _, _ = qp.solve(mats, e, b0, np.full(na, -0.2), np.full(na, 0.2), warm)
    assert ok and moves.shape == (len(MOVE_STEPS), na)
    S = mats["S"]
    Q = np.tile([1.0, 2.0], qp.N)
    g2 = np.abs(np.reshape(S[:, :na], (qp.N, qp.n_out, na))).max((0, 1)) ** 2 + 1e-9
    R = np.diag(np.tile(DEFAULTS["move_weight"] * qp.N * g2, qp.M))
    Rabs = np.tile(DEFAULTS["bias_weight"] * g2, qp.N)
    H = S.T @ (Q[:, None] * S) + R + qp.Cb.T @ (Rabs[:, None] * qp.Cb)
    rhs = S.T @ (Q * e.ravel()) - qp.Cb.T @ (Rabs * np.tile(b0, qp.N))
    np.testing.assert_allclose(moves.ravel(), np.linalg.solve(H, rhs), atol=1e-5)


def test_qp_respects_bias_and_rate_bounds():
    qp, mats, na = _toy_qp(0.05)
    warm = (np.zeros(qp.nz), np.zeros(qp.nc))
    lo, hi = np.array([-0.2, -0.1]), np.array([0.15, 0.2])
    ok, moves, _, _ = qp.solve(mats, np.full((qp.N, qp.n_out), 50.0), np.zeros(na), lo, hi, warm)
    assert ok
    assert np.all(np.abs(moves) <= 0.05 + 1e-4)
    b = np.cumsum(moves, 0)
    assert np.all((b >= lo - 1e-4) & (b <= hi + 1e-4))
    assert np.abs(b).max() > 0.09  # a large error drives the bias to its bounds


def test_knobs_are_keywords_with_checked_ranges():
    env = gym.make(BTM, scenario="load_ramp_100_50")
    names = [k.name for k in MPCEVARX.KNOBS]
    assert set(names) == set(DEFAULTS)
    pol = baselines.make("mpc_evarx", env, move_weight=0.2, secondary_weight=0.5)
    assert pol.knobs["move_weight"] == 0.2 and pol.qp.w["secondary_weight"] == 0.5
    # a knob not given takes the stored common tuning of the plant
    assert pol.knobs["bias_weight"] == tuning.stored("mpc_evarx", BTM)["bias_weight"]
    with pytest.raises(ValueError, match="move_weight"):
        baselines.make("mpc_evarx", env, move_weight=-1.0)


def _run_steps(env, mpc, k_steps: int) -> list[np.ndarray]:
    obs, _ = env.reset(seed=0)
    out = []
    for k in range(k_steps):
        a, _ = mpc.predict(obs, episode_start=np.array([k == 0]))
        out.append(np.asarray(a, float))
        obs, *_ = env.step(a)
    return out


def test_fallback_removes_the_bias_at_the_move_limit():
    """The safety layer: with the residual monitor tripping at every check from the second
    model interval on and a bias of 0.1 of stroke held before it, the bias falls back to the
    plain loops by at most the move limit per interval (no jump), reaches zero, and the
    policy then acts as cascade_pi bit for bit."""
    env = gym.make(BTM, scenario="load_ramp_100_50")
    mpc, pi = baselines.make("mpc_evarx", env), baselines.make("cascade_pi", env)
    mpc.monitor_K = np.zeros_like(mpc.monitor_K)
    mpc.expected_signs = np.zeros_like(mpc.expected_signs)  # the residual monitor alone
    obs, _ = env.reset(seed=0)
    bias = []
    for k in range(600):
        a, _ = mpc.predict(obs, episode_start=np.array([k == 0]))
        a_pi, _ = pi.predict(obs, episode_start=np.array([k == 0]))
        if k == mpc.n - 1:
            mpc._st["b"][0] = 0.1
        bias.append(mpc._st["b"][0].copy())
        if k > 400:
            np.testing.assert_array_equal(a, a_pi)
        obs, *_ = env.step(a)
    bias = np.array(bias)
    assert np.abs(bias[: mpc.n - 1]).max() > 0  # the first interval's QP did move the biases
    assert np.all(np.abs(np.diff(bias[mpc.n - 1 :], axis=0)) <= mpc.move_max + 1e-12)
    assert np.all(bias[-1] == 0.0)
    assert mpc.stats["fallbacks"]["model"] == 600 // mpc.n - 1


def test_monitor_detects_a_sign_flipped_model_and_falls_back():
    """A deliberately sign-flipped model (every bias coefficient negated): the monitor's
    sign check against the closed-loop step tests rejects it at every load, and the policy
    is the plain loops (no bias ever applied); the identified model passes at 50 and 75 %
    load (at 100 % one channel's sign is wrong: the first test above)."""
    env = gym.make(BTM, scenario="load_ramp_100_50")
    mpc = baselines.make("mpc_evarx", env)
    m = mpc.model
    ny = E.N_Y * m.n_out
    theta = m.theta.copy()
    theta[..., ny : ny + E.N_U * m.n_act] *= -1.0
    for L in (0.5, 0.75):
        assert mpc.signs_ok(m.step_response(L, mpc.N))
    flipped = dataclasses.replace(m, theta=theta)
    for L in (0.5, 0.75, 1.0):
        assert not mpc.signs_ok(flipped.step_response(L, mpc.N))
    mpc.model = flipped
    mpc._frozen_cache.clear()
    pi = baselines.make("cascade_pi", env)
    a_mpc = _run_steps(env, mpc, 200)
    a_pi = _run_steps(env, pi, 200)
    np.testing.assert_array_equal(np.array(a_mpc), np.array(a_pi))
    assert mpc.stats["fallbacks"]["sign"] == 200 // mpc.n and mpc.stats["solves"] == 0


# -- claims of Toyoda and Wada 1999 ------------------------------------------------------
FIT = {"evarx": (48.7, 42.5), "arx": (40.2, 10.7)}  # validation fit %, STE / RTE


def test_pin_validation_fit(ident):
    """Simulation fit % (eq. 14) on the validation ramp, as measured (+-3 points)."""
    for kind, v in FIT.items():
        np.testing.assert_allclose(ident["fit_pct"][kind], v, atol=3.0)


def test_claim_evarx_models_the_ramped_plant_better_than_interpolated_arx(ident):
    """Section 7.1 / Fig. 8: under ramped load the EV-ARX predicts (infinite-step, eq. 14)
    better than linear ARX models identified at constant loads and interpolated by load,
    on both outputs. Measured: fit 48.7 / 42.5 % (STE / RTE) against 40.2 / 10.7 %."""
    fit = ident["fit_pct"]
    assert np.all(fit["evarx"] > fit["arx"])


def _iae(names: tuple[str, ...], seeds: range) -> dict[str, np.ndarray]:
    env = gym.make(BTM, scenario="load_ramp_100_50")
    out = {}
    for name in names:
        pol = baselines.make(name, env)
        m = [run_episode(env, pol, seed=s)["metrics"] for s in seeds]
        assert all(x["tripped"] == 0.0 for x in m)
        out[name] = np.array(
            [[x["iae_K_s"], x["reheat_temp_C_iae_K_s"], x["valve_travel"]] for x in m]
        ).mean(0)
    return out


@pytest.fixture(scope="module")
def ramp():
    return _iae(("cascade_pi", "cascade_pi_ff", "mpc_evarx", "mpc_arx"), range(2))


@pytest.mark.parametrize(
    "name",
    [
        "mpc_evarx",
        pytest.param(
            "mpc_arx",
            marks=pytest.mark.xfail(
                strict=True,
                reason="load_ramp_100_50, seeds 0-1, IAE K s STE / RTE: mpc_arx 2327 / 5671 "
                "against cascade_pi 2336 / 5666 (RTE 0.1 % worse)",
            ),
        ),
    ],
)
def test_claim_mpc_beats_pi_on_ste_and_rte(ramp, name):
    """Section 7.2 / Fig. 9: the MPC on the model keeps STE and RTE closer than the
    conventional PI under a ramped load change. Measured (seeds 0-1, IAE K s STE / RTE):
    mpc_evarx 2307 / 5619 against cascade_pi 2336 / 5666, 1.2 % and 0.8 % lower: the
    direction of the paper's claim, by a small margin."""
    assert ramp[name][0] < ramp["cascade_pi"][0] and ramp[name][1] < ramp["cascade_pi"][1]


@pytest.mark.parametrize("name", ["mpc_evarx", "mpc_arx"])
def test_mpc_valve_travel_within_twice_cascade_pi_ff(ramp, name):
    assert ramp[name][2] <= 2.0 * ramp["cascade_pi_ff"][2]
