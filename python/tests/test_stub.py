"""photopose/__init__.pyi (what editors complete) names what the module has, no more, no less, and
its functions take the module's parameter names; mypy's stubtest finds it valid and true to the
built module."""

import ast
import importlib.util
import inspect
import pathlib
import re
import subprocess
import sys

import pytest

import photopose
import photopose._photopose as module

STUB = pathlib.Path(photopose.__file__).with_name("__init__.pyi")


def stub_tree():
    assert STUB.exists(), f"{STUB} is not installed beside the module"
    return ast.parse(STUB.read_text())


def public(names):
    return {n for n in names if not n.startswith("_")}


def test_the_stub_names_every_public_name_and_no_other():
    tree = stub_tree()
    stub = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            stub.add(node.name)
        elif isinstance(node, ast.AnnAssign):
            stub.add(node.target.id)
    assert public(dir(module)) - stub == set(), "missing from the stub"
    assert public(stub) - public(dir(module)) == set(), "in the stub, not in the module"


def test_each_stub_class_has_the_members_of_its_class():
    for node in stub_tree().body:
        if not isinstance(node, ast.ClassDef) or node.name == "Error":
            continue
        cls = getattr(module, node.name)
        members = set()
        for item in node.body:
            if isinstance(item, ast.FunctionDef):
                members.add(item.name)
            elif isinstance(item, ast.AnnAssign):
                members.add(item.target.id)
        expected = public(name for name in vars(cls))
        assert public(members) == expected, node.name


def test_stub_functions_take_the_module_parameter_names():
    for node in stub_tree().body:
        if not isinstance(node, ast.FunctionDef):
            continue
        doc = getattr(module, node.name).__doc__
        signature = re.match(rf"{node.name}\((.*?)\) ->", doc)
        assert signature, node.name
        names = [p.split(":")[0].strip().lstrip("*") for p in re.split(r",\s*(?![^\[]*\])", signature.group(1))
                 if p.strip() and p.strip() != "*"]
        stub_names = [a.arg for a in node.args.args + node.args.kwonlyargs]
        if node.args.kwarg:
            stub_names.append(node.args.kwarg.arg)
        assert stub_names == names, node.name
    assert inspect.isclass(module.Error) and issubclass(module.Error, ValueError)


def test_stubtest_finds_the_stub_valid_and_true_to_the_module(tmp_path):
    # mypy comes with .ci/install-deps (python3-mypy): missing, the stub goes unchecked, a failure.
    if importlib.util.find_spec("mypy") is None:
        pytest.fail(f"{sys.executable} has no mypy: install python3-mypy (.ci/install-deps)")
    allowlist = pathlib.Path(__file__).with_name("stubtest_allowlist.txt")
    # stubtest type-checks the stub with mypy first (an invalid stub fails there), then compares
    # it with the module that `import photopose` loads. Its cache goes to the scratch folder.
    done = subprocess.run([sys.executable, "-m", "mypy.stubtest", "photopose", "--allowlist",
                           str(allowlist)], cwd=tmp_path, capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
