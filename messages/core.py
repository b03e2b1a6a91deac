"""Typed messages: frozen dataclasses with a registered schema id ``name/version``.

A message class is declared with :func:`message`::

    @message("camera.Frame", 1)
    class Frame:
        stamp: int = 0          # ns, CLOCK_MONOTONIC at capture of the originating frame
        seq: int = 0            # frame number
        image: np.ndarray = EMPTY
        encoding: str = "bgr8"

Every message carries ``stamp`` and ``seq``; the decorator adds them (with default 0) when the class
does not declare them. Field types are plain Python types, ``np.ndarray``, lists/tuples/dicts of them,
``X | None`` and nested :func:`struct` dataclasses (which may hold arrays themselves). Fields added in
a later version must have defaults, so that messages from older senders still decode.
"""

from __future__ import annotations

import dataclasses
import functools
import sys
import types
import typing
from collections.abc import Callable
from typing import Any, TypeVar

import numpy as np

T = TypeVar("T")

#: schema id ("name/version") -> message class
REGISTRY: dict[str, type] = {}

EMPTY = np.zeros(0, dtype=np.float32)
EMPTY.setflags(write=False)


def _same(value: Any) -> Any:
    return value


def empty_array() -> np.ndarray:
    """Default factory for array fields (a shared read-only empty float32 array)."""
    return EMPTY


def schema_id(cls_or_msg: Any) -> str:
    """The ``name/version`` id of a message class or instance.

    Parameters
    ----------
    cls_or_msg : type or Any
        A message class or a message.

    Returns
    -------
    str
        The schema id, ``name/version``.

    Raises
    ------
    TypeError
        If the class is not a registered message class.
    """
    cls = cls_or_msg if isinstance(cls_or_msg, type) else type(cls_or_msg)
    try:
        return cls.__schema_id__
    except AttributeError:
        raise TypeError(f"{cls.__name__} is not a registered message class (use @message)") from None


def _add_stamp_seq(cls: type) -> None:
    ann = cls.__dict__.get("__annotations__", {})
    if "stamp" not in ann or "seq" not in ann:
        # stamp and seq go first so that positional construction stays predictable
        new_ann = {"stamp": int, "seq": int}
        new_ann.update(ann)
        cls.__annotations__ = new_ann
        if "stamp" not in cls.__dict__:
            cls.stamp = 0
        if "seq" not in cls.__dict__:
            cls.seq = 0


def _array_defaults(cls: type) -> None:
    """Mutable defaults (arrays, lists, dicts) become default factories; ``list`` fields default to
    lists even when written as ``= ()``, so that a decoded message equals a constructed one.
    """
    ann = cls.__dict__.get("__annotations__", {})
    for name, default in list(cls.__dict__.items()):
        if name not in ann:
            continue
        if isinstance(default, np.ndarray):
            factory = functools.partial(_same, default)
        elif isinstance(default, (list, tuple)) and str(ann[name]).startswith(("list", "typing.List")):
            factory = functools.partial(list, tuple(default))
        elif isinstance(default, dict):
            factory = functools.partial(dict, dict(default))
        else:
            continue
        setattr(cls, name, dataclasses.field(default_factory=factory))


def struct(cls: type[T]) -> type[T]:
    """A frozen dataclass usable as a nested field type inside messages (no schema id of its own).

    Parameters
    ----------
    cls : type
        The class to decorate.

    Returns
    -------
    type
        The frozen, keyword-only dataclass.
    """
    _array_defaults(cls)
    dc = dataclasses.dataclass(frozen=True, kw_only=True)(cls)
    dc.__struct__ = True
    return dc


def message(name: str, version: int) -> Callable[[type[T]], type[T]]:
    """Register a frozen dataclass as message ``name/version``.

    Parameters
    ----------
    name : str
        The message's name, e.g. ``"camera.Frame"``: non-empty, without '/'.
    version : int
        The schema version, >= 1.

    Returns
    -------
    callable
        The class decorator: it adds ``stamp`` and ``seq`` where the class lacks them, makes the class a
        frozen, keyword-only dataclass and registers it in ``REGISTRY``.

    Raises
    ------
    ValueError
        For a bad name or version, and (from the decorator) when the schema id is registered twice by
        different classes.
    """
    if "/" in name or not name:
        raise ValueError(f"message name {name!r} must be non-empty and contain no '/'")
    if not isinstance(version, int) or version < 1:
        raise ValueError(f"message version must be an int >= 1, got {version!r}")

    def wrap(cls: type[T]) -> type[T]:
        _add_stamp_seq(cls)
        _array_defaults(cls)
        dc = dataclasses.dataclass(frozen=True, kw_only=True)(cls)
        sid = f"{name}/{version}"
        if sid in REGISTRY and REGISTRY[sid].__qualname__ != dc.__qualname__:
            raise ValueError(f"schema id {sid} registered twice ({REGISTRY[sid].__qualname__}, {dc.__qualname__})")
        dc.__schema_id__ = sid
        dc.__struct__ = True
        REGISTRY[sid] = dc
        return dc

    return wrap


