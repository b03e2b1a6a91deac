"""Wire codec: ``[topic, msgpack header, raw buffer, raw buffer, ...]``.

The header is a msgpack map ``{"s": schema id, "f": fields, "a": [[dtype, shape], ...]}``. Arrays
never travel inside msgpack: each one is replaced in ``f`` by an ext reference (code 1, the index of
its buffer) and sent as its own ZeroMQ frame, so that large images go out and come in without
copies (``np.frombuffer`` over the received frame; decoded arrays are read-only views).

Decoding is defensive, because anything can connect to a socket: the header size, the msgpack
container sizes, the number of arrays, their dtypes, ranks and byte sizes are all bounded, the schema
id must be registered, and every field is checked against the class's type hints. Anything wrong
raises :class:`DecodeError` with a short ``kind`` that receivers count and log once per kind.

This module is the plain codec (:func:`encode_plain`, :func:`build_plain`): read it to know what
goes on the wire. :func:`encode` and :func:`decode` take the shortcuts of
:mod:`counterpart.messages.fastpath` where they apply (the trade is written there); both paths give
the same bytes and the same messages.
"""

from __future__ import annotations

import dataclasses
import functools
import types
import typing
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import msgpack
import numpy as np

from . import fastpath
from .core import REGISTRY, field_types, schema_id

ARRAY_EXT = 1
ALLOWED_DTYPES = frozenset(
    np.dtype(t).str for t in ("?", "u1", "u2", "u4", "u8", "i1", "i2", "i4", "i8", "f2", "f4", "f8", "c8", "c16")
)


@dataclass(frozen=True)
class Limits:
    """Upper bounds enforced while decoding (bytes unless stated).

    Parameters
    ----------
    max_header : int, default=1 << 20
        Size of the msgpack header, bytes.
    max_arrays : int, default=4096
        Arrays of a message whose class is not known here (or holds ``Any`` fields); a known class
        allows what its fields can hold (:func:`array_capacity`).
    max_items : int, default=256
        Items per list or dict counted for a known class's capacity (people per frame).
    max_ndim : int, default=8
        Rank of an array.
    max_array_bytes : int, default=256 << 20
        Size of one array, bytes.
    max_total_bytes : int, default=512 << 20
        Size of all arrays of a message, bytes.
    max_container_len : int, default=1 << 16
        Length of a list or map in the header (a header no larger than this is bounded by its own size).
    """

    max_header: int = 1 << 20
    #: arrays of a message whose class is not known here (or holds ``Any`` fields); a known class
    #: allows what its fields can hold, counting ``max_items`` items per list (people per frame)
    max_arrays: int = 4096
    max_items: int = 256
    max_ndim: int = 8
    max_array_bytes: int = 256 << 20
    max_total_bytes: int = 512 << 20
    max_container_len: int = 1 << 16


DEFAULT_LIMITS = Limits()


class DecodeError(ValueError):
    """A received message that cannot be decoded.

    Parameters
    ----------
    kind : str
        Short category used for counting (``malformed``, ``oversized``, ``unknown_schema``, ``bad_array``,
        ``bad_field``).
    detail : str
        What was wrong, for the log.
    """

    def __init__(self, kind: str, detail: str) -> None:
        super().__init__(f"{kind}: {detail}")
        self.kind = kind
        self.detail = detail


# ----------------------------------------------------------------------------------------- encode


_SCALARS = (bool, int, float, str, bytes, type(None))
#: an ext value (array reference) as the header unpacker returns it: plain, fast path
_EXT_TYPES = (msgpack.ExtType, slice)


def array_ref(index: int) -> msgpack.ExtType:
    """The header's reference to buffer ``index``.

    Parameters
    ----------
    index : int
        Position of the buffer among the message's arrays (0 = first buffer after the header).

    Returns
    -------
    msgpack.ExtType
        Ext type ``ARRAY_EXT`` holding ``index`` as 4 little-endian bytes.
    """
    return msgpack.ExtType(ARRAY_EXT, index.to_bytes(4, "little"))


def _to_wire(value: Any, arrays: list[np.ndarray]) -> Any:
    if type(value) in _SCALARS:
        return value
    if isinstance(value, np.ndarray):
        arrays.append(value)
        return array_ref(len(arrays) - 1)
    if isinstance(value, (bool, int, float, str, bytes)) or value is None:
        return value
    if isinstance(value, (np.integer, np.floating, np.bool_)):
        return value.item()
    if isinstance(value, (list, tuple)):
        return [_to_wire(v, arrays) for v in value]
    if isinstance(value, dict):
        return {k: _to_wire(v, arrays) for k, v in value.items()}
    if dataclasses.is_dataclass(value):
        return {n: _to_wire(getattr(value, n), arrays) for n in field_types(type(value))}
    raise TypeError(f"cannot encode value of type {type(value).__name__}")


