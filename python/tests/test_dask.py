"""toolconf.dask on a 2-worker LocalCluster against toolconf on the concatenated rows: the same
table row for row and digit for digit (global row numbers, ties across partitions broken by
global row order), the same first error in row order, the same warnings; simulate_batch the
same entry for entry."""

import warnings

import numpy as np
import pandas as pd
import pytest
from dask import delayed

import dask.array as da
import dask.dataframe as dd

import toolconf
import toolconf.dask as tdask

GIANT = [1e5, 1e5, 1e5, 1e5]


def tools(n=90, seed=3):
    """Random arm2 tools with three copies of one tool spread over the frame (a tie in
    confidence across partitions), a few arm3 and unnamed tools, and a giant whose episode
    diverges on the position task."""
    rng = np.random.default_rng(seed)
    frame = pd.DataFrame({
        "name": [f"tool {i}" for i in range(n)],
        "model": ["arm2"] * n,
        "m1": 0.1 + 0.5 * rng.random(n), "m2": 0.1 + 0.5 * rng.random(n),
        "m3": np.nan, "l1": 0.1 + 0.5 * rng.random(n), "l2": 0.1 + 0.5 * rng.random(n),
        "l3": np.nan,
    })
    best = frame.loc[[0]].assign(m1=0.1, m2=0.1, l1=0.12, l2=0.1)
    for row in (20, 50, 75):
        frame.loc[row, ["m1", "m2", "l1", "l2"]] = best[["m1", "m2", "l1", "l2"]].values[0]
    for row in (33, 60):
        frame.loc[row, ["model", "m3", "l3"]] = ["arm3", 0.2, 0.2]
    frame.loc[[5, 40], "name"] = None
    frame.loc[44, ["m1", "m2", "l1", "l2"]] = GIANT
    return frame


def partitioned(frame, cuts):
    """A dask DataFrame whose partitions are frame[cuts[i]:cuts[i+1]] (an empty one included
    when two cuts are equal)."""
    bounds = [0, *cuts, len(frame)]
    parts = [delayed(frame.iloc[a:b]) for a, b in zip(bounds, bounds[1:])]
    return dd.from_delayed(parts, meta=frame.iloc[:0], verify_meta=False)


CUTS = [15, 30, 30, 52, 70]


def test_the_workers_import_the_clients_extension_on_the_loopback(dask_client):
    here = toolconf._toolconf.__file__
    there = dask_client.run(lambda: __import__("toolconf")._toolconf.__file__)
    assert len(there) == 2 and set(there.values()) == {here}
    assert all(address.startswith("tcp://127.0.0.1:") for address in there)


@pytest.mark.parametrize("task, screen, objective, screen_by", [
    ("position", None, "free-energy", None),
    ("position", 3, "free-energy", "confidence"),
    ("position", 3, "free-energy", None),
    ("velocity", 7, "cost-j", None),
    ("velocity", 7, "cost-j", "confidence"),
    ("task file", 25, "confidence", None),
    ("task file", 25, "free-energy", "predicted"),
])
def test_rank_equals_toolconf_rank_on_the_concatenated_rows(task, screen, objective, screen_by,
                                                            dask_client, tmp_path):
    if task == "task file":
        # Read on the client and sent as text: the workers need not see the file.
        task = tmp_path / "task.toml"
        task.write_text('kind = "velocity"\n[precision]\ntheta_dot = 40.0\n[episode]\n'
                        't_end = 3.0\nperturbation = -0.3\n')
    frame = tools()
    ddf = partitioned(frame, CUTS)
    got = tdask.rank(ddf, task, screen=screen, objective=objective, client=dask_client,
                     screen_by=screen_by)
    expected = toolconf.rank(ddf.compute(), task, screen=screen, objective=objective,
                             screen_by=screen_by)
    pd.testing.assert_frame_equal(got, expected, check_exact=True)
    if screen == 3 and screen_by == "confidence":
        # The giant (row 45) is the most confident, then a tie of three equal tools (rows 21,
        # 51, 76 in three partitions): the two earlier rows are kept.
        assert sorted(got["row"]) == [21, 45, 51]
    if screen is None and task == "position":
        assert got["name"].iloc[-1] == "tool 44" and "diverged" in got["error"].iloc[-1]
        assert len(got) == len(frame)


