"""Exogenous-variable-dependent ARX (EV-ARX) model and its fits (one-step and
simulation error).

Source: Toyoda and Wada 1999 (docs/references.md), sections 3-4 (model, eq. 7-20) and 7.1
(identification test, comparison with linear ARX models interpolated by load, Fig. 8).
Identified through the env by
baselines/evarx_identification.py; used by baselines/mpc_evarx.py.

Model (eq. 7-13). Per output j on a model interval Ts (the plant's control interval times
n, the multiple nearest to ``TS_TARGET_S``):

    y_j(t+1) = theta_j(w_t)^T phi(t),   theta_j(w) = theta_j0 + sum_i theta_ji f(w | gamma_ji)
    f(w | gamma_ji) = exp(-gamma_ji (w - w0_i)^2)                               (12)-(13)

y are the deviations STE, RTE (eq. 11's outputs: the measured main steam less its
setpoint, every other controlled output less its value at the start). phi(t) = [xi_y(t),
xi_u(t), xi_w(t)] (eq. 8-10): ``N_Y`` lags of every output (MIMO, eq. 11), ``N_U`` lags of
every bias and ``N_W`` lags of the load change Delta w(t) = w(t) - w(t - Ts). The biases
enter as changes of their block means over the model interval, Delta ubar(t), as the
load enters as its change (ours: the loops integrate a held bias out, the step tests of
the real closed loop end at zero, and a model on the levels fitted steady gains of either
sign to the slow unmeasured disturbances). gamma has one entry per output and reference
load (the diag{} of eq. 12). Reference loads ``W0`` = (0.5, 0.75, 1.0): the paper's
10/50/80 % span its simulator's range; this benchmark's scenarios span 50-100 % and a
basis centred outside the data is not identifiable. Orders (the paper gives none) chosen
on the training data's fit.

Identification for infinite-step prediction (section 4.2, eq. 14-20). The paper builds
the model to predict any number of steps ahead with the future load known: eq. (14) feeds
the model its own past outputs, and the Gauss-Newton cost (16) is written on that
prediction yhat. Read that way, theta and gamma minimise the *simulation* (output-error)
sum of squares, and the Gauss-Newton Jacobian d yhat / d Theta carries the recursion
through the fed-back outputs (:func:`simulation_sensitivities`):

    D(t+1) = d/dTheta [theta(w_t)^T phi] |_(yhat lags held) + A(w_t) [D(t), D(t-Ts), ...]

with A(w_t) the output-lag block of the frozen coefficients. Two stages: the one-step
(equation-error) Gauss-Newton of eq. (16) with the measured outputs in phi
(:func:`fit_evarx`, gamma from ``GAMMA0`` = 1 / (2 x 0.25^2), half-width = centre
spacing), then Gauss-Newton eq. (17)-(20) on the simulation error from that start
(:func:`fit_output_error`: Levenberg-Marquardt damped, gamma kept in [``GAMMA_MIN``,
``GAMMA_MAX``]). The residuals are divided by each output's standard deviation on the
training data, so STE and RTE count alike. The data are simulated as Ts-spaced
sequences started at ``SEQ_STARTS`` control intervals spread over the first Ts, each
started from the measured outputs. One-step estimates are biased where the outputs are
noisy (the noise sits in the regressors); tests/test_mpc_evarx.py shows it on a known
system, and that the simulation-error fit recovers it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

TS_TARGET_S = 20.0
N_Y, N_U, N_W = 3, 4, 3
W0 = (0.5, 0.75, 1.0)
GAMMA0 = 1.0 / (2.0 * 0.25**2)
GAMMA_MIN, GAMMA_MAX = 0.5, 500.0
#: iterations of the simulation-error Gauss-Newton (Levenberg-Marquardt damped)
OE_ITERS = 30
#: interleaved sequences per model interval in the simulation-error fit; the one-step
#: start uses the alignments of the same grid
SEQ_STARTS = 2
#: iterations of the one-step Gauss-Newton (the start)
EE_ITERS = 10
ARX_LOADS = (0.55, 0.7, 0.85, 1.0)


def regressors(data: dict[str, np.ndarray], n: int) -> tuple[np.ndarray, ...]:
    """(phi (T', p), w (T',), target y(t + n) (T', n_out)) on the model interval of n
    samples, at every alignment t of the fine grid (overlapping). The bias lags enter as
    differences of block means, Delta ubar(t) = ubar(t) - ubar(t - Ts), as the load does."""
    y, u, w = data["y"], data["u"], data["w"]
    csum = np.vstack([np.zeros((1, u.shape[1])), np.cumsum(u, 0)])
    t = np.arange(max(N_Y, N_U + 1, N_W + 1) * n, len(w) - n)

    def ubar(tt: np.ndarray) -> np.ndarray:  # block mean of the inputs over [tt, tt + n)
        return (csum[tt + n] - csum[tt]) / n

    cols = [y[t - lag * n] for lag in range(N_Y)]
    cols += [ubar(t - lag * n) - ubar(t - (lag + 1) * n) for lag in range(N_U)]
    cols += [(w[t - lag * n] - w[t - (lag + 1) * n])[:, None] for lag in range(N_W)]
    return np.hstack(cols), w[t], y[t + n]


def sequences(
    data: dict[str, np.ndarray], n: int, starts: int = SEQ_STARTS
) -> tuple[np.ndarray, ...]:
    """The regressors as interleaved Ts-spaced sequences, ``starts`` of them evenly spread
    over the first model interval: (phi (K, S, p), w (K, S), target (K, S, n_out))."""
    phi, w, y = regressors(data, n)
    K = len(w) // n
    o = np.unique(np.arange(min(starts, n)) * n // min(starts, n))
    return (
        phi[: K * n].reshape(K, n, -1)[:, o],
        w[: K * n].reshape(K, n)[:, o],
        y[: K * n].reshape(K, n, -1)[:, o],
    )


def gaussian_basis(w: np.ndarray, gamma: np.ndarray) -> np.ndarray:
    """(..., 1 + n_w0): f_0 = 1 and f_i = exp(-gamma_i (w - w0_i)^2), eq. (13); no
    Gaussian columns where gamma is empty (a plain ARX)."""
    w0 = np.asarray(W0)[: len(gamma)]
    d2 = (np.asarray(w, float)[..., None] - w0) ** 2
    return np.concatenate([np.ones(d2.shape[:-1] + (1,)), np.exp(-gamma * d2)], -1)


def evarx_predict(
    theta: np.ndarray, gamma: np.ndarray, phi: np.ndarray, w: np.ndarray
) -> np.ndarray:
    """One-step prediction of one output, eq. (11)-(12): theta (1 + n_w0, p)."""
    return np.einsum("ti,ip,tp->t", gaussian_basis(w, gamma), theta, phi)


def lstsq_scaled(J: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Least squares J x = r with the columns of J scaled to unit norm."""
    sc = np.linalg.norm(J, axis=0) + 1e-12
    return np.linalg.lstsq(J / sc, r, rcond=1e-10)[0] / sc


def fit_evarx(
    phi: np.ndarray, w: np.ndarray, y: np.ndarray, iters: int = 30, gamma0: float = GAMMA0
) -> tuple[np.ndarray, np.ndarray, dict]:
    """One-step (equation-error) Gauss-Newton on theta and gamma of one output, eq. (15)-(20)
    with the measured outputs in phi: the start of :func:`fit_output_error`.

    Returns (theta (1 + n_w0, p), gamma (n_w0,), info with the cost history).
    """
    n0, p = len(W0), phi.shape[1]
    gamma = np.full(n0, gamma0)

    def jac_theta(g: np.ndarray) -> np.ndarray:
        return (gaussian_basis(w, g)[:, :, None] * phi[:, None, :]).reshape(len(w), -1)

    theta = lstsq_scaled(jac_theta(gamma), y).reshape(n0 + 1, p)
    cost = [float(np.sum((y - evarx_predict(theta, gamma, phi, w)) ** 2))]
    for _ in range(iters):
        f = gaussian_basis(w, gamma)
        r = y - evarx_predict(theta, gamma, phi, w)
        d2 = (w[:, None] - np.asarray(W0)) ** 2
        Jg = -d2 * f[:, 1:] * (phi @ theta[1:].T)  # d yhat / d gamma_i
        delta = lstsq_scaled(np.hstack([jac_theta(gamma), Jg]), r)  # eq. (17)-(18)
        step = 1.0
        while step > 1e-4:
            th = theta + step * delta[: (n0 + 1) * p].reshape(n0 + 1, p)  # eq. (20)
            g = np.clip(gamma + step * delta[(n0 + 1) * p :], GAMMA_MIN, GAMMA_MAX)
            c = float(np.sum((y - evarx_predict(th, g, phi, w)) ** 2))
            if c < cost[-1]:
                break
            step *= 0.5
        if step <= 1e-4:
            break
        theta, gamma = th, g
        cost.append(c)
        if cost[-2] - cost[-1] < 1e-9 * cost[-2]:
            break
    return theta, gamma, {"cost": cost}


def simulate_coef(C: np.ndarray, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eq. (14) on sequences: coefficients C (K, S, n_out, p) frozen per step, regressors
    phi (K, S, p) whose output lags are replaced by the model's own outputs (started from
    the measured ones). Returns (yhat (K, S, n_out), the regressors used (K, S, p))."""
    K, S, no, _ = C.shape
    ny = N_Y * no
    x = phi.copy()
    yh = np.empty((K, S, no))
    lag = phi[0, :, :ny].copy()
    for k in range(K):
        x[k, :, :ny] = lag
        yk = (C[k] @ x[k][:, :, None])[:, :, 0]
        yh[k] = yk
        lag[:, no:] = lag[:, :-no].copy()
        lag[:, :no] = yk
    return yh, x


def simulation_sensitivities(
    theta: np.ndarray, gamma: np.ndarray, phi: np.ndarray, w: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Simulated outputs (K, S, n_out) of the EV-ARX (theta (n_out, 1 + n_w0, p), gamma
    (n_out, n_w0)) on sequences phi (K, S, p), w (K, S), and their derivatives D (K, S,
    n_out, P) with the parameters [theta.ravel(), gamma.ravel()] (module docstring)."""
    no, nb, p = theta.shape
    n0 = nb - 1
    K, S, _ = phi.shape
    ny = N_Y * no
    F = np.stack([gaussian_basis(w, gamma[j]) for j in range(no)], 2)  # (K, S, no, nb)
    C = np.einsum("ksjb,jbp->ksjp", F, theta)
    yh, x = simulate_coef(C, phi)
    d2 = (w[..., None] - np.asarray(W0)[:n0]) ** 2
    D = np.zeros((K, S, no, theta.size + gamma.size))
    for j in range(no):  # the derivatives with the fed-back lags held
        D[:, :, j, j * nb * p : (j + 1) * nb * p] = (
            F[:, :, j, :, None] * x[:, :, None, :]
        ).reshape(K, S, -1)
        if n0:
            g = theta.size + j * n0
            D[:, :, j, g : g + n0] = -d2 * F[:, :, j, 1:] * (x @ theta[j, 1:].T)
    Dlag = np.zeros((S, ny, D.shape[-1]))
    for k in range(K):  # plus their recursion through the fed-back outputs
        D[k] += C[k, :, :, :ny] @ Dlag
        Dlag[:, no:] = Dlag[:, :-no].copy()
        Dlag[:, :no] = D[k]
    return yh, D


def fit_output_error(
    theta0: np.ndarray,
    gamma0: np.ndarray,
    phi: np.ndarray,
    w: np.ndarray,
    y: np.ndarray,
    iters: int = OE_ITERS,
) -> tuple[np.ndarray, np.ndarray, dict]:
    """Simulation-error (infinite-step prediction, eq. 14 and 16) Gauss-Newton fit of an
    EV-ARX, or of a plain ARX where gamma0 has no columns, from (theta0, gamma0); sequences
    phi (K, S, p), w (K, S), measured outputs y (K, S, n_out).

    Each step solves eq. (17)-(18), (chi + lambda diag chi) delta = beta on the simulation
    sensitivities, with the columns scaled to unit norm and a Levenberg-Marquardt damping
    lambda (divided by 3 after a step that lowers J, multiplied by 4 and retried otherwise:
    a safeguard the paper does not state); gamma is kept in [GAMMA_MIN, GAMMA_MAX].

    Returns (theta, gamma, info): info ``cost`` is the normalized simulation-error sum of
    squares after each accepted step (the first entry at the start).
    """
    sy = y.reshape(-1, y.shape[-1]).std(0) + 1e-9
    nt, shape_t, shape_g = theta0.size, theta0.shape, gamma0.shape
    lo = np.concatenate([np.full(nt, -np.inf), np.full(gamma0.size, GAMMA_MIN)])
    hi = np.concatenate([np.full(nt, np.inf), np.full(gamma0.size, GAMMA_MAX)])

    def unpack(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return x[:nt].reshape(shape_t), x[nt:].reshape(shape_g)

    def cost(x: np.ndarray) -> float:
        th, ga = unpack(x)
        C = np.einsum(
            "ksjb,jbp->ksjp", np.stack([gaussian_basis(w, ga[j]) for j in range(len(th))], 2), th
        )
        with np.errstate(all="ignore"):
            c = float(np.sum(((y - simulate_coef(C, phi)[0]) / sy) ** 2))
        return c if np.isfinite(c) else np.inf

    x = np.clip(np.concatenate([theta0.ravel(), gamma0.ravel()]), lo, hi)
    hist, lam = [cost(x)], 1e-3
    for _ in range(iters):
        yh, D = simulation_sensitivities(*unpack(x), phi, w)
        r = ((y - yh) / sy).reshape(-1)
        J = (D / sy[:, None]).reshape(len(r), -1)  # d yhat / d Theta, normalized
        chi, beta = J.T @ J, J.T @ r  # eq. (17)
        sc = np.sqrt(np.diag(chi)) + 1e-12
        chi_s, beta_s = chi / np.outer(sc, sc), beta / sc
        while lam < 1e8:
            delta = np.linalg.solve(chi_s + lam * np.eye(len(sc)), beta_s) / sc  # eq. (18)
            xn = np.clip(x + delta, lo, hi)  # eq. (20)
            cn = cost(xn)
            if cn < hist[-1]:
                break
            lam *= 4.0
        if lam >= 1e8:
            break
        x, lam = xn, max(lam / 3.0, 1e-9)
        hist.append(cn)
        if hist[-2] - hist[-1] < 1e-7 * hist[-2]:
            break
    th, ga = unpack(x)
    return th, ga, {"cost": hist}


@dataclass(frozen=True)
class Model:
    """A load-dependent ARX model: ``coef(w)`` gives the frozen coefficients (n_out, p)."""

    kind: str
    n_out: int
    n_act: int
    n: int  # model interval in control intervals
    theta: np.ndarray | None = None  # (n_out, 1 + n_w0, p)  EV-ARX
    gamma: np.ndarray | None = None  # (n_out, n_w0)
    arx: np.ndarray | None = None  # (n_loads, n_out, p)  interpolated ARX

    def coef(self, w: Any) -> np.ndarray:
        """Coefficients (..., n_out, p) frozen at the load(s) w."""
        w = np.asarray(w, float)
        if self.kind == "evarx":
            F = np.stack([gaussian_basis(w, self.gamma[j]) for j in range(self.n_out)], -2)
            return np.einsum("...jb,jbp->...jp", F, self.theta)
        L = np.asarray(ARX_LOADS)
        x = np.clip(w, L[0], L[-1])
        k = np.clip(np.searchsorted(L, x, side="right") - 1, 0, len(L) - 2)
        s = ((x - L[k]) / (L[k + 1] - L[k]))[..., None, None]
        return (1.0 - s) * self.arx[k] + s * self.arx[k + 1]

    def one_step(self, phi: np.ndarray, w: np.ndarray) -> np.ndarray:
        """One-interval-ahead predictions (T, n_out) for regressors phi (T, p)."""
        return np.einsum("tjp,tp->tj", self.coef(w), phi)

    def step_response(self, w: float, N: int) -> np.ndarray:
        """(N, n_out, n_act): y(k + 1 .. k + N) after a unit bias step at k, frozen at w."""
        a, b, _ = split(self.coef(w), self.n_out, self.n_act)
        return step_responses(a, b, N)


def split(c: np.ndarray, n_out: int, n_act: int) -> tuple[np.ndarray, ...]:
    """Coefficients (n_out, p) -> a (n_out, N_Y, n_out), b (n_out, N_U + 1, n_act) on the
    bias block means ubar(t), ubar(t - Ts), ... (the differences' coefficients expanded:
    their sum is zero, a held bias has no steady effect), c (n_out, N_W)."""
    i = N_Y * n_out
    a = c[:, :i].reshape(-1, N_Y, n_out)
    bd = c[:, i : i + N_U * n_act].reshape(-1, N_U, n_act)
    b = np.zeros((bd.shape[0], N_U + 1, n_act))
    b[:, :-1] += bd
    b[:, 1:] -= bd
    i += N_U * n_act
    return a, b, c[:, i : i + N_W]


def advance(
    a: np.ndarray, b: np.ndarray, c: np.ndarray, dy: np.ndarray, du: np.ndarray, ddw: np.ndarray
) -> np.ndarray:
    """One model interval of the differenced model: Delta y(t + 1) from the past output
    differences dy (N_Y, n_out), bias differences du (N_U + 1, n_act) and load-change
    differences ddw (N_W,), newest first."""
    return np.einsum("jlo,lo->j", a, dy) + np.einsum("jlm,lm->j", b, du) + c @ ddw


def step_responses(a: np.ndarray, b: np.ndarray, N: int) -> np.ndarray:
    """(N, n_out, n_act): y(k + 1 .. k + N) after a unit step of each input at k (frozen)."""
    n_out, n_act = b.shape[0], b.shape[2]
    G = np.zeros((N, n_out, n_act))
    for m in range(n_act):
        dy, du = np.zeros((N_Y, n_out)), np.zeros((b.shape[1], n_act))
        du[0, m] = 1.0
        y = np.zeros(n_out)
        for k in range(N):
            d = advance(a, b, np.zeros((n_out, N_W)), dy, du, np.zeros(N_W))
            y = y + d
            G[k, :, m] = y
            dy = np.vstack([d[None], dy[:-1]])
            du = np.vstack([np.zeros((1, n_act)), du[:-1]])
    return G


def steady_gains(model: Model, w: float) -> np.ndarray:
    """(n_out, n_act) steady gain of the model frozen at w: (I - sum A)^-1 sum B."""
    a, b, _ = split(model.coef(w), model.n_out, model.n_act)
    return np.linalg.solve(np.eye(model.n_out) - a.sum(1), b.sum(1))


def first_lobe(G: np.ndarray, frac: float = 0.5) -> np.ndarray:
    """(n_out, n_act) signed extremum of the first lobe of step responses G (N, n_out,
    n_act): the lobe holding the first sample whose size reaches ``frac`` of the largest
    (0 where a response is identically 0)."""
    N, no, na = G.shape
    out = np.zeros((no, na))
    for j in range(no):
        for m in range(na):
            g = G[:, j, m]
            big = np.abs(g).max()
            if big == 0.0:
                continue
            i = int(np.argmax(np.abs(g) >= frac * big))
            s = np.sign(g[i])
            end = i + int(np.argmax(np.sign(g[i:]) != s)) if np.any(np.sign(g[i:]) != s) else N
            lobe = g[i:end]
            out[j, m] = lobe[np.argmax(np.abs(lobe))]
    return out


def simulate(model: Model, data: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Eq. (14): the model fed its own past outputs over ``data``, every interleaved
    sequence; (measured y, simulated yhat), each (K S, n_out)."""
    phi, w, y = sequences(data, model.n)
    yh, _ = simulate_coef(model.coef(w), phi)
    return y.reshape(-1, model.n_out), yh.reshape(-1, model.n_out)


def fit_percent(y: np.ndarray, yh: np.ndarray) -> np.ndarray:
    """100 (1 - ||y - yhat|| / ||y - mean y||) per output."""
    return 100.0 * (1.0 - np.linalg.norm(y - yh, axis=0) / np.linalg.norm(y - y.mean(0), axis=0))
