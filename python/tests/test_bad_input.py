"""Bad input raises ValueError with the command line's one-line message, never a crash."""

import re

import numpy as np
import pytest

import toolconf

from conftest import DRAWER

PAPER_ARM = [0.3, 0.4, 0.5, 0.2]


@pytest.mark.parametrize("arm", ["-0.3,0.4,0.5,0.2", "0.3,0,0.5,0.2", "0.3,0.4,nan,0.2",
                                 "0.3,0.4,0.5,inf"])
def test_a_bad_parameter_gives_the_command_lines_message(arm, cli):
    # clap reports it: "error: invalid value '…' for '--arm <ARM>': <the crate's message>".
    status, _, stderr = cli("confidence", "--arm", arm, "--task", "position")
    assert status == 2
    expected = stderr.splitlines()[0].split("for '--arm <ARM>': ", 1)[1]
    params = [float(v) for v in arm.split(",")]
    with pytest.raises(ValueError) as caught:
        toolconf.confidence("arm2", params, "position")
    assert str(caught.value) == expected
    with pytest.raises(ValueError) as caught:
        toolconf.simulate("arm2", params, "position")
    assert str(caught.value) == expected


def test_a_bad_tool_in_a_batch_is_named_by_its_row():
    params = np.full((5, 4), 0.3)
    params[3, 1] = -1.0
    with pytest.raises(ValueError, match=r"^tool 3 \(m1=0.3 m2=-1 l1=0.3 l2=0.3\): invalid arm "
                                         r"parameter m2 = -1: must be a number in \[1e-6, 1e6\]$"):
        toolconf.confidence("arm2", params, "position")


@pytest.mark.parametrize("params, shape", [([0.3, 0.4, 0.5], "[3]"),
                                           (np.ones((2, 5)), "[2, 5]"),
                                           (np.ones((2, 2, 4)), "[2, 2, 4]")])
def test_the_wrong_number_of_parameters(params, shape):
    with pytest.raises(ValueError, match="^" + re.escape(f"params of shape {shape}: model arm2 "
                                                         "takes 4 parameters (m1,m2,l1,l2)")):
        toolconf.confidence("arm2", params, "position")


def test_text_parameters_are_refused():
    with pytest.raises((ValueError, TypeError)):
        toolconf.confidence("arm2", ["0.3", "heavy", "0.5", "0.2"], "position")


def test_an_unknown_model_names_the_models():
    with pytest.raises(ValueError, match="unknown model 'arm9': expected one of arm2, "
                                         "arm2_exact, arm2_payload, arm3, msd"):
        toolconf.confidence("arm9", PAPER_ARM, "position")


def test_an_unknown_task(cli_error):
    with pytest.raises(ValueError, match=r"^task 'reach': neither a built-in task"):
        toolconf.confidence("arm2", PAPER_ARM, "reach")
    with pytest.raises(ValueError, match=r"^task = 3.5: expected a built-in task name"):
        toolconf.confidence("arm2", PAPER_ARM, 3.5)


