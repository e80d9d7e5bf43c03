"""Model libraries loaded at run time in Python (``toolconf.load_model``) and on Dask's workers.

Run by ``make loaded-models-test`` (part of ``make test``), which builds every model of the
repository into a library (``make model IR=generated/<model>.json``) and the UFactory xArm7 from
its unedited URDF (``make model DESC=examples/robots/xarm7.toml``), into the folder
``TOOLCONF_TEST_LIBRARIES`` names, one sub-folder per model. Without it these tests fail.

* Every model, loaded as ``<model>_loaded``, gives the built-in model's numbers bit for bit.
* ``toolconf.dask`` runs a loaded model on worker processes that never loaded it themselves.
* The xArm7, which the repository does not ship as a model, equals Pinocchio's ``aba`` on the
  same unedited URDF to 1e-10, and its tools rank.
"""

import math
import os
import sys
from pathlib import Path

import numpy as np
import pandas
import pytest

import toolconf

import pinocchio as pin

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "benches" / "peers"))
import pin_robot  # noqa: E402

LIBRARIES = Path(os.environ["TOOLCONF_TEST_LIBRARIES"])
BUILT_IN = ["arm2", "arm2_exact", "arm2_payload", "arm3", "msd", "panda", "ur5"]
XARM7 = REPO / "examples" / "robots" / "xarm7.toml"
# Normwise relative, per state: round-off of a rigid-body dynamics' few hundred
# double-precision operations, against Pinocchio; far below what a modelling slip moves.
TOLERANCE = 1e-10


def bits(a):
    return np.ascontiguousarray(np.asarray(a, dtype=np.float64)).view(np.uint64)


def same(a, b, where):
    """Equal bit for bit, through dicts and lists; text with the loaded name as the built-in's."""
    if isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for k in a:
            same(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, (list, tuple)) and a and isinstance(a[0], (dict, str, list, tuple)):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            same(x, y, f"{where}[{i}]")
    elif isinstance(a, str):
        assert a == b.replace("_loaded", ""), where
    elif a is None or isinstance(a, (bool, int)):
        assert a == b, where
    else:
        np.testing.assert_array_equal(bits(a), bits(b), err_msg=where)


def tools(name, count, seed):
    """Valid tools from the model's sample box."""
    info = toolconf.models()[name]
    sample = info["domains"]["sample"]
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < count:
        p = np.array([rng.uniform(*sample[k]) if sample[k][0] < sample[k][1] else sample[k][0]
                      for k in info["parameters"]])
        try:
            toolconf.confidence(name, p, next(iter(info_tasks(name))))
        except ValueError:
            continue
        out.append(p)
    return np.array(out)


def info_tasks(name):
    return ["position", "velocity", "acceleration"] + (
        ["tip_position", "tip_velocity", "tip_acceleration"] if toolconf.models()[name]["has_tip"] else [])


@pytest.fixture(scope="module")
def loaded():
    return {name: toolconf.load_model(LIBRARIES / name, f"{name}_loaded") for name in BUILT_IN}


@pytest.mark.parametrize("name", BUILT_IN)
def test_a_loaded_model_gives_the_built_in_numbers_bit_for_bit(loaded, name):
    other = loaded[name]
    assert other == f"{name}_loaded"
    models = toolconf.models()
    same(models[name], models[other], "models()")
    params = tools(name, 5, 3)
    n = models[name]["dof"]
    for task in info_tasks(name):
        try:
            want = toolconf.confidence(name, params, task)
        except ValueError as e:
            with pytest.raises(ValueError) as got:
                toolconf.confidence(other, params, task)
            assert str(got.value).replace("_loaded", "") == str(e)
            continue
        same(want, toolconf.confidence(other, params, task), f"confidence {task}")
        for p in params[:2]:
            try:
                want = toolconf.simulate(name, p, task)
            except toolconf.SimulationError as e:
                with pytest.raises(toolconf.SimulationError) as got:
                    toolconf.simulate(other, p, task)
                assert str(got.value).replace("_loaded", "") == str(e)
                continue
            same(want, toolconf.simulate(other, p, task), f"simulate {task}")
    rng = np.random.default_rng(5)
    x, u = rng.uniform(-1.5, 1.5, (len(params), 2 * n)), rng.uniform(-5, 5, (len(params), n))
    same(toolconf.dynamics(name, params, x, u), toolconf.dynamics(other, params, x, u), "dynamics")
    if models[name]["has_tip"]:
        same(toolconf.tip(name, params, x[:, :n], x[:, n:]), toolconf.tip(other, params, x[:, :n], x[:, n:]),
             "tip")


