"""The codec's fast path (``counterpart.messages.fastpath``) against the plain one: for every
registered message type, the same bytes out and the same message back, arrays and nested structs
included, and the same refusals.
"""

from __future__ import annotations

import dataclasses
import types
import typing
from collections.abc import Iterator
from typing import Any

import msgpack
import numpy as np
import pytest

from counterpart.messages import REGISTRY, Control, DecodeError, Frame, Partner, codec, decode, encode
from counterpart.messages.core import field_types

#: values a field must hold for the message to be made (the contract's names)
VALID = {Control: {"model": "gpdm", "speaker": "partner", "interest": 2, "emotion": "sad", "strength": 0.5}}


def sample(tp: Any, k: int) -> Any:
    """A value of declared type ``tp`` (``k`` varies it), arrays of several dtypes and ranks."""
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if tp is np.ndarray:
        return (np.arange(6 * (k + 1), dtype=(np.float32, np.uint8, np.int64)[k % 3]) * 3).reshape(-1, 2)
    if tp in (int, float):
        return tp(k + 3)
    if tp is bool:
        return k % 2 == 0
    if tp is str:
        return f"s{k}"
    if tp is bytes:
        return bytes([k, 1, 2])
    if origin in (typing.Union, types.UnionType):
        return sample(next(a for a in args if a is not type(None)), k)
    if origin is list:
        return [sample(args[0], k + i) for i in range(2)]
    if origin is tuple:
        return tuple(sample(a, k + i) for i, a in enumerate(args)) if Ellipsis not in args else (sample(args[0], k),)
    if origin is dict:
        return {sample(args[0], k): sample(args[1], k + 1)}
    if dataclasses.is_dataclass(tp):
        return make(tp, k)
    if tp is Any:
        return [k, "any"]
    raise AssertionError(f"no sample for {tp}")


def make(cls: type, k: int = 0) -> Any:
    values = {name: sample(tp, k + i) for i, (name, tp) in enumerate(field_types(cls).items())}
    return cls(**{**values, **VALID.get(cls, {})})


def same(a: Any, b: Any) -> bool:
    """Deep equality with arrays compared by dtype, shape and values."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return type(a) is type(b) and a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b)
    if dataclasses.is_dataclass(a):
        return type(a) is type(b) and all(same(getattr(a, f.name), getattr(b, f.name)) for f in dataclasses.fields(a))
    if isinstance(a, (list, tuple)):
        return type(a) is type(b) and len(a) == len(b) and all(map(same, a, b))
    if isinstance(a, dict):
        return type(a) is type(b) and a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    return type(a) is type(b) and a == b


@pytest.fixture
def plain() -> Iterator[None]:
    codec.use_fast_path(False)
    yield
    codec.use_fast_path(True)


def both_paths(parts: list[Any]) -> tuple[Any, Any]:
    """``parts`` decoded through the fast path and through the plain one."""
    frames = [bytes(p) for p in parts]
    fast = decode(frames)
    codec.use_fast_path(False)
    try:
        return fast, decode(frames)
    finally:
        codec.use_fast_path(True)


@pytest.mark.parametrize("sid", sorted(REGISTRY))
def test_every_message_type_gives_the_same_bytes_and_message_through_both_paths(sid: str) -> None:
    for k in (0, 1):
        msg = make(REGISTRY[sid], k)
        fast, ref = encode(msg, counter=5), codec.encode_plain(msg, counter=5)
        assert [bytes(p) for p in fast] == [bytes(p) for p in ref]
        out_fast, out_plain = both_paths(fast)
        assert same(out_fast, msg) and same(out_plain, msg)


def test_values_the_fast_path_does_not_take_go_the_plain_way() -> None:
    strided = np.arange(24, dtype=np.float32).reshape(4, 6)[:, ::2]
    for msg in (
        Frame(stamp=np.int64(4), seq=2, image=strided, source_time=np.float32(0.5)),  # numpy scalars, a view
        Partner(joints=np.zeros((14, 3), np.float32), avatar_frames=np.arange(3, dtype=np.int32)),
        Frame(image=np.zeros((0, 3), np.uint8)),
    ):
        fast, ref = encode(msg), codec.encode_plain(msg)
        assert [bytes(p) for p in fast] == [bytes(p) for p in ref]
        out_fast, out_plain = both_paths(fast)
        assert same(out_fast, out_plain)


def _frames(fields: dict[str, Any], arrays: list[list[Any]], *buffers: bytes) -> list[bytes]:
    return [msgpack.packb({"s": "camera.Frame/1", "f": fields, "a": arrays}, use_bin_type=True), *buffers]


def test_a_foreign_sender_converts_and_is_refused_the_same_on_both_paths() -> None:
    ref = codec.array_ref(0)
    # an int for a float, a field left out (default), an unknown field (ignored), an array
    ok = _frames({"seq": 1, "source_time": 3, "image": ref, "future": [1]}, [["|u1", [2, 2]]], b"abcd")
    out_fast, out_plain = both_paths(ok)
    assert same(out_fast, out_plain) and type(out_fast.source_time) is float and out_fast.encoding == "bgr8"
    assert not out_fast.image.flags.writeable
    for fields in ({"seq": True}, {"seq": 1.0}, {"source_time": "x"}, {"encoding": b"bgr8"}, {"image": None}):
        errors = []
        for fast in (True, False):
            codec.use_fast_path(fast)
            try:
                with pytest.raises(DecodeError) as err:
                    decode(_frames(fields, []))
            finally:
                codec.use_fast_path(True)
            errors.append((err.value.kind, err.value.detail))
        assert errors[0] == errors[1] and errors[0][0] == "bad_field", errors
        assert f"camera.Frame/1.{next(iter(fields))}" in errors[0][1]


def test_the_plain_path_alone_carries_a_message(plain: None) -> None:
    msg = Partner(seq=3, model="listener", joints=np.ones((14, 3), np.float32), speaker="partner", interest=1)
    assert encode(msg)[0] == codec.encode_plain(msg)[0]
    assert same(decode([bytes(p) for p in encode(msg)]), msg)


def test_an_array_reference_reads_the_same_as_either_path_unpacks_it() -> None:
    from counterpart.messages import fastpath

    head = codec.encode_plain(Frame(image=np.zeros((2, 2), np.uint8)))[0]
    plain = msgpack.unpackb(head)["f"]["image"]
    fast = fastpath.unpack_header(memoryview(head))["f"]["image"]
    assert type(plain) is msgpack.ExtType and type(fast) is slice
    assert codec.array_index(plain) == codec.array_index(fast) == 0
    assert fast == fastpath.unpacked_ref(codec.ARRAY_EXT, 0)
    assert codec.array_index(slice(2, b"\0\0\0\0")) is None and codec.array_index("x") is None
