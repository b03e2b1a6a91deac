"""Per-class encoders and decoders, written out once per message class.

The generic codec (:mod:`counterpart.messages.codec`) walks a class's fields with a loop of lookups and calls
per field. For the small messages that make up most of a graph's traffic that walk cost more than the
socket send itself, and it runs cold (the process has just woken up for the message), where every
extra bytecode shows. So, the way :mod:`dataclasses` writes ``__init__``, each class gets two
functions with one straight-line block per field:

- the encoder builds the header map in one expression when every field already holds its wire
  type (Python scalars, C-contiguous arrays, whose buffer references are then fixed per class) and
  hands any other message (numpy scalars, lists, dicts, nested structs, strided views) to
  ``encode_generic``; the header is the same msgpack map, byte for byte, either way;
- the decoder accepts a value of exactly the declared scalar type inline and hands every other value
  to the generic checker, which converts it (``int`` to ``float``) or raises the same
  :class:`~counterpart.messages.codec.DecodeError` with the same ``where``.

Nothing here changes what is accepted or refused; ``tests/test_messages.py`` checks both paths agree.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import msgpack
import numpy as np

from .core import field_types

#: declared scalar types whose values the decoder accepts inline when their type matches exactly
_INLINE_SCALARS = (int, float, bool, str, bytes)

Encoder = Callable[[Any, "int | None"], list[Any]]
Decoder = Callable[[dict[str, Any], list[np.ndarray]], Any]


_DTYPE_STR: dict[np.dtype, str] = {}


def _dtype_str(dtype: np.dtype) -> str:
    """``dtype.str`` (which builds a new string on every call), remembered per dtype."""
    text = _DTYPE_STR.get(dtype)
    if text is None:
        text = _DTYPE_STR[dtype] = dtype.str
    return text


def _compile(name: str, lines: list[str], namespace: dict[str, Any]) -> Callable[..., Any]:
    exec("\n".join(lines), namespace)  # noqa: S102 - source built above from field names only
    return namespace[name]


def compile_encoder(cls: type) -> Encoder:
    """``encode(msg, counter) -> [header, buffers...]`` for instances of message class ``cls``.

    The written-out path covers a message whose scalar fields hold Python scalars and whose
    ``np.ndarray`` fields hold C-contiguous arrays; any other value (a numpy scalar, a list, a
    nested struct, a strided view) sends the whole message through ``encode_generic``.
    """
    from .codec import _SCALARS, encode_generic, pack_header

    hints = field_types(cls)
    ns: dict[str, Any] = {
        "_SCALARS": _SCALARS,
        "_generic": encode_generic,
        "_ndarray": np.ndarray,
        "_dstr": _dtype_str,
        "_pack": pack_header,
        "_SID": cls.__schema_id__,
    }
    lines = ["def encode(msg, counter):"]
    wire, arrays = [], []
    for i, f in enumerate(dataclasses.fields(cls)):
        tp, v = hints[f.name], f"v{i}"
        lines.append(f"    {v} = msg.{f.name}")
        if tp is np.ndarray:
            k = len(arrays)
            ns[f"_R{k}"] = msgpack.ExtType(1, k.to_bytes(4, "little"))
            lines.append(
                f"    if type({v}) is not _ndarray or not {v}.flags.c_contiguous: return _generic(msg, counter)"
            )
            wire.append(f"{f.name!r}: _R{k}")
            arrays.append(v)
        elif tp in _INLINE_SCALARS:
            lines.append(f"    if type({v}) not in _SCALARS: return _generic(msg, counter)")
            wire.append(f"{f.name!r}: {v}")
        else:
            return encode_generic  # lists, dicts, structs: nothing to gain from a written-out copy
    specs = ", ".join(f"[_dstr({a}.dtype), list({a}.shape)]" for a in arrays)
    lines += [
        f"    head = {{'s': _SID, 'f': {{{', '.join(wire)}}}, 'a': [{specs}]}}",
        "    if counter is not None:",
        "        head['n'] = counter",
        "    return [_pack(head)" + "".join(f", {a}.data if {a}.size else b''" for a in arrays) + "]",
    ]
    return _compile("encode", lines, ns)


def compile_decoder(cls: type) -> Decoder:
    """``decode(fields, arrays) -> instance`` of message class ``cls`` from a header's field map and
    the already checked arrays; raises DecodeError like :func:`counterpart.messages.codec._build`.
    """
    from .codec import DecodeError, _array, _check

    hints = field_types(cls)
    prefix = cls.__schema_id__
    ns: dict[str, Any] = {
        "_MISSING": dataclasses.MISSING,
        "_array": _array,
        "_check": _check,
        "DecodeError": DecodeError,
        "_new": object.__new__,
        "_cls": cls,
    }
    lines = ["def decode(f, arrays):"]
    names = []
    for i, fld in enumerate(dataclasses.fields(cls)):
        tp, v, where = hints[fld.name], f"v{i}", f"{prefix}.{fld.name}"
        names.append((fld.name, v))
        ns[f"_t{i}"] = tp
        lines.append(f"    {v} = f.get({fld.name!r}, _MISSING)")
        if fld.default is not dataclasses.MISSING:
            ns[f"_d{i}"] = fld.default
            lines.append(f"    if {v} is _MISSING: {v} = _d{i}")
        elif fld.default_factory is not dataclasses.MISSING:
            ns[f"_f{i}"] = fld.default_factory
            lines.append(f"    if {v} is _MISSING: {v} = _f{i}()")
        else:
            lines.append(
                f"    if {v} is _MISSING: raise DecodeError('bad_field', {f'{prefix}: required field {fld.name!r} is missing'!r})"
            )
        if tp is np.ndarray:
            lines.append(f"    else: {v} = _array({v}, arrays, {where!r})")
        elif tp in _INLINE_SCALARS:
            lines.append(f"    elif type({v}) is not _t{i}: {v} = _check({v}, _t{i}, arrays, {where!r})")
        else:
            lines.append(f"    else: {v} = _check({v}, _t{i}, arrays, {where!r})")
    values = ", ".join(f"{n}={v}" for n, v in names)
    if hasattr(cls, "__post_init__"):
        lines.append(f"    return _cls({values})")
    else:
        # frozen dataclass filled without __init__ (a setattr call per field, which shows on small messages)
        lines += ["    obj = _new(_cls)", f"    obj.__dict__.update({values})", "    return obj"]
    return _compile("decode", lines, ns)


__all__ = ["compile_encoder", "compile_decoder", "Encoder", "Decoder"]
