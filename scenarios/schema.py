"""A small declarative schema for scenario files: every key with its type, unit, default and allowed range.

Validation stops at the first fault and raises one ``ScenarioError`` naming the file, the key path and what was
expected, so a user fixes one thing at a time and never gets a traceback from deep inside the simulator.
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import math
import re
from dataclasses import dataclass
from typing import Any, Callable

from .errors import Error


class _Remove:
    """The value of a key tagged ``!remove`` in a scenario file (scenarios/reader.py): the key is left out."""

    def __repr__(self) -> str:
        return "!remove"


REMOVE = _Remove()


class ScenarioError(Error):
    """A scenario file (or argument) that does not satisfy the schema."""

    def __init__(self, source: str, key: str, message: str):
        super().__init__(f"{source}: {key}: {message}")
        self.source, self.key, self.message = source, key, message

    def __reduce__(self):  # whole again in another process (crowdsim navigate's workers)
        return type(self), (self.source, self.key, self.message)


@dataclass(frozen=True)
class Field:
    """One key: ``kind`` is 'float', 'int', 'str', 'bool', 'point' ([x, y]), 'point3' ([x, y, z]), 'pose'
    ([x, y, yaw]), 'points' (a list of [x, y]), a nested ``Schema``, ``ListOf``, ``MapOf`` or ``Typed``. An
    ``optional`` section (a ``Schema`` or ``Typed``) left out, or given as null, is None rather than its defaults."""

    kind: Any
    default: Any = None
    required: bool = False
    min: float | None = None
    max: float | None = None
    exclusive_min: bool = False
    choices: tuple | None = None
    allow_inf: bool = False
    doc: str = ""
    optional: bool = False  # a section (a Schema or Typed) that may be left out: None then, not its defaults


@dataclass(frozen=True)
class Schema:
    """A mapping's keys. With ``presets``, the key ``preset`` names a bundle of values (a sensor model, say) that
    fills the keys the mapping leaves out, before the fields' own defaults. ``legacy`` maps an old key (a field of
    its own, checked there) to the key ``section.name`` of this mapping that now holds it: files written before the
    change keep working, and the validated data holds the new spelling only. ``upgrade`` does the same for an older
    form of the whole mapping: given the mapping (``!remove`` keys left out), the file and the mapping's key, it
    returns the mapping in the current form (or raises ScenarioError naming the old key at fault)."""

    fields: dict[str, Field]
    presets: dict[str, dict] | None = None
    legacy: dict[str, str] | None = None
    # checks across the mapping's keys, run on its validated values: each returns None, or (key, what was expected)
    checks: tuple[Callable[[dict], tuple[str, str] | None], ...] = ()
    upgrade: Callable[[dict, str, str], dict] | None = None


@dataclass(frozen=True)
class ListOf:
    item: Any
    min_items: int = 0


@dataclass(frozen=True)
class MapOf:
    """A mapping from user-chosen names to items of one schema. With ``by_name``, a given mapping merges by name
    into the field's default one (a named item over the default item of that name, the given names first; ``name:
    !remove`` drops a default item; a mapping tagged ``!replace`` replaces the defaults whole)."""

    item: Any
    by_name: bool = False


@dataclass(frozen=True)
class Typed:
    """A mapping whose key ``type`` chooses its schema: a built-in type of ``types`` (name -> the type's parameters)
    or ``module.path:ClassName``, a user's class imported when the file is loaded. Such a class's parameters are
    checked by its ``SCHEMA`` (a ``Schema``, defaults filled) or else by its constructor's signature, and it must
    have ``methods``. ``role`` names the part in messages (``tracker``)."""

    types: dict[str, Schema]
    default: str
    role: str
    methods: tuple[str, ...] = ()

    @property
    def expected(self) -> str:
        return f"one of {', '.join(self.types)} or module.path:ClassName" if self.types else "module.path:ClassName"

    def type_field(self) -> Field:
        built_in = f"{', '.join(self.types)} (built in) or " if self.types else ""
        return Field("str", self.default, required=not self.types,
                     doc=f"which {self.role}: {built_in}module.path:ClassName, a class of your own imported when the "
                         "file is loaded; the other keys are its constructor's keyword arguments, checked by its "
                         "SCHEMA (a scenarios.schema.Schema) if it has one")


def schema_of(cls: type, presets: dict[str, dict] | None = None) -> Schema:
    """The parameters a part declares on its class (pipeline/params.py ``param``: dataclass fields with
    their default, range and doc) as a Schema, with the class's ``CHECKS`` across them; with ``presets`` (a sensor's
    models), the part's ``preset`` parameter names one of them (``Schema.presets``)."""
    fields = {}
    for f in dataclasses.fields(cls):
        declared = f.metadata.get("param")
        if declared is not None:
            fields[f.name] = _declared(f.default if f.default_factory is dataclasses.MISSING else f.default_factory(),
                                       declared)
    if presets is not None:
        # the preset's default None names no model: a string key like any other, not a section left out
        fields["preset"] = dataclasses.replace(fields["preset"], choices=tuple(presets), optional=False)
    return Schema(fields, presets=presets, checks=tuple(getattr(cls, "CHECKS", ())))