def test_a_tie_in_prediction_across_partitions_keeps_the_earlier_rows(dask_client):
    # Row 36 is the tool predicted cheapest on the position task; copies of it in rows 11 and
    # 71 (other partitions) tie with it: the screen of 2 keeps rows 11 and 36.
    frame = tools()
    params = ["m1", "m2", "l1", "l2"]
    assert sorted(toolconf.rank(frame, "position", screen=1)["row"]) == [36]
    for index in (10, 70):
        frame.loc[index, params] = frame.loc[35, params].values
    ddf = partitioned(frame, CUTS)
    got = tdask.rank(ddf, "position", screen=2, client=dask_client)
    pd.testing.assert_frame_equal(got, toolconf.rank(frame, "position", screen=2),
                                  check_exact=True)
    assert sorted(got["row"]) == [11, 36]
    assert got["predicted_free_energy"].iloc[0] == got["predicted_free_energy"].iloc[1]


def test_episodes_spread_in_small_blocks_give_the_same_table(dask_client):
    ddf = partitioned(tools(), CUTS)
    got = tdask.rank(ddf, "velocity", screen=30, client=dask_client, episodes_per_task=4)
    expected = toolconf.rank(ddf.compute(), "velocity", screen=30)
    pd.testing.assert_frame_equal(got, expected, check_exact=True)


def bad(frame, rows):
    frame = frame.astype({"m2": object})
    for row in rows:
        frame.loc[row, "m2"] = "heavy"
    return frame


def test_the_first_bad_row_in_row_order_raises_toolconfs_error(dask_client):
    frame = bad(tools(), [58, 35])
    ddf = partitioned(frame, CUTS)
    with pytest.raises(ValueError) as expected:
        toolconf.rank(ddf.compute(), "position", screen=5)
    assert str(expected.value).startswith("tools DataFrame, row 36: m2 = 'heavy'")
    with pytest.raises(ValueError) as got:
        tdask.rank(ddf, "position", screen=5, client=dask_client)
    assert str(got.value) == str(expected.value)


def test_skipped_rows_warn_in_row_order(dask_client):
    frame = bad(tools(), [58, 3, 35])
    ddf = partitioned(frame, CUTS)
    with pytest.warns(UserWarning) as expected_warnings:
        expected = toolconf.rank(ddf.compute(), "velocity", screen=6, skip_bad_rows=True)
    with pytest.warns(UserWarning) as got_warnings:
        got = tdask.rank(ddf, "velocity", screen=6, skip_bad_rows=True, client=dask_client)
    pd.testing.assert_frame_equal(got, expected, check_exact=True)
    messages = [str(w.message) for w in got_warnings]
    assert messages == [str(w.message) for w in expected_warnings]
    assert [m.split(", ")[1].split(":")[0] for m in messages] == ["row 4", "row 36", "row 59"]


@pytest.mark.parametrize("frame, task", [
    (tools(), {"kind": "position", "goal": {"theta": [0.1, 0.2]}}),
    (tools().assign(m2="heavy"), "position"),
    (tools(), {"kind": "position", "precision": {"theta": 0.0, "theta_dot": 0.0,
                                                  "theta_ddot": 0.0, "u": 0.0}}),
    (tools().iloc[:0], "position"),
    (tools().assign(weight=1.0), "position"),
])
def test_whole_table_errors_equal_toolconfs(frame, task, dask_client):
    ddf = partitioned(frame, [0] if len(frame) == 0 else CUTS)
    with pytest.raises(ValueError) as expected, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        toolconf.rank(ddf.compute(), task, skip_bad_rows=True)
    with pytest.raises(ValueError) as got, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tdask.rank(ddf, task, skip_bad_rows=True, client=dask_client)
    assert str(got.value) == str(expected.value)


