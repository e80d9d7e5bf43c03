"""What the two fuzz suites (test_fuzz.py, test_fuzz_arguments.py) require of every call: an
error is one short line that does not speak of a panic, and every number returned is finite."""

import math

import numpy as np

# The longest error message a user should have to read.
MAX_MESSAGE = 800


def one_line(err: BaseException) -> None:
    message = str(err)
    assert "\n" not in message, message
    assert len(message) <= MAX_MESSAGE, message[:200]
    assert "panicked" not in message, message


def finite(out) -> None:
    if isinstance(out, dict):
        for v in out.values():
            finite(v)
    elif isinstance(out, (list, tuple)):
        for v in out:
            finite(v)
    elif isinstance(out, np.ndarray) and out.dtype.kind == "f":
        assert np.isfinite(out).all(), out
    elif isinstance(out, float):
        assert math.isfinite(out), out
