"""toolconf.simulate_batch against a loop of toolconf.simulate: every (tool, perturbation) row
has simulate's metrics digit for digit, or the message simulate raises; one failed tool never
stops the batch; the rows do not depend on the number of threads."""


import numpy as np
import pytest

import toolconf

from conftest import stdout_per_thread_count

METRICS = ["task_error", "free_energy", "cost_j", "logdet", "control_effort", "rhs_evals",
           "steps", "rejected_steps", "jacobian_evals", "factorisations"]
# Its episode diverges on the position task (|state| > 1e6 at t = 0.55 s).
GIANT = [1e5, 1e5, 1e5, 1e5]


def arm2_tools(n, seed):
    return 0.1 + 0.5 * np.random.default_rng(seed).random((n, 4))


def loop_of_simulate(model, params, task, perturbations, method, **options):
    rows = []
    for p in params:
        for dt in perturbations:
            try:
                e = toolconf.simulate(model, p, task, method, perturbation=dt, **options)
                rows.append({k: e[k] for k in METRICS})
            except (ValueError, toolconf.SimulationError) as failure:
                rows.append(str(failure))
    return rows


def assert_rows_equal(batch, rows, perturbations):
    p = len(perturbations)
    assert len(batch["error"]) == len(rows)
    for i, expected in enumerate(rows):
        assert (batch["tool"][i], batch["perturbation"][i]) == (i // p, i % p)
        if isinstance(expected, str):
            assert batch["error"][i] == expected
            assert all(np.isnan(batch[k][i]) for k in METRICS[:5])
            assert all(batch[k][i] == -1 for k in METRICS[5:])
        else:
            assert batch["error"][i] is None
            for k in METRICS:
                assert batch[k][i] == expected[k], (i, k)


@pytest.mark.parametrize("method", ["fast", "explicit"])
def test_the_batch_equals_a_loop_of_simulate_and_a_failed_tool_does_not_stop_it(method):
    params = np.vstack([arm2_tools(4, 1), GIANT, arm2_tools(2, 2)])
    perturbations = [-0.8, 0.0, [0.3, -0.2]]
    batch = toolconf.simulate_batch("arm2", params, "position", perturbations, method,
                                    t_end=3.0)
    assert_rows_equal(batch, loop_of_simulate("arm2", params, "position", perturbations,
                                              method, t_end=3.0), perturbations)
    failed = [i for i, e in enumerate(batch["error"]) if e is not None]
    assert {batch["tool"][i] for i in failed} == {4}
    assert all("diverged" in batch["error"][i] for i in failed)


def test_another_model_a_task_dict_and_the_tasks_own_perturbation():
    params = np.array([[0.3, 0.3, 0.2, 0.4, 0.3, 0.2], [0.2, 0.4, 0.3, 0.3, 0.3, 0.3]])
    task = {"kind": "velocity", "episode": {"perturbation": [0.1, 0.0, -0.1]}}
    batch = toolconf.simulate_batch("arm3", params, task)
    expected = []
    for p in params:
        e = toolconf.simulate("arm3", p, task)
        expected.append({k: e[k] for k in METRICS})
    assert_rows_equal(batch, expected, [None])
    one = toolconf.simulate_batch("arm3", params[1], task)
    assert list(one["tool"]) == [0] and one["task_error"][0] == expected[1]["task_error"]


def test_rows_do_not_depend_on_the_number_of_threads():
    script = (
        "import sys, numpy as np, toolconf\n"
        "p = 0.1 + 0.5 * np.random.default_rng(5).random((40, 4))\n"
        "b = toolconf.simulate_batch('arm2', p, 'velocity', [-1.0, 0.0, 1.0])\n"
        "print(repr({k: (v.tolist() if hasattr(v, 'tolist') else v) for k, v in b.items()}))\n"
    )
    outputs = stdout_per_thread_count(script)
    assert outputs[0] == outputs[1]


def test_a_bad_tool_is_named_by_its_row_before_any_episode():
    params = np.full((5, 4), 0.3)
    params[3, 1] = -1.0
    with pytest.raises(ValueError) as caught:
        toolconf.confidence("arm2", params, "position")
    with pytest.raises(ValueError) as batch:
        toolconf.simulate_batch("arm2", params, "position", [0.0, 0.5])
    assert str(batch.value) == str(caught.value)
    assert str(batch.value).startswith("tool 3 (m1=0.3 m2=-1 l1=0.3 l2=0.3): ")
    with pytest.raises(ValueError) as chunk:
        toolconf.simulate_batch("arm2", params[2:], "position", first_tool=2)
    assert str(chunk.value) == str(caught.value)
    with pytest.raises(ValueError) as single:
        toolconf.simulate("arm2", params[3], "position")
    with pytest.raises(ValueError) as one:
        toolconf.simulate_batch("arm2", params[3], "position")
    assert str(one.value) == str(single.value)


@pytest.mark.parametrize("kwargs, message", [
    ({"perturbations": [0.1], "perturbation": 0.2}, "perturbation and perturbations: give"),
    ({"perturbations": []}, "perturbations = []: give at least one perturbation"),
    ({"perturbations": "0.1"}, "perturbations = '0.1': expected a list of torques"),
    ({"method": "rk4"}, "method = "),
])
def test_bad_batch_options(kwargs, message):
    with pytest.raises(ValueError) as caught:
        toolconf.simulate_batch("arm2", arm2_tools(2, 0), "position", **kwargs)
    assert str(caught.value).startswith(message), str(caught.value)


def test_a_bad_perturbation_or_option_gets_simulates_message():
    for options in ({"perturbation": [0.1, 0.2, 0.3]}, {"t_end": -1.0}, {"t_ned": 1.0}):
        with pytest.raises(ValueError) as single:
            toolconf.simulate("arm2", [0.3, 0.3, 0.3, 0.3], "position", **options)
        if "perturbation" in options:
            call = {"perturbations": [options["perturbation"]]}
        else:
            call = options
        with pytest.raises(ValueError) as batch:
            toolconf.simulate_batch("arm2", arm2_tools(2, 0), "position", **call)
        assert str(batch.value) == str(single.value)


@pytest.mark.parametrize("params, shape", [(np.ones((2, 5)), "[2, 5]"),
                                           (np.ones((2, 2, 4)), "[2, 2, 4]")])
def test_the_wrong_shape_of_params(params, shape):
    with pytest.raises(ValueError, match=rf"^params of shape \{shape}: model arm2 takes 4"):
        toolconf.simulate_batch("arm2", params, "position")
