"""The .pyi stubs describe the module as built: every public name and member, both ways round, and
every binding has a docstring where it does work."""
import ast
import math
import re
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


# Dunders the stub must declare where the module defines them (copy.copy and deepcopy are typed by them;
# __eq__ and __hash__ = None tell a type checker that the parameter structs compare by value, unhashable).
CHECKED_DUNDERS = {"__copy__", "__deepcopy__", "__eq__", "__hash__"}


def runtime_members(cls):
    """Public names a class defines (a pybind11 enum's values are among them, with its name and value),
    and the checked dunders."""
    return {n for n in vars(cls) if not n.startswith("_") or n in CHECKED_DUNDERS}


def runtime_enums():
    """The module's pybind11 enums: classes with __members__ (name -> value)."""
    return {n: c for n, c in vars(_core).items() if isinstance(c, type) and hasattr(c, "__members__")}


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
        members = {m for m in members if not m.startswith("_") or m in CHECKED_DUNDERS}
        assert members - built == set(), f"{name}: in the stub, not in the module"


def test_enum_stubs_declare_pybind11_enums_as_they_are_at_runtime():
    """The stub declared UpdateMode, ShotShape, ... as enum.Enum subclasses, but pybind11 enums are not:
    isinstance(x, enum.Enum) is False and list(UpdateMode) raises. They are declared as pybind11-stubgen
    does: a plain class with __members__, every value a class attribute of the class's type, name and
    value properties, __int__, __index__, __eq__, __hash__ and __init__(self, value: int)."""
    import enum

    enums = runtime_enums()
    assert set(enums) >= {"UpdateMode", "ShotShape", "RefineBy", "LocalModel", "DepthPredictionRule"}
    stub = {n.name: n for n in ast.parse(STUB.read_text()).body if isinstance(n, ast.ClassDef)}
    for name, cls in enums.items():
        some = next(iter(cls.__members__.values()))
        assert not isinstance(some, enum.Enum)  # what the stub must not claim
        assert cls(some.value) == some and int(some) == some.value and hash(some) == hash(cls(some.value))
        node = stub[name]
        assert node.bases == [], f"{name}: a base in the stub ({ast.unparse(node.bases[0])}), none at runtime"
        annotated = {n.target.id: ast.unparse(n.annotation) for n in node.body if isinstance(n, ast.AnnAssign)}
        assert annotated.pop("__members__") == f"ClassVar[dict[str, {name}]]"
        assert annotated == {m: f"ClassVar[{name}]" for m in cls.__members__}, f"{name}: values differ"
        functions = {f.name: f for f in node.body if isinstance(f, ast.FunctionDef)}
        for method in ("__init__", "__int__", "__index__", "__eq__", "__hash__", "name", "value"):
            assert method in functions and hasattr(cls, method), f"{name}.{method}"
        assert [ast.unparse(a) for a in functions["__init__"].args.args] == ["self", "value: int"]
        for prop in ("name", "value"):
            assert [ast.unparse(d) for d in functions[prop].decorator_list] == ["property"], f"{name}.{prop}"
            assert isinstance(vars(cls)[prop], property)
    subclasses_enum = [n for n, c in stub.items() if any("Enum" in ast.unparse(b) for b in c.bases)]
    assert subclasses_enum == []


def test_functions_and_methods_have_docstrings():
    undocumented = [n for n, f in vars(_core).items() if callable(f) and not n.startswith("__")
                    and not inspect.isclass(f) and not (f.__doc__ or "").strip()]
    methods = [f"Mapper.{n}" for n, f in vars(_core.Mapper).items() if not n.startswith("_") and callable(f)
               and len((f.__doc__ or "").split("\n", 1)[-1].strip()) < 10]
    assert undocumented == [] and methods == []


def test_the_package_re_exports_every_public_name():
    public = {n for n in dir(_core) if not n.startswith("_")}
    assert public - set(dir(oi)) == set()


def stub_default(node):
    """A default the stub spells out: a literal, or an enum value like ShotShape.rays; None for `...`."""
    if isinstance(node, ast.Constant) and node.value is Ellipsis:
        return None
    if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
        return (getattr(getattr(_core, node.value.id), node.attr),)
    return (ast.literal_eval(node),)


def documented_defaults(function):
    """(name, value) of every argument of a stub function whose default is spelled out."""
    args = function.args
    positional = list(zip(args.args[len(args.args) - len(args.defaults):], args.defaults))
    keyword = [(a, d) for a, d in zip(args.kwonlyargs, args.kw_defaults) if d is not None]
    for arg, node in positional + keyword:
        value = stub_default(node)
        if value is not None:
            yield arg.arg, value[0]


def same_value(stub, runtime):
    if isinstance(stub, float) and isinstance(runtime, float):
        return math.isclose(stub, runtime, rel_tol=1e-6)  # float32 fields come back widened
    return stub == runtime and type(stub) is type(runtime)


def signature_default(function, name):
    """The default pybind11 reports for argument `name` in the function's signature line. The type may
    hold commas and brackets (pybind11 3: `typing.Annotated[numpy.typing.ArrayLike, numpy.float64] | None`),
    so the text is scanned with the bracket depth rather than matched by a pattern."""
    doc = function.__doc__ or ""
    match = re.search(rf"[(,] ?{name}: ", doc)
    assert match, f"{function.__name__}: no argument '{name}' in {doc.splitlines()[:1]}"
    depth, i, start = 0, match.end(), None
    while i < len(doc):
        c = doc[i]
        if c in "([{":
            depth += 1
        elif c in ")]}":
            if depth == 0:
                break
            depth -= 1
        elif depth == 0 and c == ",":
            break
        elif depth == 0 and start is None and doc.startswith(" = ", i):
            start = i + 3
            i += 2
        i += 1
    assert start is not None, f"{function.__name__}: no default for '{name}' in {doc.splitlines()[:1]}"
    return ast.literal_eval(doc[start:i])


def test_every_default_the_stub_documents_is_the_runtime_default():
    """RegionOptions once said 0.05 where the runtime said 0.2: the stub's defaults are checked against a
    default-constructed object (keyword constructors) or the signature pybind11 reports (functions)."""
    tree = ast.parse(STUB.read_text())
    checked, wrong = 0, []
    for node in tree.body:
        if isinstance(node, ast.ClassDef) and hasattr(_core, node.name):
            cls = getattr(_core, node.name)
            for method in (n for n in node.body if isinstance(n, ast.FunctionDef)):
                for name, value in documented_defaults(method):
                    if method.name == "__init__" and method.args.kwonlyargs:  # keyword constructor: a field
                        runtime = getattr(cls(), name)
                    else:
                        runtime = signature_default(getattr(cls, method.name), name)
                    checked += 1
                    if not same_value(value, runtime):
                        wrong.append(f"{node.name}.{method.name}({name}): stub {value!r}, runtime {runtime!r}")
        elif isinstance(node, ast.FunctionDef) and hasattr(_core, node.name):
            for name, value in documented_defaults(node):
                runtime = signature_default(getattr(_core, node.name), name)
                checked += 1
                if not same_value(value, runtime):
                    wrong.append(f"{node.name}({name}): stub {value!r}, runtime {runtime!r}")
    assert wrong == []
    print(f"{checked} defaults checked")
    assert checked >= 60, f"only {checked} defaults checked: the stub lost its defaults"


def test_the_default_check_sees_a_wrong_default():
    fake = ast.parse("def f(*, min_improvement: float = 0.05) -> None: ...").body[0]
    (name, value), = documented_defaults(fake)
    assert not same_value(value, _core.RegionOptions().min_improvement)
