"""The package's public surface: every public name documented and typed in the stubs."""
import ast
import inspect
import os

import physid

STUBS = os.path.join(os.path.dirname(physid.__file__), "_physid.pyi")


def stub_names():
    tree = ast.parse(open(STUBS).read())
    names = {}
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            names[node.name] = None
        elif isinstance(node, ast.ClassDef):
            names[node.name] = {n.name for n in node.body if isinstance(n, ast.FunctionDef)}
    return names


def public_members(cls):
    return sorted(n for n in dir(cls) if not n.startswith("_"))


def test_every_public_name_has_a_docstring():
    missing = []
    for name in physid.__all__:
        obj = getattr(physid, name)
        if not inspect.getdoc(obj):
            missing.append(name)
        if inspect.isclass(obj) and obj.__module__ == "physid":  # the extension's classes
            missing += [f"{name}.{m}" for m in public_members(obj) if not inspect.getdoc(getattr(obj, m))]
    assert missing == []


def test_every_class_of_the_stubs_is_exported():
    # A class a user meets as a return value (physid.simulate's Simulation) is importable and
    # in physid.__all__, as the stubs promise.
    classes = [name for name in stub_names() if name[0].isupper()]
    assert "Simulation" in classes
    assert [c for c in classes if c not in physid.__all__ or not hasattr(physid, c)] == []


def test_every_public_name_is_in_the_stubs():
    stubs = stub_names()
    missing = []
    for name in physid.__all__:
        obj = getattr(physid, name)
        if getattr(obj, "__module__", "physid").startswith("physid.") and not obj.__module__.startswith("physid._physid"):
            continue  # pure Python, typed where it is defined
        if name not in stubs:
            missing.append(name)
        elif inspect.isclass(obj):
            missing += [f"{name}.{m}" for m in public_members(obj) if m not in stubs[name]]
    assert missing == []


def test_the_stubs_name_nothing_that_is_not_there():
    extra = []
    for name, members in stub_names().items():
        if not hasattr(physid._physid, name):
            extra.append(name)
        for m in members or ():
            if not m.startswith("_") and not hasattr(getattr(physid._physid, name), m):
                extra.append(f"{name}.{m}")
    assert extra == []


def test_pyproject_declares_the_package():
    import tomllib

    from conftest import ROOT

    with open(os.path.join(ROOT, "python", "pyproject.toml"), "rb") as f:
        project = tomllib.load(f)["project"]
    assert project["name"] == "physid" and project["version"] == physid.__version__
    assert project["license"] == {"text": "MIT OR Apache-2.0"}
    assert any(d.startswith("numpy") for d in project["dependencies"])
    assert any(d.startswith("pandas") for d in project["optional-dependencies"]["tables"])
