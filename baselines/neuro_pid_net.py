"""The neuro-PID's net: the three-layer perceptron that sets the PID gains of eq. (4),
and its online training by minimum error entropy (MEE) or mean squared error (MSE).

Source: Zhang et al. 2012 (docs/references.md), Sections 3-5 (equation numbers of the
paper). The controller around it (loops, disturbance inputs, anti-windup, registry names)
is baselines/neuro_pid.py; its commissioning PID, baselines/neuro_pid_commissioning.py.

- Gains from a three-layer perceptron, eq. (5)-(8): inputs O^(1) = (e_k, e_(k-1), e_(k-2),
  omega, omega_2) plus a bias, Q = 4 hidden units f = tanh, three outputs g(x) = e^x /
  (e^x + e^-x) (section 5: five inputs, four hidden nodes). Errors enter the net
  normalized as in the observation (by T0 = 20 K, steamtemp_gym.signals), the disturbances
  normalized by their signals' scales. g maps to (0, 1); gain l is k_l = k_l0 (1 - r + 2 r
  g_l) with r = GAIN_RANGE = 0.5 and k_l0 its commissioning value
  (baselines/neuro_pid_commissioning.py), so the net starts at g's midpoint (steepest
  slope) exactly on the commissioning PID and every gain stays within k_l0 (1 -+ 1/2)
  whatever the training does. That bound keeps the loops stable on every plant and
  scenario (tests/test_neuro_pid.py): gains free to grow to g's unscaled range (k_i up to
  1 per step against ~0.01) drove the MSE net unstable on the fast deep load ramp, and
  even gains up to twice the commissioning values, reached when a large eta drives the
  outputs to their ends, limit-cycle there and under high sensor noise. The paper's
  unscaled outputs in (0, 1) could not hold an integral gain of ~0.01 per step at their
  midpoint, and its initial weights are not given.
- Online training during the episode, one update per sample, procedure of Section 4
  steps (4)-(6): weights updated first (eq. (9), (13)), then the PID output computed
  with the updated net. Sensitivities eq. (11), (12), (15)-(18) with the plant
  Jacobian replaced by its sign (the paper's option under eq. (11)); the sign is that
  of the identified outer process gain, so de_k/dO_l = -dU_l (dU = (e_k - e_(k-1),
  e_k, e_k - 2 e_(k-1) + e_(k-2)), eq. (12)'s du/dO).
- ``mee``: information potential with the Gaussian kernel of variance 2 sigma^2 over
  the receding window of L past errors with forgetting lambda, eq. (3); its gradient
  by eq. (10)/(14): -(lambda / (2 L sigma^2)) sum_(i=k-L)^(k-1) (e_i - e_k)
  kappa(e_i - e_k, 2 sigma^2) (de_i/dw - de_k/dw) + (1 - lambda) dV_(k-1)/dw, and
  gradient ascent on V (eq. (9), (13), (19)). The sensitivities de_i/dw are those
  computed at sample i (stored with e_i in a ring buffer of L), as eq. (10) reads;
  the recursion makes the exact per-step cost O(L n_w) (n_w = 39 weights), not
  O(L^2). Constants (Section 5): sigma = 2 (K), L = 200, lambda = 0.04, eta = 1e-4.
  The window holds fewer than L samples during the first L steps of an episode (the
  sum runs over those; the 1/L factor stays). V_0 of step (2) is the single-sample
  potential kappa(0, 2 sigma^2) with zero gradient.
- ``mse``: the same net, the same eta and lambda; the criterion is the mean squared
  error estimated by the same forgetting recursion as eq. (2)-(3),
  M_k = (1 - lambda) M_(k-1) + lambda e_k^2, with gradient descent on M_k / 2:
  G_k = (1 - lambda) G_(k-1) + lambda e_k de_k/dw, w <- w - eta G_k. The paper gives
  no equation for its MSE comparison; this is the conventional BP neuro-PID
  criterion (its refs. [13], [25]-[27]) written with the MEE variant's forgetting so
  that the two differ only in the criterion (the long-run step size equals the
  instantaneous e_k de_k/dw rule's).
"""

from __future__ import annotations

import math

import numpy as np

from steamtemp_gym._jit import njit

#: Paper, Section 5: kernel size (K), window, forgetting factor, learning rate, hidden units.
SIGMA_K, WINDOW, LAMBDA, ETA, N_HIDDEN = 2.0, 200, 0.04, 1e-4, 4
N_IN = 5  # e_k, e_(k-1), e_(k-2), omega, omega_2 (Section 5: P = 5)
N_W2 = N_HIDDEN * (N_IN + 1)  # input -> hidden weights (with bias), row p: (bias, inputs)
N_W = N_W2 + 3 * (N_HIDDEN + 1)  # plus hidden -> output weights (with bias)
#: Seed and half-width of the uniform initial weights (documented, reproducible).
INIT_SEED, INIT_HALFWIDTH = 0, 0.5
#: Every PID gain of eq. (4) stays within (1 -+ GAIN_RANGE) times its commissioning value.
GAIN_RANGE = 0.5


@njit(cache=True)
def forward(w, x, h, g):
    """Eq. (5)-(8): hidden tanh outputs h (N_HIDDEN), output g(net) in (0, 1) (3)."""
    for p in range(N_HIDDEN):
        a = w[p * (N_IN + 1)]
        for q in range(N_IN):
            a += w[p * (N_IN + 1) + 1 + q] * x[q]
        h[p] = math.tanh(a)
    for m in range(3):
        o = N_W2 + m * (N_HIDDEN + 1)
        a = w[o]
        for p in range(N_HIDDEN):
            a += w[o + 1 + p] * h[p]
        g[m] = 1.0 / (1.0 + math.exp(-2.0 * a))  # e^a / (e^a + e^-a)