def encode_plain(msg: Any, counter: int | None = None) -> list[Any]:
    """The reference encoder: every field to its wire form, the header packed by ``msgpack.packb``.

    Parameters
    ----------
    msg
        An instance of a registered message class.
    counter
        The publisher's send count, for drop detection (None: not sent).

    Returns
    -------
    list
        The header bytes, then one buffer per array (not copied unless not C-contiguous).
    """
    arrays: list[np.ndarray] = []
    fields = {n: _to_wire(getattr(msg, n), arrays) for n in field_types(type(msg))}
    contiguous = [a if a.flags.c_contiguous else np.ascontiguousarray(a) for a in arrays]
    head = {"s": schema_id(msg), "f": fields, "a": [[a.dtype.str, list(a.shape)] for a in contiguous]}
    if counter is not None:
        head["n"] = counter
    return [msgpack.packb(head, use_bin_type=True), *(a.data if a.size else b"" for a in contiguous)]


#: the fast path in use (:func:`use_fast_path`)
FAST = True
#: message class -> its encoder / decoder (made on first use)
_ENCODERS: dict[type, Callable[[Any, int | None], list[Any]]] = {}
_DECODERS: dict[type, Callable[[dict[str, Any], list[np.ndarray]], Any]] = {}


def use_fast_path(on: bool) -> None:
    """Take the shortcuts of :mod:`counterpart.messages.fastpath` (the default) or the plain path
    alone (the bus bench compares the two; the equivalence test runs both).

    Parameters
    ----------
    on : bool
        True: use the fast path where it applies; False: the plain encoder and decoder only. The cached
        per-class encoders and decoders are cleared either way.
    """
    global FAST
    FAST = bool(on)
    _ENCODERS.clear()
    _DECODERS.clear()


def encode(msg: Any, counter: int | None = None) -> list[Any]:
    """Header bytes followed by one buffer per array (no topic frame): :func:`encode_plain`'s
    bytes, through the fast path where it applies.

    Parameters
    ----------
    msg : object
        An instance of a registered message class.
    counter : int or None, default=None
        The publisher's send count, for drop detection (None: not sent).

    Returns
    -------
    list
        The header bytes, then one buffer per array.

    Raises
    ------
    TypeError
        When ``msg`` is not an instance of a registered message class.
    """
    enc = _ENCODERS.get(type(msg))
    if enc is None:
        cls = type(msg)
        schema_id(msg)  # TypeError for anything that is not a registered message
        flat = FAST and fastpath.is_flat(cls)
        enc = _ENCODERS[cls] = fastpath.flat_encoder(cls, encode_plain, array_ref) if flat else encode_plain
    return enc(msg, counter)


def encode_frames(topic: str | bytes, msg: Any) -> list[Any]:
    """The full multipart message ``[topic, header, buffers...]``.

    Parameters
    ----------
    topic : str or bytes
        The topic frame (str is UTF-8 encoded).
    msg : object
        An instance of a registered message class.

    Returns
    -------
    list
        The topic bytes, the header bytes, then one buffer per array.
    """
    t = topic.encode() if isinstance(topic, str) else topic
    return [t, *encode(msg)]


# ----------------------------------------------------------------------------------------- decode


def _buffer(frame: Any) -> memoryview:
    """A memoryview over a received part: zmq.Frame (copy=False), bytes or memoryview."""
    if type(frame) is bytes:
        return memoryview(frame)
    buf = getattr(frame, "buffer", None)
    if buf is not None:
        return buf
    return memoryview(frame)


