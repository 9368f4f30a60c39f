"""Neuro-PID by MEE / MSE (baselines/neuro_pid.py): the mechanism against independent
references, the batched contract, the inner loop, realism and stability, and one test per
claim of Zhang et al. 2012 on steamtemp/Cascade300MW-v0, scenario ``setpoint_step_535_545``
(the Claims table of docs/baselines/neuro_pid.md)."""

from __future__ import annotations

import functools
import math

import gymnasium as gym
import numpy as np
import pytest

import baselines
import steamtemp_gym
from agents.evaluation import run_batch
from agents.leaderboard.plan import DEFAULT_SCENARIOS
from baselines import neuro_pid as npid
from baselines import neuro_pid_commissioning as commissioning
from baselines import neuro_pid_net as npnet
from steamtemp_gym import scenarios
from steamtemp_gym.metrics import limit_cycles

ID = "steamtemp/Cascade300MW-v0"
LAM, SIG = npnet.LAMBDA, npnet.SIGMA_K
#: The realism bound on valve travel against cascade_pi_ff's (tests/test_baseline_realism.py).
TRAVEL_MAX = 3.0


def _net(w, x, scale, base=0.0):
    """Reference forward pass of eq. (5)-(8) in plain numpy: gains b_l + s_l g(net_l)."""
    W2 = w[: npnet.N_W2].reshape(npnet.N_HIDDEN, npnet.N_IN + 1)
    W3 = w[npnet.N_W2 :].reshape(3, npnet.N_HIDDEN + 1)
    h = np.tanh(W2 @ np.r_[1.0, x])
    net = W3 @ np.r_[1.0, h]
    return base + scale * np.exp(net) / (np.exp(net) + np.exp(-net))


def _sens(w, x, E, scale):
    h, g, s = np.empty(npnet.N_HIDDEN), np.empty(3), np.empty(npnet.N_W)
    du = np.array([E[0] - E[1], E[0], E[0] - 2 * E[1] + E[2]])
    npnet.forward(w, x, h, g)
    npnet.sensitivity(w, x, h, g, du, scale, s)
    return s, du


def test_sensitivity_is_minus_du_dw_by_finite_differences():
    """Eq. (11), (15) with the Jacobian sign +1: de_k/dw = -d(sum_l dU_l k_l)/dw."""
    rng = np.random.default_rng(1)
    w = rng.uniform(-1, 1, npnet.N_W)
    x, E, scale = rng.normal(size=npnet.N_IN), rng.normal(size=3), np.array([1.2, 1.0, 1.0])
    s, du = _sens(w, x, E, scale)
    fd = np.empty(npnet.N_W)
    for j in range(npnet.N_W):
        dw = np.zeros(npnet.N_W)
        dw[j] = 1e-6
        fd[j] = -(du @ (_net(w + dw, x, scale) - _net(w - dw, x, scale))) / 2e-6
    np.testing.assert_allclose(s, fd, rtol=1e-6, atol=1e-9)


def _run_kernel(mee, es, xs, w, L, eta=0.0):
    n = 1
    W, G, V = w[None].copy(), np.zeros((n, npnet.N_W)), np.zeros(n)
    Eb, Sb = np.zeros((n, L)), np.zeros((n, L, npnet.N_W))
    nb, hd, gains = np.zeros(n, np.int64), np.zeros(n, np.int64), np.zeros((n, 3))
    base, scale = np.zeros((n, 3)), np.ones((n, 3))
    Gs, Vs = [], []
    for k in range(len(es)):
        E = np.array([[es[k], es[k - 1] if k else es[0], es[k - 2] if k > 1 else es[0]]])
        npnet.npid_step(
            xs[k][None], E, W, G, V, Eb, Sb, nb, hd, base, scale, mee, SIG, LAM, L, eta, gains
        )
        Gs.append(G[0].copy())
        Vs.append(V[0])
    return np.array(Gs), np.array(Vs)


