"""The codec's fast path: what the bus bench showed is worth its code, kept out of the plain path.

:mod:`counterpart.messages.codec` is the codec a reader should start from: it walks a message's
fields, packs the header with ``msgpack.packb``, and makes the message with its constructor. This
module holds the shortcuts the codec takes instead where they pay end to end, each with the plain
function it stands for:

- :func:`flat_encoder` (for ``codec.encode_plain``): for a message whose fields are all Python
  scalars or ``np.ndarray``, one closure per class reads every field in one ``attrgetter`` call
  and builds the header in one pass; a value of another type (a numpy scalar, a strided view)
  sends the whole message to the plain encoder. Same bytes either way.
- :func:`flat_decoder` (for ``codec.build_plain``): reads every field in one ``itemgetter`` call
  and accepts the values when each has exactly its declared type; anything else (a missing field,
  an ``int`` for a ``float``, a bad value) goes to the plain builder, which converts it or raises
  the same error. The frozen instance is filled through its ``__dict__``, as the dataclass's own
  ``__init__`` would fill it, without its call per field (a class with ``__post_init__``, which
  checks its values, is made by its constructor).
- :func:`unpack_header` (for ``msgpack.unpackb``): ext values (the array references) come back as
  ``slice(code, data)``: the builtin keeps both without running Python code, where msgpack's
  ``ExtType`` runs a Python constructor per reference. ``codec.array_index`` reads either.
- :class:`HeaderPacker` (for ``msgpack.packb``): one reusable ``msgpack.Packer`` per thread.

The trade: four small pieces to keep equal to the plain ones (``tests/test_codec_paths.py`` checks
bytes and objects of every registered message type through both), against the time they save on
every message a node sends and receives. ``bench/bus_latency.py`` measures it end to end, fast
against plain against raw pyzmq, as ``codec_fast_vs_plain_*`` (below 1: the fast path pays).
Code generated with ``exec`` is gone: these closures do its work. This module imports nothing of
the codec: the plain functions are handed in. (The one shortcut outside it is the transport's frame
send, ``counterpart.bus.transport._send_multipart``, with its own figure.)
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from operator import attrgetter, itemgetter
from typing import Any

import msgpack
import numpy as np

from .core import field_types

Encoder = Callable[[Any, "int | None"], list[Any]]
Decoder = Callable[[dict[str, Any], list[np.ndarray]], Any]

#: declared field types a flat message may have besides ``np.ndarray``
FLAT_SCALARS = (int, float, bool, str, bytes)
#: value types that travel in msgpack as they are
WIRE_SCALARS = frozenset((bool, int, float, str, bytes, type(None)))


class HeaderPacker(threading.local):
    """``msgpack.packb(head, use_bin_type=True)`` with a reusable per-thread packer: ``packb`` makes
    and frees a packer and its buffer on every call.
    """

    def __init__(self) -> None:
        self.packer = msgpack.Packer(use_bin_type=True)

    def __call__(self, head: dict[str, Any]) -> bytes:
        """The packed header.

        Parameters
        ----------
        head : dict of str to Any
            The header.

        Returns
        -------
        bytes
            ``head`` packed by msgpack (binary type for bytes).
        """
        return self.packer.pack(head)


pack_header = HeaderPacker()


def unpack_header(buf: memoryview) -> Any:
    """``msgpack.unpackb(buf, max_ext_len=16)`` with ext values as ``slice(code, data)``.

    Parameters
    ----------
    buf : memoryview
        A packed header.

    Returns
    -------
    Any
        The unpacked header.
    """
    return msgpack.unpackb(buf, max_ext_len=16, ext_hook=slice)


def unpacked_ref(code: int, index: int) -> slice:
    """An array reference as :func:`unpack_header` returns it.

    Parameters
    ----------
    code : int
        The msgpack ext code.
    index : int
        The index of the buffer referenced.

    Returns
    -------
    slice
        ``slice(code, data)``, data the index as 4 little-endian bytes.
    """
    return slice(code, index.to_bytes(4, "little"))


def is_flat(cls: type) -> bool:
    """Every field of a message class is declared a Python scalar or an ``np.ndarray``.

    Parameters
    ----------
    cls : type
        A registered message class.

    Returns
    -------
    bool
        Whether every field's declared type is one of ``FLAT_SCALARS`` or ``np.ndarray``.
    """
    return all(tp is np.ndarray or tp in FLAT_SCALARS for tp in field_types(cls).values())


def _getter(get: Callable[[Any], Any], n: int) -> Callable[[Any], tuple[Any, ...]]:
    """``attrgetter``/``itemgetter`` of ``n`` names always returning a tuple (one name: a value)."""
    return get if n > 1 else (lambda obj: (get(obj),))


def flat_encoder(cls: type, plain: Encoder, array_ref: Callable[[int], Any]) -> Encoder:
    """``encode(msg, counter) -> [header, buffers...]`` for a flat message class ``cls``.

    Parameters
    ----------
    cls : type
        A registered message class for which :func:`is_flat` holds.
    plain : Encoder
        The plain encoder, for messages whose values are not all of the flat kinds.
    array_ref : callable
        The header's reference to buffer k (an msgpack ext value).

    Returns
    -------
    Encoder
        Writes the same bytes as ``plain``.
    """
    hints = field_types(cls)
    names = tuple(hints)
    at_array = tuple(i for i, n in enumerate(names) if hints[n] is np.ndarray)
    at_scalar = tuple(i for i in range(len(names)) if i not in at_array)
    refs = tuple(array_ref(k) for k in range(len(at_array)))
    get = _getter(attrgetter(*names), len(names))
    sid = cls.__schema_id__
    dtype_str: dict[np.dtype, str] = {}  # dtype.str builds a new string on every call

    def encode(msg: Any, counter: int | None) -> list[Any]:
        values = list(get(msg))
        for i in at_scalar:
            if type(values[i]) not in WIRE_SCALARS:
                return plain(msg, counter)
        arrays = []
        for k, i in enumerate(at_array):
            a = values[i]
            if type(a) is not np.ndarray or not a.flags.c_contiguous:
                return plain(msg, counter)
            arrays.append(a)
            values[i] = refs[k]
        specs = []
        for a in arrays:
            text = dtype_str.get(a.dtype)
            if text is None:
                text = dtype_str[a.dtype] = a.dtype.str
            specs.append([text, list(a.shape)])
        head = {"s": sid, "f": dict(zip(names, values)), "a": specs}
        if counter is not None:
            head["n"] = counter
        return [pack_header(head), *(a.data if a.size else b"" for a in arrays)]

    return encode


def flat_decoder(cls: type, plain: Decoder, array_ref: Callable[[int], Any]) -> Decoder:
    """``decode(fields, arrays) -> instance`` of a flat message class ``cls`` from a header's field
    map and the checked arrays.

    Parameters
    ----------
    cls : type
        A registered message class for which :func:`is_flat` holds.
    plain : Decoder
        The plain builder, for headers whose values are not exactly as the fast encoder writes them.
    array_ref : callable
        The reference to buffer k as the header unpacker returns it.

    Returns
    -------
    Decoder
        Returns what ``plain`` returns, or raises what it raises.
    """
    hints = field_types(cls)
    names = tuple(hints)
    at_array = tuple(i for i, n in enumerate(names) if hints[n] is np.ndarray)
    at_scalar = tuple(i for i in range(len(names)) if i not in at_array)
    scalar_types = tuple(hints[names[i]] for i in at_scalar)
    refs = tuple(array_ref(k) for k in range(len(at_array)))
    get = _getter(itemgetter(*names), len(names))
    checked = hasattr(cls, "__post_init__")
    new = object.__new__

    def decode(fields: dict[str, Any], arrays: list[np.ndarray]) -> Any:
        try:
            values = list(get(fields))
        except KeyError:  # a field left out (an older sender): the plain builder fills defaults
            return plain(fields, arrays)
        if len(arrays) != len(refs) or tuple(type(values[i]) for i in at_scalar) != scalar_types:
            return plain(fields, arrays)
        for k, i in enumerate(at_array):
            if values[i] != refs[k]:
                return plain(fields, arrays)
            values[i] = arrays[k]
        if checked:
            return cls(**dict(zip(names, values)))
        obj = new(cls)
        obj.__dict__.update(zip(names, values))
        return obj

    return decode


__all__ = [
    "flat_encoder",
    "flat_decoder",
    "is_flat",
    "pack_header",
    "unpack_header",
    "unpacked_ref",
    "HeaderPacker",
    "FLAT_SCALARS",
]
