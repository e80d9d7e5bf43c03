"""Progress of one derivation, for a caller that shows it (`make model`: derive/make_model.py runs
derive.py with --progress). Each step, as it finishes, is one line on the stream given to
`enable`: `progress<TAB>stage<TAB>what`, with stage `deriving` (the equations, a task's closed
forms, a function's code) or `checking` (a function's test vectors against the reference: CasADi,
or for a URDF model the reference graph in 50-digit arithmetic). Off unless enabled, and then
cheap: one short line per function."""

from __future__ import annotations

from typing import TextIO

_stream: TextIO | None = None


def enable(stream: TextIO | None) -> None:
    """Report steps on `stream` (None: stop reporting)."""
    global _stream
    _stream = stream


def step(stage: str, what: str) -> None:
    """`what` of `stage` has finished."""
    if _stream is not None:
        _stream.write(f"progress\t{stage}\t{' '.join(what.split())}\n")
        _stream.flush()