def test_mee_gradient_is_eq_10_over_the_receding_window():
    """Kernel (ring buffer of L = 5, wrapped several times) vs eq. (3) and (10) summed
    directly over the stored errors and sensitivities, weights frozen (eta = 0)."""
    rng = np.random.default_rng(2)
    L, K = 5, 23
    w = rng.uniform(-0.5, 0.5, npnet.N_W)
    es, xs = rng.normal(0, 2, K), rng.normal(size=(K, npnet.N_IN))
    G_k, V_k = _run_kernel(True, es, xs, w, L)
    S = []
    G, V = np.zeros(npnet.N_W), 0.0
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
    w = rng.uniform(-0.5, 0.5, npnet.N_W)
    es, xs = rng.normal(0, 2, K), rng.normal(size=(K, npnet.N_IN))
    G_k, V_k = _run_kernel(False, es, xs, w, 5)
    G, M = np.zeros(npnet.N_W), 0.0
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
    w = rng.uniform(-0.5, 0.5, npnet.N_W)
    es, xs = rng.normal(0, 2, 40), rng.normal(size=(40, npnet.N_IN))
    G_mee, _ = _run_kernel(True, es, xs, w, 200)
    G_mse, _ = _run_kernel(False, es, xs, w, 200)
    assert np.linalg.norm(G_mee[-1]) > 0 and np.linalg.norm(G_mse[-1]) > 0
    # with the paper's constants the MEE gradient is far smaller than the MSE one
    assert np.linalg.norm(G_mee[-1]) < 0.2 * np.linalg.norm(G_mse[-1])


def test_initial_net_gives_the_commissioning_gains_at_the_midpoint_of_their_bounds():
    table = commissioning.commissioning_gains(npid.NeuroPID, ID, "{}")
    assert table.shape == (len(npid.GAIN_LOADS), 1, 4)
    k0 = table[-1, 0]  # rated load
    w, base, scale = npnet.initial_weights(k0[:3])
    np.testing.assert_allclose(_net(w, np.zeros(npnet.N_IN), scale, base), k0[:3], rtol=1e-12)
    # the gains can move within k0 (1 -+ 0.5) whatever the training does
    np.testing.assert_allclose(base, 0.5 * k0[:3])
    np.testing.assert_allclose(base + scale, 1.5 * k0[:3])
    assert k0[3] == 1.0
    # SIMC PI on the identified outer process with the inner P loop closed: loop gain
    # G_C2 |K2| = 0.08 stroke/K x 9 kg/s x 2.01 K s/kg = 1.447, so K = 2.09 * 1.447/2.447
    m = commissioning.outer_models(npid.NeuroPID, ID, "{}")[0]
    assert m.K == pytest.approx(2.09 * 1.4472 / 2.4472, rel=0.01)
    w2, _, _ = npnet.initial_weights(k0[:3])
    np.testing.assert_array_equal(w, w2)  # reproducible
    with pytest.raises(ValueError, match="positive"):
        npnet.initial_weights(np.array([0.5, 0.0, 0.05]))


def test_commissioning_gains_follow_the_load_schedule():
    """k_l0(L) linear between the commissioning loads, held beyond them."""
    env = gym.make(ID)
    pol = npid.NeuroPIDMEE(env)
    table = commissioning.commissioning_gains(npid.NeuroPID, ID, "{}")[:, 0, :3]
    k = pol.commissioning(np.array([0.3, 0.5, 0.625, 1.0, 1.1]))[:, 0]
    np.testing.assert_allclose(k[[0, 1]], table[[0, 0]])
    np.testing.assert_allclose(k[2], table[:2].mean(axis=0))
    np.testing.assert_allclose(k[[3, 4]], table[[2, 2]])
    assert table[0, 1] < table[-1, 1]  # the integral gain is lower at low load (slower plant)


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


def test_knobs_and_bad_eta():
    assert [k.name for k in npid.NeuroPIDMEE.KNOBS] == ["eta"]
    assert [k.name for k in npid.NeuroPIDMSE.KNOBS] == ["eta"]
    for cls in (npid.NeuroPIDMEE, npid.NeuroPIDMSE):
        assert cls.knob_defaults(ID) == {"eta": npid.ETA}  # the paper's
        k = cls.KNOBS[0]
        assert k.lo < npid.ETA < k.hi
    env = gym.make(ID)
    assert npid.NeuroPIDMSE(env).eta == npid.ETA and npid.NeuroPIDMSE(env, eta=0.3).eta == 0.3
    for bad in (-1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="eta"):
            npid.NeuroPIDMEE(env, eta=bad)


