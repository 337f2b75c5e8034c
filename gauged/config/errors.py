"""Errors of configuration loading that name the YAML key path and line."""

from __future__ import annotations

from dataclasses import dataclass

Path = tuple[str | int, ...]


def format_path(path: Path) -> str:
    """``('gauges', 1, 'alarms', 'high')`` -> ``gauges[1].alarms.high``."""
    out = ""
    for part in path:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += f".{part}" if out else str(part)
    return out or "<root>"


@dataclass(frozen=True)
class ConfigIssue:
    """One problem in a config file: where (file, line, key path) and what."""

    path: Path
    message: str
    line: int | None = None
    file: str | None = None

    def __str__(self) -> str:
        where = self.file or "<config>"
        if self.line is not None:
            where += f":{self.line}"
        return f"{where} {format_path(self.path)}: {self.message}"


class ConfigError(Exception):
    """A config that cannot be used. ``issues`` lists every problem found, each with its place."""

    def __init__(self, issues: list[ConfigIssue]):
        self.issues = issues
        super().__init__("\n".join(str(issue) for issue in issues))


class FieldIssues(ValueError):
    """Raised by a model validator to blame specific fields (paths relative to that model).

    Pydantic keeps the raised exception in the error's ``ctx['error']``; the loader unpacks it so a
    cross-field error names the field at fault (``gauges[1].alarms.high``), not just the model.
    """

    def __init__(self) -> None:
        super().__init__()
        self.issues: list[tuple[Path, str]] = []

    def add(self, path: Path, message: str) -> None:
        self.issues.append((path, message))

    def raise_if_any(self) -> None:
        if self.issues:
            raise self

    def __str__(self) -> str:
        return "; ".join(f"{format_path(p)}: {m}" for p, m in self.issues)