def test_bad_options_raise_before_the_cluster_works(dask_client):
    ddf = partitioned(tools(), CUTS)
    for kwargs in ({"screen": 0}, {"objective": "speed"}, {"method": "rk4"},
                   {"screen": 3, "screen_by": "speed"}):
        with pytest.raises(ValueError) as expected:
            toolconf.rank(ddf.compute(), "position", **kwargs)
        with pytest.raises(ValueError) as got:
            tdask.rank(ddf, "position", client=dask_client, **kwargs)
        assert str(got.value) == str(expected.value)


def arrays_equal(got, expected):
    assert list(got) == list(expected)
    for key in expected:
        if key == "error":
            assert got[key] == expected[key]
        else:
            assert got[key].dtype == expected[key].dtype, key
            assert np.array_equal(got[key], expected[key], equal_nan=True), key


def test_simulate_batch_equals_toolconf_simulate_batch(dask_client):
    rng = np.random.default_rng(8)
    params = np.vstack([0.1 + 0.5 * rng.random((10, 4)), GIANT, 0.1 + 0.5 * rng.random((6, 4))])
    perturbations = [-0.8, 0.0, [0.5, -0.5]]
    expected = toolconf.simulate_batch("arm2", params, "position", perturbations, t_end=3.0)
    assert expected["error"][30] is not None
    got = tdask.simulate_batch("arm2", params, "position", perturbations, client=dask_client,
                               tools_per_task=3, t_end=3.0)
    arrays_equal(got, expected)
    chunked = da.from_array(params, chunks=(5, 2))
    arrays_equal(tdask.simulate_batch("arm2", chunked, "position", perturbations,
                                      client=dask_client, t_end=3.0), expected)
    task = {"kind": "velocity", "goal": {"theta_dot": [0.2, -0.1]}}
    arrays_equal(tdask.simulate_batch("arm2", params, task, client=dask_client),
                 toolconf.simulate_batch("arm2", params, task))


def test_simulate_batch_errors_equal_toolconfs(dask_client):
    params = np.full((9, 4), 0.3)
    params[7, 2] = -1.0
    for args, kwargs in [((params, "position"), {}),
                         ((np.ones((9, 5)), "position"), {}),
                         ((params[:6], "position"), {"t_end": -1.0}),
                         ((params[:6], "reach"), {})]:
        with pytest.raises(ValueError) as expected:
            toolconf.simulate_batch("arm2", *args, **kwargs)
        with pytest.raises(ValueError) as got:
            tdask.simulate_batch("arm2", *args, client=dask_client, tools_per_task=2, **kwargs)
        assert str(got.value) == str(expected.value)
    empty = tdask.simulate_batch("arm2", np.empty((0, 4)), "position", client=dask_client)
    arrays_equal(empty, toolconf.simulate_batch("arm2", np.empty((0, 4)), "position"))


def test_simulate_batch_with_a_task_file_equals_toolconfs(dask_client, tmp_path):
    # The task file is read on the client and sent as text, with the episode options put over
    # its [episode] on the workers, as toolconf.simulate_batch puts them over the file's.
    task = tmp_path / "task.toml"
    task.write_text('kind = "velocity"\n[goal]\ntheta_dot = [0.2, -0.1]\n[precision]\n'
                    'theta_dot = 40.0\n[episode]\nt_end = 2.0\nlearning_rate = 2.0\n')
    rng = np.random.default_rng(11)
    params = np.vstack([0.1 + 0.5 * rng.random((7, 4)), GIANT])
    for perturbations, options in [(None, {}), ([-0.4, [0.3, 0.0]], {"dt": 0.1})]:
        expected = toolconf.simulate_batch("arm2", params, task, perturbations, **options)
        got = tdask.simulate_batch("arm2", params, task, perturbations, client=dask_client,
                                   tools_per_task=3, **options)
        arrays_equal(got, expected)
        assert np.isfinite(got["free_energy"][:7 * (1 if perturbations is None else 2)]).all()
    # Its errors name the file, as toolconf.simulate_batch's do.
    task.write_text('kind = "velocity"\n[episode]\nt_end = -1.0\n')
    with pytest.raises(ValueError) as expected:
        toolconf.simulate_batch("arm2", params, task)
    with pytest.raises(ValueError) as got:
        tdask.simulate_batch("arm2", params, task, client=dask_client)
    assert str(got.value) == str(expected.value) and str(task) in str(got.value)