def lookup(sid: str) -> type:
    """The message class registered under ``sid``.

    Parameters
    ----------
    sid : str
        The schema id, ``name/version``.

    Returns
    -------
    type
        The message class.

    Raises
    ------
    KeyError
        For an unknown id (the message lists the known ids).
    """
    try:
        return REGISTRY[sid]
    except KeyError:
        raise KeyError(f"unknown message schema {sid!r}; known: {', '.join(sorted(REGISTRY))}") from None


def by_name(name: str) -> type:
    """Resolve a type name as written in launch files: ``camera.Frame`` or ``camera.Frame/1``.

    Without a version the highest registered version is returned.

    Parameters
    ----------
    name : str
        ``name`` or ``name/version``.

    Returns
    -------
    type
        The message class.

    Raises
    ------
    KeyError
        For an unknown name (the message lists the known ids).
    """
    if "/" in name:
        return lookup(name)
    versions = [(int(s.rsplit("/", 1)[1]), c) for s, c in REGISTRY.items() if s.rsplit("/", 1)[0] == name]
    if not versions:
        raise KeyError(f"unknown message type {name!r}; known: {', '.join(sorted(REGISTRY))}")
    return max(versions, key=lambda vc: vc[0])[1]


def field_types(cls: type) -> dict[str, Any]:
    """Resolved type hints of a message or struct class (cached on the class).

    Parameters
    ----------
    cls : type
        A message or struct class.

    Returns
    -------
    dict of str to Any
        Field name -> resolved type, in field order.
    """
    cached = cls.__dict__.get("__cp_hints__")
    if cached is None:
        module = sys.modules.get(cls.__module__)
        ns = dict(vars(module)) if module else {}
        ns.setdefault("np", np)
        cached = typing.get_type_hints(cls, globalns=ns)
        cached = {f.name: cached[f.name] for f in dataclasses.fields(cls)}
        cls.__cp_hints__ = cached
    return cached


def describe(cls: type) -> dict[str, Any]:
    """A JSON-able description of a message class (stored in bags so they are self-describing).

    Parameters
    ----------
    cls : type
        A message or struct class.

    Returns
    -------
    dict of str to Any
        ``schema`` (the schema id, or the class name for a struct) and ``fields`` (field name -> type
        name, as :func:`type_name` writes it).
    """
    out: dict[str, Any] = {"schema": getattr(cls, "__schema_id__", cls.__qualname__), "fields": {}}
    for fname, tp in field_types(cls).items():
        out["fields"][fname] = type_name(tp)
    return out


def type_name(tp: Any) -> str:
    """A readable name of a field type.

    Parameters
    ----------
    tp : Any
        A resolved type hint.

    Returns
    -------
    str
        Its name, e.g. ``list[int]``, ``str | None``, or ``struct Name{field: type, ...}`` for a struct.
    """
    origin = typing.get_origin(tp)
    if origin is None:
        if dataclasses.is_dataclass(tp):
            return "struct " + describe_struct(tp)
        return getattr(tp, "__name__", str(tp))
    args = ", ".join(type_name(a) for a in typing.get_args(tp))
    if origin in (typing.Union, types.UnionType):
        return " | ".join(type_name(a) for a in typing.get_args(tp))
    return f"{getattr(origin, '__name__', str(origin))}[{args}]"


def describe_struct(tp: type) -> str:
    """A readable description of a struct class: its name and its fields' types.

    Parameters
    ----------
    tp : type
        A struct class.

    Returns
    -------
    str
        ``Name{field: type, ...}``.
    """
    inner = ", ".join(f"{k}: {type_name(v)}" for k, v in field_types(tp).items())
    return f"{tp.__qualname__}{{{inner}}}"
