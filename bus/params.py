"""Node parameters: declared with types, defaults and checks; validated before anything starts."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import yaml


class ParamError(ValueError):
    """A parameter that is unknown, of the wrong type or out of range; the message names it."""


_TYPE_NAMES = {int: "int", float: "float", str: "str", bool: "bool", list: "list", dict: "dict"}


@dataclass(frozen=True)
class Param:
    """A typed parameter.

    Parameters
    ----------
    type : type
        The parameter's type (int, float, str, bool, list or dict).
    default : Any, default=None
        Its default; None with ``type`` set means optional.
    doc : str, default=""
        One line of help.
    choices : tuple or None, default=None
        The allowed values, checked.
    min, max : float or None, default=None
        The allowed range, checked.
    check : callable or None, default=None
        Called with the value; may raise or return an error string (falsy for OK).
    """

    type: type
    default: Any = None
    doc: str = ""
    choices: tuple[Any, ...] | None = None
    min: float | None = None
    max: float | None = None
    check: Callable[[Any], str | None] | None = field(default=None, compare=False)

    def coerce(self, name: str, value: Any) -> Any:
        """The value converted to ``type`` and checked.

        Parameters
        ----------
        name : str
            The parameter's name, for the error message.
        value : Any
            The given value; a string is parsed as YAML when ``type`` is not str.

        Returns
        -------
        Any
            The value of type ``type`` (None stays None).

        Raises
        ------
        ParamError
            Naming the parameter, for a value that cannot be parsed, of the wrong type, not one of
            ``choices``, out of [``min``, ``max``] or refused by ``check``.
        """
        tp = self.type
        if value is None:
            return None
        if isinstance(value, str) and tp is not str:
            try:
                value = yaml.safe_load(value)
            except yaml.YAMLError as exc:
                raise ParamError(f"parameter {name!r}: cannot parse {value!r}: {exc}") from None
        if tp is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if tp is str and isinstance(value, (int, float)) and not isinstance(value, bool):
            value = str(value)
        if tp is list and isinstance(value, tuple):
            value = list(value)
        if not isinstance(value, tp) or (tp is int and isinstance(value, bool)):
            raise ParamError(
                f"parameter {name!r}: expected {_TYPE_NAMES.get(tp, tp.__name__)}, got {value!r} ({type(value).__name__})"
            )
        if self.choices is not None and value not in self.choices:
            raise ParamError(f"parameter {name!r}: {value!r} is not one of {', '.join(map(repr, self.choices))}")
        if self.min is not None and value < self.min:
            raise ParamError(f"parameter {name!r}: {value!r} is below the minimum {self.min}")
        if self.max is not None and value > self.max:
            raise ParamError(f"parameter {name!r}: {value!r} is above the maximum {self.max}")
        if self.check is not None:
            problem = self.check(value)
            if problem:
                raise ParamError(f"parameter {name!r}: {problem}")
        return value


def resolve_params(specs: Mapping[str, Param], given: Mapping[str, Any], where: str = "") -> dict[str, Any]:
    """Defaults overlaid with ``given``; every value coerced and checked.

    Parameters
    ----------
    specs : Mapping of str to Param
        The declared parameters.
    given : Mapping of str to Any
        The given values.
    where : str, default=""
        Where they come from, for the error message (e.g. ``demo.yaml: node 'tracker'``).

    Returns
    -------
    dict of str to Any
        Every declared parameter's value.

    Raises
    ------
    ParamError
        Naming ``where`` and the parameter, for an unknown parameter or a bad value.
    """
    prefix = f"{where}: " if where else ""
    unknown = sorted(set(given) - set(specs))
    if unknown:
        known = ", ".join(sorted(specs)) or "(none)"
        raise ParamError(f"{prefix}unknown parameter(s) {', '.join(map(repr, unknown))}; known: {known}")
    out: dict[str, Any] = {}
    for name, spec in specs.items():
        try:
            out[name] = spec.coerce(name, given.get(name, spec.default))
        except ParamError as exc:
            raise ParamError(f"{prefix}{exc}") from None
    return out


def parse_assignments(items: list[str] | None, what: str = "--param") -> dict[str, Any]:
    """``["a=1", "b=x"]`` -> ``{"a": "1", "b": "x"}`` (values are coerced later by type).

    Parameters
    ----------
    items : list of str or None
        ``KEY=VALUE`` assignments.
    what : str, default="--param"
        The option they come from, for the error message.

    Returns
    -------
    dict of str to Any
        Key -> value string.

    Raises
    ------
    ParamError
        For an item that is not ``KEY=VALUE``.
    """
    out: dict[str, Any] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise ParamError(f"{what} {item!r}: expected KEY=VALUE")
        out[key.strip()] = value
    return out
