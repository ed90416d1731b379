"""Check mbody's import graph: no cycles between its modules, and say where imports hide.

    python tools/check_imports.py [--verbose]

Every ``import`` of an mbody module counts, at module level or inside a function (an
import inside a function is still a dependency, only a later one); imports under
``if TYPE_CHECKING:`` do not (they never run). A cycle is printed with the file and line
of each of its imports, and the exit code is 1.

An import inside a function is kept only where it saves start-up time: the target loads
a slow library (scipy, matplotlib, networkx, meshcat, numba, tqdm, sympy,
mujoco, defusedxml, nbformat, nbclient) when imported, or the
importer is a command module (`mbody.cli`: every command registers its arguments at
start-up, and must not load what only another command uses), or the import is one of
`DEFERRED`: a module every simulation imports leaves for later one that only some runs,
or only a run file's reading and writing, use (a fresh process's first `mbody.simulate`
pays for every module it imports: issue 24). Any other import inside a function hides a
dependency for nothing: it is listed, and the exit code is 1.
``--verbose`` lists every import made inside a function, with its reason.

One upward import is allowed by design, a display hook: a notebook display method of an
object (``_repr_html_``, ``_repr_latex_``, ``_repr_svg_``, ``_repr_png_``,
``_repr_pretty_``) may import the
presentation layer (`mbody.present`) that draws it. Such an edge is listed, and left out
of the cycle search: the presentation layer imports the object's module, and the method
runs only when the object is shown. Importing an mbody module by a string
(``import_module("mbody...")``) hides the edge from this check, and is refused.

The same holds between folders (`mbody.model`, `mbody.equations`...: the package's steps,
docs/codebase.md): counting every import but the display hooks', the folders must form
no cycle, so that they can be read and changed in one order. Modules directly in `mbody/`
(the public entry points and `errors`, `conventions`) sit outside that order. The folders'
order is printed with ``--verbose``.
"""

from __future__ import annotations

import argparse
import ast
import sys
from dataclasses import dataclass
from pathlib import Path

import networkx as nx

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "mbody"


SLOW = ("scipy", "matplotlib", "networkx", "meshcat", "numba", "tqdm", "sympy", "mujoco",
        "defusedxml", "nbformat", "nbclient")
"""Libraries that take tens to hundreds of milliseconds to import."""


DEFERRED = {
    ("mbody.simulate.simulation", "mbody.simulate.kinematic"):
        "a fully driven model's run, and the drivers' figures and summary lines of a run "
        "with drivers",
    ("mbody.simulate.simulation", "mbody.simulate.axes"): "a run stored in world axes",
    ("mbody.simulate.simulation", "mbody.simulate.budget"):
        "a run that outgrows its step or wall-time budget, or whose integration fails",
    ("mbody.simulate.trajectory", "mbody.simulate.run_file"): "saving and loading a run",
    ("mbody.simulate.trajectory", "mbody.model.yaml_write"):
        "the model text of a run of a model not read from a YAML file",
}
"""(importer, imported) -> the only work that needs the imported module: imports a simulation's
modules make inside a function, kept out of a fresh process's first `mbody.simulate`
(about 1 ms of its 4.3 ms on the double pendulum: docs/performance.md; issue 24)."""


DISPLAY_HOOKS = ("_repr_html_", "_repr_latex_", "_repr_svg_", "_repr_png_", "_repr_pretty_")
"""Methods that may import `mbody.present` (see the module's docstring)."""


@dataclass(frozen=True)
class Import:
    source: str  # importing module, dotted
    target: str  # imported mbody module, dotted
    line: int
    in_function: bool
    function: str = ""  # the innermost enclosing function's name

    @property
    def display_hook(self) -> bool:
        return self.function in DISPLAY_HOOKS and self.target.startswith("mbody.present")


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _is_type_checking(node: ast.If) -> bool:
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or (
        isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING")


def _targets(node: ast.Import | ast.ImportFrom, source: str, is_package: bool,
             modules: set[str]) -> list[str]:
    """The mbody modules an import statement loads (the deepest that exists)."""
    if isinstance(node, ast.Import):
        names = [a.name for a in node.names]
    else:
        base = node.module or ""
        if node.level:
            pkg = source.split(".") if is_package else source.split(".")[:-1]
            pkg = pkg[: len(pkg) - (node.level - 1)]
            base = ".".join(pkg + ([base] if base else []))
        names = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base
                 for a in node.names]
    found = []
    for name in names:
        while name and name not in modules:
            name = name.rpartition(".")[0]
        if name.startswith("mbody") and name != source:
            found.append(name)
    return sorted(set(found))


