"""The walls around a user policy's process (agents/leaderboard/isolated.py), on Linux.

Before the policy's code is imported, its process enters namespaces of its own and forks
once (:func:`enter`); the policy then runs in the child, which

- is PID 1 of a new PID namespace with a /proc of its own: the leaderboard's process and
  every other process of the machine have no PID there, so it can neither signal nor
  trace them (``kill``, ``ptrace``, ``pidfd`` all name processes by PID), nor read their
  command lines;
- sees the run's output directory read-only (a bind mount in a mount namespace of its own):
  it cannot rewrite the record the leaderboard writes;
- runs in a session of its own (``kill(0, ...)`` reaches only itself) and under an
  address-space limit (:data:`MEMORY_BYTES`, ``RLIMIT_AS``);
- dies with its parent (``PR_SET_PDEATHSIG``), which stays in the leaderboard's namespace,
  relays its exit status and itself ends within a poll of the leaderboard's death.

The namespaces come from one ``unshare(CLONE_NEWUSER | CLONE_NEWPID | CLONE_NEWNS)``, which
needs no privilege where the kernel allows unprivileged user namespaces (most Linux
distributions). Where it is refused (another OS, a kernel or container that forbids them),
:func:`available` says why and the leaderboard says so at its start; the policy then runs
with the session and memory limit only.
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import functools
import os
import resource
import signal
import sys
import time
from collections.abc import Callable

#: The address space a policy's process may use (bytes): beyond it its allocations fail
#: (a MemoryError in the policy, which fails its episodes).
MEMORY_BYTES = 16 * 2**30
_CLONE_NEWNS, _CLONE_NEWUSER, _CLONE_NEWPID = 0x00020000, 0x10000000, 0x20000000
_MS_RDONLY, _MS_NOSUID, _MS_NODEV, _MS_NOEXEC = 1, 2, 4, 8
_MS_REMOUNT, _MS_BIND, _MS_REC, _MS_PRIVATE = 32, 4096, 16384, 1 << 18
_PR_SET_PDEATHSIG = 1


def _libc() -> ctypes.CDLL | None:
    if not sys.platform.startswith("linux"):
        return None
    return ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)


def _check(rc: int, what: str) -> None:
    if rc != 0:
        err = ctypes.get_errno()
        raise OSError(err, f"{what}: {os.strerror(err)}")


def _write(path: str, text: str) -> None:
    with open(path, "w") as f:
        f.write(text)


def _unshare(libc: ctypes.CDLL) -> None:
    """New user, PID and mount namespaces, this process's uid and gid mapped to themselves."""
    uid, gid = os.getuid(), os.getgid()
    _check(libc.unshare(_CLONE_NEWUSER | _CLONE_NEWPID | _CLONE_NEWNS), "unshare")
    _write("/proc/self/setgroups", "deny")
    _write("/proc/self/uid_map", f"{uid} {uid} 1")
    _write("/proc/self/gid_map", f"{gid} {gid} 1")


def _mount(libc: ctypes.CDLL, src: str | None, target: str, fstype: str | None, flags: int) -> None:
    b = [None if s is None else s.encode() for s in (src, target, fstype)]
    _check(libc.mount(b[0], b[1], b[2], ctypes.c_ulong(flags), None), f"mount {target}")


@functools.lru_cache(maxsize=1)
def available() -> str | None:
    """None where :func:`enter` builds every wall, else why not (a child is forked to try)."""
    libc = _libc()
    if libc is None:
        return f"namespaces are Linux's ({sys.platform} has none)"
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # the trial: unshare and report
        os.close(r)
        try:
            _unshare(libc)
            msg = b""
        except OSError as exc:
            msg = str(exc).encode()[:500]
        os.write(w, msg)
        os._exit(0)
    os.close(w)
    with os.fdopen(r, "rb") as f:
        msg = f.read()
    os.waitpid(pid, 0)
    return msg.decode() or None


def enter(
    readonly: tuple[str, ...], parent: int, watch: Callable[[], None], poll_s: float = 0.5
) -> str | None:
    """Build the walls (module docstring) around the rest of this process's life; the paths
    of ``readonly`` become read-only. Call it while the process has one thread (a threaded
    process cannot enter a user namespace). Forks: only the child returns (None, or why the
    namespaces could not be made); the parent stays outside, polls every ``poll_s`` that
    the leaderboard (``parent``) lives (after the unshare it can start no thread) and ends
    with the child's status, or kills it and ends when the leaderboard has died. Without
    namespaces the process calls ``watch`` (a thread watching the leaderboard) and returns
    why."""
    libc = _libc()
    why = None
    try:
        if libc is None:
            raise OSError(0, f"namespaces are Linux's ({sys.platform} has none)")
        _unshare(libc)
    except OSError as exc:
        why = str(exc)
        watch()
    if why is None:
        pid = os.fork()
        if pid:
            _relay(pid, parent, poll_s)
        _check(libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0), "prctl")
        os.setsid()  # a process group of its own: kill(0, ...) reaches no process outside
        _mount(libc, None, "/", None, _MS_REC | _MS_PRIVATE)
        _mount(libc, "proc", "/proc", "proc", _MS_NOSUID | _MS_NODEV | _MS_NOEXEC)
        for path in readonly:
            if os.path.isdir(path):
                _mount(libc, path, path, None, _MS_BIND | _MS_REC)
                _mount(libc, None, path, None, _MS_REMOUNT | _MS_BIND | _MS_RDONLY)
    else:
        with contextlib.suppress(OSError):  # a group leader already has a group of its own
            os.setsid()
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    limit = MEMORY_BYTES if hard == resource.RLIM_INFINITY else min(MEMORY_BYTES, hard)
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
    return why


def _relay(pid: int, parent: int, poll_s: float) -> None:
    """The process outside the walls: wait for the child ``pid`` and end as it ended; kill
    it and end when the leaderboard (``parent``) has died."""
    while True:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            break
        if os.getppid() != parent:
            os.kill(pid, signal.SIGKILL)
            os._exit(1)
        time.sleep(poll_s)
    if os.WIFSIGNALED(status):
        signal.signal(os.WTERMSIG(status), signal.SIG_DFL)
        os.kill(os.getpid(), os.WTERMSIG(status))
    os._exit(os.waitstatus_to_exitcode(status))
