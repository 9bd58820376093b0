"""The conventions every ``hop-impedance`` sub-command follows, as argparse pieces.

- Inputs are positional (``hop-impedance pipeline REC.mcap``); outputs are flags.
- Body size is ``--mass-kg`` / ``--height-m``; an .rrd output is ``--rrd PATH``.
- A renamed flag keeps its old name as a :class:`DeprecatedAlias`: it still works
  and says on stderr which flag to use instead.
- A default that belongs to the core is read from where the core defines it
  (an option dataclass field, a function's keyword default, a module constant)
  with :class:`OptionDefault`, never typed again here. It is looked up only
  when a parse needs it or help shows it, so building the parser (``--help``)
  imports nothing heavy (scipy, rclpy).
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib
import inspect
import sys
from typing import Any


class OptionDefault:
    """A default that lives in the core: ``OptionDefault("pkg.module:Name", "field")``.

    ``Name`` may be a dataclass (the field's default or default factory), a
    function (the keyword's default) or any other object (its attribute).
    ``str()`` gives the value, so ``%(default)s`` in help shows it.
    """

    def __init__(self, where: str, name: str) -> None:
        self.where = where
        self.name = name

    @property
    def value(self) -> Any:
        module, _, attr = self.where.partition(":")
        owner = getattr(importlib.import_module(module), attr)
        if dataclasses.is_dataclass(owner) and isinstance(owner, type):
            for f in dataclasses.fields(owner):
                if f.name == self.name:
                    if f.default is not dataclasses.MISSING:
                        return f.default
                    if f.default_factory is not dataclasses.MISSING:
                        return f.default_factory()
                    raise AttributeError(f"{self.where}.{self.name} has no default")
            raise AttributeError(f"{self.where} has no field {self.name}")
        if callable(owner) and not isinstance(owner, type):
            default = inspect.signature(owner).parameters[self.name].default
            if default is inspect.Parameter.empty:
                raise AttributeError(f"{self.where}({self.name}=...) has no default")
            return default
        return getattr(owner, self.name)

    def __str__(self) -> str:
        return str(self.value)

    def __repr__(self) -> str:
        return f"OptionDefault({self.where!r}, {self.name!r})"


def resolve_defaults(namespace: argparse.Namespace) -> argparse.Namespace:
    """Replace every :class:`OptionDefault` left in ``namespace`` (options not given) by its value."""
    for key, value in vars(namespace).items():
        if isinstance(value, OptionDefault):
            setattr(namespace, key, value.value)
    return namespace


class Parser(argparse.ArgumentParser):
    """``ArgumentParser`` whose parses come back with core defaults resolved (sub-parsers inherit the class)."""

    def parse_known_args(self, args=None, namespace=None):
        parsed, extras = super().parse_known_args(args, namespace)
        return resolve_defaults(parsed), extras


class DeprecatedAlias(argparse.Action):
    """The old name of a renamed option: stores into the new option's ``dest`` and warns on stderr.

    ``p.add_argument("--mass", action=DeprecatedAlias, new="--mass-kg", dest="mass_kg", type=float)``.
    For a positional that used to be a flag, give ``dest`` a name of its own and merge the two with
    :func:`positional_or_alias`. Hidden from ``--help``.
    """

    def __init__(self, option_strings, dest, new: str, nargs=None, **kwargs) -> None:
        self.new = new
        kwargs["help"] = argparse.SUPPRESS
        super().__init__(option_strings, dest, nargs=nargs, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        print(f"{parser.prog}: warning: {option_string} is deprecated; use {self.new}", file=sys.stderr)
        setattr(namespace, self.dest, values)


def positional_or_alias(args: argparse.Namespace, name: str, alias_dest: str, flag: str) -> Any:
    """The positional ``name`` or its deprecated flag (stored in ``alias_dest``); both given is an error."""
    positional, old = getattr(args, name, None), getattr(args, alias_dest, None)
    if positional is not None and old is not None:
        raise ValueError(f"give the {name} once: positionally ({positional}) or with the deprecated {flag} ({old})")
    return positional if positional is not None else old


def add_rrd_argument(p: argparse.ArgumentParser, help: str, old: tuple[str, ...] = (), **kwargs: Any) -> None:
    """``--rrd PATH``, the one flag for an .rrd output; ``old`` names are kept as deprecated aliases."""
    p.add_argument("--rrd", metavar="OUT.rrd", help=help, **kwargs)
    for flag in old:
        p.add_argument(flag, action=DeprecatedAlias, new="--rrd", dest="rrd", metavar="OUT.rrd")
