"""Print ``name==version`` for every lower bound (``>=``) of the project's dependencies and
of its ``agents`` extra in pyproject.toml: the oldest versions .ci/oldest installs."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import tomllib

project = tomllib.loads((Path(__file__).parents[1] / "pyproject.toml").read_text())["project"]
skip = set(sys.argv[1:])  # names left to the CI environment (torch)
for req in [*project["dependencies"], *project["optional-dependencies"]["agents"]]:
    m = re.match(r"^([A-Za-z0-9_.-]+)\s*>=\s*([0-9][0-9.]*)", req)
    if m is None:
        raise SystemExit(f"pyproject.toml: {req!r} has no lower bound")
    if m.group(1) not in skip:
        print(f"{m.group(1)}=={m.group(2)}")
