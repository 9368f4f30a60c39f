"""Provenance digests: one hash of the code a stored result depends on, and of nothing else.

A stored result (a leaderboard row, a baseline's tuning, the score's ends on the tuning
episodes, the compiled kernels) is valid while the code that produced it is unchanged. What
counts is the code's meaning: every Python file enters as its syntax tree with docstrings
removed (comments and formatting never reach the tree), so editing a docstring, a comment or
the layout changes no digest; any other file (a stored tuning's JSON) enters as its bytes.
Each file enters under its path relative to the folder that holds the packages, so a moved
checkout or an installed copy gives the same digest.

Scopes (which files a result depends on):

- :func:`plant_files`: a plant's own module or package and the code every plant shares
  (the env, scenarios, reward, metrics, steam tables, the shared plant modules and the
  registry), not the other plants' packages and not the modules no trajectory depends on
  (:data:`NO_DYNAMICS`, the ``testing`` package). Editing one plant changes its digest only.
- :func:`module_files`: a module and, transitively, every module of the given packages it
  imports (``import a.b``, ``from a.b import c``, relative imports), found by reading the
  syntax trees, never by importing. A policy's scope is its module's closure.

:func:`digest` hashes a list of files. Parsing takes milliseconds per file; the digest of
each file is memoized in the process under its path, size and modification time.
"""

from __future__ import annotations

import ast
import functools
import hashlib
from collections.abc import Iterable
from pathlib import Path

from steamtemp_gym import catalog

#: The folder that holds steamtemp_gym (and, beside it, baselines and agents).
ROOT = Path(__file__).resolve().parent.parent
#: Modules of steamtemp_gym that no trajectory depends on (drawing, docs, the command line,
#: the ahead-of-time compile command, where the compile cache lives), left out of every
#: scope with the testing package.
NO_DYNAMICS = ("render.py", "docs.py", "__main__.py", "precompile.py", "provenance.py", "_cache.py")
_NO_DYNAMICS_PACKAGES = ("testing",)
#: Length of a digest (hex characters).
LENGTH = 16


def strip_docstrings(tree: ast.AST) -> ast.AST:
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
    return tree


@functools.lru_cache(maxsize=4096)
def _file_digest(path: str, size: int, mtime_ns: int) -> str:
    """SHA-256 of one file's normalized content (see the module docstring)."""
    data = Path(path).read_bytes()
    if path.endswith(".py"):
        data = ast.dump(strip_docstrings(ast.parse(data))).encode()
    return hashlib.sha256(data).hexdigest()


def file_digest(path: Path) -> str:
    """The normalized content's SHA-256 of one file (memoized per size and mtime)."""
    st = path.stat()
    return _file_digest(str(path), st.st_size, st.st_mtime_ns)


def _relative(path: Path, root: Path) -> str:
    try:
        return path.resolve().relative_to(root.resolve()).as_posix()
    except ValueError:
        return path.name


def digest(files: Iterable[Path], *extra: str, root: Path | None = None) -> str:
    """Short hash of ``files`` (each under its path relative to ``root``, in sorted order)
    and of the strings ``extra`` (e.g. a library version); ``root`` defaults to :data:`ROOT`."""
    root = ROOT if root is None else root
    h = hashlib.sha256()
    for e in extra:
        h.update(f"extra|{e}\n".encode())
    for name, f in sorted((_relative(Path(f), root), Path(f)) for f in set(map(Path, files))):
        h.update(f"{name}|{file_digest(f)}\n".encode())
    return h.hexdigest()[:LENGTH]


def _dynamic(f: Path, pkg: Path) -> bool:
    rel = f.relative_to(pkg).parts
    return f.name not in NO_DYNAMICS and not set(rel[:-1]) & set(_NO_DYNAMICS_PACKAGES)


def package_files(root: Path | None = None) -> list[Path]:
    """Every Python file of steamtemp_gym that a trajectory can depend on."""
    pkg = (ROOT if root is None else root) / "steamtemp_gym"
    return sorted(f for f in pkg.rglob("*.py") if _dynamic(f, pkg))