@pytest.mark.parametrize("value, error, message", [
    (-5, ValueError, "must be at least 1"),
    (0, ValueError, "must be at least 1"),
    (True, TypeError, "expected an integer, not a bool"),
    (2.0, TypeError, "expected an integer"),
])
def test_block_sizes_below_one_or_not_integers_are_refused(value, error, message):
    # Checked before any cluster is looked for: -5 was an IndexError, 0 the default.
    with pytest.raises(error, match=f"^tools_per_task = {value!r}: {message}"):
        tdask.simulate_batch("arm2", np.full((4, 4), 0.3), "position", tools_per_task=value)
    with pytest.raises(error, match=f"^episodes_per_task = {value!r}: {message}"):
        tdask.rank(partitioned(tools(), CUTS), "position", screen=3, episodes_per_task=value)


def test_complex_and_boolean_params_are_refused_as_toolconf_refuses_them(dask_client):
    for params in (np.full((4, 4), 0.3 + 0.1j), np.ones((4, 4), dtype=bool)):
        with pytest.raises(TypeError) as expected:
            toolconf.simulate_batch("arm2", params, "position")
        with pytest.raises(TypeError) as got:
            tdask.simulate_batch("arm2", params, "position", client=dask_client)
        assert str(got.value) == str(expected.value)


def test_without_a_client_the_error_is_one_line(monkeypatch):
    import distributed

    def no_client():
        # distributed's own words when no client runs (the session's cluster may be running).
        raise ValueError("No clients found\nStart a client and point it to the scheduler address\n")

    monkeypatch.setattr(distributed, "default_client", no_client)
    with pytest.raises(ValueError) as caught:
        tdask.simulate_batch("arm2", np.full((2, 4), 0.3), "position")
    assert str(caught.value) == ("client = None and no distributed.Client is running: start one "
                                 "(distributed.Client(cluster)) or pass client=")


@pytest.mark.parametrize("screen_by", [None, "confidence"])
@pytest.mark.parametrize("cuts", [[2, 5, 5, 8], [1, 10], [6], [0, 3, 4, 7, 9]])
def test_tools_without_a_prediction_go_last_in_row_order_whatever_the_partitioning(
        cuts, screen_by, dask_client, tmp_path):
    # The Panda's touch task at a learning rate where some tools' linearised loop is unstable
    # (python/tests/test_rank.py): by prediction, those tools come after every tool with one,
    # in row order across the partitions, and the warning counts them all.
    from test_rank import PANDA_TOOLS, SPLIT_RATE, touch_with

    task = touch_with(tmp_path, SPLIT_RATE)
    frame = pd.read_csv(PANDA_TOOLS, comment="#")
    ddf = partitioned(frame, cuts)
    for screen in (3, 8, 11):
        with warnings.catch_warnings(record=True) as expected_warnings:
            warnings.simplefilter("always")
            expected = toolconf.rank(frame, task, screen=screen, screen_by=screen_by)
        with warnings.catch_warnings(record=True) as got_warnings:
            warnings.simplefilter("always")
            got = tdask.rank(ddf, task, screen=screen, screen_by=screen_by, client=dask_client)
        pd.testing.assert_frame_equal(got, expected, check_exact=True)
        assert [str(w.message) for w in got_warnings] == [str(w.message) for w in expected_warnings]
        assert len(got_warnings) == (0 if screen_by == "confidence" else 1)