def _by_string(node: ast.AST) -> str | None:
    """The module named in ``import_module("mbody...")`` / ``__import__("mbody...")``."""
    if not isinstance(node, ast.Call) or not node.args:
        return None
    f = node.func
    name = f.attr if isinstance(f, ast.Attribute) else f.id if isinstance(f, ast.Name) else ""
    arg = node.args[0]
    if name in ("import_module", "__import__") and isinstance(arg, ast.Constant) \
            and isinstance(arg.value, str) and arg.value.startswith("mbody"):
        return arg.value
    return None


def imports(modules: dict[str, Path], slow: dict[str, bool],
            hidden: list[str] | None = None) -> list[Import]:
    """Imports between mbody modules; fills `slow` with the modules that import a slow
    library at module level themselves, and `hidden` with imports made by a string."""
    out = []
    for source, path in modules.items():
        tree = ast.parse(path.read_text("utf-8"), str(path))
        is_package = path.name == "__init__.py"

        def walk(node: ast.AST, in_function: bool, source=source, is_package=is_package,
                 function: str = "", path=path):
            for child in ast.iter_child_nodes(node):
                if isinstance(child, ast.If) and _is_type_checking(child):
                    # the else branch runs: walk its statements themselves, not only
                    # their children (an import directly under else: is one)
                    walk(ast.Module(body=child.orelse, type_ignores=[]), in_function,
                         function=function)
                    continue
                named = _by_string(child)
                if named is not None and hidden is not None:
                    hidden.append(f"{path.relative_to(ROOT)}:{child.lineno}: {source} "
                                  f"imports {named} by a string (the check cannot see it)")
                if isinstance(child, ast.Import | ast.ImportFrom) and not in_function:
                    names = ([a.name for a in child.names] if isinstance(child, ast.Import)
                             else [child.module or ""] if not child.level else [])
                    if any(n.split(".")[0] in SLOW for n in names):
                        slow[source] = True
                if isinstance(child, ast.Import | ast.ImportFrom):
                    for target in _targets(child, source, is_package, set(modules)):
                        out.append(Import(source, target, child.lineno, in_function,
                                          function))
                is_function = isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef)
                walk(child, in_function or is_function or isinstance(child, ast.Lambda),
                     function=child.name if is_function else function)

        walk(tree, False)
    return out


def old_paths(modules: dict[str, Path]) -> list[str]:
    """Imports inside the package of a path that has moved (`mbody._moved.MOVED`: an
    alias kept for users' code, which warns on import): the package uses the new homes."""
    moved = _moved_paths()
    out = []
    for name, path in modules.items():
        if name == "mbody._moved":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                full = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                full = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
            else:
                continue
            for f in full:
                old = f.removeprefix("mbody.")
                if f.startswith("mbody.") and old in moved:
                    out.append(f"{path.relative_to(ROOT)}:{node.lineno}: {name} imports "
                               f"{f}, an old path: use mbody.{moved[old]}")
    return out


