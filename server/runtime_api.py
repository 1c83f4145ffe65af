"""The hub runtime's API as a program sees it, read from the `openbricks` package's own source.

The editor's completion and hover help come from here (`GET /api/runtime/api`), so they never drift
from the runtime: every public module, class, function and method with its signature (defaults
included) and its docstring's summary. The source is parsed (`ast`), never imported: the runtime's
modules expect a hub (`machine`, `esp32`, the native cores), which the host only has inside the
simulator's shim.
"""

from __future__ import annotations

import ast
import functools
from dataclasses import asdict, dataclass, field
from pathlib import Path

import openbricks

# The host's side of the wire (host calls, the launcher, the BLE REPL): modules the hub runs for the
# host, which a program has no business calling. Everything else public is offered.
HOST_SIDE_MODULES = frozenset(
    {"openbricks.host_calls", "openbricks.host_protocol", "openbricks.launcher", "openbricks.ble_repl"}
)


@dataclass
class Symbol:
    """One name a program can use: a class, function, method, property or constant."""

    name: str
    kind: str  # "class", "function", "method", "property", "constant"
    signature: str  # "(distance_mm, then='coast', wait=True)"; "" for properties and constants
    doc: str  # the docstring's summary: its first paragraph on one line
    members: list[Symbol] = field(default_factory=list)
    bases: list[str] = field(default_factory=list)  # a class's base classes, as named in its source


@dataclass
class Module:
    name: str  # "openbricks.robotics.drivebase"
    doc: str
    symbols: list[Symbol]


_FUNCTIONS = ast.FunctionDef | ast.AsyncFunctionDef


def _first_line(node: ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef) -> str:
    doc = (ast.get_docstring(node) or "").strip()
    return " ".join(doc.split("\n\n")[0].split())


def _decorators(node: ast.AST) -> set[str]:
    names = set()
    for d in getattr(node, "decorator_list", []):
        target = d.func if isinstance(d, ast.Call) else d
        names.add(target.attr if isinstance(target, ast.Attribute) else getattr(target, "id", ""))
    return names


def signature(fn: ast.FunctionDef | ast.AsyncFunctionDef, *, bound: bool) -> str:
    """The call signature as a program writes it: `self`/`cls` left out of a method's."""
    args = fn.args
    positional = [*args.posonlyargs, *args.args]
    defaults: list[ast.expr | None] = [None] * (len(positional) - len(args.defaults)) + list(args.defaults)
    parts = [
        a.arg + ("" if d is None else "=" + ast.unparse(d)) for a, d in zip(positional, defaults, strict=True)
    ]
    if args.posonlyargs:
        parts.insert(len(args.posonlyargs), "/")
    if bound and positional:
        parts.pop(0)
    if args.vararg:
        parts.append("*" + args.vararg.arg)
    elif args.kwonlyargs:
        parts.append("*")
    for a, d in zip(args.kwonlyargs, args.kw_defaults, strict=True):
        parts.append(a.arg + ("" if d is None else "=" + ast.unparse(d)))
    if args.kwarg:
        parts.append("**" + args.kwarg.arg)
    return "(" + ", ".join(parts) + ")"


def _public(name: str) -> bool:
    return not name.startswith("_")


def _class(node: ast.ClassDef) -> Symbol:
    members: list[Symbol] = []
    init_sig = "()"
    for item in node.body:
        if isinstance(item, _FUNCTIONS):
            decorators = _decorators(item)
            if item.name == "__init__":
                init_sig = signature(item, bound=True)
            elif not _public(item.name) or "setter" in decorators or "deleter" in decorators:
                continue
            elif "property" in decorators:
                members.append(Symbol(item.name, "property", "", _first_line(item)))
            else:
                members.append(
                    Symbol(
                        item.name,
                        "method",
                        signature(item, bound="staticmethod" not in decorators),
                        _first_line(item),
                    )
                )
        elif isinstance(item, ast.Assign | ast.AnnAssign):
            for name in _assigned(item):
                if _public(name):
                    members.append(Symbol(name, "constant", "", ""))
    bases = [ast.unparse(b).rsplit(".", 1)[-1] for b in node.bases]
    return Symbol(node.name, "class", init_sig, _first_line(node), members, bases)


def _assigned(node: ast.Assign | ast.AnnAssign) -> list[str]:
    targets = node.targets if isinstance(node, ast.Assign) else [node.target]
    return [t.id for t in targets if isinstance(t, ast.Name)]


def module_api(name: str, source: str) -> Module:
    tree = ast.parse(source, name)
    symbols: list[Symbol] = []
    for node in tree.body:
        if isinstance(node, ast.ClassDef) and _public(node.name):
            symbols.append(_class(node))
        elif isinstance(node, _FUNCTIONS) and _public(node.name):
            symbols.append(Symbol(node.name, "function", signature(node, bound=False), _first_line(node)))
        elif isinstance(node, ast.Assign | ast.AnnAssign):
            symbols.extend(
                Symbol(n, "constant", "", "") for n in _assigned(node) if n.isupper() and _public(n)
            )
    return Module(name, _first_line(tree), symbols)


def _module_name(root: Path, path: Path) -> str:
    parts = ["openbricks", *path.relative_to(root).with_suffix("").parts]
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


@functools.cache
def runtime_api() -> dict:
    """Every public module of the installed runtime, read once per process."""
    root = Path(openbricks.__file__).parent
    modules = []
    for path in sorted(root.rglob("*.py")):
        name = _module_name(root, path)
        if any(part.startswith("_") for part in name.split(".")) or name in HOST_SIDE_MODULES:
            continue
        modules.append(asdict(module_api(name, path.read_text(encoding="utf-8"))))
    return {"version": openbricks.__version__, "modules": modules}
