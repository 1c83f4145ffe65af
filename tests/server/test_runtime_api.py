"""Signatures and summaries read from the runtime's source, as the editor shows them."""

import ast

from openbricks_server.runtime_api import module_api, runtime_api, signature

SOURCE = '''
"""A module.

More text."""

LIMIT = 3


class Base:
    pass


class Thing(pkg.Base):
    """Does a thing,
    over two lines.

    Details nobody reads in a tooltip."""

    KIND = "x"

    def __init__(self, port, *, speed=100):
        pass

    def go(self, a, /, b=1, *rest, c, d=None, **extra):
        """Go."""

    @property
    def level(self):
        """The level."""

    @level.setter
    def level(self, value):
        pass

    @staticmethod
    def make(x):
        pass

    def _hidden(self):
        pass


def helper(n=2 ** 3):
    pass


def _private():
    pass
'''


def test_a_module_is_read_with_signatures_defaults_and_summaries():
    module = module_api("pkg.mod", SOURCE)
    assert module.doc == "A module."
    by_name = {s.name: s for s in module.symbols}
    assert set(by_name) == {"LIMIT", "Base", "Thing", "helper"}
    thing = by_name["Thing"]
    assert (thing.signature, thing.doc, thing.bases) == (
        "(port, *, speed=100)",
        "Does a thing, over two lines.",
        ["Base"],
    )
    members = {m.name: (m.kind, m.signature, m.doc) for m in thing.members}
    assert members == {
        "KIND": ("constant", "", ""),
        "go": ("method", "(a, /, b=1, *rest, c, d=None, **extra)", "Go."),
        "level": ("property", "", "The level."),
        "make": ("method", "(x)", ""),
    }
    assert by_name["helper"].signature == "(n=2 ** 3)"


def test_a_bound_signature_leaves_self_out_only_for_methods():
    fn = ast.parse("def f(self, x): pass").body[0]
    assert (signature(fn, bound=True), signature(fn, bound=False)) == ("(x)", "(self, x)")


def test_the_installed_runtime_offers_its_public_modules():
    names = [m["name"] for m in runtime_api()["modules"]]
    assert "openbricks.robotics.drivebase" in names and "openbricks.tools" in names
    assert "openbricks.launcher" not in names and "openbricks._native" not in names
