"""Fuzzing every public function's argument handling (Hypothesis): each argument is drawn from
values of every Python type a careless or hostile caller passes (ints of any size and sign,
floats with NaN, inf and subnormals, text, bytes, None, bools, complex numbers, lists, dicts,
NumPy scalars, and arrays of every dtype, of odd shapes and memory layouts), mixed with valid
values so that the later checks are reached too.

A call returns a value whose numbers are all finite, or raises ValueError or TypeError (bad
input) or MemoryError, with a one-line message; the documented failures of a run are the only
others: ``SimulationError`` (a failed episode) and ``RuntimeError`` (a result that is not
finite, the command line's status 1). Any other exception fails the test, and a crash (an abort,
a segfault) ends the run. test_fuzz.py fuzzes the values inside task dicts and tools files.

Episodes are kept short (t_end ≤ 0.2 s): the numbers drawn for the episode options are small or
outside their ranges, never in the slow middle. ``TOOLCONF_FUZZ_CASES`` cases per test (100 by
default, about 20 s in all; docs/reference/errors.md).
"""

import math
import os

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import toolconf
import toolconf.dask as tdask

from conftest import DRAWER
from fuzz_checks import finite, one_line

CASES = int(os.environ.get("TOOLCONF_FUZZ_CASES", "100"))
FUZZ = settings(max_examples=CASES, deadline=None, suppress_health_check=list(HealthCheck))
BAD_INPUT = (ValueError, TypeError, MemoryError)
FAILED_RUN = (toolconf.SimulationError, RuntimeError)

# Numbers of every size and kind, but none in the middle of a range where an episode is slow.
integers = st.one_of(st.integers(-3, 3), st.sampled_from(
    [2**31, 2**63 - 1, 2**63, 2**64, 10**20, 2**70, -(2**63) - 1, -(2**70), 10**400, -(10**400)]))
floats = st.one_of(st.floats(-1.0, 1.0), st.sampled_from(
    [math.nan, math.inf, -math.inf, 5e-324, -5e-324, 1e-300, 1e300, -1e300, 1e308, 0.2, 0.05]))
numbers = st.one_of(integers, floats)


def float32(x):
    with np.errstate(over="ignore"):
        return np.float32(x)


numpy_scalars = st.one_of(
    floats.map(np.float64), floats.map(float32), st.integers(-3, 3).map(np.int8),
    st.sampled_from([np.uint64(2**64 - 1), np.int64(-(2**63)), np.bool_(True), np.longdouble(1e300),
                     np.complex128(0.3 + 0.1j), np.datetime64("2024-01-01"), np.str_("position")]))
scalars = st.one_of(numbers, numpy_scalars, st.none(), st.booleans(), st.text(max_size=12),
                    st.binary(max_size=12), st.complex_numbers(max_magnitude=1e3))
anything = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.tuples(inner, inner),
    st.dictionaries(st.one_of(st.text(max_size=8), integers), inner, max_size=3)), max_leaves=8)

DTYPES = ["float64", "float32", "float16", "longdouble", "int8", "int64", "uint64", "bool",
          "complex128", "object", "<U5", "S3", "datetime64[s]", "V8"]


@st.composite
def arrays(draw, width, valid, row=None):
    """An array whose rows are `width` wide or not, of any dtype and layout; its values from
    `valid` (a strategy of valid values; `row`, a valid row, when given) or from the odd
    numbers above."""
    # Most arrays are valid but for one thing (the shape, the dtype, a value, the layout).
    odd = draw(st.sampled_from(["shape", "dtype", "value", "layout", "none"]))
    shape = (width,) if draw(st.booleans()) else (draw(st.sampled_from([1, 3])), width)
    if odd == "shape":
        shape = draw(st.sampled_from([(width - 1,), (width + 1,), (0, width), (3, width + 1),
                                      (1, width, 1), ()]))
    size = math.prod(shape)
    value = st.one_of(valid, floats) if odd == "value" else valid
    values = np.array([draw(value) for _ in range(size)], dtype="float64").reshape(shape)
    if row is not None and odd not in ("shape", "value"):
        values = np.broadcast_to(np.asarray(row, dtype="float64"), shape).copy()
    dtype = draw(st.sampled_from(DTYPES)) if odd == "dtype" else "float64"
    if dtype == "object":
        items = [draw(st.one_of(valid, scalars)) for _ in range(size)]
        array = np.empty(size, dtype=object)
        array[:] = items
        array = array.reshape(shape)
    elif dtype == "V8":
        array = np.zeros(shape, dtype=[("m", "f8")])
    elif dtype.startswith("datetime"):
        array = np.zeros(shape, dtype=dtype)
    else:
        with np.errstate(all="ignore"):
            array = values.astype(dtype)
    layout = "plain"
    if odd == "layout":
        layout = draw(st.sampled_from(["fortran", "strided", "readonly", "list"]))
    if layout == "fortran":
        array = np.asfortranarray(array)
    elif layout == "strided" and array.ndim:
        wide = np.repeat(array, 2, axis=-1)
        array = wide[..., ::2]
    elif layout == "readonly":
        array.flags.writeable = False
    elif layout == "list":
        return array.tolist()
    return array


good = st.floats(0.1, 0.6)


def mostly(valid):
    """`valid` three times in four, else anything: most cases are wrong in one argument only,
    so the checks after the first are reached."""
    return st.one_of(valid, valid, valid, anything)


