"""How every part declares its parameters, once, on the class; and how a part is given its own parts.

Why: a part's parameter (its default, allowed range, unit and where the value comes from) was written in the scenario
format and again in the tracker, with tests to keep the copies equal. Each part is now a dataclass whose fields are
its parameters, made with ``param``; the scenario format reads them from there (``scenarios.schema.schema_of``), so
a part made in Python and one named in a scenario have the same defaults. No scenario code is imported here: the
scenario format imports these parts, and a user's robot can run them without it.
"""

from __future__ import annotations

import copy
import dataclasses
import importlib
from typing import Any, NamedTuple

__all__ = ["param", "REQUIRED", "declared", "given", "ordered", "Slot", "made"]

REQUIRED = dataclasses.MISSING  # the default of a parameter that must be given (its ``kind`` named)


def param(default: Any, doc: str, *, kind: str | None = None, min: float | None = None, max: float | None = None,
          exclusive_min: bool = False, choices: tuple | None = None, item: dict | type | None = None,
          parts: Slot | None = None, min_items: int = 0) -> Any:
    """A dataclass field that is a parameter of its part: ``doc`` gives its unit and the seed section (or the
    measurement) its default comes from; its kind is its default's (int, float, str, bool, or a list: of ``item``,
    keyword arguments of ``param`` without the default and doc, or of parts of the ``parts`` slot; or a mapping of
    names to ``item``s; or a frozen dataclass of declared parameters, a section of its own), or ``kind`` where the
    default does not tell it: a default None (the parameter may be left out) or a point (``point3``), or one without
    a default (``REQUIRED``), and may be a class of declared parameters (a section of its own) or a scenario kind
    (scenarios/schema.py); a list's ``item`` may be a class whose declared parameters are each item's keys; ``parts``
    makes it a part (a list of parts with a list default)."""
    limits = dict(doc=doc, kind=kind, min=min, max=max, exclusive_min=exclusive_min, choices=choices, item=item,
                  parts=parts, min_items=min_items)
    if isinstance(default, (list, dict)):
        return dataclasses.field(default_factory=lambda: copy.deepcopy(default), metadata={"param": limits})
    return dataclasses.field(default=default, metadata={"param": limits})


def declared(part: Any) -> dict[str, Any]:
    """A part's declared parameters and their values, in their order (what it records of itself: a dataset's
    calibration)."""
    return {f.name: getattr(part, f.name) for f in dataclasses.fields(part) if "param" in f.metadata}


def given(cls: type, section: Any) -> dict[str, Any]:
    """The values a section (a scenario's mapping) gives ``cls``'s declared parameters: its keyword arguments, where
    the section holds other parts' keys too (the robot's section: the body's and the drivers')."""
    return {f.name: section[f.name] for f in dataclasses.fields(cls) if "param" in f.metadata}


def ordered(low: str, high: str, strict: bool = False):
    """A check across a part's parameters (its ``CHECKS``): ``low`` at most (``strict``: below) ``high``."""
    def check(p: dict):
        if p[low] > p[high] or (strict and p[low] == p[high]):
            return low, f"{p[low]:g}; expected {'below' if strict else 'at most'} {high} ({p[high]:g})"
    return check


class Slot(NamedTuple):
    """A place for a part in another part (the NNT's deletion logic, an IMM's models): the built-in types by name,
    the one made when none is given (None: no part), the methods the holder calls on it, and what it is for."""

    types: dict[str, type]
    default: str | None
    methods: tuple[str, ...]
    doc: str
    role: str


def made(part: Any, slot: Slot) -> Any:
    """The part to use: ``part`` itself, or the one its specification names (a mapping of ``type``, a built-in type's
    name or ``module.path:ClassName``, and its parameters, which may specify parts in turn), or the slot's default
    when None."""
    if part is None:
        return None if slot.default is None else slot.types[slot.default]()
    if not isinstance(part, dict):
        return part
    params = {k: v for k, v in part.items() if k != "type"}
    name = part.get("type", slot.default)
    if name in slot.types:
        return slot.types[name](**params)
    module, _, cls = name.partition(":")
    return getattr(importlib.import_module(module), cls)(**params)
