"""Where the compiled kernels are cached, and a notice while they compile.

The plants' numba kernels are compiled on first use and cached on disk
(``cache=True``), so that later processes load them in about a second instead of
compiling for 5-25 s per plant.

Location: ``$STEAMTEMP_GYM_CACHE_DIR`` if set, else ``$NUMBA_CACHE_DIR``, else
``$XDG_CACHE_HOME/steamtemp_gym`` (default ``~/.cache/steamtemp_gym``). Inside it,
one folder per version of the code, ``numba-<package version>-<key>``. The key
hashes numba's version and the *code* of every module of the package but its
``testing`` checks: their syntax trees without docstrings, so editing a comment or a
docstring keeps the cache, while any change of code makes a new one (numba itself
checks only the file of each kernel, not the functions it calls in other files). At
import, folders of other versions are removed once unused for :data:`GRACE_S` and not
among the :data:`KEEP` most recently used, which bounds the cache to a few versions
(about 23 MB each) while several checkouts are in use.

The steam tables are not part of the cached code (steamtemp_gym/steam), which keeps
each folder small.

Compiling announces itself once per burst through the ``steamtemp_gym`` logger at
WARNING level (shown on stderr without any logging set-up). Silence it with
``logging.getLogger("steamtemp_gym").setLevel(logging.ERROR)``.
"""

from __future__ import annotations

import ast
import hashlib
import json
import logging
import os
import shutil
import time
from pathlib import Path

import numba
from numba.core import event

log = logging.getLogger("steamtemp_gym")

#: folders of other code versions kept besides the current one
KEEP = 2
#: a folder used within this many seconds is never removed (another process may use it)
GRACE_S = 3600.0
_PACKAGES = ("steamtemp_gym", "baselines")
#: subpackages without kernels, left out of the key (editing them keeps the cache)
_NO_KERNELS = ("testing",)
_STAMP = "last_used"
_MEMO_SIZE = 32


def base_dir() -> Path:
    """The cache's parent folder (see the module docstring)."""
    for var in ("STEAMTEMP_GYM_CACHE_DIR", "NUMBA_CACHE_DIR"):
        if os.environ.get(var):
            return Path(os.environ[var]).expanduser()
    xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(xdg) / "steamtemp_gym"


def _code_digest(roots: list[Path], memo: Path) -> str:
    """SHA-256 over numba's version and the docstring-free syntax trees under ``roots``.

    Parsing takes ~0.5 s, so the result is memoized in the file ``memo`` under a key of
    the files' paths, sizes and modification times (an installed package never moves).
    """
    files = sorted(
        f
        for root in roots
        for f in root.rglob("*.py")
        if not set(f.relative_to(root).parts[:-1]) & set(_NO_KERNELS)
    )
    stats = hashlib.sha256(numba.__version__.encode())
    for f in files:
        st = f.stat()
        stats.update(f"{f}|{st.st_size}|{st.st_mtime_ns}\n".encode())
    key = stats.hexdigest()
    try:
        known = json.loads(memo.read_text())
        if not isinstance(known, dict):
            known = {}
    except (OSError, ValueError):
        known = {}
    if isinstance(known.get(key), str):
        return known[key]
    digest = hashlib.sha256(numba.__version__.encode())
    for f in files:
        tree = ast.parse(f.read_bytes())
        for node in ast.walk(tree):
            body = getattr(node, "body", None)
            if (
                isinstance(body, list)
                and body
                and isinstance(body[0], ast.Expr)
                and isinstance(body[0].value, ast.Constant)
                and isinstance(body[0].value.value, str)
            ):
                body[0] = ast.Pass()
        digest.update(f"{f.parent.name}/{f.name}".encode())
        digest.update(ast.dump(tree).encode())
    known = dict(list(known.items())[-(_MEMO_SIZE - 1):])
    known[key] = digest.hexdigest()[:16]
    try:
        memo.parent.mkdir(parents=True, exist_ok=True)
        tmp = memo.with_name(f"{memo.name}.{os.getpid()}")
        tmp.write_text(json.dumps(known))
        tmp.replace(memo)
    except OSError:
        pass
    return known[key]


def _prune(base: Path, current: Path) -> None:
    """Remove other versions' folders beyond the KEEP most recent, unused for GRACE_S."""
    others = []
    for d in base.glob("numba-*"):
        if d == current or not d.is_dir():
            continue
        stamp = d / _STAMP
        others.append(((stamp if stamp.exists() else d).stat().st_mtime, d))
    others.sort(reverse=True)
    now = time.time()
    for used, d in others[KEEP:]:
        if now - used > GRACE_S:
            shutil.rmtree(d, ignore_errors=True)


def configure(version: str) -> Path:
    """Point numba's cache at this code version's folder, stamp it used, prune others."""
    roots = [Path(__file__).parent]  # baselines' kernels call no other baselines module's
    base = base_dir()
    current = base / f"numba-{version}-{_code_digest(roots, base / 'code_keys.json')}"
    numba.config.CACHE_DIR = str(current)
    try:
        current.mkdir(parents=True, exist_ok=True)
        (current / _STAMP).touch()
        _prune(base, current)
    except OSError as exc:  # a read-only home: numba then compiles without caching
        log.debug("steamtemp_gym: cache folder %s not usable: %s", current, exc)
    return current


class _CompileNotice(event.Listener):
    """Logs one line when numba starts compiling a kernel of this project."""

    def __init__(self, where: Path) -> None:
        self.where = where
        self.depth = 0
        self.last = -1e9

    def on_start(self, ev: event.Event) -> None:
        self.depth += 1
        if self.depth > 1:
            return
        func = getattr(ev.data.get("dispatcher"), "py_func", None)
        module = getattr(func, "__module__", "") or ""
        if module.split(".")[0] not in _PACKAGES or time.monotonic() - self.last < 5.0:
            return
        self.last = time.monotonic()
        log.warning(
            "steamtemp_gym: compiling kernels on first use (once per code version, about "
            "5-25 s per plant; cached in %s)",
            self.where,
        )

    def on_end(self, ev: event.Event) -> None:
        self.depth -= 1
        if self.depth == 0:
            self.last = time.monotonic()


def announce_compiles(where: Path) -> None:
    """Install the compile notice (once per process)."""
    global _NOTICE
    if _NOTICE is None:
        _NOTICE = _CompileNotice(where)
        event.register("numba:compile", _NOTICE)


_NOTICE: _CompileNotice | None = None