def read_header(raw: Any, limits: Limits = DEFAULT_LIMITS) -> dict[str, Any]:
    """Unpack and shape-check the msgpack header.

    Parameters
    ----------
    raw : zmq.Frame, bytes or memoryview
        The header part as received.
    limits : Limits, default=DEFAULT_LIMITS
        Bounds on the header's size and its containers' lengths.

    Returns
    -------
    dict
        The header map: schema id ``"s"``, fields ``"f"``, array specs ``"a"`` (optional) and send
        counter ``"n"`` (optional).

    Raises
    ------
    DecodeError
        ``oversized`` when the header exceeds ``limits.max_header`` bytes; ``malformed`` when it is not
        valid msgpack or not a map with ``"s"``, ``"f"`` and (if present) a list ``"a"``.
    """
    buf = _buffer(raw)
    size = buf.nbytes
    if size > limits.max_header:
        raise DecodeError("oversized", f"header of {size} bytes exceeds {limits.max_header}")
    try:
        if size <= limits.max_container_len:
            # msgpack bounds every string and container by the buffer's own length when no limit is
            # given, which is within ours here: the plain call is the cheaper one
            header = fastpath.unpack_header(buf) if FAST else msgpack.unpackb(buf, max_ext_len=16)
        else:
            n = limits.max_container_len
            header = msgpack.unpackb(
                buf,
                raw=False,
                strict_map_key=True,
                max_str_len=limits.max_header,
                max_bin_len=limits.max_header,
                max_array_len=n,
                max_map_len=n,
                max_ext_len=16,
                ext_hook=slice if FAST else msgpack.ExtType,  # as fastpath.unpack_header
            )
    except Exception as exc:  # msgpack raises several unrelated types on garbage
        raise DecodeError("malformed", f"header is not valid msgpack ({type(exc).__name__}: {exc})") from None
    if type(header) is not dict or type(header.get("s")) is not str:
        raise DecodeError("malformed", "header is not a map with a schema id 's'")
    if type(header.get("f")) is not dict or type(header.get("a", _NO_ARRAYS)) is not list:
        raise DecodeError("malformed", "header lacks the fields map 'f' or the array list 'a'")
    return header


_NO_ARRAYS: list[Any] = []
_DTYPES = {d: np.dtype(d) for d in ALLOWED_DTYPES}


def array_capacity(cls: type | None, limits: Limits = DEFAULT_LIMITS) -> int:
    """How many arrays a message of class ``cls`` can hold: its array fields, nested structs
    included, with ``limits.max_items`` items per list or dict (e.g. 1 + 256 people x 3 arrays for
    ``silhouette.Silhouettes``).

    Parameters
    ----------
    cls : type or None
        The message class; None when it is not known here.
    limits : Limits, default=DEFAULT_LIMITS
        Supplies ``max_items`` (items per list or dict) and ``max_arrays``.

    Returns
    -------
    int
        The array capacity; ``limits.max_arrays`` for an unknown class or ``Any`` fields.
    """
    if cls is None:
        return limits.max_arrays
    key = (cls, limits.max_items, limits.max_arrays)
    cap = _CAPACITY.get(key)
    if cap is None:
        n = _capacity(cls, limits.max_items, 0)
        cap = _CAPACITY[key] = limits.max_arrays if n is None else n
    return cap


def check_array_count(n: int, cls: type | None, limits: Limits = DEFAULT_LIMITS) -> None:
    """Check a header's array count against what a ``cls`` message can hold.

    Parameters
    ----------
    n : int
        Number of arrays the header names.
    cls : type or None
        The message class; None when it is not known here.
    limits : Limits, default=DEFAULT_LIMITS
        The bounds used by :func:`array_capacity`.

    Raises
    ------
    DecodeError
        ``oversized`` when ``n`` exceeds :func:`array_capacity` of ``cls``.
    """
    cap = array_capacity(cls, limits)
    if n > cap:
        what = getattr(cls, "__schema_id__", "a message of an unknown type")
        raise DecodeError("oversized", f"{n} arrays exceed the {cap} that {what} can hold")


#: (class, max_items, max_arrays) -> array capacity
_CAPACITY: dict[tuple[type, int, int], int] = {}


def _capacity(tp: Any, items: int, depth: int) -> int | None:
    """Arrays a value of declared type ``tp`` can hold; None when unbounded (``Any``)."""
    if tp is np.ndarray:
        return 1
    if tp is Any or depth > 16:
        return None
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin in (typing.Union, types.UnionType):
        caps = [_capacity(a, items, depth + 1) for a in args]
        return None if None in caps else max(caps)
    if origin is tuple and args and args[-1] is not Ellipsis:
        caps = [_capacity(a, items, depth + 1) for a in args]
        return None if None in caps else sum(caps)
    if origin in (list, tuple, typing.Sequence, dict):
        caps = [_capacity(a, items, depth + 1) for a in (args or (Any,))]
        return None if None in caps else items * sum(caps)
    if dataclasses.is_dataclass(tp):
        caps = [_capacity(t, items, depth + 1) for t in field_types(tp).values()]
        return None if None in caps else sum(caps)
    return 0


