"""toolconf.rank of tools in memory (a pandas DataFrame, a dict of 1-D arrays or lists, a NumPy
structured array) against toolconf.rank of the same rows written to a tools file: the same
table digit for digit, and the same message for a bad row with ``row N`` for ``line N+1``."""

import json
import math

import numpy as np
import pandas as pd
import pytest

import toolconf

from conftest import DRAWER

PARAMETERS = ["m1", "m2", "m3", "l1", "l2", "l3"]


def tools_frame():
    """The drawer, three-link arms, unnamed tools, and a giant whose episode diverges on the
    position task (so that the table has a failed tool too)."""
    frame = pd.read_csv(DRAWER)
    extra = pd.DataFrame({
        "name": ["three", None, "giant", None, "three again"],
        "model": ["arm3", "arm2", "arm2", None, "arm3"],
        "m1": [0.3, 0.2, 1e5, 0.25, 0.3],
        "m2": [0.3, 0.3, 1e5, 0.35, 0.3],
        "m3": [0.2, np.nan, np.nan, np.nan, 0.2],
        "l1": [0.3, 0.4, 1e5, 0.3, 0.3],
        "l2": [0.3, 0.3, 1e5, 0.2, 0.3],
        "l3": [0.2, np.nan, np.nan, np.nan, 0.2],
    })
    return pd.concat([frame, extra], ignore_index=True)


def assert_same_table(got, expected):
    assert list(got) == list(expected)
    for key in expected:
        if isinstance(expected[key], np.ndarray):
            assert got[key].dtype == expected[key].dtype, key
            assert np.array_equal(got[key], expected[key], equal_nan=True), key
        else:
            assert list(got[key]) == list(expected[key]), key


def structured(frame):
    fields = [("name", "U32"), ("model", "U16")] + [(p, "f8") for p in PARAMETERS]
    array = np.zeros(len(frame), dtype=fields)
    array["name"] = frame["name"].fillna("").to_numpy(dtype=str)
    array["model"] = frame["model"].fillna("").to_numpy(dtype=str)
    for p in PARAMETERS:
        array[p] = frame[p].to_numpy(dtype="float64")
    return array


@pytest.mark.parametrize("task, screen, objective", [
    ("position", None, "free-energy"),
    ("position", None, "cost-j"),
    ("velocity", 6, "confidence"),
])
def test_a_frame_a_dict_and_a_structured_array_rank_as_their_file(task, screen, objective,
                                                                   tmp_path):
    frame = tools_frame()
    csv = tmp_path / "tools.csv"
    frame.to_csv(csv, index=False)
    records = [{k: v for k, v in row.items() if not (isinstance(v, float) and math.isnan(v))
                and v is not None} for row in frame.to_dict(orient="records")]
    js = tmp_path / "tools.json"
    js.write_text(json.dumps(records))
    expected = toolconf.rank(csv, task, screen=screen, objective=objective)
    assert_same_table(toolconf.rank(js, task, screen=screen, objective=objective), expected)
    if task == "position":
        assert expected["name"][-1] == "giant" and "diverged" in expected["error"][-1]
    ranked = toolconf.rank(frame, task, screen=screen, objective=objective)
    assert isinstance(ranked, pd.DataFrame)
    pd.testing.assert_frame_equal(ranked, pd.DataFrame(expected), check_exact=True)
    as_lists = {c: frame[c].tolist() for c in frame.columns}
    as_arrays = {c: frame[c].to_numpy() for c in frame.columns}
    for tools in (as_lists, as_arrays, structured(frame)):
        got = toolconf.rank(tools, task, screen=screen, objective=objective)
        assert isinstance(got, dict)
        assert_same_table(got, expected)


def test_nullable_and_text_dtypes_read_as_plain_columns():
    frame = tools_frame()
    expected = toolconf.rank(frame, "position", screen=4)
    typed = frame.astype({"name": "string", "model": "category", "m3": "Float64",
                          "l3": "Float64"})
    pd.testing.assert_frame_equal(toolconf.rank(typed, "position", screen=4), expected,
                                  check_exact=True)


