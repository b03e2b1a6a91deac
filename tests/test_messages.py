"""The message contract: typed round trips, zero-copy arrays, validation, limits, evolution."""

from __future__ import annotations

import msgpack
import numpy as np
import pytest
import zmq

from counterpart.messages import (
    DecodeError,
    EndOfStream,
    Frame,
    Limits,
    NodeStats,
    TopicStats,
    by_name,
    decode,
    decode_frames,
    describe,
    encode,
    encode_frames,
    message,
)
from counterpart.messages.codec import ARRAY_EXT


@message("test.Evolved", 2)
class Evolved:
    name: str = ""
    points: np.ndarray = np.zeros((0, 2), np.float32)
    added_later: float = 1.5
    tags: list[str] = ()


def test_frame_round_trip_keeps_dtype_shape_and_bytes() -> None:
    img = np.random.default_rng(0).integers(0, 255, (240, 320, 3), dtype=np.uint8)
    msg = Frame(stamp=123, seq=7, image=img, source="x.avi", source_time=0.28)
    topic, out = decode_frames(encode_frames("frame", msg))
    assert topic == "frame" and out.stamp == 123 and out.seq == 7 and out.source == "x.avi"
    assert out.image.dtype == np.uint8 and out.image.shape == (240, 320, 3)
    assert np.array_equal(out.image, img)


def test_arrays_travel_as_raw_frames_and_decode_without_copy() -> None:
    ctx = zmq.Context()
    a, b = ctx.socket(zmq.PAIR), ctx.socket(zmq.PAIR)
    a.bind("inproc://codec")
    b.connect("inproc://codec")
    img = np.arange(76800, dtype=np.uint8).reshape(240, 320)
    parts = encode_frames("gray", Frame(image=img, encoding="mono8"))
    assert len(parts) == 3 and len(bytes(parts[1])) < 200  # the pixels are not inside the header
    a.send_multipart(parts, copy=False)
    frames = b.recv_multipart(copy=False)
    _, msg = decode_frames(frames)
    assert np.array_equal(msg.image, img)
    assert not msg.image.flags.writeable  # a view over the received buffer, not a copy
    assert np.shares_memory(msg.image, np.frombuffer(frames[2].buffer, np.uint8))
    a.close()
    b.close()
    ctx.term()


def test_nested_structs_lists_and_dicts() -> None:
    s = NodeStats(node="n", inputs=[TopicStats(topic="a", count=3, drops=1)], decode_errors={"malformed": 2})
    _, out = decode_frames(encode_frames("n/stats", s))
    assert out == s


def test_non_contiguous_array_is_sent_correctly() -> None:
    base = np.arange(24, dtype=np.float64).reshape(4, 6)
    _, out = decode_frames(encode_frames("t", Evolved(points=base[:, ::2])))
    assert np.array_equal(out.points, base[:, ::2])


def _raw(header: dict, *bufs: bytes) -> list[bytes]:
    return [msgpack.packb(header, use_bin_type=True), *bufs]


def test_old_sender_without_new_field_decodes_with_default() -> None:
    old = {
        "s": "test.Evolved/2",
        "f": {"stamp": 1, "seq": 2, "name": "old", "points": msgpack.ExtType(ARRAY_EXT, (0).to_bytes(4, "little"))},
        "a": [["<f4", [1, 2]]],
    }
    out = decode(_raw(old, np.ones((1, 2), np.float32).tobytes()))
    assert out.added_later == 1.5 and out.name == "old" and out.points.shape == (1, 2)


def test_unknown_fields_are_ignored() -> None:
    newer = {"s": "test.Evolved/2", "f": {"name": "n", "from_the_future": [1, 2, 3]}, "a": []}
    assert decode(_raw(newer)).name == "n"