# ------------------------------------------------------------------- the inner loop
def test_inner_p_is_8_pct_of_stroke_per_K_through_the_input_filter():
    """G_C2 = 8 % of stroke per K of the intermediate temperature, read through the 5 s
    first-order DCS filter: a +1 K step of the measured intermediate temperature opens the
    valve by 0.08 (1 - a^k) after k samples, a = exp(-T_s / 5 s); the outer output held."""
    env = gym.make(ID, scenario="setpoint_step_535_545")
    plant = env.unwrapped.plant
    pol = npid.NeuroPID(env, force_u=0.0, k0=np.full((1, 3), 0.5))
    names = [s.name for s in env.unwrapped.signals.observation]
    i = names.index(plant.control_loops[0][0])
    obs, _ = env.reset(seed=0)
    a0, _ = pol.predict(obs)
    stepped = obs.copy()
    stepped[i] += 1.0 / env.unwrapped.signals.observation[i].scale
    a = np.exp(-plant.dt_s / npid.FILTER_S)
    for k in range(1, 30):
        act, _ = pol.predict(stepped)
        dv = (float(act[0]) - float(a0[0])) / 2.0  # action = 2 v - 1
        assert dv == pytest.approx(0.08 * (1.0 - a**k), rel=1e-5), k


# ------------------------------------------------------------- realism and stability
@functools.cache
def _metrics(env_id: str, scenario: str, name: str, eta: float | None, seeds: int) -> dict:
    venv = gym.make_vec(
        env_id,
        num_envs=seeds,
        scenario=scenarios.resolve(scenario, env_id),
        vectorization_mode="vector_entry_point",
    )
    kw = {} if eta is None else {"eta": eta}
    res = run_batch(venv, baselines.make(name, venv, **kw), list(range(seeds)))
    return {k: float(np.mean([r["metrics"][k] for r in res])) for k in res[0]["metrics"]}


@pytest.mark.parametrize(
    "scenario",
    [
        "setpoint_step_535_545",
        pytest.param("load_ramp_100_50", marks=pytest.mark.slow),
        pytest.param("heldout:high_noise", marks=pytest.mark.slow),
    ],
)
def test_travel_within_three_times_cascade_pi_ff_on_the_papers_plant(scenario):
    """The paper's P inner loop through the filter strokes the valve about as much as the
    industrial cascade (measured 0.80x, 0.95x and 0.94x; 40x, 52x and 25x with G_C2 read
    as 8 kg/s per K on the unfiltered temperature)."""
    ref = _metrics(ID, scenario, "cascade_pi_ff", None, 1)
    for name in ("neuro_pid_mee", "neuro_pid_mse"):
        m = _metrics(ID, scenario, name, None, 1)
        assert m["valve_travel"] <= TRAVEL_MAX * ref["valve_travel"], (name, m["valve_travel"])
        assert not limit_cycles(m["quiet_p2p_K"], ref["quiet_p2p_K"]), name


#: A learning rate that drives the MSE net's gains to their bounds within an episode.
ETA_SATURATING = 10.0


@pytest.mark.parametrize(
    "env_id",
    [
        "steamtemp/SupercriticalFSH-v0",
        pytest.param("steamtemp/DrumBoilerSH-v0", marks=pytest.mark.slow),
    ],
)
def test_bounded_gains_keep_the_deep_fast_ramp_stable(env_id):
    """Even with its gains driven to their bounds, the MSE net holds the held-out deep fast
    ramp: no trip, no limit cycle against cascade_pi_ff, a peak no larger than the plain
    cascade PI's. Measured peaks 12.8 K (FSH) and 16.5 K (drum), cascade_pi 15.6 and
    16.9 K; gains bounded to twice their commissioning values instead: quiet p2p 28.7 K
    on the FSH against cascade_pi_ff's 8.7 K; unbounded (the paper's eta): peaks 34.4 K
    and 42.5 K."""
    ref = _metrics(env_id, "heldout:deep_fast_ramp", "cascade_pi_ff", None, 1)
    pi = _metrics(env_id, "heldout:deep_fast_ramp", "cascade_pi", None, 1)
    m = _metrics(env_id, "heldout:deep_fast_ramp", "neuro_pid_mse", ETA_SATURATING, 1)
    assert not m["tripped"]
    assert m["max_abs_dev_K"] <= pi["max_abs_dev_K"], (m["max_abs_dev_K"], pi["max_abs_dev_K"])
    assert not limit_cycles(m["quiet_p2p_K"], ref["quiet_p2p_K"]), m["quiet_p2p_K"]
    assert m["valve_travel"] <= TRAVEL_MAX * ref["valve_travel"]


