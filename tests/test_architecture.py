"""The three layers: toolkit <- problem <- workbook, checked on the source and at import;
the module index of docs/architecture.md kept true."""

import ast
import dataclasses
import functools
import importlib
import inspect
import json
import pathlib
import re
import subprocess
import sys

import pytest

import piezolib

PACKAGE = pathlib.Path(piezolib.__file__).parent

TOOLKIT = ("robust", "hysteresis", "uncertainty", "identification", "signals", "metrics",
           "records", "files", "_checks", "progress", "notebook_display")
PROBLEM = ("problem",)
WORKBOOK = ("workbook", "__main__")
# what each layer may not import (at any depth of the module)
FORBIDDEN = {
    "toolkit": ("piezolib.problem", "piezolib.workbook"),
    "problem": ("piezolib.workbook",),
    "workbook": (),
}
# third-party imports the toolkit may not make at module level
TOOLKIT_HEAVY = ("matplotlib", "pandas")


def layer_of(path):
    top = path.relative_to(PACKAGE).parts[0].removesuffix(".py")
    for name, members in (("toolkit", TOOLKIT), ("problem", PROBLEM), ("workbook", WORKBOOK)):
        if top in members:
            return name
    return None


@functools.lru_cache(maxsize=None)
def _parsed(path):
    """The syntax tree of a source file (parsed once for all the checks of this module)."""
    return ast.parse(path.read_text(), filename=str(path))


def imports_of(path):
    """(module name, at module level?) for every import statement of a source file."""
    tree = _parsed(path)
    module_level = {id(node) for node in tree.body}
    package = ".".join(("piezolib",) + path.relative_to(PACKAGE).with_suffix("").parts[:-1])
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(alias.name, id(node) in module_level) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parent = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                base = f"{parent}.{base}" if base else parent
            names = [f"{base}.{alias.name}" for alias in node.names] if base == "piezolib" else [base]
            found += [(name, id(node) in module_level) for name in names]
    return found


SOURCES = sorted(PACKAGE.rglob("*.py"))


def test_every_module_belongs_to_a_layer():
    orphans = [str(p.relative_to(PACKAGE)) for p in SOURCES
               if p.name != "__init__.py" or p.parent != PACKAGE
               if layer_of(p) is None]
    assert not orphans, f"modules outside toolkit/problem/workbook: {orphans}"