def test_loading_again_is_the_same_model_and_refusals_are_value_errors(loaded):
    assert toolconf.load_model(LIBRARIES / "panda", "panda_loaded") == "panda_loaded"
    with pytest.raises(ValueError, match="'panda' is already built in"):
        toolconf.load_model(LIBRARIES / "panda")
    with pytest.raises(ValueError, match="is not a shared library"):
        toolconf.load_model(LIBRARIES / "panda" / "toolconf_model.h")
    with pytest.raises(ValueError, match="holds no model library"):
        toolconf.load_model(LIBRARIES)
    with pytest.raises(TypeError):
        toolconf.load_model(3)


def test_rank_of_a_frame_of_loaded_tools_is_the_built_in_ranking(loaded):
    frame = pandas.read_csv(REPO / "examples" / "tools" / "panda_tools.csv", comment="#")
    task = str(REPO / "examples" / "tasks" / "panda_touch_point.toml")
    want = toolconf.rank(frame, task)
    got = toolconf.rank(frame.assign(model="panda_loaded"), task)
    same({c: want[c].tolist() for c in want}, {c: got[c].tolist() for c in got}, "rank")


def test_dask_workers_load_the_clients_libraries(loaded, dask_client):
    import dask.dataframe as dd

    import toolconf.dask

    frame = pandas.read_csv(REPO / "examples" / "tools" / "panda_tools.csv", comment="#")
    task = str(REPO / "examples" / "tasks" / "panda_push_off.toml")
    want = toolconf.rank(frame, task, screen=6)
    got = toolconf.dask.rank(dd.from_pandas(frame.assign(model="panda_loaded"), npartitions=3), task,
                             screen=6, client=dask_client)
    same({c: want[c].tolist() for c in want}, {c: got[c].tolist() for c in got}, "dask rank")
    params = tools("panda", 8, 9)
    same(toolconf.simulate_batch("panda", params, "tip_position"),
         toolconf.dask.simulate_batch("panda_loaded", params, "tip_position", client=dask_client),
         "dask simulate_batch")
    # The workers are other processes: they loaded the library themselves.
    pids = dask_client.run(os.getpid)
    assert os.getpid() not in pids.values()
    names = dask_client.run(lambda: sorted(toolconf.models()))
    assert all("panda_loaded" in v for v in names.values())


def test_the_xarm7_from_its_unedited_urdf_equals_pinocchio_aba():
    name = toolconf.load_model(LIBRARIES / "xarm7")
    assert name == "xarm7" and toolconf.models()[name]["dof"] == 7
    rng = np.random.default_rng(29)
    sample = toolconf.models()[name]["domains"]["sample"]
    worst, rows = 0.0, 0
    for _ in range(30):
        m = rng.uniform(*sample["tool_mass"])
        com = [rng.uniform(*sample[k]) for k in ("tool_com_x", "tool_com_y", "tool_com_z")]
        a, b, c = rng.uniform(0.01, 0.30, 3)
        tool = [m, *com, m * (b * b + c * c) / 12, m * (a * a + c * c) / 12, m * (a * a + b * b) / 12]
        model, data = pin_robot.model_with_tool(str(XARM7), tool)
        assert model.nq == 7
        for _ in range(5):
            q, qd = rng.uniform(-math.pi, math.pi, 7), rng.uniform(-3.0, 3.0, 7)
            u = rng.uniform(-20.0, 20.0, 7)
            want = np.concatenate([qd, pin.aba(model, data, q, qd, u)])
            got = toolconf.dynamics(name, tool, np.concatenate([q, qd]), u)
            worst = max(worst, float(np.max(np.abs(got - want)) / np.max(np.abs(want))))
            rows += 1
    assert worst <= TOLERANCE, f"xarm7: worst normwise relative difference {worst:.2e} over {rows} states"


