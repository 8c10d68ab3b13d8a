"""The loaded scenario as a read-only typed object: ``scenario.robot.radius``, ``scenario.sensors.lasers[0].rate``.

Why: the packages read the scenario; reading it as nested dicts by string key spreads the format's spelling over
every module, and a typo is a KeyError at run time. Each section is an object whose attributes are the keys its
schema declares (scenarios/format.py, and the parts' own declarations), made from the validated data: a nested
mapping is a section, a list a tuple, a mapping of named items (routes, waypoints, agent types) a read-only
``Names``. Nothing can be assigned; ``replace`` gives a changed copy. ``plain`` turns it back into the dicts and lists
a YAML or JSON file holds, and a part's section into the keyword arguments of its constructor (``params``).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Iterator


class Section(Mapping):
    """One mapping of the scenario, its keys as attributes. It is a read-only Mapping too, so that ``**section``
    gives a part's keyword arguments."""

    __slots__ = ("_values", "_spec")

    def __init__(self, values: dict[str, Any], spec: Any = None):
        """``values`` as ``typed`` makes them from data that ``spec`` (a Schema; None: none) validated."""
        object.__setattr__(self, "_values", dict(values))
        object.__setattr__(self, "_spec", spec)

    def __getattr__(self, name: str) -> Any:
        try:
            return self._values[name]
        except KeyError:
            raise AttributeError(f"the scenario section has no key {name!r}; it has: {', '.join(self._values)}") \
                from None

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"the scenario is read-only: {name} cannot be set; use replace({name}=...)")

    def __getitem__(self, key: str) -> Any:
        return self._values[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({', '.join(f'{k}={v!r}' for k, v in self._values.items())})"

    def __reduce__(self):  # whole again in another process (the experiments' and datasets' workers)
        return typed, (plain(self), self._spec)

    def __dir__(self):
        return [*super().__dir__(), *self._values]

    def replace(self, **changes: Any) -> Section:
        """A copy with ``changes`` to its keys (a section's value given as a mapping)."""
        unknown = set(changes) - set(self._values)
        if unknown:
            raise AttributeError(f"the scenario section has no key {', '.join(sorted(unknown))}")
        return typed({**plain(self), **{k: plain(v) for k, v in changes.items()}}, self._spec)

    @property
    def params(self) -> dict[str, Any]:
        """The section as the keyword arguments of a part's constructor: its keys but ``type``, plain values."""
        return {k: plain(v) for k, v in self._values.items() if k != "type"}


class Scenario(Section):
    """A whole loaded scenario: ``source`` is the file it came from (or a name for one given as data)."""

    __slots__ = ()

    def __reduce__(self):
        return scenario_of, (plain(self),)

    def replace(self, **changes: Any) -> Scenario:
        return scenario_of(plain(super().replace(**changes)))


class MapSection(Section):
    """The map, with its walls and obstacle edges as segments [m, 2, 2] (made once)."""

    __slots__ = ("_segments",)

    @property
    def segments(self):
        try:
            return self._segments
        except AttributeError:
            from .geometry import segments_of

            object.__setattr__(self, "_segments", segments_of(plain(self.walls), plain(self.obstacles)))
            return self._segments


class Names(Mapping):
    """Named items (routes, waypoints, agent types), read-only, in the file's order."""

    __slots__ = ("_items",)

    def __init__(self, items: dict[str, Any]):
        self._items = {k: typed(v) for k, v in items.items()}

    def __getitem__(self, name: str) -> Any:
        return self._items[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._items)

    def __len__(self) -> int:
        return len(self._items)

    def __repr__(self) -> str:
        return f"Names({self._items!r})"

    def __reduce__(self):
        return Names, (plain(self),)


def typed(value: Any, spec: Any = None) -> Any:
    """Validated scenario data as sections, tuples and Names, by the schema ``spec`` that validated it (a ``Field``,
    ``Schema``, ``ListOf``, ``MapOf`` or ``Typed``; None: by the data's own shape, as for a user's part without a
    schema). Data already typed passes as it is."""
    from .schema import Field, ListOf, MapOf, Schema, Typed

    if isinstance(spec, Field):
        spec = spec.kind
    if value is None or isinstance(value, (Section, Names)):
        return value
    if isinstance(value, dict):
        if isinstance(spec, MapOf):
            return Names({k: typed(v, spec.item) for k, v in value.items()})
        if isinstance(spec, Typed):
            spec = spec.types.get(value.get("type"))
        fields = spec.fields if isinstance(spec, Schema) else {}
        return Section({k: typed(v, fields.get(k)) for k, v in value.items()}, spec)
    if isinstance(value, (list, tuple)):
        item = spec.item if isinstance(spec, ListOf) else None
        return tuple(typed(v, item) for v in value)
    return value


def plain(value: Any) -> Any:
    """The dicts and lists a YAML or JSON file holds."""
    if isinstance(value, Section):
        return {k: plain(v) for k, v in value._values.items()}
    if isinstance(value, Names):
        return {k: plain(v) for k, v in value._items.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    return value


def scenario_of(data: dict) -> Scenario:
    """Validated scenario data (with its ``source``) as the typed Scenario."""
    from .format import SCENARIO

    values = typed(data, SCENARIO)._values
    values["map"] = MapSection(values["map"]._values, values["map"]._spec)
    return Scenario(values, SCENARIO)


def as_written(value: Any) -> Any:
    """The data as a scenario file writes it: the keys left unset (None) left out, so that it loads to the same
    scenario; a named item given as null (a sensor without a detector) is kept."""
    if isinstance(value, Section):
        return {k: as_written(v) for k, v in value._values.items() if v is not None}
    if isinstance(value, Names):
        return {k: as_written(v) for k, v in value._items.items()}
    if isinstance(value, (list, tuple)):
        return [as_written(v) for v in value]
    return value
