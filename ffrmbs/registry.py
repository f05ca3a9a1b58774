"""Registries of kinds: a name (or a tuple of names) -> the class or constructor of that kind.

Each library package keeps the registries of the kinds it owns — :data:`contours.CONTOURS`,
:data:`contact.LAWS`, :data:`contact.PAIR_KINEMATICS`, :data:`contact.SOLVERS`,
:data:`mbs.BODIES`, :data:`mbs.JOINTS`, :data:`mbs.LOADS`, :data:`mbs.INTEGRATORS`,
:data:`mbs.ROTATIONS` — and both the Python API and the scene reader look kinds up there.
A new kind is its class plus one line ``REGISTRY.register(name, cls)`` (or the decorator
``@REGISTRY.register(name)``).
"""

from __future__ import annotations

from ffrmbs.errors import ModelError


def _spell(name) -> str:
    """A key for messages: 'impact', or 'point'/'2s' for a pair."""
    return "/".join(map(repr, name)) if isinstance(name, tuple) else repr(name)


class Registry:
    """Names of one kind of thing (``what``: "contact law", ...) -> their classes, in the
    order registered.

    ``REGISTRY[name]`` (or :meth:`lookup`) raises :class:`~ffrmbs.errors.ModelError`
    "unknown <what> <name>; choose one of <the names>" for a name not registered.
    """

    def __init__(self, what: str):
        self.what = what
        self._entries: dict = {}

    def register(self, name, cls=None):
        """Register ``cls`` as ``name`` and return it; without ``cls`` a class decorator.
        A name registered twice is a ModelError (unregister it first)."""
        if cls is None:
            return lambda cls: self.register(name, cls)
        if name in self._entries:
            raise ModelError(f"{self.what} {_spell(name)} is already registered "
                             f"(as {getattr(self._entries[name], '__name__', self._entries[name])})")
        self._entries[name] = cls
        return cls

    def unregister(self, name) -> None:
        """Remove ``name`` (a ModelError if it is not registered)."""
        self.lookup(name)
        del self._entries[name]

    def lookup(self, name):
        """The class registered as ``name``."""
        try:
            return self._entries[name]
        except (KeyError, TypeError):
            spelled = _spell(name) if isinstance(name, (str, tuple)) else repr(name)
            raise ModelError(f"unknown {self.what} {spelled}; "
                             f"choose one of {', '.join(map(_spell, self._entries))}") from None

    __getitem__ = lookup

    def name_of(self, obj):
        """The name under which the class of ``obj`` (or ``obj`` itself, a class) is
        registered: its own class first, then its base classes in method resolution
        order; None if none is."""
        cls = obj if isinstance(obj, type) else type(obj)
        for base in cls.__mro__:
            for name, entry in self._entries.items():
                if entry is base:
                    return name
        return None

    def names(self) -> tuple:
        """The registered names, in the order registered."""
        return tuple(self._entries)

    def items(self):
        return self._entries.items()

    def __contains__(self, name) -> bool:
        try:
            return name in self._entries
        except TypeError:       # an unhashable name is never registered
            return False

    def __iter__(self):
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def __repr__(self):
        return f"Registry({self.what!r}: {', '.join(map(_spell, self._entries))})"
