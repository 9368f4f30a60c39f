"""Policy names for the checker and ``python -m steamtemp_gym``, without this package
importing any controller.

steamtemp_gym knows the plants and the contracts, not the policies. A package that ships
policies declares a *policy source* under the entry-point group :data:`GROUP` of its
distribution (steamtemp-gym's own is ``agents.specs``: the baselines, the shipped trained
agents, a trained agent's files and ``module:callable`` factories, the names of
``steamtemp-leaderboard --policies``), or hands one to :func:`register` at run time, which
takes precedence. A source is any object (a module will do) with:

- ``parse(name)``: the spec of a policy name, ValueError naming the valid forms otherwise.
  A spec has ``envs`` (the env ids it is available for; None: every env),
  ``available(env_id)``, ``make(env_id, env)`` (the policy), ``is_factory`` (the user's
  own code: the checker builds it once up front to report a broken factory as a bad
  argument) and ``needs_extra`` (an ImportError while building means an optional extra is
  missing, and the checks skip);
- ``FORMS``: one sentence naming the forms a name takes;
- ``everyday_names()``: the names ``steamtemp-check --policy all`` stands for;
- ``listing()``: the lines ``python -m steamtemp_gym`` prints about the policies.

Without any source the checker takes policy factories only.
"""

from __future__ import annotations

import sys
from importlib.metadata import entry_points
from typing import Any

#: The entry-point group a policy source is declared under.
GROUP = "steamtemp_gym.policies"
_ATTRS = ("parse", "FORMS", "everyday_names", "listing")
_registered: list[Any] = []
_warned: set[str] = set()


def _check(source: Any, where: str) -> Any:
    missing = [a for a in _ATTRS if not hasattr(source, a)]
    if missing:
        raise ValueError(
            f"policy source {where} lacks {missing}; a source has "
            f"{', '.join(_ATTRS)} (steamtemp_gym.policy_sources)"
        )
    return source


def register(source: Any) -> None:
    """Use ``source`` for policy names from now on (before any declared one); ValueError,
    changing nothing, when it lacks one of the attributes the module docstring lists."""
    _registered.insert(0, _check(source, repr(source)[:60]))


def unregister(source: Any) -> None:
    """Stop using a source given to :func:`register` (ValueError if it was not)."""
    if source not in _registered:
        raise ValueError(f"{repr(source)[:60]} is not a registered policy source")
    _registered.remove(source)


def find() -> Any | None:
    """The policy source in use: the last registered, else the first declared under
    :data:`GROUP` (by entry-point name) that loads and has every attribute (a broken one is
    passed over, said once on stderr), else None."""
    if _registered:
        return _registered[0]
    for ep in sorted(entry_points(group=GROUP), key=lambda e: e.name):
        where = f"{ep.name} = {ep.value}"
        try:
            return _check(ep.load(), where)
        except ImportError:  # declared by a distribution whose code is not importable here
            continue
        except KeyboardInterrupt:
            raise
        except BaseException as exc:  # noqa: BLE001 - a broken source: said, and passed over
            _warn(where, exc)
    return None


def _warn(where: str, exc: BaseException) -> None:
    """Say once on stderr that the declared source ``where`` is passed over, and why."""
    if where not in _warned:
        _warned.add(where)
        print(
            f"note: the policy source {where} (entry point group {GROUP}) is passed over: "
            f"{type(exc).__name__}: {str(exc)[:200]}",
            file=sys.stderr,
        )


def parse(name: str) -> Any:
    """The spec of ``name`` from the source in use; ValueError if none is installed or it
    does not know the name."""
    source = find()
    if source is None:
        raise ValueError(
            f"no policy source is installed to look up {name!r}: install "
            "steamtemp-gym with its agents package, register one "
            "(steamtemp_gym.policy_sources.register) or pass a policy "
            "factory"
        )
    return source.parse(name)
