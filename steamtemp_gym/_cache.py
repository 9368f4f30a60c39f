"""Where the compiled kernels are cached, and a notice while they compile.

The plants' numba kernels are compiled on first use and cached on disk
(``cache=True``), so that later processes load them in about a second instead of
compiling for 10-30 s per plant (``python -m steamtemp_gym.precompile`` compiles them
ahead, several plants at once).

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

Every kernel of the package is bound to that folder when it is defined
(``steamtemp_gym._jit.njit`` calls :func:`pointed`): numba's own ``CACHE_DIR`` setting
is left as the user has it, so numba reloading its configuration (when a ``NUMBA_*``
variable changes) does not move the package's kernels, and other code's kernels do not
land in the package's folder.

A folder that cannot be written (a read-only container image, a shared cache) is read,
never written: if it holds kernels, numba loads them from a temporary folder of links to
its files (kernels missing there compile into that folder, which is removed at exit);
if it holds none, or no temporary folder can be made, kernels compile in memory, again
in every process, and the first compile says so in one warning.

The steam tables are not part of the cached code (steamtemp_gym/steam), which keeps
each folder small.

Compiling announces itself once per burst through the ``steamtemp_gym`` logger at
WARNING level (shown on stderr without any logging set-up). Silence it with
``logging.getLogger("steamtemp_gym").setLevel(logging.ERROR)``.
"""

from __future__ import annotations

import atexit
import contextlib
import hashlib
import json
import logging
import os
import shutil
import tempfile
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numba

from steamtemp_gym import provenance

try:  # numba's event API (documented as experimental): only the compile notice uses it
    from numba.core import event
except ImportError:  # pragma: no cover - the notice is then off (tests/test_cache.py)
    event = None

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


def _code_digest(
    roots: list[Path], memo: Path, *extra: str, suffixes: tuple[str, ...] = (".py",)
) -> str:
    """The provenance digest (steamtemp_gym/provenance.py: docstring-free syntax trees; other
    files as bytes) of the files under ``roots`` with these ``suffixes`` (not in
    :data:`_NO_KERNELS` folders), numba's version and the ``extra`` strings.

    Parsing takes ~0.5 s, so the result is memoized in the file ``memo`` under a key of
    the files' paths, sizes and modification times (an installed package never moves).
    """
    files = sorted(
        f
        for root in roots
        for f in root.rglob("*")
        if f.suffix in suffixes and not set(f.relative_to(root).parts[:-1]) & set(_NO_KERNELS)
    )
    extra = (f"numba {numba.__version__}", *extra)
    stats = hashlib.sha256("|".join(extra).encode())
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
    digest = provenance.digest(files, *extra, root=roots[0].parent)
    known = dict(list(known.items())[-(_MEMO_SIZE - 1) :])
    known[key] = digest
    try:
        memo.parent.mkdir(parents=True, exist_ok=True)
        tmp = memo.with_name(f"{memo.name}.{os.getpid()}")
        tmp.write_text(json.dumps(known))
        tmp.replace(memo)
    except OSError:
        pass
    return known[key]


def _prune(base: Path, current: Path, kind: str = "numba") -> None:
    """Remove other versions' ``<kind>-*`` folders beyond the KEEP most recent, unused for
    GRACE_S."""
    others = []
    for d in base.glob(f"{kind}-*"):
        if d == current or not d.is_dir():
            continue
        stamp = d / _STAMP
        others.append(((stamp if stamp.exists() else d).stat().st_mtime, d))
    others.sort(reverse=True)
    now = time.time()
    for used, d in others[KEEP:]:
        if now - used > GRACE_S:
            shutil.rmtree(d, ignore_errors=True)


def _use(base: Path, current: Path, kind: str) -> bool:
    """Make ``current``, stamp it used and prune the other ``<kind>-*`` folders; whether it
    can be written (False: a read-only cache, nothing changed)."""
    if not _can_write(current):
        return False
    try:
        (current / _STAMP).touch()
        _prune(base, current, kind)
    except OSError as exc:
        log.debug("steamtemp_gym: cache folder %s not stamped or pruned: %s", current, exc)
    return True


def versioned_folder(
    kind: str, roots: list[Path], *extra: str, suffixes: tuple[str, ...] = (".py",)
) -> Path | None:
    """``<cache>/<kind>-<key>``, the folder of this version of the code under ``roots`` (the
    key of :func:`_code_digest` over those files and ``extra``), made, stamped used, and the
    other versions' ``<kind>-*`` folders pruned like the kernels'; None where it cannot be
    written (a read-only cache)."""
    base = base_dir()
    key = _code_digest(roots, base / "code_keys.json", *extra, suffixes=suffixes)
    current = base / f"{kind}-{key}"
    return current if _use(base, current, kind) else None


