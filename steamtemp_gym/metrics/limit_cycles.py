"""The limit-cycle measure: the peak-to-peak of the control error once a scenario has gone
quiet, compared with the industrial reference's."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from steamtemp_gym.metrics.calculus import as_signal, as_time

#: The quiet stretch of :func:`quiet_peak_to_peak` starts this long after a scenario's last
#: scheduled change (s): the time a well-damped loop needs to settle after it.
QUIET_SETTLE_S: float = 600.0
#: Shortest quiet stretch (s) on which the peak-to-peak is read: a limit cycle of the slowest
#: loops (periods of 4-8 min) shows in it at least once.
QUIET_MIN_S: float = 600.0
#: A loop limit-cycles when its quiet peak-to-peak exceeds this multiple of the industrial
#: reference's on the same episode (:func:`limit_cycles`) ...
LIMIT_CYCLE_RATIO: float = 2.0
#: ... and this floor (K): the sensor noise and coloured disturbance alone swing a settled
#: loop by about 1 K peak to peak.
LIMIT_CYCLE_FLOOR_K: float = 1.5


def quiet_peak_to_peak(
    time_s: ArrayLike,
    error_K: ArrayLike,
    quiet_from_s: float,
    min_length_s: float = QUIET_MIN_S,
) -> float:
    """Peak-to-peak of the control error (K) over the quiet stretch ``time_s >= quiet_from_s``.

    The limit-cycle measure: after a scenario's last scheduled change (plus
    :data:`QUIET_SETTLE_S`), a loop that settles shows only the response to noise and the
    coloured disturbance; one that limit-cycles shows the cycle's full swing.

    Returns:
        ``max(e) - min(e)`` over the samples in the stretch, or NaN if it is shorter than
        ``min_length_s`` (the measure does not apply).

    Raises:
        ValueError: On mismatched lengths, fewer than 2 samples, non-finite values or
            non-increasing time.
    """
    t = as_time(time_s)
    e = as_signal(error_K, "error_K", t.size)
    if not math.isfinite(quiet_from_s) or not math.isfinite(min_length_s):
        raise ValueError(
            f"quiet_from_s and min_length_s must be finite, got {quiet_from_s!r}, {min_length_s!r}"
        )
    quiet = t >= quiet_from_s
    if not quiet.any() or t[-1] - t[quiet][0] < min_length_s:
        return math.nan
    return float(np.max(e[quiet]) - np.min(e[quiet]))


def limit_cycles(quiet_p2p_K: float, reference_p2p_K: float) -> bool:
    """Whether a quiet peak-to-peak (:func:`quiet_peak_to_peak`) shows a sustained oscillation:
    above ``max(LIMIT_CYCLE_RATIO * reference_p2p_K, LIMIT_CYCLE_FLOOR_K)``, the reference's
    on the same episode. False where the measure does not apply (NaN)."""
    if np.isnan(quiet_p2p_K):
        return False
    return bool(quiet_p2p_K > max(LIMIT_CYCLE_RATIO * reference_p2p_K, LIMIT_CYCLE_FLOOR_K))
