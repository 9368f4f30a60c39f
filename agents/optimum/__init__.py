"""The clairvoyant optimum of an episode: the score's 1, solved as one problem.

With counter-based noise and a known scenario, the best any controller can do on an
episode is one deterministic open-loop problem: choose the whole command sequence
u_0 .. u_{T-1} (every valve's opening, in [0, 1]) that maximizes the episode's return

    J(u) = sum_t r(z_t, u_t, u_{t-1}),   x_{t+1} = f(x_t, u_t, d_t),  z_t = h(x_t, u_t, d_t)

where f and h are one control interval of the plant's own compiled kernel (the physics
the env runs, nothing else), d_t the row's disturbances (the scenario's schedules and
the coloured heat-absorption disturbance, which no command changes) and r the env's
reward (steamtemp_gym/rewards.py). The observation noise does not enter: the reward reads
the true outlet temperature.

The method is gradient based on the true plant:

- **Gradient.** The Jacobians of f and h along the whole trajectory are central finite
  differences of the kernel, every step's perturbations evaluated as rows of one batched
  kernel call (2 (n_x + n_u) rows per step); the gradient of J with respect to every
  command is then the adjoint (backward) recursion through them. The reward's kinks
  (|e|, the band's hinge, spray above design, |du|) are smoothed
  (:func:`steamtemp_gym.rewards.smooth_reward`) with a width that is driven towards zero
  (continuation); the return reported is always the exact one, of a replay in the env.
- **Search.** L-BFGS-B (Byrd, Lu, Nocedal and Zhu 1995, through scipy) with the commands'
  bounds, on a sequence of parameterizations: a piecewise-linear correction of the
  incoming sequence through knots every 30 s, then 10 s, then 2 s, then the commands of
  every control interval themselves. Each level starts from the last level's result (a
  zero correction), so no level returns less than it was given.
- **Warm starts.** The command sequences of the receding-horizon CEM (agents/oracle.py),
  ``mpc_linear`` and ``cascade_pi_ff`` on the same episode; the best start is refined and a
  second one solved independently to check that both reach the same return.

A certificate (certificate.py) states how close a solution is to the optimum: the return a
projected-gradient step from it still finds (the KKT residual as a return), the return
gained by the last refinement of the parameterization, and the agreement of the
independent start, each in shares of the episode's headroom (the return above
``cascade_pi_ff``'s).

Modules: ``problem`` (the episode, its simulation, smoothed return and gradient),
``certificate`` and ``search`` (the levels, the continuation, :func:`solve`).
"""

from agents.optimum.certificate import TOLERANCES, certify, independent_check
from agents.optimum.problem import Episode, episode, exact_return, to_actions
from agents.optimum.search import solve

__all__ = [
    "TOLERANCES",
    "Episode",
    "certify",
    "episode",
    "exact_return",
    "independent_check",
    "solve",
    "to_actions",
]
