"""What an env takes as an action batch: :func:`check_action` reads any array-like of real
numbers of the right shape into the float array the compiled step takes, or refuses it
with a ValueError naming the expected shape; :func:`non_finite_action` is the error of a
batch holding NaN or infinite values, which the compiled step detects before anything
changes.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from steamtemp_gym.checks import is_real


def non_finite_action(A: np.ndarray) -> ValueError:
    """The error of an action batch holding NaN or infinite values."""
    return ValueError(f"action contains NaN or infinite values: {A.tolist()!r}")


def check_action(action: Any, shape: tuple[int, ...], single: bool = False) -> np.ndarray:
    """An action batch of ``shape`` (n_rows, n_actuators) as a native float32 or float64 array.

    Accepted: any array-like of real numbers (every float dtype and byte order, integers,
    Python integers beyond int64, a masked array without masked entries; not bool,
    complex, strings or other objects) of exactly ``shape`` (vector env) or, for the
    single env (``single``, one row), of shape (n_actuators,) or, with one actuator, a
    scalar. Finiteness is checked by :meth:`Core.step` (compiled, before anything changes).

    Raises:
        ValueError: anything else, naming the expected shape.
    """
    if (
        type(action) is np.ndarray
        and action.dtype.char in "fd"
        and action.dtype.isnative
        and (action.shape == (shape[1:] if single else shape))
    ):
        return action.reshape(shape)  # the common case, checked in a fraction of a µs
    expected = f"({shape[1]},)" if single else str(shape)
    if isinstance(action, np.ma.MaskedArray):
        masked = int(np.ma.count_masked(action))
        if masked:
            raise ValueError(f"action has {masked} masked entries; every command must be given")
        action = np.ma.getdata(action)
    try:
        a = np.asarray(action)
    except Exception as exc:  # noqa: BLE001 - TypeError, ValueError, a tensor's RuntimeError
        raise ValueError(
            f"action must be an array of shape {expected}: {type(exc).__name__}: {exc}"
        ) from None
    if a.dtype.kind == "O" and a.size and all(is_real(v) for v in a.flat):
        try:  # Python integers beyond int64
            a = a.astype(np.float64)
        except OverflowError:
            raise ValueError(
                f"action holds a number beyond the float range ({str(action)[:80]})"
            ) from None
    if a.dtype.kind not in "fiu":
        raise ValueError(
            f"action must hold real numbers (float or integer), got dtype {a.dtype} "
            f"({str(action)[:80]})"
        )
    ok = (
        (a.shape == shape[1:] or (a.shape == () and shape[1] == 1))
        if single
        else (a.shape == shape)
    )
    if not ok:
        raise ValueError(f"action has shape {a.shape}, expected {expected}")
    if a.dtype != np.float64 and a.dtype != np.float32:  # the dtypes the kernels take
        a = a.astype(np.float64)
    return a.reshape(shape)