@pytest.mark.parametrize("path", SOURCES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_imports_point_down_only(path):
    layer = layer_of(path)
    if layer is None:       # piezolib/__init__.py: lazy loader, imports nothing
        return
    bad = [name for name, _ in imports_of(path)
           if any(name == f or name.startswith(f + ".") for f in FORBIDDEN[layer])]
    assert not bad, f"{layer} module imports a higher layer: {bad}"
    if layer == "toolkit":
        heavy = [name for name, top in imports_of(path)
                 if top and name.split(".")[0] in TOOLKIT_HEAVY]
        assert not heavy, f"toolkit module imports {heavy} at module level"


def test_package_init_imports_nothing_eagerly():
    names = [name for name, _ in imports_of(PACKAGE / "__init__.py")]
    assert all(not n.startswith("piezolib") for n in names), names


#: imported in this order by one fresh interpreter, sys.modules recorded after each
IMPORT_STEPS = ("control", "piezolib.robust", "piezolib.hysteresis", "piezolib.uncertainty",
                "piezolib.identification", "piezolib.signals")


@pytest.fixture(scope="module")
def loaded_after():
    """Step -> the modules loaded once it and every step before it are imported (one fresh
    interpreter for all steps: a module a step may not load is absent after it only if no
    earlier step loaded it either, so a step passes alone if it passes here)."""
    code = "\n".join(["import importlib, json, sys", "steps = {}"]
                     + [f"importlib.import_module({m!r}); steps[{m!r}] = sorted(sys.modules)"
                        for m in IMPORT_STEPS] + ["print(json.dumps(steps))"])
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    return {m: set(names) for m, names in
            json.loads(out.stdout.strip().splitlines()[-1]).items()}


def test_robust_imports_no_paper_pandas_or_plotting(loaded_after):
    loaded = loaded_after["piezolib.robust"]
    assert "piezolib.robust.mu" in loaded          # the import did load the toolkit
    assert "pandas" not in loaded
    assert not {m for m in loaded if m.startswith(("piezolib.problem",
                                                   "piezolib.workbook"))}
    # python-control 0.10 imports matplotlib itself; piezolib.robust must add nothing to it
    by_control = loaded_after["control"]
    assert {m for m in loaded if m.startswith("matplotlib")} <= by_control


@pytest.mark.parametrize("module", ["piezolib.hysteresis", "piezolib.uncertainty",
                                    "piezolib.identification", "piezolib.signals"])
def test_toolkit_packages_import_without_the_paper(module, loaded_after):
    loaded = loaded_after[module]
    assert module in loaded
    assert "piezolib.problem.paper" not in loaded
    assert "piezolib.workbook.plotting" not in loaded
    assert "pandas" not in loaded


def test_the_paper_at_its_old_address_is_the_problem_layers_module():
    from piezolib import paper as by_name
    import piezolib.problem.paper

    assert by_name is piezolib.paper is piezolib.problem.paper
    assert by_name.__name__ == "piezolib.problem.paper"


def test_no_two_modules_share_a_name():
    # a notebook importing two modules of one name has to alias one of them
    by_name = {}
    for path in PACKAGE.rglob("*.py"):
        if path.name != "__init__.py":
            by_name.setdefault(path.stem, []).append(str(path.relative_to(PACKAGE)))
    assert {name: where for name, where in by_name.items() if len(where) > 1} == {}


# unit suffixes are SI symbols with their case (docs/architecture.md, "Naming conventions");
# these lower-case spellings are never a signal name, so a name ending in one is a wrong unit
LOWER_CASE_UNITS = {"hz": "Hz", "khz": "kHz", "mhz": "MHz", "mv": "mV", "kv": "kV"}


def public_names_with_units():
    """(where, name) for every parameter of a public function or method and every field of a
    public dataclass defined in a piezolib module."""
    found = []
    for path in SOURCES:
        module = importlib.import_module(_module_name(path))
        for name, obj in vars(module).items():
            if name.startswith("_") or getattr(obj, "__module__", None) != module.__name__:
                continue
            where = f"{module.__name__}.{name}"
            functions = [(where, obj)] if inspect.isfunction(obj) else []
            if inspect.isclass(obj):
                # methods, static and class methods (their __func__), __init__ with them
                functions += [(f"{where}.{attr}", getattr(member, "__func__", member))
                              for attr, member in vars(obj).items()
                              if not attr.startswith("_") or attr == "__init__"]
                if dataclasses.is_dataclass(obj):
                    found += [(where, f.name) for f in dataclasses.fields(obj)]
            found += [(at, p) for at, function in functions if inspect.isfunction(function)
                      for p in inspect.signature(function).parameters]
    return found


def test_unit_suffixes_keep_their_si_case():
    names = public_names_with_units()
    assert len(names) > 500                             # the walk did reach the library
    wrong = sorted(f"{where}: {name} (-> {stem}_{LOWER_CASE_UNITS[suffix]})"
                   for where, name in names
                   for stem, _, suffix in [name.rpartition("_")]
                   if stem and suffix in LOWER_CASE_UNITS)
    assert not wrong, f"lower-case unit suffixes (docs/architecture.md): {wrong}"


def test_lazy_subpackages_resolve():
    assert piezolib.robust.mussv is not None
    with pytest.raises(AttributeError, match="no attribute 'nonexistent'"):
        piezolib.nonexistent


INDEX = PACKAGE.parent / "docs" / "architecture.md"


def indexed_modules():
    """Paths (relative to piezolib/) that the module index of docs/architecture.md lists."""
    section = INDEX.read_text().split("## Module index", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"^- `([\w/]+\.py)`:", section, flags=re.MULTILINE)


def test_module_index_lists_every_module_once():
    listed = indexed_modules()
    modules = {str(p.relative_to(PACKAGE)) for p in SOURCES
               if p.name not in ("__init__.py", "__main__.py")}
    twice = sorted({m for m in listed if listed.count(m) > 1})
    assert not twice, f"listed more than once in docs/architecture.md: {twice}"
    assert not modules - set(listed), \
        f"modules missing from docs/architecture.md: {sorted(modules - set(listed))}"
    assert not set(listed) - modules, \
        f"docs/architecture.md lists modules that do not exist: {sorted(set(listed) - modules)}"


def _module_name(path, package=PACKAGE):
    parts = (package.name,) + path.relative_to(package).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _import_graph(sources, package=PACKAGE):
    """Module -> the modules of ``package`` it imports (also inside functions)."""
    names = {_module_name(p, package): p for p in sources}
    graph = {}
    for name, path in names.items():
        tree = _parsed(path)
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        targets = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                targets |= {alias.name for alias in node.names}
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    parent = package.rsplit(".", node.level - 1)[0]
                    base = f"{parent}.{base}" if base else parent
                # "from package import module" imports the module, not the package's names
                targets |= {f"{base}.{a.name}" if f"{base}.{a.name}" in names else base
                            for a in node.names}
        graph[name] = {t for t in targets if t in names and t != name}
    return graph


def _cycle(graph):
    """One import cycle of the graph as a list of modules, or None."""
    state = {}

    def visit(node, path):
        state[node] = "open"
        for nxt in sorted(graph[node]):
            if state.get(nxt) == "open":
                return path[path.index(nxt):] + [nxt]
            if nxt not in state and (found := visit(nxt, path + [nxt])):
                return found
        state[node] = "done"

    for start in sorted(graph):
        if start not in state and (found := visit(start, [start])):
            return found
    return None


def test_the_package_has_no_import_cycle():
    # imports inside functions count: they hide a cycle from the interpreter, not from a reader
    graph = _import_graph(SOURCES)
    assert len(graph) == len(SOURCES)                        # every module is checked
    assert _cycle(graph) is None, f"import cycle: {' -> '.join(_cycle(graph))}"


def test_the_cycle_check_sees_imports_inside_functions(tmp_path):
    package = tmp_path / "pkg"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "a.py").write_text("from pkg import b\n")
    (package / "b.py").write_text("def f():\n    from pkg.a import g\n")
    (package / "c.py").write_text("from . import a\n")
    graph = _import_graph(sorted(package.rglob("*.py")), package)
    assert graph == {"pkg": set(), "pkg.a": {"pkg.b"}, "pkg.b": {"pkg.a"}, "pkg.c": {"pkg.a"}}
    assert _cycle(graph) == ["pkg.a", "pkg.b", "pkg.a"]