@pytest.mark.parametrize(
    "parts, kind",
    [
        ([b"\xc1\xff garbage"], "malformed"),
        ([msgpack.packb([1, 2, 3])], "malformed"),
        (_raw({"s": "no.Such/1", "f": {}, "a": []}), "unknown_schema"),
        (_raw({"s": "test.Evolved/2", "f": {"name": 5}, "a": []}), "bad_field"),
        (_raw({"s": "test.Evolved/2", "f": {"tags": "notalist"}, "a": []}), "bad_field"),
        (_raw({"s": "camera.Frame/1", "f": {"image": 3}, "a": []}), "bad_field"),
        (_raw({"s": "camera.Frame/1", "f": {}, "a": [["|O", [2]]]}, b"xx"), "bad_array"),
        (_raw({"s": "camera.Frame/1", "f": {}, "a": [["|u1", [4]]]}, b"xx"), "bad_array"),
        (_raw({"s": "camera.Frame/1", "f": {}, "a": [["|u1", [1 << 40]]]}, b""), "oversized"),
        (_raw({"s": "camera.Frame/1", "f": {}, "a": [["|u1", [2]]] * 100}, *[b"xx"] * 100), "oversized"),
        ([b"\x81\xa1s" + msgpack.packb("x" * (2 << 20))], "oversized"),
    ],
)
def test_bad_messages_raise_decode_error_with_kind(parts: list[bytes], kind: str) -> None:
    with pytest.raises(DecodeError) as err:
        decode(parts)
    assert err.value.kind == kind


def test_container_bomb_is_refused() -> None:
    # a header claiming a 2**31-element array must be refused before allocating it
    bomb = b"\x83\xa1s\xaecamera.Frame/1\xa1f\xdd\x7f\xff\xff\xff"
    with pytest.raises(DecodeError):
        decode([bomb], Limits(max_container_len=1000))


def test_type_lookup_and_description() -> None:
    assert by_name("camera.Frame") is Frame and by_name("system.EndOfStream/1") is EndOfStream
    with pytest.raises(KeyError, match="unknown message type"):
        by_name("nope.Nothing")
    d = describe(Frame)
    assert d["schema"] == "camera.Frame/1" and d["fields"]["image"] == "ndarray"


def test_encode_rejects_unregistered_objects() -> None:
    with pytest.raises(TypeError):
        encode(object())


def _samples() -> list:
    rng = np.random.default_rng(1)
    return [
        Frame(stamp=5, seq=np.int64(3), image=rng.integers(0, 255, (4, 5, 3), dtype=np.uint8), source_time=2),
        Frame(image=np.zeros((0, 3), np.uint8)),
        Evolved(name="e", points=np.arange(12, dtype=np.float32).reshape(6, 2)[::2], tags=["a", "b"]),
        NodeStats(node="n", inputs=[TopicStats(topic="a", rate_hz=np.float32(2.5))], decode_errors={"x": 1}),
        EndOfStream(node="n", reason="end"),
    ]


@pytest.mark.parametrize("msg", _samples(), ids=lambda m: type(m).__name__)
def test_compiled_encoder_writes_the_generic_encoders_bytes(msg) -> None:
    from counterpart.messages.codec import encode_plain as encode_generic

    fast, ref = encode(msg, counter=9), encode_generic(msg, counter=9)
    assert [bytes(p) for p in fast] == [bytes(p) for p in ref]
    out = decode([bytes(p) for p in fast])
    assert type(out) is type(msg) and out.stamp == msg.stamp and out.seq == msg.seq
    for name in msg.__dataclass_fields__:
        a, b = getattr(out, name), getattr(msg, name)
        assert np.array_equal(a, b) if isinstance(b, np.ndarray) else a == b, name


def test_compiled_decoder_converts_and_refuses_like_the_field_checks() -> None:
    ref = msgpack.ExtType(ARRAY_EXT, (0).to_bytes(4, "little"))
    ok = decode(_raw({"s": "camera.Frame/1", "f": {"source_time": 3, "image": ref}, "a": [["|u1", [2, 2]]]}, b"abcd"))
    assert type(ok.source_time) is float and ok.source_time == 3.0 and ok.image.shape == (2, 2)
    assert not ok.image.flags.writeable
    for fields in ({"seq": True}, {"seq": 1.0}, {"source_time": "x"}, {"encoding": b"bgr8"}, {"image": None}):
        with pytest.raises(DecodeError) as err:
            decode(_raw({"s": "camera.Frame/1", "f": fields, "a": []}))
        assert err.value.kind == "bad_field" and f"camera.Frame/1.{next(iter(fields))}" in err.value.detail