@pytest.mark.parametrize("toml, task", [
    ('kind = "position"\n[precision]\ntheta = [[80.0, 5.0], [1.0, 80.0]]\n',
     {"kind": "position", "precision": {"theta": [[80.0, 5.0], [1.0, 80.0]]}}),
    ('kind = "velocity"\n[goal]\ntheta = [0.5, 0.5]\n',
     {"kind": "velocity", "goal": {"theta": [0.5, 0.5]}}),
    ('kind = "position"\n[goal]\ntheta = [0.5, 0.5, 0.5]\n',
     {"kind": "position", "goal": {"theta": [0.5, 0.5, 0.5]}}),
    ('kind = "sideways"\n', {"kind": "sideways"}),
    ('kind = "position"\n[precision]\nu = -1.0\n', {"kind": "position", "precision": {"u": -1.0}}),
    ('kind = "position"\n[episode]\nt_end = -1.0\n', {"kind": "position", "episode": {"t_end": -1.0}}),
    ('kind = "position"\n[goal]\ntheta = [nan, 0.0]\n',
     {"kind": "position", "goal": {"theta": [float("nan"), 0.0]}}),
    # The valid ranges (toolconf.ranges()), checked by the same code on both sides.
    ('kind = "position"\n[episode]\nrtol = 1e10\n', {"kind": "position", "episode": {"rtol": 1e10}}),
    ('kind = "position"\n[episode]\ndt = 5e-324\n', {"kind": "position", "episode": {"dt": 5e-324}}),
    ('kind = "position"\n[precision]\ntheta = 1e300\n',
     {"kind": "position", "precision": {"theta": 1e300}}),
    ('kind = "position"\n[goal]\ntheta = [1e300, 0.0]\n',
     {"kind": "position", "goal": {"theta": [1e300, 0.0]}}),
    ('kind = "acceleration"\n[precision]\ntheta_ddot = 0.0\nu = 0.0\n',
     {"kind": "acceleration", "precision": {"theta_ddot": 0.0, "u": 0.0}}),
])
def test_a_bad_task_dict_gives_the_task_files_message_for_the_same_key(toml, task, cli_error,
                                                                       tmp_path):
    path = tmp_path / "task.toml"
    path.write_text(toml)
    expected = cli_error("confidence", "--arm", "0.3,0.4,0.5,0.2", "--task-file", path)
    with pytest.raises(ValueError) as caught:
        toolconf.confidence("arm2", PAPER_ARM, task)
    assert str(caught.value) == expected.replace(str(path), "task dict")


@pytest.mark.parametrize("task, message", [
    ({"kind": "position", "goal": {"theta": 0.5}}, "task dict, key goal.theta: invalid type"),
    ({"kind": "position", "gaol": {}}, "task dict: unknown field `gaol`"),
    ({"kind": "position", "precision": {"thetaa": 1.0}},
     "task dict, key precision: unknown field `thetaa`"),
    ({"kind": "position", "goal": {"theta": [0.5, object()]}}, "task dict, key goal.theta: <object"),
    ({"goal": {}}, "task dict: missing field `kind`"),
])
def test_a_dict_of_the_wrong_shape_names_the_key(task, message):
    with pytest.raises(ValueError) as caught:
        toolconf.confidence("arm2", PAPER_ARM, task)
    assert str(caught.value).startswith(message), str(caught.value)


def test_unknown_or_bad_episode_options_name_the_key():
    with pytest.raises(ValueError, match="key episode: unknown field `t_ned`"):
        toolconf.simulate("arm2", PAPER_ARM, "position", t_ned=3.0)
    with pytest.raises(ValueError,
                       match=r"key episode.dt: the output step dt = 10 s is larger than t_end = 5 s"):
        toolconf.simulate("arm2", PAPER_ARM, "position", dt=10.0)
    with pytest.raises(ValueError, match=r"key episode.t_end: episode too long"):
        toolconf.simulate("arm2", PAPER_ARM, "position", t_end=1e5)
    with pytest.raises(ValueError, match=r"key episode.t_end: 1e9 must be a number in \(0, 1e6\] s"):
        toolconf.simulate("arm2", PAPER_ARM, "position", t_end=1e9)
    with pytest.raises(ValueError, match=r"key episode.perturbation: 3 values \[.*\], but model "
                                         r"arm2 has 2 joints"):
        toolconf.simulate("arm2", PAPER_ARM, {"kind": "position"}, perturbation=[0.1, 0.2, 0.3])


def test_simulate_takes_one_tool():
    with pytest.raises(ValueError, match="takes one tool's 4 parameters"):
        toolconf.simulate("arm2", np.ones((2, 4)), "position")


def test_a_bad_tools_row_gives_the_command_lines_message(cli_error, tmp_path):
    path = tmp_path / "tools.csv"
    path.write_text("name,m1,m2,l1,l2\nok,0.3,0.3,0.3,0.3\nmallet,0.3,heavy,0.3,0.3\n")
    expected = cli_error("rank", "--tools", path, "--task", "position")
    assert "line 3: m2 = 'heavy' is not a number (tool 'mallet')" in expected
    with pytest.raises(ValueError) as caught:
        toolconf.rank(path, "position")
    assert str(caught.value) == expected
    with pytest.warns(UserWarning, match="skipping .*line 3"):
        ranked = toolconf.rank(path, "position", skip_bad_rows=True)
    assert ranked["name"] == ["ok"]