def _kind(value: Any) -> str:
    return next(k for t, k in ((bool, "bool"), (int, "int"), (float, "float"), (str, "str")) if isinstance(value, t))


def _declared(default: Any, p: dict) -> Field:
    """The Field of one declared parameter (its kind that of its default, or the one it names: optional when its
    default is None, required when it has none)."""
    if p["parts"] is not None and not isinstance(default, list):  # one part (a driver's planner)
        return Field(slot_typed(p["parts"]), doc=p["doc"])
    if p["kind"] is not None:
        required = default is dataclasses.MISSING
        kind = schema_of(p["kind"]) if isinstance(p["kind"], type) else p["kind"]  # a class: its declared keys
        return Field(kind, None if required else default, required=required, min=p["min"], max=p["max"],
                     exclusive_min=p["exclusive_min"], choices=p["choices"], doc=p["doc"],
                     optional=default is None)
    if dataclasses.is_dataclass(default):  # a section of its own (the robot's odometry)
        return Field(schema_of(type(default)), doc=p["doc"])
    if isinstance(default, dict):
        return Field(MapOf(_item(next(iter(default.values())), p["item"])), default, doc=p["doc"])
    if not isinstance(default, list):
        return Field(_kind(default), default, min=p["min"], max=p["max"], exclusive_min=p["exclusive_min"],
                     choices=p["choices"], doc=p["doc"])
    if p["parts"] is not None:
        item = Field(slot_typed(p["parts"]))
    elif isinstance(p["item"], type):
        item = Field(schema_of(p["item"]))
    else:
        item = _item(default[0], p["item"])
    return Field(ListOf(item, min_items=p["min_items"]), default, doc=p["doc"])


def _item(example: Any, limits: dict | None) -> Field:
    """The Field of a list's or mapping's items: the kind of ``example``, the limits ``param``'s ``item`` gives."""
    limits = limits or {}
    return Field(_kind(example), min=limits.get("min"), max=limits.get("max"),
                 exclusive_min=limits.get("exclusive_min", False), choices=limits.get("choices"))


def slot_typed(slot: Any) -> Typed:
    """The Typed of a slot for a part (pipeline/params.py ``Slot``): its built-in types' declared
    parameters, its default type (the first type where the slot's default is none), its methods."""
    return Typed({name: schema_of(cls) for name, cls in slot.types.items()}, slot.default or next(iter(slot.types)),
                 slot.role, slot.methods)


def slot_field(slot: Any) -> Field:
    """The Field of a slot for a part: left out, its default type with its defaults, or None where the slot's default
    is none."""
    return Field(slot_typed(slot), optional=slot.default is None, doc=slot.doc)


CLASS_PATH = re.compile(r"[A-Za-z_][\w.]*:[A-Za-z_]\w*")


def import_class(path: str) -> type:
    """The class ``module.path:ClassName`` names; ImportError (or what the module raises) when it is not there."""
    module, _, name = path.partition(":")
    cls = getattr(importlib.import_module(module), name, None)
    if not isinstance(cls, type):
        raise ImportError(f"module {module!r} has no class {name!r}")
    return cls


INT_LIMIT = 2 ** 63  # integers pass to numpy as int64


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _describe(v: Any) -> str:
    text = repr(v)
    return f"{type(v).__name__} {text}" if len(text) <= 60 else type(v).__name__


def _finite(c: Any) -> bool:
    """A number that is a finite float (an integer of hundreds of digits is none)."""
    try:
        return _is_number(c) and math.isfinite(float(c))
    except OverflowError:
        return False


def _check_point(v: Any, n: int, where: Callable[[str], ScenarioError], what: str):
    if not isinstance(v, (list, tuple)) or len(v) != n or not all(_finite(c) for c in v):
        raise where(f"expected {what} (a list of {n} numbers, finite), got {_describe(v)}")
    return [float(c) for c in v]


