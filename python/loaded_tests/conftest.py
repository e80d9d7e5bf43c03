"""The Dask cluster fixture of python/tests (its conftest.py), shared rather than copied."""

import importlib.util
from pathlib import Path

_spec = importlib.util.spec_from_file_location(
    "toolconf_tests_conftest", Path(__file__).resolve().parents[1] / "tests" / "conftest.py")
_tests = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_tests)
dask_client = _tests.dask_client
cli = _tests.cli
cli_json = _tests.cli_json