@pytest.mark.parametrize("args, kwargs, message", [
    ((DRAWER, "position"), {"screen": 0}, "screen = 0: must be at least 1"),
    ((DRAWER, "position"), {"objective": "speed"}, "objective 'speed': expected free-energy"),
    (("no/such/tools.csv", "position"), {}, "no/such/tools.csv: cannot open the tools file"),
])
def test_bad_rank_arguments(args, kwargs, message):
    with pytest.raises(ValueError) as caught:
        toolconf.rank(*args, **kwargs)
    assert str(caught.value).startswith(message)


def test_a_task_that_does_not_fit_a_tool_of_the_file(cli_error, tmp_path):
    task = tmp_path / "three.toml"
    task.write_text('kind = "position"\n[goal]\ntheta = [0.1, 0.2, 0.3]\n')
    expected = cli_error("rank", "--tools", DRAWER, "--task", task)
    with pytest.raises(ValueError) as caught:
        toolconf.rank(DRAWER, task)
    assert str(caught.value) == expected


def test_a_parameter_outside_its_range_is_refused_with_the_range(cli):
    status, _, stderr = cli("confidence", "--arm", "1e308,1e308,1e308,1e308", "--task", "velocity")
    assert status == 2
    expected = stderr.splitlines()[0].split("for '--arm <ARM>': ", 1)[1]
    assert expected == "invalid arm parameter m1 = 1e308: must be a number in [1e-6, 1e6]"
    with pytest.raises(ValueError) as caught:
        toolconf.confidence("arm2", [1e308] * 4, "velocity")
    assert str(caught.value) == expected
    assert toolconf.ranges()["tool_parameter"] == {"low": 1e-6, "high": 1e6, "low_open": False,
                                                   "unit": ""}


def _unaligned(values):
    """`values` as float64 at an odd byte offset: unaligned, as an array unpickled from
    out-of-band buffers can be."""
    values = np.asarray(values, dtype=np.float64)
    buffer = bytearray(values.nbytes + 1)
    array = np.ndarray(values.shape, dtype=np.float64, buffer=buffer, offset=1)
    array[...] = values
    assert not array.flags.aligned
    return array


def test_arrays_in_any_memory_layout_give_the_same_numbers():
    # An unaligned view once panicked in the extension ("The pointer must be aligned").
    tools = np.array([PAPER_ARM, [0.2, 0.5, 0.4, 0.3], [0.6, 0.1, 0.3, 0.5]])
    plain = toolconf.confidence("arm2", tools, "velocity")["logdet"]
    strided = np.zeros((3, 8))
    strided[:, ::2] = tools
    for layout in (_unaligned(tools), strided[:, ::2], np.asfortranarray(tools)):
        assert np.array_equal(toolconf.confidence("arm2", layout, "velocity")["logdet"], plain)
    one = toolconf.confidence("arm2", tools[0], "velocity")["logdet"]
    assert toolconf.confidence("arm2", _unaligned(tools[0]), "velocity")["logdet"] == one
    episode = toolconf.simulate("arm2", _unaligned(PAPER_ARM), "velocity", t_end=1.0)
    assert episode["task_error"] == toolconf.simulate("arm2", PAPER_ARM, "velocity",
                                                      t_end=1.0)["task_error"]
    tool, state = [0.5, 0.0, 0.0, 0.1, 1e-3, 1e-3, 1e-3], np.linspace(-0.5, 0.5, 14)
    torque = np.linspace(-1.0, 1.0, 7)
    plain = toolconf.dynamics("panda", tool, state, torque)
    layouts = toolconf.dynamics("panda", _unaligned(tool), _unaligned(state), torque[::-1][::-1])
    assert np.array_equal(layouts, plain)