def validate(value: Any, spec: Any, source: str, key: str = "") -> Any:
    """Return ``value`` checked against ``spec`` with defaults filled in; raise ScenarioError on the first fault."""

    def err(message: str) -> ScenarioError:
        return ScenarioError(source, key or "<top level>", message)

    if isinstance(spec, Field):
        kind = spec.kind
        if spec.optional and value is None:
            return None
        if isinstance(kind, MapOf) and kind.by_name and isinstance(spec.default, dict):
            value = _by_name(spec.default, value)
        if isinstance(kind, (Schema, ListOf, MapOf, Typed)):
            out = validate(value, kind, source, key)
        elif kind == "float":
            if not _is_number(value):
                raise err(f"expected a number, got {_describe(value)}")
            try:
                out = float(value)
            except OverflowError:  # an integer of hundreds of digits
                raise err(f"expected a finite number, got an integer of {len(str(abs(value)))} digits") from None
            if math.isnan(out) or (math.isinf(out) and not spec.allow_inf):
                raise err(f"expected a finite number, got {out!r}")
        elif kind == "int":
            if not isinstance(value, int) or isinstance(value, bool):
                raise err(f"expected an integer, got {_describe(value)}")
            if not -INT_LIMIT < value < INT_LIMIT:
                raise err(f"expected an integer of at most 18 digits, got one of {len(str(abs(value)))}")
            out = value
        elif kind == "str":
            if not isinstance(value, str):
                raise err(f"expected a string, got {_describe(value)}")
            out = value
        elif kind == "bool":
            if not isinstance(value, bool):
                raise err(f"expected true or false, got {_describe(value)}")
            out = value
        elif kind == "point":
            out = _check_point(value, 2, err, "a point [x, y] in metres")
        elif kind == "point3":
            out = _check_point(value, 3, err, "a point [x, y, z] in metres")
        elif kind == "pose":
            out = _check_point(value, 3, err, "a pose [x, y, yaw] in metres and radians")
        elif kind == "points":
            if not isinstance(value, list) or len(value) < 2:
                raise err(f"expected a list of two or more points [x, y], got {_describe(value)}")
            out = [validate(p, Field("point"), source, f"{key}[{i}]") for i, p in enumerate(value)]
        else:  # pragma: no cover - a schema bug, not a user fault
            raise TypeError(f"unknown field kind {kind!r}")
        if spec.choices is not None and out not in spec.choices:
            raise err(f"expected one of {', '.join(map(str, spec.choices))}, got {out!r}")
        if spec.min is not None and (out < spec.min or (spec.exclusive_min and out == spec.min)):
            bound = f"greater than {spec.min}" if spec.exclusive_min else f"at least {spec.min}"
            raise err(f"expected a value {bound}, got {out!r}")
        if spec.max is not None and out > spec.max:
            raise err(f"expected a value at most {spec.max}, got {out!r}")
        return out
    if isinstance(spec, Typed):
        return _validate_typed(value, spec, source, key)
    if isinstance(spec, Schema):
        if value is None:
            value = {}
        if not isinstance(value, dict):
            raise err(f"expected a mapping of keys, got {_describe(value)}")
        value = {k: v for k, v in value.items() if v is not REMOVE}  # ``!remove``: left out, the default applies
        if spec.upgrade is not None:
            value = spec.upgrade(value, source, key)
        unknown = [k for k in value if k not in spec.fields]
        if unknown:
            k = unknown[0]
            raise ScenarioError(source, f"{key}.{k}" if key else str(k),
                                f"unknown key; expected one of: {', '.join(spec.fields)}")
        if spec.presets and value.get("preset") is not None:
            name = validate(value["preset"], spec.fields["preset"], source, f"{key}.preset" if key else "preset")
            value = {**spec.presets[name], **value}
        legacy = spec.legacy or {}
        for old, new in legacy.items():
            if old in value:
                value = _move_legacy(value, old, new, spec.fields[old], source, key)
        out = {}
        for name, field in spec.fields.items():
            sub = f"{key}.{name}" if key else name
            if name in legacy:
                continue
            if name in value:
                out[name] = validate(value[name], field, source, sub)
            elif field.required:
                raise ScenarioError(source, sub, "missing required key")
            elif isinstance(field.kind, (Schema, Typed)) and not field.optional:
                out[name] = validate({}, field.kind, source, sub)
            else:
                out[name] = field.default
        for check in spec.checks:
            fault = check(out)
            if fault is not None:
                sub, message = fault
                raise ScenarioError(source, f"{key}.{sub}" if key else sub, message)
        return out
    if isinstance(spec, ListOf):
        if not isinstance(value, list):
            raise err(f"expected a list, got {_describe(value)}")
        if len(value) < spec.min_items:
            raise err(f"expected at least {spec.min_items} item(s), got {len(value)}")
        if any(v is REMOVE for v in value):
            raise err("!remove tags a list item; expected it on a key of a mapping (a list is replaced whole)")
        return [validate(v, spec.item, source, f"{key}[{i}]") for i, v in enumerate(value)]
    if isinstance(spec, MapOf):
        if not isinstance(value, dict):
            raise err(f"expected a mapping of names to entries, got {_describe(value)}")
        return {str(k): validate(v, spec.item, source, f"{key}.{k}") for k, v in value.items() if v is not REMOVE}
    raise TypeError(f"unknown spec {spec!r}")  # pragma: no cover