def _moved_paths() -> dict[str, str]:
    """`mbody._moved.MOVED`, read from its source (importing mbody is not needed)."""
    path = PACKAGE / "_moved.py"
    if not path.exists():
        return {}
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(
                isinstance(t, ast.Name) and t.id == "MOVED" for t in node.targets):
            return ast.literal_eval(node.value)
    return {}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--verbose", action="store_true", help="list imports made in functions")
    a = p.parse_args(argv)
    modules = {module_name(f): f for f in sorted(PACKAGE.rglob("*.py"))}
    direct: dict[str, bool] = {}
    hidden: list[str] = []
    found = imports(modules, direct, hidden)
    for line in hidden:
        print(line)
    stale = old_paths(modules)
    for line in stale:
        print(line)
    g = nx.DiGraph()
    g.add_nodes_from(modules)
    for imp in found:
        if imp.display_hook:
            continue
        # importing mbody.x.y runs mbody.x's __init__ first, but the importer depends on
        # mbody.x.y only: the edge goes to the module
        g.add_edge(imp.source, imp.target, at=imp)
    # one cycle per strongly connected knot names the loop to break; simple_cycles would
    # list every loop (and on networkx 3.0 cannot rebuild a graph from its edge view)
    cycles = sorted(
        ([src for src, _ in nx.find_cycle(g.subgraph(knot))]
         for knot in nx.strongly_connected_components(g) if len(knot) > 1),
        key=len)
    for cycle in cycles[:20]:
        print("import cycle:")
        for src, dst in zip(cycle, cycle[1:] + cycle[:1], strict=True):
            imp = g.edges[src, dst]["at"]
            where = " (in a function)" if imp.in_function else ""
            print(f"  {modules[src].relative_to(ROOT)}:{imp.line}: {src} -> {dst}{where}")
    eager = nx.DiGraph()  # networkx 3.0 tries pandas on a generator passed to DiGraph()
    eager.add_edges_from((i.source, i.target) for i in found if not i.in_function)
    eager.add_nodes_from(modules)
    slow = {m for m in modules if any(direct.get(d) for d in nx.descendants(eager, m) | {m})}
    late = [imp for imp in found if imp.in_function]
    needless = []
    for imp in late:
        if imp.source.startswith("mbody.cli"):
            why = "a command module"
        elif imp.display_hook:
            why = f"a display hook ({imp.function})"
        elif imp.target in slow:
            why = "loads a slow library"
        elif (imp.source, imp.target) in DEFERRED:
            why = f"deferred: needed only for {DEFERRED[imp.source, imp.target]}"
        else:
            why = "NEEDLESS"
            needless.append(imp)
        if a.verbose or why == "NEEDLESS":
            print(f"{modules[imp.source].relative_to(ROOT)}:{imp.line}: {imp.source} imports "
                  f"{imp.target} in a function: {why}")
    folders = nx.DiGraph()
    for imp in found:
        src, dst = folder_of(imp.source, modules), folder_of(imp.target, modules)
        if imp.display_hook or src is None or dst is None or src == dst:
            continue
        folders.add_edge(src, dst)
        folders.edges[src, dst].setdefault("at", []).append(imp)
    knots = [sorted(k) for k in nx.strongly_connected_components(folders) if len(k) > 1]
    for knot in knots:
        print("folder cycle: " + ", ".join(knot))
        for src, dst in folders.subgraph(knot).edges:
            imp = folders.edges[src, dst]["at"][0]
            print(f"  {src} -> {dst}: {len(folders.edges[src, dst]['at'])} import(s), e.g. "
                  f"{modules[imp.source].relative_to(ROOT)}:{imp.line} -> {imp.target}")
    if a.verbose and not knots:  # importers after what they import
        order = list(reversed(list(nx.topological_sort(folders))))
        print("folders, each importing only from those before it: " + " -> ".join(order))
    print(f"{len(modules)} modules, {len(found)} imports between them "
          f"({len(late)} inside functions, {len(needless)} needless, {len(hidden)} by a "
          f"string), {len(cycles)} cycle(s); {folders.number_of_nodes()} folders, "
          f"{len(knots)} folder cycle(s)")
    return 1 if cycles or needless or hidden or knots or stale else 0


def folder_of(module: str, modules: dict[str, Path]) -> str | None:
    """The folder (sub-package of mbody) a module lives in; None for a module directly in
    mbody/ (outside the folders' order)."""
    parts = module.split(".")
    if len(parts) < 2:
        return None
    top = f"mbody.{parts[1]}"
    return parts[1] if modules.get(top, Path()).name == "__init__.py" else None


if __name__ == "__main__":
    sys.exit(main())