def test_the_xarm7_ranks_tools_with_no_rebuild():
    name = toolconf.load_model(LIBRARIES / "xarm7")
    frame = pandas.read_csv(REPO / "examples" / "tools" / "panda_tools.csv", comment="#")
    ranked = toolconf.rank(frame.assign(model=name), "tip_acceleration")
    assert len(ranked) == len(frame) and set(ranked["model"]) == {name}
    assert np.isfinite(ranked["free_energy"]).all()


def test_toolconf_model_path_loads_at_import_and_names_itself_when_refused(tmp_path):
    import subprocess

    code = "import toolconf; print(sorted(toolconf.models()))"
    env = {**os.environ, "TOOLCONF_MODEL_PATH": f"arm2_env={LIBRARIES / 'arm2'}::{LIBRARIES / 'xarm7'}"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "'arm2_env'" in out.stdout and "'xarm7'" in out.stdout
    bad = tmp_path / "notes.txt"
    bad.write_text("not a library")
    env["TOOLCONF_MODEL_PATH"] = str(bad)
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert out.returncode == 1
    assert f"ValueError: TOOLCONF_MODEL_PATH: model library {bad}: is not a shared library" in out.stderr


def test_a_relative_path_is_resolved_at_load_so_workers_elsewhere_find_it(loaded, dask_client, monkeypatch):
    import toolconf.dask

    # The mass-spring-damper's size has a slot left beside msd_loaded.
    monkeypatch.chdir(LIBRARIES)
    assert toolconf.load_model("msd", "msd_relative") == "msd_relative"
    monkeypatch.undo()
    # Recorded for the workers as the file it named, whatever folder they run in.
    assert (str(LIBRARIES / "msd"), "msd_relative") in toolconf._LOADED
    assert all(cwd != str(LIBRARIES) for cwd in dask_client.run(os.getcwd).values())
    params = tools("msd", 6, 4)
    same(toolconf.simulate_batch("msd", params, "position"),
         toolconf.dask.simulate_batch("msd_relative", params, "position", client=dask_client),
         "dask simulate_batch")


def test_a_name_in_capitals_is_refused_not_lower_cased(loaded):
    with pytest.raises(ValueError, match=r"the model name 'Arm2_Caps' is not one.*\('arm2_caps' is\)"):
        toolconf.load_model(LIBRARIES / "arm2", "Arm2_Caps")
    assert "arm2_caps" not in toolconf.models()


def _segments(elf):
    """(offset, size in the file) of every program header of a 64-bit little-endian ELF file."""
    import struct

    phoff, = struct.unpack_from("<Q", elf, 0x20)
    phentsize, phnum = struct.unpack_from("<HH", elf, 0x36)
    return [(struct.unpack_from("<Q", elf, phoff + i * phentsize + 8)[0],
             struct.unpack_from("<Q", elf, phoff + i * phentsize + 32)[0]) for i in range(phnum)]


def test_a_truncated_library_is_a_value_error_never_a_crash(tmp_path):
    import subprocess

    whole = next((LIBRARIES / "panda").glob("libtoolconf_model_*.so")).read_bytes()
    cuts = {300_000, len(whole) // 2, len(whole) - 1}
    cuts |= {c for offset, size in _segments(whole) for c in (offset, offset + size) if 0 < c < len(whole)}
    for cut in sorted(cuts):
        t = tmp_path / f"t{cut}.so"
        t.write_bytes(whole[:cut])
        # In other interpreters: a SIGBUS there fails the test instead of killing pytest.
        out = subprocess.run([sys.executable, "-c", f"import toolconf; toolconf.load_model({str(t)!r})"],
                             capture_output=True, text=True)
        assert out.returncode == 1, (cut, out.returncode, out.stderr)
        assert out.stderr.splitlines()[-1].startswith(f"ValueError: model library {t}: is truncated or damaged"), \
            out.stderr
        env = {**os.environ, "TOOLCONF_MODEL_PATH": str(t)}
        out = subprocess.run([sys.executable, "-c", "import toolconf"], env=env, capture_output=True, text=True)
        assert out.returncode == 1, (cut, out.returncode, out.stderr)
        assert out.stderr.splitlines()[-1].startswith(
            f"ValueError: TOOLCONF_MODEL_PATH: model library {t}: is truncated or damaged"), out.stderr