# --- tests use public names; the one exception is stated in docs/architecture.md ---------------
TESTS = PACKAGE.parent / "tests"
MODULES = {_module_name(p) for p in SOURCES}


def module_under_test(test_file):
    """The module ``tests/<path>/test_<name>.py`` tests: ``piezolib/<path>/<name>.py``, or the
    private ``_<name>.py``; None for conftest files and test-data modules."""
    rel = test_file.relative_to(TESTS)
    if not rel.name.startswith("test_"):
        return None
    stem = rel.stem.removeprefix("test_")
    for name in (stem, f"_{stem}"):
        candidate = PACKAGE.joinpath(*rel.parts[:-1], f"{name}.py")
        if candidate.exists():
            return _module_name(candidate)
    return None


def _is_private(name):
    return name.startswith("_") and not name.startswith("__")


def _owner(dotted):
    """The longest prefix of a dotted piezolib path that is a module, or None."""
    parts = dotted.split(".")
    for end in range(len(parts), 0, -1):
        if ".".join(parts[:end]) in MODULES:
            return ".".join(parts[:end])
    return None


def private_uses(path):
    """(module, what) for every private name of a piezolib module a test file reaches: by
    import, by attribute (``module._helper``) and by name (``monkeypatch.setattr(module,
    "_helper", ...)``).  A private module counts as a private name of itself."""
    tree = ast.parse(path.read_text(), filename=str(path))
    aliases, imported = {}, set()               # local name -> dotted path; every path imported
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "piezolib":
                    imported.add(alias.name)
                    aliases[alias.asname or "piezolib"] = alias.name if alias.asname else "piezolib"
        elif isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "piezolib":
            for alias in node.names:
                imported.add(f"{node.module}.{alias.name}")
                aliases[alias.asname or alias.name] = f"{node.module}.{alias.name}"

    def dotted(expr):
        if isinstance(expr, ast.Name):
            return aliases.get(expr.id)
        if isinstance(expr, ast.Attribute) and (base := dotted(expr.value)):
            return f"{base}.{expr.attr}"
        return None

    def private_part(path_):
        """(owner module, name) if the dotted path passes through a private part."""
        parts = path_.split(".")
        for i, part in enumerate(parts):
            if _is_private(part):
                return _owner(".".join(parts[:i + 1])), ".".join(parts[i:])
        return None

    found = []
    for path_ in imported:
        if hit := private_part(path_):
            found.append(hit)
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and _is_private(node.attr):
            if (base := dotted(node.value)) and (hit := private_part(f"{base}.{node.attr}")):
                found.append(hit)
        elif (isinstance(node, ast.Call) and isinstance(node.func, (ast.Name, ast.Attribute))
              and getattr(node.func, "id", getattr(node.func, "attr", None))
              in ("setattr", "getattr", "delattr", "hasattr")):
            args = node.args
            if (len(args) >= 2 and isinstance(args[1], ast.Constant)
                    and isinstance(args[1].value, str) and (base := dotted(args[0]))):
                hit = private_part(f"{base}.{args[1].value}")
            elif args and isinstance(args[0], ast.Constant) and isinstance(args[0].value, str) \
                    and args[0].value.startswith("piezolib."):
                hit = private_part(args[0].value)         # monkeypatch.setattr("mod._x", ...)
            else:
                hit = None
            if hit:
                found.append(hit)
    return sorted(set(found))


