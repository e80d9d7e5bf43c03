"""The named quantities of a description: a parameter, constant or coordinate with its LaTeX, unit
and doc, as the generated code and the reports name it.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Named:
    name: str
    latex: str
    unit: str = ""
    doc: str = ""


@dataclass(frozen=True)
class Constant(Named):
    value: float = 0.0