def _arrays(specs: list[Any], parts: Sequence[Any], limits: Limits, cls: type | None = None) -> list[np.ndarray]:
    if not specs and not parts:
        return []
    check_array_count(len(specs), cls, limits)
    if len(specs) != len(parts):
        raise DecodeError("bad_array", f"header names {len(specs)} arrays but {len(parts)} buffers arrived")
    out = []
    total = 0
    for i, spec in enumerate(specs):
        if not (type(spec) is list and len(spec) == 2 and type(spec[1]) is list):
            raise DecodeError("bad_array", f"array {i}: spec must be [dtype, shape]")
        dtype = _DTYPES.get(spec[0]) if type(spec[0]) is str else None
        if dtype is None:
            raise DecodeError("bad_array", f"array {i}: dtype {spec[0]!r} not allowed")
        shape = spec[1]
        if len(shape) > limits.max_ndim:
            raise DecodeError("bad_array", f"array {i}: rank {len(shape)} exceeds {limits.max_ndim}")
        nbytes = dtype.itemsize
        for dim in shape:
            if type(dim) is not int or dim < 0:
                raise DecodeError("bad_array", f"array {i}: bad shape {shape!r}")
            nbytes *= dim
        total += nbytes
        if nbytes > limits.max_array_bytes or total > limits.max_total_bytes:
            raise DecodeError("oversized", f"array {i}: {nbytes} bytes exceed the limits")
        buf = _buffer(parts[i])
        if buf.nbytes != nbytes:
            raise DecodeError("bad_array", f"array {i}: {buf.nbytes} bytes received, {dtype}{shape} needs {nbytes}")
        if nbytes:
            # a read-only view over the received frame (copy before changing it); making the view
            # read-only first is cheaper than clearing the array's writeable flag afterwards
            arr = np.frombuffer(buf.toreadonly(), dtype)
            if len(shape) != 1:
                arr = arr.reshape(shape)
        else:
            arr = np.zeros(shape, dtype)
            arr.flags.writeable = False
        out.append(arr)
    return out


def decode(parts: Sequence[Any], limits: Limits = DEFAULT_LIMITS) -> Any:
    """Decode ``[header, buffers...]`` (no topic frame) into a message instance.

    Parameters
    ----------
    parts : sequence of zmq.Frame, bytes or memoryview
        The header part, then one buffer per array.
    limits : Limits, default=DEFAULT_LIMITS
        Bounds enforced while decoding.

    Returns
    -------
    object
        An instance of the registered message class; its arrays are read-only views over the parts.

    Raises
    ------
    DecodeError
        As :func:`decode_counted`.
    """
    return decode_counted(parts, limits)[0]


def decode_counted(parts: Sequence[Any], limits: Limits = DEFAULT_LIMITS) -> tuple[Any, int | None]:
    """Like :func:`decode`, also returning the publisher's send counter.

    Parameters
    ----------
    parts : sequence of zmq.Frame, bytes or memoryview
        The header part, then one buffer per array.
    limits : Limits, default=DEFAULT_LIMITS
        Bounds enforced while decoding.

    Returns
    -------
    msg : object
        An instance of the registered message class.
    counter : int or None
        The publisher's send counter; None when absent.

    Raises
    ------
    DecodeError
        ``malformed`` (no header frame or a bad header), ``oversized``, ``unknown_schema`` (the schema is
        not registered here), ``bad_array`` (array specs that do not match the buffers) or ``bad_field``
        (a value the message class rejects).
    """
    if len(parts) < 1:
        raise DecodeError("malformed", "no header frame")
    header = read_header(parts[0], limits)
    cls = REGISTRY.get(header["s"])
    if cls is None:
        raise DecodeError("unknown_schema", f"schema {header['s']!r} is not registered here")
    dec = _DECODERS.get(cls)
    if dec is None:
        plain = functools.partial(build_plain, cls)
        flat = FAST and fastpath.is_flat(cls)
        ref = functools.partial(fastpath.unpacked_ref, ARRAY_EXT)
        dec = _DECODERS[cls] = fastpath.flat_decoder(cls, plain, ref) if flat else plain
    arrays = _arrays(header.get("a", _NO_ARRAYS), parts[1:], limits, cls)
    counter = header.get("n")
    try:
        msg = dec(header["f"], arrays)
    except DecodeError:
        raise
    except ValueError as exc:  # a class's own check of its values (__post_init__), e.g. a name outside the contract
        raise DecodeError("bad_field", f"{header['s']}: {exc}") from None
    return msg, counter if type(counter) is int else None


