"""Counter-based random numbers for compiled kernels: a value is a pure function of
(key, counter, channel), so a row's noise depends only on its episode seed and the
vector env reproduces the single env bit for bit (splitmix64, Steele et al. 2014)."""

from __future__ import annotations

import numpy as np

from steamtemp_gym._jit import njit


@njit(cache=True, error_model="numpy")
def splitmix64(z):
    """The splitmix64 finalizer of a uint64."""
    z = z + np.uint64(0x9E3779B97F4A7C15)
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


@njit(cache=True, error_model="numpy")
def uniform(key, counter, channel):
    """Uniform number in (0, 1) determined by (key, counter, channel); channel < 64."""
    z = splitmix64(
        np.uint64(key) ^ splitmix64(np.uint64(counter) * np.uint64(64) + np.uint64(channel))
    )
    return (np.float64(z >> np.uint64(11)) + 0.5) * (1.0 / 9007199254740992.0)


@njit(cache=True, error_model="numpy")
def gauss(key, counter, channel):
    """Standard normal number determined by (key, counter, channel) (Box-Muller); channel < 32."""
    u1 = uniform(key, counter, 2 * channel)
    u2 = uniform(key, counter, 2 * channel + 1)
    return np.sqrt(-2.0 * np.log(u1)) * np.cos(2.0 * np.pi * u2)
