"""Fuzzing the package's inputs (Hypothesis): task dicts with a task file's keys and values of
every kind (numbers from 5e-324 to 1e308, NaN, inf, strings, nested lists, NumPy arrays, None),
episode keyword arguments, parameter arrays of every shape, model names, and tools files mutated
from valid ones. Each call must return numbers that are all finite, or raise ValueError or
TypeError (bad input), SimulationError (a failed episode) or RuntimeError, with a one-line
message of at most a few hundred characters: never a panic (pyo3's PanicException) or another
exception.

200 cases per test; ``TOOLCONF_FUZZ_CASES=20000 python -m pytest python/tests/test_fuzz.py`` is
the long run (docs/reference/errors.md).
"""

import os

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import toolconf

from fuzz_checks import finite, one_line

CASES = int(os.environ.get("TOOLCONF_FUZZ_CASES", "200"))
FUZZ = settings(max_examples=CASES, deadline=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
EXPECTED = (ValueError, TypeError, toolconf.SimulationError, RuntimeError)

numbers = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 5e-324, 1e-6, 1e6, 1e308, -1e308, 0.3, 1.0, 100.0]),
    st.integers(-(2**70), 2**70),
)
values = st.recursive(
    st.one_of(numbers, st.none(), st.booleans(), st.text(max_size=30)),
    lambda inner: st.one_of(st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=8), inner,
                                                                       max_size=3)),
    max_leaves=12,
)
terms = ["theta", "theta_dot", "theta_ddot", "u"]
kinds = st.one_of(st.sampled_from(["position", "velocity", "acceleration", "1", "2"]),
                  st.text(max_size=10))
# Short episodes, whatever else is wrong with the options: the fuzz is of the checks.
episode_keys = {
    "t_end": st.one_of(st.floats(0.01, 0.2), numbers),
    "dt": st.one_of(st.floats(0.01, 0.05), numbers),
    "perturbation": st.one_of(numbers, st.lists(numbers, max_size=4)),
    "learning_rate": numbers,
    "initial_theta": st.lists(numbers, max_size=4),
    "initial_theta_dot": st.lists(numbers, max_size=4),
    "initial_torque": st.one_of(numbers, st.lists(numbers, max_size=4)),
    "rtol": numbers,
    "atol": numbers,
}
precision = st.one_of(numbers, st.lists(st.lists(numbers, min_size=2, max_size=2), min_size=2,
                                        max_size=2), values)
task_dicts = st.fixed_dictionaries(
    {"kind": kinds},
    optional={
        "goal": st.dictionaries(st.sampled_from(terms[:3]), st.lists(numbers, max_size=3), max_size=2),
        "precision": st.dictionaries(st.sampled_from(terms + ["extra"]), precision, max_size=3),
        "episode": st.fixed_dictionaries({}, optional=episode_keys),
        "description": values,
        "colour": values,
    },
)
tasks = st.one_of(task_dicts, kinds, st.just(0), st.just([1, 2]))
params = st.one_of(
    st.lists(numbers, min_size=4, max_size=4),
    st.lists(numbers, max_size=7),
    st.lists(st.lists(numbers, min_size=4, max_size=4), min_size=1, max_size=3).map(np.array),
    st.sampled_from([np.zeros((0, 4)), np.ones((2, 2, 4)), np.array([0.3, 0.4, 0.5, 0.2])]),
)
models = st.one_of(st.sampled_from(list(toolconf.models())), st.text(max_size=12))


def call(fn, *args, **kwargs) -> None:
    try:
        out = fn(*args, **kwargs)
    except EXPECTED as err:
        one_line(err)
        return
    finite(out)


@FUZZ
@given(models, params, tasks)
def test_confidence(model, p, task):
    call(toolconf.confidence, model, p, task)


@FUZZ
@given(st.sampled_from(["arm2", "msd", "arm3"]), params, task_dicts,
       st.fixed_dictionaries({}, optional=episode_keys),
       st.sampled_from(["fast", "explicit", "auto", "stiff", "slow"]))
def test_simulate(model, p, task, options, method):
    # Only short episodes: bound the run time, not the options' checks.
    episode = task.setdefault("episode", {})
    if not isinstance(episode, dict):
        return call(toolconf.simulate, model, p, task)
    for key in ("t_end", "dt"):
        for where in (episode, options):
            value = where.get(key)
            if isinstance(value, float) and value > 0.2:
                where[key] = 0.2
    call(toolconf.simulate, model, p, task, method=method, **options)


CSV = "name,model,m1,m2,l1,l2\nshort hammer,arm2,0.30,0.40,0.25,0.20\nrod,arm2_exact,0.3,0.3,0.4,0.4\n"
TOKENS = ['"', ",", "\n", "nan", "1e308", "-1", "m1", "model", "arm3", "\0", "é", "[", "{"]


@FUZZ
@given(st.lists(st.tuples(st.floats(0, 1), st.sampled_from(TOKENS), st.integers(1, 3000)),
                max_size=5),
       st.booleans(), st.one_of(st.none(), st.integers(-2, 3)), st.sampled_from(
           ["free-energy", "cost_j", "confidence", "speed"]))
def test_rank(tmp_path_factory, edits, as_json, screen, objective):
    text = CSV
    for at, token, n in edits:
        i = int(at * len(text))
        text = text[:i] + token * n + text[i:]
    if as_json:
        lines = text.splitlines()
        text = "[" + ",".join('{"name": "%s"}' % line.replace('"', "") for line in lines) + "]"
    path = tmp_path_factory.mktemp("rank") / ("tools.json" if as_json else "tools.csv")
    path.write_text(text)
    task = {"kind": "position", "episode": {"t_end": 0.2}}
    try:
        out = toolconf.rank(path, task, screen=screen, objective=objective,
                            skip_bad_rows=screen == 1)
    except EXPECTED as err:
        one_line(err)
        return
    # NaN marks a missing number only where the row's `error` says why.
    for i, error in enumerate(out["error"]):
        row = {k: v[i] for k, v in out.items() if isinstance(v, np.ndarray) and v.dtype.kind == "f"}
        if error is None:
            finite(row)
        else:
            one_line(Exception(error))