def decode_frames(frames: Sequence[Any], limits: Limits = DEFAULT_LIMITS) -> tuple[str, Any]:
    """Decode a full multipart message into ``(topic, message)``.

    Parameters
    ----------
    frames : sequence of zmq.Frame, bytes or memoryview
        The topic frame, the header, then one buffer per array.
    limits : Limits, default=DEFAULT_LIMITS
        Bounds enforced while decoding.

    Returns
    -------
    topic : str
        The topic.
    msg : object
        An instance of the registered message class.

    Raises
    ------
    DecodeError
        ``malformed`` for fewer than two frames or a topic that is not UTF-8; otherwise as :func:`decode`.
    """
    if len(frames) < 2:
        raise DecodeError("malformed", f"{len(frames)} frame(s); need at least topic and header")
    try:
        topic = bytes(_buffer(frames[0])).decode()
    except UnicodeDecodeError:
        raise DecodeError("malformed", "topic frame is not UTF-8") from None
    return topic, decode(frames[1:], limits)


@dataclass(frozen=True)
class UntypedMessage:
    """A message whose schema is not registered in this process (introspection tools, bags):
    its fields as plain values, arrays resolved.

    Parameters
    ----------
    schema : str
        The schema id from the header.
    fields : dict of str to object
        The fields as plain values, array references replaced by read-only arrays.
    """

    schema: str
    fields: dict[str, Any]

    @property
    def stamp(self) -> int:
        return int(self.fields.get("stamp", 0) or 0)

    @property
    def seq(self) -> int:
        return int(self.fields.get("seq", 0) or 0)


def decode_any(parts: Sequence[Any], limits: Limits = DEFAULT_LIMITS) -> tuple[Any, int | None]:
    """Decode typed when the schema is registered here, else as an :class:`UntypedMessage`.

    Parameters
    ----------
    parts : sequence of zmq.Frame, bytes or memoryview
        The header part, then one buffer per array.
    limits : Limits, default=DEFAULT_LIMITS
        Bounds enforced while decoding.

    Returns
    -------
    msg : object or UntypedMessage
        The message instance, or an :class:`UntypedMessage` for a schema not registered here.
    counter : int or None
        The publisher's send counter; None when absent.

    Raises
    ------
    DecodeError
        As :func:`decode_counted`.
    """
    if len(parts) < 1:
        raise DecodeError("malformed", "no header frame")
    header = read_header(parts[0], limits)
    if header["s"] in REGISTRY:
        return decode_counted(parts, limits)
    arrays = _arrays(header.get("a", []), parts[1:], limits)
    counter = header.get("n")
    return UntypedMessage(header["s"], _resolve_any(header["f"], arrays)), counter if type(counter) is int else None


# ------------------------------------------------------------------------------ type validation


_MISSING = dataclasses.MISSING
#: class -> per-field decoding plan: (name, type, fast checker or None, where, default, factory)
_PLANS: dict[type, tuple[tuple[Any, ...], ...]] = {}


def _plan(cls: type) -> tuple[tuple[Any, ...], ...]:
    """Everything about ``cls``'s fields that decoding needs, worked out once per class."""
    plan = _PLANS.get(cls)
    if plan is None:
        prefix = getattr(cls, "__schema_id__", cls.__qualname__)
        hints = field_types(cls)
        plan = _PLANS[cls] = tuple(
            (f.name, hints[f.name], _CHECKERS.get(hints[f.name]), f"{prefix}.{f.name}", f.default, f.default_factory)
            for f in dataclasses.fields(cls)
        )
    return plan


def build_plain(cls: type, fields: dict[str, Any], arrays: list[np.ndarray], where: str = "") -> Any:
    """The reference decoder of a header's field map: every field checked against the class's type
    hints (converted where the type allows, ``int`` to ``float``), missing ones given their
    defaults, unknown ones ignored, and the instance made by the class's constructor.

    Parameters
    ----------
    cls
        A message or struct class.
    fields
        The header's field map (``f``), arrays as references.
    arrays
        The message's checked arrays, by buffer index.
    where
        Names the value in errors (default: the class's schema id).

    Returns
    -------
    object
        The instance.

    Raises
    ------
    DecodeError
        ``bad_field`` naming the field and what it takes.
    """
    values = {}
    for name, tp, checker, field_where, default, factory in _plan(cls):
        if name in fields:
            v = fields[name]
            values[name] = (
                checker(v, arrays, field_where) if checker is not None else _check(v, tp, arrays, field_where)
            )
        elif default is not _MISSING:
            values[name] = default
        elif factory is not _MISSING:
            values[name] = factory()
        else:
            where = where or getattr(cls, "__schema_id__", cls.__qualname__)
            raise DecodeError("bad_field", f"{where}: required field {name!r} is missing")
    return cls(**values)


