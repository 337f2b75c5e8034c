"""Load a YAML config into :class:`GaugedConfig`, with errors that name the key path and line."""

from __future__ import annotations

from importlib import resources
from pathlib import Path as FsPath
from typing import Any

import yaml
from pydantic import ValidationError

from gauged.config.errors import ConfigError, ConfigIssue, FieldIssues, Path
from gauged.config.model import GaugedConfig

DEFAULT_CONFIG_NAME = "default.yaml"


def _line_map(node: yaml.Node, path: Path = (), lines: dict[Path, int] | None = None) -> dict[Path, int]:
    """Map every key path in a composed YAML tree to its 1-based line number.

    A mapping entry is mapped to the line of its key (where a person looks for it); list items to
    the line where the item starts.
    """
    if lines is None:
        lines = {}
    lines.setdefault(path, node.start_mark.line + 1)
    if isinstance(node, yaml.MappingNode):
        for key_node, value_node in node.value:
            key_path = (*path, key_node.value)
            lines[key_path] = key_node.start_mark.line + 1
            _line_map(value_node, key_path, lines)
    elif isinstance(node, yaml.SequenceNode):
        for index, item in enumerate(node.value):
            _line_map(item, (*path, index), lines)
    return lines


def _line_of(path: Path, lines: dict[Path, int]) -> int | None:
    """Line of ``path`` or of its nearest ancestor present in the file (missing keys have none)."""
    for cut in range(len(path), -1, -1):
        if path[:cut] in lines:
            return lines[path[:cut]]
    return None


def _clean_loc(loc: tuple[Any, ...]) -> Path:
    # Pydantic puts the discriminator tag into loc for tagged unions ('source', 'mcap', 'path'): drop it.
    out: list[str | int] = []
    for part in loc:
        if isinstance(part, str) and out and out[-1] == "source" and part in ("zenoh", "mcap"):
            continue
        out.append(part)
    return tuple(out)


def _issues_from(error: ValidationError, lines: dict[Path, int], file: str | None) -> list[ConfigIssue]:
    issues: list[ConfigIssue] = []
    for err in error.errors():
        loc = _clean_loc(err["loc"])
        cause = (err.get("ctx") or {}).get("error")
        if isinstance(cause, FieldIssues):
            for rel, message in cause.issues:
                path = (*loc, *rel)
                issues.append(ConfigIssue(path, message, _line_of(path, lines), file))
            continue
        message = err["msg"]
        if err["type"] == "extra_forbidden":
            message = "unknown key (check the spelling against config/gauged.example.yaml)"
        elif err["type"] == "missing":
            message = "required key is missing"
        elif message.startswith("Value error, "):
            message = message[len("Value error, "):]
        issues.append(ConfigIssue(loc, message, _line_of(loc, lines), file))
    return issues


def parse_config(text: str, file: str | None = None) -> GaugedConfig:
    """Validate YAML text as a gauged config. Raises :class:`ConfigError` naming every problem."""
    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        line = mark.line + 1 if mark is not None else None
        problem = getattr(exc, "problem", None) or str(exc)
        raise ConfigError([ConfigIssue((), f"not valid YAML: {problem}", line, file)]) from exc
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ConfigError([ConfigIssue((), "the top level must be a mapping of keys", 1, file)])
    lines = _line_map(node) if node is not None else {}
    try:
        return GaugedConfig.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(_issues_from(exc, lines, file)) from None


def load_config(path: str | FsPath) -> GaugedConfig:
    """Read and validate a config file. Raises :class:`ConfigError` (also for an unreadable file)."""
    name = str(path)
    try:
        text = FsPath(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise ConfigError([ConfigIssue((), f"cannot read the file: {exc.strerror or exc}", None, name)]) from exc
    return parse_config(text, name)


def default_config_text() -> str:
    """The embedded default config (what ``gauged run`` uses without ``--config``)."""
    return resources.files("gauged.config").joinpath(DEFAULT_CONFIG_NAME).read_text(encoding="utf-8")


def load_default_config() -> GaugedConfig:
    return parse_config(default_config_text(), f"<embedded {DEFAULT_CONFIG_NAME}>")
