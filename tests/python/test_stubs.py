"""The .pyi stubs describe the module as built: every public name and member, both ways round, and
every binding has a docstring where it does work."""
import ast
import inspect
from pathlib import Path

import occ_improve as oi
from occ_improve import _core

STUB = Path(oi.__file__).with_name("_core.pyi")
OCTOMAP_ONLY = {"OctomapExportOptions", "OctomapExportReport"}


def stub_tree():
    tree = ast.parse(STUB.read_text())
    names, classes = set(), {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            names.add(node.name)
            classes[node.name] = {n.name for n in node.body if isinstance(n, ast.FunctionDef)} | {
                n.target.id for n in node.body if isinstance(n, ast.AnnAssign)} | {
                t.id for n in node.body if isinstance(n, ast.Assign) for t in n.targets}
        elif isinstance(node, ast.FunctionDef):
            names.add(node.name)
        elif isinstance(node, ast.AnnAssign) and not node.target.id.startswith("_"):
            names.add(node.target.id)
    return names, classes


def runtime_members(cls):
    if hasattr(cls, "__members__"):  # a pybind11 enum: its values are its members
        return set(cls.__members__)
    return {n for n in vars(cls) if not n.startswith("_")}


def test_every_module_name_is_in_the_stub_and_back():
    stub_names, _ = stub_tree()
    built = {n for n in dir(_core) if not n.startswith("__")}
    if not oi.HAS_OCTOMAP:
        stub_names -= OCTOMAP_ONLY
    assert built - stub_names == set(), "in the module, missing from _core.pyi"
    assert stub_names - built == set(), "in _core.pyi, not in the module"


def test_every_class_member_is_in_the_stub_and_back():
    _, classes = stub_tree()
    for name, members in classes.items():
        if not hasattr(_core, name):
            continue
        cls = getattr(_core, name)
        if issubclass(cls, BaseException):
            continue
        built = runtime_members(cls)
        if not oi.HAS_OCTOMAP and name == "Mapper":
            members = members - {"export_octomap"}
        assert built - members == set(), f"{name}: in the module, missing from the stub"
        members = {m for m in members if not m.startswith("_")}
        assert members - built == set(), f"{name}: in the stub, not in the module"


def test_functions_and_methods_have_docstrings():
    undocumented = [n for n, f in vars(_core).items() if callable(f) and not n.startswith("__")
                    and not inspect.isclass(f) and not (f.__doc__ or "").strip()]
    methods = [f"Mapper.{n}" for n, f in vars(_core.Mapper).items() if not n.startswith("_") and callable(f)
               and len((f.__doc__ or "").split("\n", 1)[-1].strip()) < 10]
    assert undocumented == [] and methods == []


def test_the_package_re_exports_every_public_name():
    public = {n for n in dir(_core) if not n.startswith("_")}
    assert public - set(dir(oi)) == set()