def _check(value: Any, tp: Any, arrays: list[np.ndarray], where: str) -> Any:
    checker = _CHECKERS.get(tp)
    if checker is not None:
        return checker(value, arrays, where)
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        errors = []
        for a in args:
            if a is type(None):
                continue
            try:
                return _check(value, a, arrays, where)
            except DecodeError as exc:
                errors.append(exc.detail)
        raise DecodeError("bad_field", f"{where}: no member of {tp} accepts the value ({'; '.join(errors)})")
    if origin in (list, tuple, typing.Sequence):
        if not isinstance(value, list):
            raise DecodeError("bad_field", f"{where}: expected a list, got {type(value).__name__}")
        if origin is tuple and args and not (len(args) == 2 and args[1] is Ellipsis):
            if len(args) != len(value):
                raise DecodeError("bad_field", f"{where}: expected {len(args)} items, got {len(value)}")
            return tuple(_check(v, a, arrays, f"{where}[{i}]") for i, (v, a) in enumerate(zip(value, args)))
        inner = args[0] if args else Any
        items = [_check(v, inner, arrays, f"{where}[{i}]") for i, v in enumerate(value)]
        return tuple(items) if origin is tuple else items
    if origin is dict:
        if not isinstance(value, dict):
            raise DecodeError("bad_field", f"{where}: expected a map, got {type(value).__name__}")
        kt, vt = args if args else (Any, Any)
        return {_check(k, kt, arrays, where): _check(v, vt, arrays, f"{where}[{k!r}]") for k, v in value.items()}
    if tp is Any:
        return _resolve_any(value, arrays)
    if dataclasses.is_dataclass(tp):
        if not isinstance(value, dict):
            raise DecodeError("bad_field", f"{where}: expected a {tp.__name__} map, got {type(value).__name__}")
        return build_plain(tp, value, arrays, where)
    raise DecodeError("bad_field", f"{where}: unsupported field type {tp}")


def _resolve_any(value: Any, arrays: list[np.ndarray]) -> Any:
    if type(value) in _EXT_TYPES:
        return _array(value, arrays, "<any>")
    if isinstance(value, list):
        return [_resolve_any(v, arrays) for v in value]
    if isinstance(value, dict):
        return {k: _resolve_any(v, arrays) for k, v in value.items()}
    return value


def array_index(value: Any) -> int | None:
    """The buffer index of an array reference in a header from :func:`read_header`.

    Parameters
    ----------
    value : object
        A value from the header's fields: a ``msgpack.ExtType`` (plain path) or a ``slice`` (fast path)
        for an array reference.

    Returns
    -------
    int or None
        The buffer index; None when ``value`` is anything else.
    """
    if type(value) is msgpack.ExtType:
        code, data = value
    elif type(value) is slice:  # as the fast path unpacks it (fastpath.unpack_header)
        code, data = value.start, value.stop
    else:
        return None
    if code == ARRAY_EXT and type(data) is bytes and len(data) == 4:
        return int.from_bytes(data, "little")
    return None


def _array(value: Any, arrays: list[np.ndarray], where: str) -> np.ndarray:
    idx = array_index(value)
    if idx is None:
        kind = "ext value" if type(value) in _EXT_TYPES else type(value).__name__
        raise DecodeError("bad_field", f"{where}: expected an array reference, got {kind}")
    if idx >= len(arrays):
        raise DecodeError("bad_array", f"{where}: array reference {idx} out of range")
    return arrays[idx]


def _scalar(*types_: type, convert: Callable[[Any], Any] | None = None) -> Callable[[Any, list, str], Any]:
    def check(value: Any, arrays: list[np.ndarray], where: str) -> Any:
        if type(value) not in types_:
            names = "/".join(t.__name__ for t in types_)
            raise DecodeError("bad_field", f"{where}: expected {names}, got {type(value).__name__}")
        return convert(value) if convert else value

    return check


_CHECKERS: dict[Any, Callable[[Any, list, str], Any]] = {
    int: _scalar(int),
    float: _scalar(float, int, convert=float),
    bool: _scalar(bool),
    str: _scalar(str),
    bytes: _scalar(bytes),
    np.ndarray: _array,
}