def bad_cases():
    """(what, cells for the second row, message after the place)."""
    return [
        ("text", {"m2": "heavy"}, "m2 = 'heavy' is not a number (tool 'mallet')"),
        ("missing", {"m2": None}, "m2 is missing (model arm2 needs it) (tool 'mallet')"),
        ("model", {"model": "arm9"}, None),
        ("other model's parameter", {"m3": 0.2}, None),
        ("negative", {"l1": -0.3}, None),
    ]


@pytest.mark.parametrize("what, cells, message", bad_cases())
def test_a_bad_row_gets_the_files_message_with_its_row(what, cells, message, tmp_path, cli_error):
    frame = pd.DataFrame({"name": ["ok", "mallet"], "model": ["arm2", "arm2"],
                          "m1": [0.3, 0.3], "m2": [0.3, 0.3], "m3": [np.nan, np.nan],
                          "l1": [0.3, 0.3], "l2": [0.3, 0.3]}).astype(object)
    for key, value in cells.items():
        frame.loc[1, key] = value
    csv = tmp_path / "t.csv"
    frame.to_csv(csv, index=False)
    expected = cli_error("rank", "--tools", csv, "--task", "position")
    prefix = f"{csv}, line 3: "
    assert expected.startswith(prefix), expected
    if message is not None:
        assert expected == prefix + message
    for tools, source in [(frame, "tools DataFrame"),
                          ({c: frame[c].tolist() for c in frame.columns}, "tools dict")]:
        with pytest.raises(ValueError) as caught:
            toolconf.rank(tools, "position")
        assert str(caught.value) == f"{source}, row 2: " + expected[len(prefix):]
        with pytest.warns(UserWarning) as warned:
            ranked = toolconf.rank(tools, "position", skip_bad_rows=True)
        assert [str(w.message) for w in warned] == [
            f"toolconf: skipping {source}, row 2: " + expected[len(prefix):]]
        assert list(ranked["name"]) == ["ok"]


def test_bad_columns_get_the_files_messages(tmp_path, cli_error):
    csv = tmp_path / "t.csv"
    csv.write_text("name,weight\nx,1\n")
    expected = cli_error("rank", "--tools", csv, "--task", "position")
    header = f"{csv}, line 1 (header): "
    assert expected.startswith(header + "unknown column 'weight'")
    with pytest.raises(ValueError) as caught:
        toolconf.rank({"name": ["x"], "weight": [1.0]}, "position")
    assert str(caught.value) == "tools dict: " + expected[len(header):]
    twice = pd.DataFrame([[0.3, 0.3, 0.3, 0.3, 0.3]], columns=["m1", "m1", "m2", "l1", "l2"])
    with pytest.raises(ValueError, match=r"^tools DataFrame: column 'm1' appears twice$"):
        toolconf.rank(twice, "position")


@pytest.mark.parametrize("tools, message", [
    ({"m1": [0.3, 0.3], "m2": [0.3], "l1": [0.3, 0.3], "l2": [0.3, 0.3]},
     "tools dict: column 'm2' has 1 values, column 'm1' 2: every column needs one value per "
     "tool"),
    ({"m1": np.ones((2, 2))}, "tools dict, column 'm1': has shape [2, 2]; a column is 1-D"),
    ({3: [0.3]}, "tools dict: column name 3 is not text"),
    ({}, "tools dict: no tools: there are no columns"),
    ({"m1": [], "m2": [], "l1": [], "l2": []}, "tools dict: no tools: the columns have no rows"),
    (pd.DataFrame({"m1": [], "m2": []}), "tools DataFrame: no tools: the columns have no rows"),
    ({"m1": [0.3, 0.3], "m2": [0.3, [0.3]], "l1": [0.3, 0.3], "l2": [0.3, 0.3]},
     "tools dict, row 2: m2 = [0.3] is not a number"),
    ({"m1": "0.3"}, "tools dict, column 'm1': has shape []; a column is 1-D"),
    ({"m1": [0.3], "m2": [True], "l1": [0.3], "l2": [0.3]},
     "tools dict, row 1: m2 = True is not a number"),
    (42, "tools = 42: expected a tools file's path, a pandas DataFrame, a dict of 1-D arrays"),
])
def test_bad_tables_are_refused_with_one_line(tools, message):
    with pytest.raises(ValueError) as caught:
        toolconf.rank(tools, "position")
    assert str(caught.value).startswith(message), str(caught.value)
    assert "\n" not in str(caught.value)
