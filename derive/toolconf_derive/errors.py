"""The error of a description that cannot be used, shared by every reader of one (the TOML
descriptions, the URDF files, the derivation's own checks). A leaf: it imports nothing of the
package, so that any layer may raise it.
"""

from __future__ import annotations

from pathlib import Path


class DescriptionError(ValueError):
    """A model or task description that cannot be used: one line naming the file, the key and
    the problem (derive.py prints it and exits with status 2)."""

    def __init__(self, path: Path | str, key: str, problem: str):
        self.path, self.key, self.problem = str(path), key, problem
        # One line whatever the problem quotes (equations may span lines in the TOML), and short
        # whatever it repeats (a key or value of 100 kB is shown by its start and length).
        key, problem = clip(one_line(key), 80), clip(one_line(problem), 300)
        super().__init__(f"{path}: {key}: {problem}" if key else f"{path}: {problem}")


def one_line(text: str) -> str:
    return " ".join(text.split())


def clip(text: str, most: int) -> str:
    return text if len(text) <= most else f"{text[:most]}… ({len(text)} characters)"
