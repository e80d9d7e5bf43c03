"""toolconf.design against `toolconf design --json`: the same object, key for key and number
for number, from a design file or the same keys as a dict; bad designs get the file's
messages."""

import pytest

import toolconf

from conftest import REPO, REACH_45

DESIGNS = REPO / "examples" / "design"
REACH_AND_BUDGET = {
    "objective": "confidence",
    "constraints": ["l1 + l2 >= 0.7", "m1 + m2 <= 0.5"],
    "bounds": {"m1": [0.1, 0.6], "m2": [0.1, 0.6], "l1": [0.1, 0.6], "l2": [0.1, 0.6]},
    "search": {"samples": 3000, "simulate": 3},
}


def toml_of(design):
    """A design dict written as a design file (strings, numbers, lists, one level of tables)."""
    def value(v):
        if isinstance(v, str):
            return f'"{v}"'
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        return repr(v)

    lines = [f"{k} = {value(v)}" for k, v in design.items() if not isinstance(v, dict)]
    for k, table in design.items():
        if isinstance(table, dict):
            lines.append(f"[{k}]")
            lines += [f"{name} = {value(v)}" for name, v in table.items()]
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("model, task, file", [
    ("arm2", "velocity", DESIGNS / "reach_and_budget.toml"),
    ("arm2_payload", REACH_45, DESIGNS / "payload.toml"),
])
def test_a_design_file_gives_the_command_lines_json(model, task, file, cli_json):
    expected = cli_json("design", "--model", model, "--task", task, "--design", file)
    assert toolconf.design(model, task, file) == expected
    assert toolconf.design(model, str(task), str(file)) == expected


def test_a_design_dict_equals_the_same_keys_as_a_file_and_the_sweep(tmp_path, cli_json):
    path = tmp_path / "design.toml"
    path.write_text(toml_of(REACH_AND_BUDGET))
    sweep = "l1 + l2 >= 0.2..1.2:3"
    expected = cli_json("design", "--task", "velocity", "--design", path, "--sweep", sweep)
    assert toolconf.design("arm2", "velocity", REACH_AND_BUDGET, sweep=sweep) == expected
    assert [p["budget"] for p in expected["sweep"]] == [0.2, 0.7, 1.2]
    free = dict(REACH_AND_BUDGET, objective="free_energy", search={"samples": 500, "simulate": 1})
    path.write_text(toml_of(free))
    expected = cli_json("design", "--task", "velocity", "--design", path)
    got = toolconf.design("arm2", "velocity", free)
    assert got == expected and got["free_energy_simulations"] > 0


@pytest.mark.parametrize("change", [
    {"bounds": {"m1": [0.0, 0.6], "m2": [0.1, 0.6], "l1": [0.1, 0.6], "l2": [0.1, 0.6]}},
    {"bounds": {"m1": [0.1, 0.6], "m2": [0.1, 0.6], "l1": [0.1, 0.6]}},
    {"bounds": {"m9": [0.1, 0.6]}},
    {"constraints": ["l1 + l9 >= 0.7"]},
    {"constraints": ["l1 + l2 >= 5"]},
    {"objective": "speed"},
    {"search": {"samples": 100_000_000}},
])
def test_a_bad_design_dict_gets_the_files_message(change, tmp_path, cli_error):
    design = dict(REACH_AND_BUDGET, **change)
    path = tmp_path / "design.toml"
    path.write_text(toml_of(design))
    expected = cli_error("design", "--task", "velocity", "--design", path)
    with pytest.raises(ValueError) as caught:
        toolconf.design("arm2", "velocity", design)
    assert str(caught.value) == expected.replace(str(path), "design dict")
    with pytest.raises(ValueError) as caught:
        toolconf.design("arm2", "velocity", path)
    assert str(caught.value) == expected


@pytest.mark.parametrize("design, message", [
    ({"bounds": {"m1": "wide"}}, "design dict, key bounds.m1: invalid type"),
    ({"bounds": {"m1": [0.1, 0.6]}, "budget": 1.0}, "design dict: unknown field `budget`"),
    (3.5, "design = 3.5: expected a design file's path or a dict"),
    ("no/such/design.toml", "no/such/design.toml: cannot read the design file"),
])
def test_a_design_of_the_wrong_shape_names_the_key(design, message):
    with pytest.raises(ValueError) as caught:
        toolconf.design("arm2", "velocity", design)
    assert str(caught.value).startswith(message), str(caught.value)


def test_a_bad_model_or_task(cli_error):
    expected = cli_error("design", "--model", "arm9", "--task", "velocity", "--design",
                         DESIGNS / "reach_and_budget.toml")
    with pytest.raises(ValueError) as caught:
        toolconf.design("arm9", "velocity", REACH_AND_BUDGET)
    assert "--model: " + str(caught.value) == expected
    with pytest.raises(ValueError, match=r"^task 'reach': neither a built-in task"):
        toolconf.design("arm2", "reach", REACH_AND_BUDGET)
