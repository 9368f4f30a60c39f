"""The keys of :func:`~steamtemp_gym.metrics.trajectory_metrics` and
:func:`~steamtemp_gym.metrics.step_response_metrics`, with their units."""

from __future__ import annotations

#: Deviation bands (K) of :func:`~steamtemp_gym.metrics.trajectory_metrics` by default.
DEFAULT_BANDS_K: tuple[float, ...] = (5.0, 8.0)


def band_key(band_K: float) -> str:
    return f"time_outside_{band_K:g}K_s"


def metric_names(bands_K: tuple[float, ...] | list[float] = DEFAULT_BANDS_K) -> tuple[str, ...]:
    """Keys of :func:`trajectory_metrics` for the given bands, in table order.

    Args:
        bands_K: Deviation bands in K, as passed to :func:`trajectory_metrics`.

    Returns:
        The metric names, in the order of the module-level table.
    """
    return (
        "iae_K_s",
        "ise_K2_s",
        "rmse_K",
        "max_abs_dev_K",
        "mean_dev_K",
        *(band_key(float(b)) for b in bands_K),
        "overshoot_pct",
        "settling_time_s",
        "rise_time_s",
        "spray_used_kg",
        "valve_travel",
        "valve_reversals",
        "valve_saturated_s",
    )


#: Keys of :func:`trajectory_metrics` with the default bands, in table order.
METRIC_NAMES: tuple[str, ...] = metric_names(DEFAULT_BANDS_K)

#: Unit of each metric in :data:`METRIC_NAMES` ("1" = dimensionless).
METRIC_UNITS: dict[str, str] = {
    "iae_K_s": "K s",
    "ise_K2_s": "K^2 s",
    "rmse_K": "K",
    "max_abs_dev_K": "K",
    "mean_dev_K": "K",
    **{band_key(b): "s" for b in DEFAULT_BANDS_K},
    "overshoot_pct": "%",
    "settling_time_s": "s",
    "rise_time_s": "s",
    "spray_used_kg": "kg",
    "valve_travel": "1",
    "valve_reversals": "1",
    "valve_saturated_s": "s",
}

#: Keys of :func:`step_response_metrics`.
STEP_RESPONSE_NAMES: tuple[str, ...] = ("gain", "Tu_s", "Tg_s", "t50_s", "t90_s")

#: Units of :data:`STEP_RESPONSE_NAMES` (the gain is in the units of ``y``).
STEP_RESPONSE_UNITS: dict[str, str] = {
    "gain": "units of y",
    "Tu_s": "s",
    "Tg_s": "s",
    "t50_s": "s",
    "t90_s": "s",
}