@pytest.mark.slow
@pytest.mark.parametrize("env_id", steamtemp_gym.ENV_IDS)
def test_realism_on_every_named_and_heldout_scenario(env_id):
    """Every variant (the paper's eta, the adapting etas, the top of each knob's box) on
    every named and held-out scenario: no trip, travel within 3x cascade_pi_ff's, no limit
    cycle (seeds 0-1)."""
    variants = [
        ("neuro_pid_mee", None),
        ("neuro_pid_mse", None),
        ("neuro_pid_mee", npid.ADAPTING_ETA["mee"]),
        ("neuro_pid_mse", npid.ADAPTING_ETA["mse"]),
        ("neuro_pid_mee", npid.NeuroPIDMEE.KNOBS[0].hi),
        ("neuro_pid_mse", npid.NeuroPIDMSE.KNOBS[0].hi),
    ]
    for scenario in DEFAULT_SCENARIOS:
        ref = _metrics(env_id, scenario, "cascade_pi_ff", None, 2)
        for name, eta in variants:
            m = _metrics(env_id, scenario, name, eta, 2)
            assert not m["tripped"], (scenario, name, eta)
            assert m["valve_travel"] <= TRAVEL_MAX * ref["valve_travel"], (scenario, name, eta)
            assert not limit_cycles(m["quiet_p2p_K"], ref["quiet_p2p_K"]), (scenario, name, eta)


# ----------------------------------------------------------------------- the claims
# Zhang et al. 2012, Section 5, on steamtemp/Cascade300MW-v0 ``setpoint_step_535_545``
# (535 C, step to 545 C at 500 s, rated load, 2000 s). e = setpoint - true outlet.
PAPER = {"mee": (0.4452, 1.7049), "mse": (0.5093, 1.7153)}  # error mean, std (K)
#: Transient of the step excluded from the "after the step" statistics (s).
SETTLED_S = 800.0
#: The two learning-rate settings compared: the paper's, and nets that adapt alike.
SETTINGS = {"paper": {"mee": npid.ETA, "mse": npid.ETA}, "adapting": npid.ADAPTING_ETA}
#: Few seeds in the default suite, 20 (the numbers quoted) in the slow one.
SEEDS = pytest.mark.parametrize("seeds", [4, pytest.param(20, marks=pytest.mark.slow)])


def renyi2(e: np.ndarray) -> float:
    """Renyi's quadratic entropy -log V of samples e (Parzen estimate with the paper's
    Gaussian kernel, sigma = 2 K: V = mean over pairs of kappa(e_i - e_j, 2 sigma^2))."""
    d = e[:, None] - e[None, :]
    k = np.exp(-d * d / (4.0 * SIG**2)) / (math.sqrt(2.0 * math.pi) * math.sqrt(2.0) * SIG)
    return float(-np.log(k.mean()))


class _NoDisturbanceInputs(npid.NeuroPID):
    """The same neuro-PID with its two measured-disturbance inputs held at zero."""

    def _inputs(self, st, y):
        x = super()._inputs(st, y)
        x[:, 3:] = 0.0
        return x


@functools.cache
def step_runs(setting: str, seeds: int, disturbance_inputs: bool = True) -> dict:
    """Per criterion, per seed: the error trace, the gains and the weights."""
    venv = gym.make_vec(
        ID,
        num_envs=seeds,
        scenario="setpoint_step_535_545",
        vectorization_mode="vector_entry_point",
    )
    cls = npid.NeuroPID if disturbance_inputs else _NoDisturbanceInputs
    out = {}
    for crit, eta in SETTINGS[setting].items():
        rec = npid.Recorder(cls(venv, criterion=crit, eta=eta))
        res = run_batch(venv, rec, list(range(seeds)))
        e = np.array([r["trace"]["setpoint_C"] - r["trace"]["outlet_temp_C"] for r in res])
        out[crit] = {
            "t": res[0]["trace"]["time_s"],
            "e": e,
            "gains": np.array(rec.gains),
            "W": np.array(rec.weights),
        }
    return out


def _paired(x: np.ndarray) -> tuple[float, float]:
    """Mean over seeds and its standard error."""
    return float(x.mean()), float(x.std(ddof=1) / math.sqrt(len(x)))


def _assert_negative(d: np.ndarray, seeds: int) -> None:
    """A paired difference below zero: its mean over the seeds; on 20 seeds also by two
    standard errors."""
    m, se = _paired(d)
    assert m < 0.0 and (seeds < 20 or m + 2.0 * se < 0.0), (m, se)


def _mean_std(run: dict) -> np.ndarray:
    return np.stack([run["e"].mean(axis=1), run["e"].std(axis=1)], axis=1)


