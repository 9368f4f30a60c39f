"""``python -m steamtemp_gym``: what is installed, without building or compiling anything.

Prints the env ids (and registered variants), the scenarios (named ones for every plant and
each plant's own, the held-out set, ``random``), the baselines and the shipped trained
agents, with the commands that use them.
"""

from __future__ import annotations

import sys

import steamtemp_gym
from steamtemp_gym import envs, plants, policy_sources, scenarios
from steamtemp_gym.scenarios import heldout


def report() -> str:
    """The listing (module docstring)."""
    common = [n for n in scenarios.names() if n != scenarios.RANDOM]
    lines = [
        f"steamtemp_gym {steamtemp_gym.__version__}",
        "",
        "Env ids (gym.make(id); the name after 'steamtemp/' is enough in the command lines):",
    ]
    for env_id in envs.ids():
        cls = plants.plant_class(env_id) if env_id in steamtemp_gym.ENV_IDS else None
        own = [n for n in scenarios.names(env_id) if n not in common and n != scenarios.RANDOM]
        lines.append(f"  {env_id}" + (f"  ({cls.source})" if cls else "  (registered variant)"))
        if own:
            lines.append(f"      its own scenarios: {', '.join(own)}")
    lines += [
        "",
        "Scenarios (gym.make(id, scenario=...), reset(options={'scenario': ...}), --scenarios):",
        f"  named: {', '.join(common)}",
        f"  held-out: {', '.join(heldout.PREFIX + n for n in heldout.NAMES)}",
        f"  {scenarios.RANDOM} (the seeded training distribution, the default), or a YAML file",
    ]
    source = policy_sources.find()
    if source is None:  # an installation without policies
        return "\n".join(lines) + "\n"
    lines += ["", *source.listing()]
    lines += [
        "",
        "Commands: steamtemp-leaderboard --help, steamtemp-check --help, "
        "steamtemp-train --help; reference pages: docs/envs/.",
    ]
    return "\n".join(lines) + "\n"


def main() -> int:
    """Print :func:`report`."""
    sys.stdout.write(report())
    return 0


if __name__ == "__main__":
    sys.exit(main())