def _by_name(default: dict, value: Any) -> Any:
    """``value`` merged by name into ``default`` (``MapOf.by_name``); anything but a plain mapping as it is."""
    if type(value) is not dict:  # a !replace mapping, or a fault the validation names
        return value
    merged = {name: {**default[name], **item} if isinstance(item, dict) and name in default else item
              for name, item in value.items()}
    return {**merged, **{name: item for name, item in default.items() if name not in value}}


def _move_legacy(value: dict, old: str, new: str, field: Field, source: str, key: str) -> dict:
    """``value`` with the old key's value (checked as its own field) moved to ``new`` (``section.name``)."""
    where = f"{key}." if key else ""
    checked = validate(value[old], field, source, where + old)
    section, name = new.split(".")
    inner = value.get(section) or {}
    if not isinstance(inner, dict):
        return value  # the section's own check names the fault
    if name in inner:
        raise ScenarioError(source, where + old,
                            f"the old spelling of {where}{new}, which is given too; expected only {where}{new}")
    return {**{k: v for k, v in value.items() if k != old}, section: {**inner, name: checked}}


def _validate_typed(value: Any, spec: Typed, source: str, key: str) -> dict:
    """A part's specification: its type (a built-in type, else a user's class, imported) and its parameters."""
    where = f"{key}." if key else ""
    if value is None:
        value = {}
    if not isinstance(value, dict):
        raise ScenarioError(source, key or "<top level>", f"expected a mapping of keys, got {_describe(value)}")
    if "type" not in value and spec.default is None:
        raise ScenarioError(source, where + "type", f"missing required key; expected {spec.expected}")
    name = value.get("type", spec.default)
    if not isinstance(name, str) or not (name in spec.types or CLASS_PATH.fullmatch(name)):
        raise ScenarioError(source, where + "type", f"expected {spec.expected}, got {_describe(name)}")
    if name in spec.types:
        schema = spec.types[name]
    else:
        cls = _user_class(name, spec, source, where + "type")
        schema = getattr(cls, "SCHEMA", None)
        if not isinstance(schema, Schema):
            params = {k: v for k, v in value.items() if k != "type"}
            _check_signature(cls, name, params, source, key)
            return {"type": name, **params}
    return validate(value, Schema({"type": spec.type_field(), **schema.fields}, schema.presets, schema.legacy,
                                  schema.checks, schema.upgrade), source, key)


def _user_class(name: str, spec: Typed, source: str, key: str) -> type:
    try:
        cls = import_class(name)
    except Exception as e:  # whatever importing the user's module raised, as one error naming the key
        raise ScenarioError(source, key, f"cannot import {name} ({type(e).__name__}: {e}); expected "
                                         f"module.path:ClassName naming a class Python can import") from None
    missing = [m for m in spec.methods if not callable(getattr(cls, m, None))]
    if missing:
        raise ScenarioError(source, key, f"{name} has no method {', '.join(missing)}; expected a {spec.role} "
                                         f"with the methods {', '.join(spec.methods)}")
    return cls


def _check_signature(cls: type, name: str, params: dict, source: str, key: str) -> None:
    """The parameters against the class's constructor: a name it does not take is an unknown key."""
    signature = inspect.signature(cls)
    keywords = [p.name for p in signature.parameters.values()
                if p.kind in (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)]
    takes_any = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in signature.parameters.values())
    where = f"{key}." if key else ""
    for k in params:
        if k not in keywords and not takes_any:
            raise ScenarioError(source, f"{where}{k}",
                                f"unknown key; expected one of: type, {', '.join(keywords)} (the parameters of {name})")
    try:
        signature.bind(**params)
    except TypeError as e:
        raise ScenarioError(source, key or "<top level>", f"{name} cannot be made from these parameters: {e}; "
                                                          f"expected its constructor's parameters") from None
