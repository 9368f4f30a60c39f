"""The hardened YAML reader of scenario files.

A scenario file is UTF-8 YAML of at most :data:`MAX_FILE_BYTES` (1 MiB) holding one mapping
of the fields of :class:`~steamtemp_gym.scenarios.model.Scenario`; anchors and aliases
(``&a`` / ``*a``, hence merge keys ``<<``), duplicate keys and unknown fields are rejected,
and so are more than :data:`_MAX_YAML_NODES` nodes. ``1e3`` and ``3.6e3`` are numbers, as
in YAML 1.2; a quoted ``"60"`` is a string. Every error is a ValueError naming the file.
"""

from __future__ import annotations

import os
import re
import stat
from pathlib import Path
from typing import Any

import yaml

from steamtemp_gym.scenarios.model import (
    CHANNELS,
    MAX_BREAKPOINTS_PER_CHANNEL,
    Scenario,
    clip,
    describe,
    excerpt,
)

#: Largest scenario file read, in bytes.
MAX_FILE_BYTES = 1 << 20
#: Most YAML nodes in one file (five full channels of pairs, with room to spare).
_MAX_YAML_NODES = 4 * len(CHANNELS) * MAX_BREAKPOINTS_PER_CHANNEL

_YamlLoader: type = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
_MERGE_TAG = "tag:yaml.org,2002:merge"


class _ScenarioLoader(_YamlLoader):  # type: ignore[misc,valid-type]
    """Safe YAML loader that refuses duplicate mapping keys (PyYAML keeps the last)."""

    def construct_mapping(self, node: yaml.Node, deep: bool = False) -> dict[Any, Any]:
        if isinstance(node, yaml.MappingNode):
            seen: set[Any] = set()
            for key_node, _ in node.value:
                key = self.construct_object(key_node, deep=True)
                try:
                    duplicate = key in seen
                    seen.add(key)
                except TypeError:  # unhashable: the base class reports it
                    continue
                if duplicate:
                    raise yaml.constructor.ConstructorError(
                        None, None, f"duplicate key {excerpt(key)}", key_node.start_mark
                    )
        return super().construct_mapping(node, deep)


# YAML 1.1 reads 1e3 or 3.6e3 (no dot or no exponent sign) as strings; 1.2 and users: floats.
_ScenarioLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?[0-9][0-9_]*(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"),
)


def _check_nodes(root: yaml.Node) -> None:
    """Reject aliases, merge keys and too many nodes before anything is constructed.

    An alias makes one node appear twice in the composed graph, so a node seen twice
    is an alias: the graph of a billion-laughs file is small, its expansion is not.
    """
    seen: set[int] = set()
    stack: list[yaml.Node] = [root]
    while stack:
        node = stack.pop()
        if id(node) in seen:
            raise ValueError(
                f"YAML anchors and aliases (&name / *name) are not supported (line "
                f"{node.start_mark.line + 1}): write each value out"
            )
        seen.add(id(node))
        if len(seen) > _MAX_YAML_NODES:
            raise ValueError(f"more than {_MAX_YAML_NODES} YAML nodes")
        if isinstance(node, yaml.SequenceNode):
            stack.extend(node.value)
        elif isinstance(node, yaml.MappingNode):
            for key, val in node.value:
                if key.tag == _MERGE_TAG:
                    raise ValueError(
                        f"YAML merge keys (<<) are not supported (line {key.start_mark.line + 1})"
                    )
                stack.extend((key, val))


def _parse_yaml(text: str) -> Any:
    """Parse one YAML document safely (see ``_ScenarioLoader`` and ``_check_nodes``).

    Raises:
        ValueError: aliases, merge keys, too many nodes (message without
            the file name); yaml.YAMLError: malformed YAML, duplicate keys.
    """
    loader = _ScenarioLoader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        _check_nodes(node)
        return loader.construct_document(node)
    finally:
        loader.dispose()


def as_path(spec: Any) -> Path:
    """A Path from a str or os.PathLike (bytes paths decoded with the file-system codec)."""
    try:
        return Path(os.fsdecode(os.fspath(spec)))
    except TypeError as exc:
        raise ValueError(
            f"a scenario file must be a str or os.PathLike, got {describe(spec)}"
        ) from exc


def load_yaml(path: str | os.PathLike[str]) -> Scenario:
    """Read a scenario YAML file (format and limits in the module docstring).

    Raises:
        ValueError: naming the file: missing, a directory or not a regular file,
            unreadable, larger than MAX_FILE_BYTES, not UTF-8, malformed YAML, or an
            invalid scenario (the message then also names the field).
    """
    p = as_path(path)
    shown = repr(clip(str(p), 200))
    try:
        st = p.stat()
    except OSError as exc:
        raise ValueError(f"cannot read scenario file {shown}: {exc.strerror or exc}") from None
    if stat.S_ISDIR(st.st_mode):
        raise ValueError(f"cannot read scenario file {shown}: it is a directory")
    if not stat.S_ISREG(st.st_mode):
        raise ValueError(f"cannot read scenario file {shown}: not a regular file")
    if st.st_size > MAX_FILE_BYTES:
        raise ValueError(
            f"scenario file {shown} has {st.st_size} bytes, more than the {MAX_FILE_BYTES} allowed"
        )
    try:
        with open(p, "rb") as f:
            raw = f.read(MAX_FILE_BYTES + 1)
    except OSError as exc:
        raise ValueError(f"cannot read scenario file {shown}: {exc.strerror or exc}") from None
    if len(raw) > MAX_FILE_BYTES:  # grew since stat
        raise ValueError(f"scenario file {shown} has more than the {MAX_FILE_BYTES} bytes allowed")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        bad = raw[exc.start : exc.start + 1]
        raise ValueError(
            f"scenario file {shown} is not valid UTF-8 (byte {exc.start}: {bad!r})"
        ) from None
    try:
        data = _parse_yaml(text)
    except yaml.YAMLError as exc:
        where = str(exc).replace('in "<unicode string>", ', "at ")
        raise ValueError(f"malformed scenario YAML {shown}: {clip(where)}") from None
    except RecursionError:
        raise ValueError(f"malformed scenario YAML {shown}: nested too deeply") from None
    except ValueError as exc:
        raise ValueError(f"scenario file {shown}: {exc}") from None
    return Scenario.from_dict(data, source=f"scenario file {shown}")