def check_mee_below_mse(stat: str, setting: str, seeds: int) -> None:
    """MEE's error ``stat`` ("mean" or "std") below MSE's: the seeds' mean relative
    difference within a factor of 2 of the paper's."""
    k = ("mean", "std").index(stat)
    r = step_runs(setting, seeds)
    rel = _mean_std(r["mee"])[:, k] / _mean_std(r["mse"])[:, k] - 1.0
    paper = PAPER["mee"][k] / PAPER["mse"][k] - 1.0
    assert 2.0 * paper <= _paired(rel)[0] <= 0.5 * paper, _paired(rel)


@pytest.mark.parametrize(
    "setting",
    [
        pytest.param(
            "paper",
            marks=pytest.mark.xfail(
                strict=True,
                reason=(
                    "MEE - MSE error mean +0.18 % (+0.0012 K) at the paper's eta (20 seeds; paper "
                    "-12.6 %): the nets barely learn"
                ),
            ),
        ),
        pytest.param(
            "adapting",
            marks=pytest.mark.xfail(
                strict=True,
                reason=(
                    "MEE - MSE error mean +9.2 % (+0.050 K) between adapting nets (20 seeds; paper "
                    "-12.6 %): MEE is shift-invariant, it does not act on the mean, MSE does"
                ),
            ),
        ),
    ],
)
@SEEDS
def test_claim_mee_smaller_error_mean(setting, seeds):
    """Claim: MEE's error mean below MSE's, by the paper's -12.6 % (0.4452 against 0.5093)
    within a factor of 2 (-6.3 % to -25 %)."""
    check_mee_below_mse("mean", setting, seeds)


@pytest.mark.parametrize(
    "setting",
    [
        pytest.param(
            "paper",
            marks=pytest.mark.xfail(
                strict=True,
                reason=(
                    "MEE - MSE error std -0.023 % (-0.0007 K) at the paper's eta (20 seeds; paper "
                    "-0.61 %): right direction, a 26th of the size, the nets barely learn"
                ),
            ),
        ),
        "adapting",
    ],
)
@SEEDS
def test_claim_mee_smaller_error_std(setting, seeds):
    """Claim: MEE's error std below MSE's, by the paper's -0.61 % (1.7049 against 1.7153)
    within a factor of 2 (-0.30 % to -1.21 %), relative: the plant's disturbances make our
    std about 1.7 times the paper's. Between nets that adapt alike, MEE narrows the error:
    -1.14 +- 0.12 % (-0.033 K) of std (20 seeds; 4 seeds: -0.86 %)."""
    check_mee_below_mse("std", setting, seeds)


@SEEDS
def test_claim_step_tracked_around_the_setpoint(seeds):
    """Claim: "both approaches can stabilize the superheated temperature around the set
    point": after the step's transient the error averages, over the seeds, within 0.5 K of
    zero (no offset; single seeds wander by up to 0.65 K with the slow disturbance omega),
    and it stays inside the trip band."""
    r = step_runs("paper", seeds)
    for crit in ("mee", "mse"):
        late = r[crit]["t"] >= SETTLED_S
        assert abs(r[crit]["e"][:, late].mean()) < 0.5, crit
        assert np.abs(r[crit]["e"]).max() < 28.0, crit


@pytest.mark.xfail(
    strict=True,
    reason="error mean / std 0.70 / 2.86 K (MEE), 0.70 / 2.86 K "
    "(MSE) at the paper's eta (20 seeds; paper 0.445 / 1.705, 0.509 / 1.715): "
    "the plant's omega (uniform +-3 K, 150 s) is larger than the paper's, and "
    "the inner P at 8 %/K tracks the step more slowly than a loop gain of 16",
)
@SEEDS
def test_claim_error_mean_and_std_of_the_papers_size(seeds):
    """Claim: error mean / std 0.4452 / 1.7049 K (MEE), 0.5093 / 1.7153 K (MSE), each within
    +-25 %."""
    r = step_runs("paper", seeds)
    for crit in ("mee", "mse"):
        m = _mean_std(r[crit]).mean(axis=0)
        assert m == pytest.approx(PAPER[crit], rel=0.25), crit


def _gain_spread(run: dict) -> np.ndarray:
    """(seeds, 3): std over time after the transient of each gain over its start value."""
    late = run["t"][1:] >= SETTLED_S  # gains[k] act on the step k -> k + 1
    g = run["gains"]
    return (g[late] / g[0]).std(axis=0)