@njit(cache=True)
def sensitivity(w, x, h, g, du, scale, s):
    """de_k/dw of every weight (eq. (11), (12), (15)-(18)), plant Jacobian by its sign (+1
    after the loop's direction): de/dO_l = -dU_l, O_l = s_l g(net_l)."""
    c = np.empty(3)
    for m in range(3):
        c[m] = -du[m] * scale[m] * 2.0 * g[m] * (1.0 - g[m])  # de/dnet_l
        o = N_W2 + m * (N_HIDDEN + 1)
        s[o] = c[m]
        for p in range(N_HIDDEN):
            s[o + 1 + p] = c[m] * h[p]
    for p in range(N_HIDDEN):
        cp = 0.0
        for m in range(3):
            cp += c[m] * w[N_W2 + m * (N_HIDDEN + 1) + 1 + p]
        cp *= 1.0 - h[p] * h[p]
        s[p * (N_IN + 1)] = cp
        for q in range(N_IN):
            s[p * (N_IN + 1) + 1 + q] = cp * x[q]


@njit(cache=True)
def npid_step(X, E, W, G, V, Ebuf, Sbuf, nbuf, head, base, scale, mee, sigma, lam, L, eta, gains):
    """One sample of every unit (row x MAIN loop): train (Section 4 step (4)), then gains.

    Args (per unit b): X (n, N_IN) net inputs; E (n, 3) = (e_k, e_(k-1), e_(k-2)) in K;
    W, G (n, N_W) weights and the recursive criterion gradient; V (n,) the criterion
    estimate (information potential eq. (3), or the forgotten mean squared error); Ebuf
    (n, L), Sbuf (n, L, N_W), nbuf, head (n,) the receding window of past errors and
    their sensitivities (MEE only); base, scale (n, 3) the gains' lower bounds b_l and the
    output scales s_l. Writes the gains b_l + s_l g_l (n, 3).
    """
    h = np.empty(N_HIDDEN)
    g = np.empty(3)
    du = np.empty(3)
    s = np.empty(N_W)
    kfac = 1.0 / (math.sqrt(2.0 * math.pi) * math.sqrt(2.0) * sigma)  # kappa(., 2 sigma^2)
    inv = 1.0 / (4.0 * sigma * sigma)
    c_mee = -lam / (2.0 * L * sigma * sigma)
    for b in range(X.shape[0]):
        e = E[b, 0]
        du[0] = E[b, 0] - E[b, 1]
        du[1] = E[b, 0]
        du[2] = E[b, 0] - 2.0 * E[b, 1] + E[b, 2]
        w = W[b]
        forward(w, X[b], h, g)
        sensitivity(w, X[b], h, g, du, scale[b], s)
        if mee:  # eq. (3), (10), (14); ascent eq. (9), (13)
            vsum = 0.0
            for j in range(N_W):
                G[b, j] *= 1.0 - lam
            for i in range(nbuf[b]):
                d = Ebuf[b, i] - e
                k = kfac * math.exp(-d * d * inv)
                vsum += k
                a = c_mee * d * k
                for j in range(N_W):
                    G[b, j] += a * (Sbuf[b, i, j] - s[j])
            V[b] = (1.0 - lam) * V[b] + lam / L * vsum
            for j in range(N_W):
                w[j] += eta * G[b, j]
            i = head[b]
            Ebuf[b, i] = e
            for j in range(N_W):
                Sbuf[b, i, j] = s[j]
            head[b] = (i + 1) % L
            if nbuf[b] < L:
                nbuf[b] += 1
        else:  # forgotten mean squared error, descent
            V[b] = (1.0 - lam) * V[b] + lam * e * e
            for j in range(N_W):
                G[b, j] = (1.0 - lam) * G[b, j] + lam * e * s[j]
                w[j] -= eta * G[b, j]
        forward(w, X[b], h, g)  # Section 4 step (5): the PID gains of the updated net
        for m in range(3):
            gains[b, m] = base[b, m] + scale[b, m] * g[m]


def initial_weights(k0: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(weights, lower bounds b_l, output scales s_l) whose net gives exactly the gains
    ``k0`` at zero input: b_l + s_l g with b_l = (1 - GAIN_RANGE) k_l0, s_l = 2 GAIN_RANGE
    k_l0, the net at g's midpoint (module docstring).
    """
    k0 = np.asarray(k0, dtype=float)
    if not np.all(k0 > 0.0):
        raise ValueError(f"commissioning gains must be positive, got {k0}")
    base, scale = gain_bounds(k0)
    w = np.random.default_rng(INIT_SEED).uniform(-INIT_HALFWIDTH, INIT_HALFWIDTH, N_W)
    h = np.tanh(w[: N_W2 : N_IN + 1])  # hidden outputs at zero input: tanh(bias)
    for m in range(3):
        o = N_W2 + m * (N_HIDDEN + 1)
        r = (k0[m] - base[m]) / scale[m]  # wanted g in (0, 1)
        w[o] = 0.5 * math.log(r / (1.0 - r)) - float(w[o + 1 : o + 1 + N_HIDDEN] @ h)
    return w, base, scale


def gain_bounds(k0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(b, s): the gains b + s g of commissioning gains ``k0`` span k0 (1 -+ GAIN_RANGE)."""
    k0 = np.asarray(k0, dtype=float)
    return (1.0 - GAIN_RANGE) * k0, 2.0 * GAIN_RANGE * k0