def plant_files(module: str, root: Path | None = None) -> list[Path]:
    """The files one plant's results depend on: its module (``steamtemp_gym.plants.x`` or
    a package of that name) and the code every plant shares, without the other plants'
    modules and packages (see the module docstring)."""
    root = ROOT if root is None else root
    plants = root / "steamtemp_gym" / "plants"
    parts = module.split(".")
    if parts[:2] != ["steamtemp_gym", "plants"] or len(parts) < 3:
        raise ValueError(f"{module!r} is not a module of steamtemp_gym.plants")
    own = parts[2]
    shared = set(_shared_plant_modules(plants))
    out = []
    for f in package_files(root):
        rel = f.relative_to(plants).parts if f.is_relative_to(plants) else None
        if rel is None or rel[0] == own or (len(rel) == 1 and f.stem == own):
            out.append(f)
        elif len(rel) == 1 and f.stem in shared:
            out.append(f)
    return out


def _shared_plant_modules(plants: Path) -> list[str]:
    """The modules directly in steamtemp_gym/plants that are no plant of their own: those
    that define no subclass of ``Plant`` (a plant module's class is listed in the catalog,
    steamtemp_gym/catalog.py)."""
    registry = (plants.parent / "catalog.py").read_text()
    out = []
    for f in plants.glob("*.py"):
        if f.stem == "__init__" or f"steamtemp_gym.plants.{f.stem}:" not in registry:
            out.append(f.stem)
    return out


def outside_plant_files(plant_id: str) -> list[Path]:
    """The files of a plant registered from outside steamtemp_gym (``register_plant``): its
    module and what it imports from its own top-level package; none for the package's own
    plants and for an id that is no plant."""
    entry = catalog.PLANTS.get(plant_id) if isinstance(plant_id, str) else None
    module = entry.split(":")[0] if entry else "steamtemp_gym"
    if module.split(".")[0] == "steamtemp_gym":
        return []
    import importlib

    path = Path(importlib.import_module(module).__file__).resolve()
    return module_files(module, (module.split(".")[0],), path.parents[module.count(".")])


def module_files(module: str, packages: tuple[str, ...], root: Path | None = None) -> list[Path]:
    """``module``'s file and, transitively, the files of every module of ``packages`` it
    imports (read from the syntax trees; a package's ``__init__`` counts when imported)."""
    root = ROOT if root is None else root
    seen: dict[str, Path] = {}
    todo = [module]
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        path = _module_path(name, root)
        if path is None:
            continue
        seen[name] = path
        st = path.stat()
        for dep in _imports(str(path), name, st.st_size, st.st_mtime_ns):
            if dep.split(".")[0] in packages and dep not in seen:
                todo.append(dep)
    return sorted(seen.values())


def _module_path(name: str, root: Path) -> Path | None:
    base = root.joinpath(*name.split("."))
    for p in (base.with_suffix(".py"), base / "__init__.py"):
        if p.is_file():
            return p
    return None


@functools.lru_cache(maxsize=4096)
def _imports(path_s: str, name: str, size: int, mtime_ns: int) -> tuple[str, ...]:
    """The modules a file imports: for ``from a import b`` both ``a`` and ``a.b`` (b may
    be a module); relative imports resolved against ``name`` (memoized per file state)."""
    path = Path(path_s)
    is_pkg = path.name == "__init__.py"
    package = name if is_pkg else name.rpartition(".")[0]
    out = []
    for node in ast.walk(ast.parse(path.read_bytes())):
        if isinstance(node, ast.Import):
            for a in node.names:
                parts = a.name.split(".")
                out += [".".join(parts[: i + 1]) for i in range(len(parts))]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            parts = mod.split(".")
            out += [".".join(parts[: i + 1]) for i in range(len(parts))]
            out += [f"{mod}.{a.name}" for a in node.names if a.name != "*"]
    return tuple(out)


__all__ = [
    "LENGTH",
    "NO_DYNAMICS",
    "ROOT",
    "digest",
    "file_digest",
    "module_files",
    "package_files",
    "plant_files",
]