@pytest.mark.xfail(
    strict=True,
    reason="gain std over time / k0 (20 seeds, paper's eta), MEE "
    "vs MSE: k_p 0.0906 vs 0.0906, k_i 0.0516 vs 0.0510, k_d 0.0392 vs 0.0393: "
    "k_i varies more under MEE; the spread is the inputs' modulation through the "
    "initial weights, not training",
)
@SEEDS
def test_claim_mee_gains_less_uncertain(seeds):
    """Claim (Fig. 7): the MEE-trained PID gains have smaller uncertainties than the MSE
    ones: the std over time of each of k_p, k_i, k_d smaller."""
    r = step_runs("paper", seeds)
    d = _gain_spread(r["mee"]) - _gain_spread(r["mse"])
    assert np.all(d.mean(axis=0) < 0.0), d.mean(axis=0)


def _entropies(run: dict, lo: float, hi: float) -> np.ndarray:
    sel = (run["t"] >= lo) & (run["t"] < hi)
    return np.array([renyi2(e[sel]) for e in run["e"]])


@pytest.mark.parametrize("setting", ["paper", "adapting"])
@SEEDS
def test_claim_mee_smaller_error_entropy(setting, seeds):
    """Claim (Fig. 8): the error entropy (Renyi's quadratic, the performance index) is
    smaller under MEE than under MSE, after the step's transient. Measured (20 seeds):
    -0.00029 +- 0.00005 (paper's eta), -0.0151 +- 0.0024 (adapting) nats; the paper gives
    no number."""
    r = step_runs(setting, seeds)
    d = _entropies(r["mee"], SETTLED_S, np.inf) - _entropies(r["mse"], SETTLED_S, np.inf)
    _assert_negative(d, seeds)


@pytest.mark.parametrize(
    "seeds",
    [
        4,
        pytest.param(
            20,
            marks=[
                pytest.mark.slow,
                pytest.mark.xfail(
                    strict=True,
                    reason="MEE - MSE entropy fall -0.0064 +- 0.0052 nats (20 seeds, adapting): "
                    "the direction, not significant",
                ),
            ],
        ),
    ],
)
def test_claim_mee_pdf_narrows_along_time(seeds):
    """Claim (Fig. 9-12): under MEE the error PDF becomes narrower and sharper along the
    sampling time, against MSE: from 800-1400 s to 1400-2000 s its entropy falls by more
    than the MSE one does (adapting nets)."""
    r = step_runs("adapting", seeds)
    fall = {
        c: _entropies(r[c], 1400.0, np.inf) - _entropies(r[c], SETTLED_S, 1400.0)
        for c in ("mee", "mse")
    }
    _assert_negative(fall["mee"] - fall["mse"], seeds)


@pytest.mark.xfail(
    strict=True,
    reason="mean-square weight increment of the MEE net, "
    "1400-2000 s over 800-1400 s: x1.16 (20 seeds, paper's eta; x1.10 adapting): "
    "with forgetting lambda = 0.04 the gradient follows the current errors, "
    "which the plant's disturbances keep alive",
)
@SEEDS
def test_claim_mee_weights_converge(seeds):
    """Claim (Section 3.3, eq. (24)-(25)): with 0 < eta < 1 / max |lambda_i| the weight
    increments vanish in mean square: the late mean of |W_(k+1) - W_k|^2 below the earlier
    one."""
    r = step_runs("paper", seeds)["mee"]
    msq = (np.diff(r["W"], axis=0) ** 2).sum(axis=2)
    t = r["t"][2:]
    early = msq[(t >= SETTLED_S) & (t < 1400.0)].mean()
    late = msq[t >= 1400.0].mean()
    assert late < early, late / early


@pytest.mark.xfail(
    strict=True,
    reason="MEE error std with - without the measured "
    "disturbance inputs +0.0014 +- 0.0056 K (20 seeds): through eq. (4) they "
    "only modulate gains that multiply errors, no additive feed-forward",
)
@SEEDS
def test_claim_disturbance_inputs_act_as_feedforward(seeds):
    """Claim (abstract, Section 4): with the measurable disturbances omega, omega_2 as net
    inputs "feedback control is combined with feedforward control": the error std at least
    2 % below that of the same net without them."""
    with_d = _mean_std(step_runs("paper", seeds)["mee"])[:, 1]
    without = _mean_std(step_runs("paper", seeds, False)["mee"])[:, 1]
    assert _paired(with_d / without - 1.0)[0] <= -0.02