@dataclass(frozen=True)
class Folder:
    """The cache folder of this code version and how numba uses it."""

    #: this code version's folder (``steamtemp_gym.CACHE_DIR``)
    path: Path
    #: whether this process can write it (the compile helper runs only then)
    writable: bool
    #: the folder numba reads and writes: ``path``, a temporary folder of links to a
    #: read-only ``path``'s files, or None (kernels compile in memory)
    numba_dir: Path | None


_FOLDER: Folder | None = None


def folder() -> Folder | None:
    """This process's cache folder (None before :func:`configure`)."""
    return _FOLDER


def _can_write(d: Path) -> bool:
    """Whether ``d`` exists or can be made and takes a new file (numba's own test)."""
    try:
        d.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=d).close()
    except OSError:
        return False
    return True


def _links(src: Path) -> Path | None:
    """A new temporary folder mirroring ``src``'s kernel files as links (removed at this
    process's exit); None if ``src`` holds no kernels or no such folder can be made."""
    try:
        if not any(src.rglob("*.nbi")):
            return None
        root = Path(tempfile.mkdtemp(prefix="steamtemp_gym-cache-"))
    except OSError:
        return None
    try:
        for dirpath, _, files in os.walk(src):
            rel = Path(dirpath).relative_to(src)
            (root / rel).mkdir(exist_ok=True)
            for f in files:
                if f.endswith((".nbi", ".nbc")):
                    os.symlink(Path(dirpath) / f, root / rel / f)
    except OSError:
        shutil.rmtree(root, ignore_errors=True)
        return None
    atexit.register(_remove, root, os.getpid())
    return root


def _remove(root: Path, pid: int) -> None:
    if os.getpid() == pid:  # not in a forked child
        shutil.rmtree(root, ignore_errors=True)


def configure(version: str) -> Path:
    """Choose this code version's folder and how numba uses it (module docstring); stamp
    it used and prune other versions' folders when it is writable."""
    global _FOLDER
    roots = [Path(__file__).parent]  # baselines' kernels call no other baselines module's
    base = base_dir()
    current = base / f"numba-{version}-{_code_digest(roots, base / 'code_keys.json')}"
    if _use(base, current, "numba"):
        _FOLDER = Folder(current, True, current)
    else:
        _FOLDER = Folder(current, False, _links(current))
    return current


@contextlib.contextmanager
def pointed() -> Iterator[bool]:
    """While a kernel is defined: numba's ``CACHE_DIR`` at this code version's folder
    (restored after); yields whether the kernel may be cached (False: compile in memory)."""
    where = _FOLDER.numba_dir if _FOLDER is not None else None
    if _FOLDER is None or where is None:
        yield _FOLDER is None  # before configure: numba's own setting
        return
    before = numba.config.CACHE_DIR
    numba.config.CACHE_DIR = str(where)
    try:
        yield True
    finally:
        numba.config.CACHE_DIR = before


class _CompileNotice(event.Listener if event is not None else object):
    """Logs one line when numba starts compiling a kernel of this project: once per burst
    at WARNING level where kernels are kept; where they are not (a read-only folder), one
    WARNING that says so, then INFO lines."""

    def __init__(self, where: Folder | None = None) -> None:
        self.fixed = where  # None: this process's folder (configure)
        self.depth = 0
        self.last = -1e9
        self.warned = False

    def on_start(self, ev) -> None:
        self.depth += 1
        if self.depth > 1:
            return
        func = getattr(ev.data.get("dispatcher"), "py_func", None)
        module = getattr(func, "__module__", "") or ""
        if module.split(".")[0] not in _PACKAGES or time.monotonic() - self.last < 5.0:
            return
        self.last = time.monotonic()
        where = self.fixed or _FOLDER
        if where is None or where.writable:
            log.warning(
                "steamtemp_gym: compiling kernels on first use (once per code version, about "
                "10-30 s per plant; cached in %s; `python -m steamtemp_gym.precompile` "
                "compiles every plant ahead)",
                where.path if where else "numba's cache",
            )
        elif not self.warned:
            self.warned = True
            log.warning(
                "steamtemp_gym: compiling kernels that are not kept (about 10-30 s per plant, "
                "again in every process): the cache folder %s is not writable%s; point "
                "STEAMTEMP_GYM_CACHE_DIR at a writable folder to keep them",
                where.path,
                "" if where.numba_dir is None else " (the kernels it holds are used)",
            )
        else:
            log.info(
                "steamtemp_gym: compiling kernels that are not kept (%s is read-only)", where.path
            )

    def on_end(self, ev) -> None:
        self.depth -= 1
        if self.depth == 0:
            self.last = time.monotonic()


def announce_compiles() -> None:
    """Install the compile notice (once per process; nothing without numba's event API)."""
    global _NOTICE
    if _NOTICE is None and event is not None:
        _NOTICE = _CompileNotice()
        event.register("numba:compile", _NOTICE)


_NOTICE: _CompileNotice | None = None
