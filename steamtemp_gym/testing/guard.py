"""Running someone else's code (a policy, its factory, a module it imports) without letting
it end the process: its ``SystemExit``, ``KeyboardInterrupt`` or any other exception is its
own failure, while a stop asked of the process (Ctrl-C, SIGTERM) still stops it.

:func:`watch` marks the signals that stop the process while it runs; :func:`own_failure`
tells, for an exception caught around such code, whether it is that code's failure (to be
reported, the run going on) or a stop to pass on. Without :func:`watch` (a caller that
handles the signals itself) every ``KeyboardInterrupt`` counts as a stop.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator
from typing import Any

#: Whether a :func:`watch` block runs, and whether a stop was asked in it.
_state = {"watching": 0, "stopped": False}


def _on_sigint(signum: int, frame: Any) -> None:
    _state["stopped"] = True
    raise KeyboardInterrupt


def stop_asked() -> None:
    """Mark that a stop was asked of this process (a signal handler calls it before it
    raises, e.g. SIGTERM's)."""
    _state["stopped"] = True


@contextlib.contextmanager
def watch() -> Iterator[None]:
    """In this block Ctrl-C raises ``KeyboardInterrupt`` marked as a stop. Only in the main
    thread and where SIGINT has Python's default handler (else nothing changes)."""
    own = (
        threading.current_thread() is threading.main_thread()
        and signal.getsignal(signal.SIGINT) is signal.default_int_handler
    )
    before = signal.signal(signal.SIGINT, _on_sigint) if own else None
    if own:
        _state["watching"] += 1
        _state["stopped"] = False
    try:
        yield
    finally:
        if own:
            signal.signal(signal.SIGINT, before)
            _state["watching"] -= 1


def own_failure(exc: BaseException) -> bool:
    """Whether ``exc``, caught around someone else's code, is that code's own failure: any
    exception but a ``KeyboardInterrupt`` while a stop is asked of the process (or outside
    :func:`watch`, where a stop cannot be told from the code's own)."""
    if not isinstance(exc, KeyboardInterrupt):
        return True
    return bool(_state["watching"]) and not _state["stopped"]


def describe(exc: BaseException, who: str = "the code under check") -> str:
    """``Type: message`` of an exception, saying so when it would have ended the process."""
    text = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
    if not isinstance(exc, Exception):
        text += f" (raised by {who}: it would have ended the process)"
    return text