models = mostly(st.sampled_from(["arm2"] * 4 + list(toolconf.models())))
methods = mostly(st.sampled_from(["fast", "explicit", "auto", "stiff"]))
SHORT = {"kind": "position", "episode": {"t_end": 0.2}}
tasks = mostly(st.one_of(st.just(SHORT), st.just({"kind": "velocity", "episode": {"t_end": 0.1}}),
                         st.sampled_from(["position", "velocity", "acceleration", "2"])))
EPISODE_KEYS = ["t_end", "dt", "perturbation", "learning_rate", "initial_theta",
                "initial_theta_dot", "initial_torque", "rtol", "atol"]
episode_options = st.one_of(st.just({}), st.dictionaries(
    st.one_of(st.sampled_from(EPISODE_KEYS), st.text(max_size=6)), anything, max_size=2))


def short(options):
    """The options with any t_end that is a number above 0.2 s lowered to 0.2 s: a long valid
    episode checks nothing more, and would only cost time."""
    t_end = options.get("t_end")
    try:
        if float(t_end) > 0.2:
            options["t_end"] = 0.2
    except (TypeError, ValueError, OverflowError):
        pass
    return options


def call(fn, *args, may_fail=(), nan_with_error=False, **kwargs) -> None:
    """`fn(*args, **kwargs)` gives finite numbers or one of the allowed exceptions, one line."""
    try:
        out = fn(*args, **kwargs)
    except BAD_INPUT + tuple(may_fail) as err:
        one_line(err)
        return
    if nan_with_error:
        # A batch's failed rows are NaN with the reason in `error`; the others are finite.
        ok = [e is None for e in out["error"]]
        for key, value in out.items():
            if isinstance(value, np.ndarray) and value.dtype.kind == "f":
                assert np.isfinite(value[ok]).all(), key
        return
    finite(out)


@FUZZ
@given(models, arrays(4, good), tasks)
def test_confidence(model, params, task):
    call(toolconf.confidence, model, params, task, may_fail=[RuntimeError])


@FUZZ
@given(models, arrays(4, good), tasks, methods, episode_options)
def test_simulate(model, params, task, method, options):
    if isinstance(task, str):
        options.setdefault("t_end", 0.2)
    call(toolconf.simulate, model, params, task if task is not SHORT else dict(SHORT), method,
         may_fail=FAILED_RUN, **short(options))


@FUZZ
@given(models, arrays(4, good), tasks, mostly(st.one_of(st.none(), arrays(2, st.floats(-1, 1)))),
       methods, mostly(st.one_of(st.just(0), integers)), episode_options)
def test_simulate_batch(model, params, task, perturbations, method, first_tool, options):
    if isinstance(task, str):
        options.setdefault("t_end", 0.2)
    call(toolconf.simulate_batch, model, params, task, perturbations, method, first_tool,
         nan_with_error=True, **short(options))


@FUZZ
@given(mostly(st.sampled_from(["panda", "ur5"])), arrays(7, good, [0.5, 0.0, 0.0, 0.1, 1e-3, 1e-3, 1e-3]),
       arrays(14, st.floats(-1, 1)), arrays(7, st.floats(-1, 1)))
def test_dynamics(model, params, state, control):
    call(toolconf.dynamics, model, params, state, control)


@FUZZ
@given(mostly(arrays(3, good)), mostly(arrays(3, good)),
       mostly(st.sampled_from([DRAWER, str(DRAWER)])), tasks,
       mostly(st.one_of(st.none(), integers)),
       mostly(st.sampled_from(["free-energy", "cost-j", "confidence"])),
       mostly(st.booleans()), methods, st.booleans())
def test_rank(m1, m2, path, task, screen, objective, skip, method, in_memory):
    if isinstance(task, str):
        task = {"kind": task, "episode": {"t_end": 0.2}}
    tools = {"name": ["a", "b", "c"], "m1": m1, "m2": m2, "l1": [0.3] * 3, "l2": [0.2] * 3}
    call(toolconf.rank, tools if in_memory else path, task, screen, objective, skip, method,
         nan_with_error=True)


@FUZZ
@given(models, tasks, anything, st.one_of(st.none(), anything, st.just("l1 + l2 <= 0.5..1:3")))
def test_design(model, task, design, sweep):
    # No design dict of valid keys is drawn: a design that runs is design's tests' business.
    call(toolconf.design, model, task, design, sweep, may_fail=[RuntimeError])


@FUZZ
@given(st.one_of(integers, anything), st.one_of(integers, anything))
def test_dask_block_sizes(tools_per_task, episodes_per_task):
    # Checked before a cluster is looked for; with none running, a valid size is then the
    # ValueError of distributed's "No clients found".
    call(tdask.simulate_batch, "arm2", np.full((2, 4), 0.3), SHORT,
         tools_per_task=tools_per_task, nan_with_error=True)
    call(tdask.rank, None, "position", episodes_per_task=episodes_per_task)


@FUZZ
@given(models, tasks, mostly(st.integers(1, 3)), mostly(st.integers(0, 2**64 - 1)),
       mostly(st.one_of(st.none(), st.just({"m1": (0.2, 0.3)}))),
       st.dictionaries(st.sampled_from(["trials", "trial_tools", "sweep_levels", "resamples", "grid_tools"]),
                       st.one_of(integers, anything), max_size=2), methods)
def test_reproduce(model, task, sample, seed, box, counts, method):
    if isinstance(task, str):
        task = {"kind": task, "episode": {"t_end": 0.2}}
    # The default population (300 tools) checks nothing more here, and would only cost time.
    sample = 2 if sample is None else sample
    call(toolconf.reproduce, model, task, None, sample, seed=seed, box=box, quick=True,
         method=method, may_fail=[RuntimeError], **counts)
