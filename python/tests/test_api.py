"""Every function the package offers has a docstring and a type stub."""

import ast
import inspect

import toolconf
import toolconf.dask
from toolconf import _toolconf

from conftest import REPO

STUBS = REPO / "python" / "toolconf" / "_toolconf.pyi"


def stubbed():
    tree = ast.parse(STUBS.read_text())
    return {node.name for node in tree.body if isinstance(node, (ast.FunctionDef, ast.ClassDef))}


def test_every_native_function_has_a_stub_and_a_docstring():
    native = {name for name, value in vars(_toolconf).items()
              if callable(value) and not name.startswith("__")}
    assert native - {"SimulationError"} <= stubbed()
    for name in native:
        assert (getattr(_toolconf, name).__doc__ or "").strip(), name


def test_the_python_layer_is_annotated_and_documented():
    for module in (toolconf, toolconf.dask):
        for name in module.__all__:
            function = getattr(module, name)
            assert (function.__doc__ or "").strip(), name
            if inspect.isfunction(function):
                signature = inspect.signature(function)
                assert signature.return_annotation is not inspect.Signature.empty, name
