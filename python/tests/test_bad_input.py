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


# One exception rule for every argument: ValueError for a value the command line would refuse
# (with its message), TypeError for a Python value of the wrong type; never OverflowError,
# IndexError, or a complex or boolean array taken as numbers.

SHORT = {"kind": "position", "episode": {"t_end": 0.2}}


@pytest.mark.parametrize("screen, message", [
    (0, "screen = 0: must be at least 1"),
    (-1, "screen = -1: must be at least 1"),
    (-(2**70), "screen = -1180591620717411303424: must be at least 1"),
    (10**20, "screen = 100000000000000000000: must be at most 18446744073709551615"),
    (2**64, "screen = 18446744073709551616: must be at most 18446744073709551615"),
])
def test_screen_outside_the_command_lines_range_is_a_value_error(screen, message):
    with pytest.raises(ValueError) as caught:
        toolconf.rank(DRAWER, SHORT, screen=screen)
    assert str(caught.value) == message


def test_screen_takes_what_the_command_line_takes(cli_json):
    # --screen is a u64 ≥ 1: 2**63 and 2**64 - 1 keep every tool, as no screen does.
    every = toolconf.rank(DRAWER, "position")
    expected = cli_json("rank", "--tools", DRAWER, "--task", "position", "--screen", 2**63)
    assert list(every["name"]) == [row["name"] for row in expected["tools"]]
    for screen in (2**63, 2**64 - 1, np.uint64(2**63), np.int64(12)):
        got = toolconf.rank(DRAWER, "position", screen=screen)
        assert list(got["name"]) == list(every["name"])
        assert np.array_equal(got["free_energy"], every["free_energy"], equal_nan=True)


@pytest.mark.parametrize("screen", [True, 2.0, "3", np.float64(3.0)])
def test_screen_that_is_not_an_integer_is_a_type_error(screen):
    with pytest.raises(TypeError, match=r"^screen = .*: expected an integer"):
        toolconf.rank(DRAWER, SHORT, screen=screen)


@pytest.mark.parametrize("first_tool, message", [
    (-1, "first_tool = -1: must be at least 0"),
    (2**70, "first_tool = 1180591620717411303424: must be at most 9223372036854775805"),
    (2**63 - 1, "first_tool = 9223372036854775807: must be at most 9223372036854775805"),
])
def test_first_tool_outside_its_range_is_a_value_error(first_tool, message):
    # Two tools: the last one's index (first_tool + 1) must fit the int64 `tool` column.
    with pytest.raises(ValueError) as caught:
        toolconf.simulate_batch("arm2", np.full((2, 4), 0.3), "position", first_tool=first_tool)
    assert str(caught.value) == message


def test_first_tool_at_its_bound_numbers_the_rows():
    out = toolconf.simulate_batch("arm2", np.full((2, 4), 0.3), SHORT, first_tool=2**63 - 3)
    assert out["tool"].tolist() == [2**63 - 3, 2**63 - 2]
    with pytest.raises(TypeError, match=r"^first_tool = True: expected an integer, not a bool"):
        toolconf.simulate_batch("arm2", np.full((2, 4), 0.3), SHORT, first_tool=True)


PANDA_TOOL = [0.5, 0.0, 0.0, 0.1, 1e-3, 1e-3, 1e-3]


def array_calls(bad):
    """Every array argument of every function, given `bad` (a function of the valid value)."""
    tools = np.array([PAPER_ARM, PAPER_ARM])
    state, torque = np.linspace(-0.5, 0.5, 14), np.linspace(-1.0, 1.0, 7)
    return {
        "confidence params": lambda: toolconf.confidence("arm2", bad(tools), "position"),
        "simulate params": lambda: toolconf.simulate("arm2", bad(tools[0]), SHORT),
        "simulate_batch params": lambda: toolconf.simulate_batch("arm2", bad(tools), SHORT),
        "dynamics params": lambda: toolconf.dynamics("panda", bad(PANDA_TOOL), state, torque),
        "dynamics state": lambda: toolconf.dynamics("panda", PANDA_TOOL, bad(state), torque),
        "dynamics control": lambda: toolconf.dynamics("panda", PANDA_TOOL, state, bad(torque)),
        "rank column": lambda: toolconf.rank({"m1": bad(tools[:, 0]), "m2": tools[:, 1],
                                               "l1": tools[:, 2], "l2": tools[:, 3]}, SHORT),
    }


@pytest.mark.parametrize("call", list(array_calls(lambda v: v)))
@pytest.mark.parametrize("dtype, words", [("complex128", "complex numbers"), (bool, "booleans")])
def test_complex_and_boolean_arrays_are_type_errors_everywhere(call, dtype, words):
    # A complex array once lost its imaginary part (with only a warning); booleans were 1 and 0
    # to confidence but refused by rank.
    argument = call.split()[1]
    as_dtype = array_calls(lambda v: np.asarray(v).astype(dtype))[call]
    with pytest.raises(TypeError) as caught:
        as_dtype()
    message = str(caught.value)
    assert words in message and f"(dtype {np.dtype(dtype)})" in message, message
    assert message.startswith("tools dict, column 'm1'" if argument == "column" else argument)


@pytest.mark.parametrize("value, error, message", [
    ([0.3, None, 0.5, 0.2], TypeError, "params: None (NoneType) is not a real number"),
    ([0.3, True, 0.5, 0.2], TypeError, "params: True (bool) is not a real number"),
    ([0.3, "0.4", 0.5, 0.2], TypeError, "params: '0.4' (str) is not a real number"),
    (np.array(["0.3", "0.4"]), TypeError, "params: an array of text (dtype <U3); expected real"),
    ("0.3", TypeError, "params: an array of text"),
    (b"0.3", TypeError, "params: an array of text"),
    ([0.3, 2**70, 0.5, 0.2], ValueError,
     "invalid arm parameter m2 = 1.1805916207174113e21: must be a number"),
    ([0.3, 10**400, 0.5, 0.2], ValueError, "params: int too large to convert to float"),
    ([0.3, 0.4, [0.5], 0.2], TypeError, "params: [0.5] (list) is not a real number"),
    ([[0.3, 0.4, 0.5, 0.2], [0.3]], TypeError,
     "params: [0.3, 0.4, 0.5, 0.2] (list) is not a real number"),
    (np.datetime64("2024-01-01"), TypeError, "params: an array of dates or times"),
    (0.3, ValueError, "params of shape []: model arm2 takes 4 parameters"),
    (np.float64(np.nan), ValueError, "params of shape []"),
])
def test_objects_text_and_odd_values_as_params(value, error, message):
    with pytest.raises(error) as caught:
        toolconf.confidence("arm2", value, "position")
    assert str(caught.value).startswith(message), str(caught.value)
    assert type(caught.value) is error


def test_a_column_name_with_a_line_break_stays_one_line():
    with pytest.raises(ValueError) as caught:
        toolconf.rank({"\n": 1.0}, "position")
    assert str(caught.value) == "tools dict, column '\\n': has shape []; a column is 1-D, one " \
                                "value per tool"