TEST_FILES = sorted(TESTS.rglob("*.py"))


@pytest.mark.parametrize("path", TEST_FILES, ids=lambda p: str(p.relative_to(TESTS)))
def test_a_test_reaches_only_the_private_names_of_the_module_it_tests(path):
    own = module_under_test(path)
    foreign = [f"{module}: {name}" for module, name in private_uses(path) if module != own]
    assert not foreign, (f"{path.relative_to(TESTS)} tests {own or 'no module'} but reaches "
                         f"private names of others (docs/architecture.md): {foreign}")


def test_the_private_name_check_sees_every_form(tmp_path):
    test_file = TESTS / "robust" / "test_hinf.py"      # only its path is used: it tests hinf
    source = tmp_path / "test_x.py"
    source.write_text(
        "import piezolib._checks\n"
        "from piezolib import robust\n"
        "from piezolib.robust import dk as D, hinf\n"
        "from piezolib.robust.lft import _POLE_CONDITION\n"
        "def test(monkeypatch):\n"
        "    D._full_blocks, robust.lti._unused, hinf._central\n"
        "    monkeypatch.setattr(hinf, '_peak_gain', None)\n"
        "    monkeypatch.setattr('piezolib.robust.margins._x', None)\n")
    uses = private_uses(source)
    assert {module for module, _ in uses} == {
        "piezolib._checks", "piezolib.robust.dk", "piezolib.robust.lti", "piezolib.robust.hinf",
        "piezolib.robust.lft", "piezolib.robust.margins"}
    assert module_under_test(test_file) == "piezolib.robust.hinf"
    assert module_under_test(TESTS / "test_checks.py") == "piezolib._checks"
    assert module_under_test(TESTS / "robust" / "conftest.py") is None


def test_every_name_in_all_exists():
    # `from piezolib.<package> import *` fails on a name left in __all__ after a rename
    missing = []
    for path in SOURCES:
        module = importlib.import_module(_module_name(path))
        missing += [f"{module.__name__}.{name}" for name in getattr(module, "__all__", ())
                    if not hasattr(module, name) and not _is_submodule(module, name)]
    assert not missing, f"__all__ names that do not exist: {missing}"


def _is_submodule(package, name):
    try:
        importlib.import_module(f"{package.__name__}.{name}")
    except ModuleNotFoundError:
        return False
    return True


# -- every package's docstring lists its modules, and only those ---------------------------------

_ENTRY = re.compile(r"^([a-z_][a-z0-9_]*)(/?)(?:\s{2,}\S|\s*$)")


def _packages():
    return sorted(p.parent for p in PACKAGE.rglob("__init__.py")
                  if "__pycache__" not in p.parts)


def _members(package):
    """Public modules and subpackages of a package (private ones need not be listed)."""
    names = {p.stem for p in package.glob("*.py") if p.stem not in ("__init__", "__main__")}
    names |= {p.name for p in package.iterdir() if (p / "__init__.py").is_file()}
    return {n for n in names if not n.startswith("_")}


@pytest.mark.parametrize("package", _packages(), ids=lambda p: str(p.relative_to(PACKAGE.parent)))
def test_a_package_docstring_lists_its_modules(package):
    members = _members(package)
    if not members:
        return
    doc = ast.get_docstring(ast.parse((package / "__init__.py").read_text(encoding="utf-8"))) or ""
    entries = {m.group(1) for line in doc.splitlines() if (m := _ENTRY.match(line))}
    # a module named by reference in prose counts as listed (the top package's layers)
    referenced = {name.split(".")[-1] for name in re.findall(r":mod:`~?\.?([\w.]+)`", doc)}
    listed = entries | referenced
    missing = sorted(members - listed)
    if package == PACKAGE:
        entries &= members          # the top package's entries are its layers (toolkit, ...)
    stale = sorted(n for n in entries if n not in members and not (package / f"{n}.py").exists()
                   and not (package / n).is_dir())
    assert not missing, f"{package.name}/__init__.py does not list {missing}"
    assert not stale, f"{package.name}/__init__.py lists modules that do not exist: {stale}"
