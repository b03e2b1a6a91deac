"""Bags: recordings of topics in MCAP files, self-describing and readable after a crash.

Layout of a bag (an ordinary MCAP file, profile ``counterpart``):

- one MCAP *schema* per message schema id: ``name`` = the schema id (``camera.Frame/1``), ``encoding``
  = ``counterpart-msgpack``, ``data`` = JSON of :func:`counterpart.messages.describe` of the class (or, when the
  recording process does not know the class, a description inferred from the wire header, marked
  ``"inferred": true``), so a bag can be understood without the code that wrote it;
- one MCAP *channel* per (topic, schema id), message encoding ``counterpart-msgpack``;
- one MCAP *message* per received message: ``log_time`` = receive time (ns, CLOCK_MONOTONIC, the
  clock of message stamps), ``publish_time`` = the message's ``stamp`` field, ``sequence`` = the
  publisher's send counter (mod 2**32), ``data`` = the wire parts packed as below;
- a metadata record ``counterpart`` with the wall-clock time and host of the recording's start, so
  monotonic times can be related to calendar time.

Packing of the wire parts (header + raw array buffers, the topic frame is the channel), little endian::

    u32 n | u64 len_0 | ... | u64 len_{n-1} | part_0 | ... | part_{n-1}

The parts come back byte for byte: a player re-sends exactly what was received.

Crash safety: messages go into compressed chunks of at most ``chunk_size`` bytes, and the writer
closes the chunk in progress and flushes it to the OS at least every ``flush_period`` seconds. A
recorder killed by SIGKILL therefore leaves an MCAP file without summary or footer whose chunks are
complete up to the last flush; :class:`BagReader` reads such a file sequentially and stops cleanly at
the truncation (``complete`` False, ``recovered`` = messages read). Nothing is fsync'ed: a crash of
the process loses at most the last ``flush_period``, a power cut may lose more.
"""

from __future__ import annotations

import json
import os
import socket
import struct
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, NamedTuple

import numpy as np
from mcap.exceptions import EndOfFile, McapError
from mcap.reader import SeekingReader
from mcap.records import Channel, Message, Metadata, Schema
from mcap.stream_reader import StreamReader
from mcap.writer import MCAP0_MAGIC, CompressionType, Writer

from counterpart.messages import REGISTRY, decode, describe, encode
from counterpart.messages.codec import DEFAULT_LIMITS, DecodeError, array_index, read_header

ENCODING = "counterpart-msgpack"
PROFILE = "counterpart"
LIBRARY = "counterpart-bag/1"
METADATA_NAME = "counterpart"
COMPRESSIONS = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}
DEFAULT_CHUNK_SIZE = 1 << 20
DEFAULT_FLUSH_PERIOD = 0.5

_COUNT = struct.Struct("<I")


# --------------------------------------------------------------------------------------- packing


def pack_parts(parts: Sequence[Any]) -> bytes:
    """Pack wire parts into one blob (module docstring for the layout).

    Parameters
    ----------
    parts : sequence of buffers
        Bytes, memoryviews, zmq frames or C-contiguous buffers.

    Returns
    -------
    bytes
        The packed blob.
    """
    views = [memoryview(p).cast("B") for p in parts]
    head = struct.pack(f"<I{len(views)}Q", len(views), *(v.nbytes for v in views))
    return b"".join([head, *views])


def unpack_parts(data: bytes | memoryview) -> list[memoryview]:
    """Inverse of :func:`pack_parts`.

    Parameters
    ----------
    data : bytes or memoryview
        A packed blob.

    Returns
    -------
    list of memoryview
        Zero-copy views into ``data``, one per part.

    Raises
    ------
    ValueError
        On a bad blob (too short, or lengths that do not add up).
    """
    buf = memoryview(data).cast("B")
    if buf.nbytes < _COUNT.size:
        raise ValueError(f"packed message of {buf.nbytes} bytes is shorter than its part count")
    (n,) = _COUNT.unpack_from(buf, 0)
    offset = _COUNT.size + 8 * n
    if offset > buf.nbytes:
        raise ValueError(f"packed message announces {n} parts but holds {buf.nbytes} bytes")
    lengths = struct.unpack_from(f"<{n}Q", buf, _COUNT.size)
    if offset + sum(lengths) != buf.nbytes:
        raise ValueError(f"packed message: parts of {sum(lengths)} bytes + {offset} header bytes != {buf.nbytes}")
    out = []
    for length in lengths:
        out.append(buf[offset : offset + length])
        offset += length
    return out


# ------------------------------------------------------------------------------------ schemas


def _infer_type(value: Any, arrays: list[list[Any]]) -> str:
    idx = array_index(value)
    if idx is not None:
        dt, shape = arrays[idx] if idx < len(arrays) else ("?", [])
        return f"ndarray[{np.dtype(dt).name if dt != '?' else '?'}, ndim={len(shape)}]"
    if isinstance(value, list):
        inner = sorted({_infer_type(v, arrays) for v in value})
        return f"list[{' | '.join(inner) or 'Any'}]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}: {_infer_type(v, arrays)}" for k, v in value.items()) + "}"
    return "None" if value is None else type(value).__name__


def schema_description(sid: str, header: dict[str, Any] | None = None) -> dict[str, Any]:
    """What a bag stores about a schema.

    Parameters
    ----------
    sid : str
        The schema id (``camera.Frame/1``).
    header : dict of str to Any or None, default=None
        One unpacked wire header, used when the class is not registered.

    Returns
    -------
    dict of str to Any
        :func:`counterpart.messages.describe` of the registered class, or a description inferred
        from ``header`` (``"inferred": true``) when the class is unknown.
    """
    cls = REGISTRY.get(sid)
    if cls is not None:
        return describe(cls)
    fields = {}
    if header is not None:
        arrays = header.get("a", [])
        fields = {k: _infer_type(v, arrays) for k, v in header.get("f", {}).items()}
    return {"schema": sid, "fields": fields, "inferred": True}


def _header_stamp(header: dict[str, Any]) -> int:
    stamp = header.get("f", {}).get("stamp")
    return stamp if type(stamp) is int and stamp >= 0 else 0


# -------------------------------------------------------------------------------------- writer


class BagWriter:
    """Write wire messages to an MCAP bag.

    Parameters
    ----------
    path : str or os.PathLike
        The bag file (its folder is made).
    compression : {"zstd", "lz4", "none"}, default="zstd"
        Compression of the chunks.
    chunk_size : int, default=DEFAULT_CHUNK_SIZE
        Bytes of messages per chunk before it is compressed and written.
    flush_period : float, default=DEFAULT_FLUSH_PERIOD
        Seconds after which the chunk in progress is closed and flushed (on the next :meth:`write`
        or :meth:`tick`), which bounds what a crash loses.
    overwrite : bool, default=False
        Replace an existing file instead of refusing.
    metadata : dict of str to str or None, default=None
        Added to the recording's ``counterpart`` metadata record.

    Attributes
    ----------
    counts : dict of str to int
        Messages written per topic.
    count : int
        Messages written.
    bytes : int
        Bytes of packed messages written (before compression).

    Raises
    ------
    ValueError
        For an unknown compression, ``chunk_size`` < 1 or ``flush_period`` <= 0.
    FileExistsError
        If the file exists and ``overwrite`` is False.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        compression: str = "zstd",
        chunk_size: int = DEFAULT_CHUNK_SIZE,
        flush_period: float = DEFAULT_FLUSH_PERIOD,
        overwrite: bool = False,
        metadata: dict[str, str] | None = None,
    ) -> None:
        if compression not in COMPRESSIONS:
            raise ValueError(f"compression {compression!r}: expected one of {', '.join(COMPRESSIONS)}")
        if chunk_size < 1:
            raise ValueError(f"chunk_size {chunk_size}: must be at least 1 byte")
        if flush_period <= 0:
            raise ValueError(f"flush_period {flush_period}: must be > 0 seconds")
        self.path = Path(path)
        if self.path.exists() and not overwrite:
            raise FileExistsError(f"bag {self.path} exists; choose another file or allow overwriting")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.compression = compression
        self.flush_period = float(flush_period)
        self._file: IO[bytes] = open(self.path, "wb")
        self._writer = Writer(self._file, chunk_size=chunk_size, compression=COMPRESSIONS[compression])
        self._writer.start(profile=PROFILE, library=LIBRARY)
        meta = {
            "start_wall_time": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
            "start_unix_ns": str(time.time_ns()),
            "start_monotonic_ns": str(time.monotonic_ns()),
            "host": socket.gethostname(),
            "packing": "u32 n, n x u64 length, parts (little endian)",
        }
        meta.update(metadata or {})
        self._writer.add_metadata(METADATA_NAME, meta)
        self._file.flush()
        self._schemas: dict[str, int] = {}
        self._channels: dict[tuple[str, str], int] = {}
        self.counts: dict[str, int] = {}
        self.count = 0
        self.bytes = 0
        self._last_flush = time.monotonic()
        self._dirty = False
        self.closed = False

    def _channel(self, topic: str, sid: str, header: dict[str, Any]) -> int:
        key = (topic, sid)
        cid = self._channels.get(key)
        if cid is None:
            schema = self._schemas.get(sid)
            if schema is None:
                data = json.dumps(schema_description(sid, header), sort_keys=True).encode()
                schema = self._schemas[sid] = self._writer.register_schema(sid, ENCODING, data)
            cid = self._channels[key] = self._writer.register_channel(topic, ENCODING, schema)
        return cid

    def write(
        self, topic: str, parts: Sequence[Any], log_time: int | None = None, header: dict[str, Any] | None = None
    ) -> None:
        """Record the wire parts of one message.

        Parameters
        ----------
        topic : str
            The topic.
        parts : sequence of buffers
            The wire parts ``[header, buffers...]``.
        log_time : int or None, default=None
            Receive time in ns (default: now, CLOCK_MONOTONIC).
        header : dict of str to Any or None, default=None
            The already unpacked header, to save unpacking it again.

        Raises
        ------
        DecodeError
            For a malformed header.
        ValueError
            If the bag is closed.
        """
        if self.closed:
            raise ValueError(f"bag {self.path} is closed")
        if header is None:
            header = read_header(parts[0], DEFAULT_LIMITS)
        now = time.monotonic_ns() if log_time is None else int(log_time)
        cid = self._channel(topic, header["s"], header)
        counter = header.get("n")
        data = pack_parts(parts)
        self._writer.add_message(
            cid,
            log_time=now,
            data=data,
            publish_time=_header_stamp(header) or now,
            sequence=counter % (1 << 32) if type(counter) is int and counter >= 0 else 0,
        )
        self.counts[topic] = self.counts.get(topic, 0) + 1
        self.count += 1
        self.bytes += len(data)
        self._dirty = True
        self.tick()

    def write_message(self, topic: str, msg: Any, log_time: int | None = None) -> None:
        """Encode a message with the wire codec and record it.

        Parameters
        ----------
        topic : str
            The topic.
        msg : Any
            A registered message.
        log_time : int or None, default=None
            Receive time in ns (default: now, CLOCK_MONOTONIC).
        """
        self.write(topic, encode(msg), log_time)

    def tick(self) -> None:
        """Flush if the last flush is older than ``flush_period`` (call this when idle too)."""
        if self._dirty and time.monotonic() - self._last_flush >= self.flush_period:
            self.flush()

    def flush(self) -> None:
        """Close the chunk in progress and hand everything written so far to the OS."""
        if self.closed:
            return
        self._writer.flush()
        self._last_flush = time.monotonic()
        self._dirty = False

    def close(self) -> None:
        """Write the summary and footer (the bag is then complete) and close the file."""
        if self.closed:
            return
        self.closed = True
        try:
            self._writer.finish()
        finally:
            self._file.close()

    def __enter__(self) -> BagWriter:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


# -------------------------------------------------------------------------------------- reader


class BagRecord(NamedTuple):
    """One recorded message.

    Attributes
    ----------
    topic : str
        The topic.
    log_time : int
        Receive time, ns, CLOCK_MONOTONIC.
    publish_time : int
        The message's ``stamp``, ns.
    sequence : int
        The publisher's send counter (mod 2**32).
    schema : str
        The schema id.
    parts : list of memoryview
        Wire parts (header + buffers) as read-only views.
    """

    topic: str
    log_time: int
    publish_time: int
    sequence: int
    schema: str
    parts: list[memoryview]


class _StrictFile:
    """A file whose short reads raise :class:`EndOfFile`, so that a truncated last record reads as
    the end of the file instead of as garbage.
    """

    def __init__(self, f: IO[bytes]) -> None:
        self._f = f

    def read(self, n: int = -1) -> bytes:
        data = self._f.read(n)
        if n is not None and n > 0 and len(data) < n:
            raise EndOfFile()
        return data


@dataclass
class _Scan:
    channels: dict[int, Channel]
    schemas: dict[int, Schema]
    metadata: dict[str, str]


class BagReader:
    """Read a bag written by :class:`BagWriter`, complete or cut short by a crash.

    After a full pass of :meth:`records` (or :meth:`messages`), ``complete`` tells whether the file
    ended with its footer and ``recovered`` how many messages were read; ``truncated`` is the reverse
    of ``complete``.

    Parameters
    ----------
    path : str or os.PathLike
        The bag file.

    Attributes
    ----------
    complete : bool or None
        Whether the file ended with its footer (None before a pass).
    recovered : int
        Messages read.
    error : str
        Why reading stopped early, or "".

    Raises
    ------
    FileNotFoundError
        If the bag does not exist.
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)
        if not self.path.is_file():
            raise FileNotFoundError(f"bag {self.path} does not exist")
        with open(self.path, "rb") as f:
            head = f.read(len(MCAP0_MAGIC))
        # a bag cut short may hold part of the magic, or nothing; any other start is another file
        if not MCAP0_MAGIC.startswith(head):
            raise ValueError(
                f"{self.path} is not a bag: bags are MCAP files (as `counterpart bag record` writes them), "
                "and this file does not start as one"
            )
        self.complete: bool | None = None
        self.recovered = 0
        self.error: str = ""

    @property
    def truncated(self) -> bool:
        return self.complete is False

    def _stream(self, f: IO[bytes]) -> Iterator[Any]:
        """MCAP records in file order; stops at a truncation and sets ``complete``."""
        reader = StreamReader(_StrictFile(f), validate_crcs=True)
        self.complete = False
        self.error = ""
        try:
            yield from reader.records
            self.complete = True
        except EndOfFile:
            self.error = "the file ends inside a record (the recorder did not finish it)"
        except (McapError, ValueError, struct.error) as exc:  # a damaged (not only cut) file
            self.error = f"unreadable record: {type(exc).__name__}: {exc}"

    def records(self, topics: Sequence[str] | None = None) -> Iterator[BagRecord]:
        """Every message in file (= receive) order.

        Parameters
        ----------
        topics : sequence of str or None, default=None
            Only these topics; None: all.

        Yields
        ------
        BagRecord
            One per message.

        Raises
        ------
        ValueError
            For a message on an undeclared channel.
        """
        wanted = None if topics is None else set(topics)
        channels: dict[int, Channel] = {}
        schemas: dict[int, Schema] = {}
        self.recovered = 0
        with open(self.path, "rb") as f:
            for record in self._stream(f):
                if isinstance(record, Message):
                    ch = channels.get(record.channel_id)
                    if ch is None:
                        raise ValueError(f"bag {self.path}: message on undeclared channel {record.channel_id}")
                    self.recovered += 1
                    if wanted is not None and ch.topic not in wanted:
                        continue
                    sch = schemas.get(ch.schema_id)
                    yield BagRecord(
                        ch.topic,
                        record.log_time,
                        record.publish_time,
                        record.sequence,
                        sch.name if sch else "",
                        unpack_parts(record.data),
                    )
                elif isinstance(record, Channel):
                    channels[record.id] = record
                elif isinstance(record, Schema):
                    schemas[record.id] = record

    def messages(
        self, topics: Sequence[str] | None = None, decode_messages: bool = False
    ) -> Iterator[tuple[str, int, Any]]:
        """Every message in file order, as wire parts or decoded.

        Parameters
        ----------
        topics : sequence of str or None, default=None
            Only these topics; None: all.
        decode_messages : bool, default=False
            Decode the messages (the message classes must be registered: import their modules).

        Yields
        ------
        topic : str
            The topic.
        log_time : int
            Receive time, ns.
        parts_or_message : list of memoryview or Any
            The wire parts, or the message with ``decode_messages``.
        """
        for r in self.records(topics):
            yield r.topic, r.log_time, (decode(r.parts) if decode_messages else r.parts)

    def _summary(self) -> tuple[_Scan, dict[int, int], int, int] | None:
        """Channels, schemas, metadata, counts and time range from the summary section of a complete
        file (no need to read the data); None when the file has no usable summary.
        """
        try:
            with open(self.path, "rb") as f:
                reader = SeekingReader(f)
                summary = reader.get_summary()
                if summary is None or summary.statistics is None:
                    return None
                metadata: dict[str, str] = {}
                for m in reader.iter_metadata():
                    if m.name == METADATA_NAME:
                        metadata = dict(m.metadata)
        except (McapError, ValueError, struct.error, OSError):
            return None
        stats = summary.statistics
        self.complete, self.recovered, self.error = True, stats.message_count, ""
        return (
            _Scan(dict(summary.channels), dict(summary.schemas), metadata),
            dict(stats.channel_message_counts),
            stats.message_start_time,
            stats.message_end_time,
        )

    def _scan(self) -> tuple[_Scan, dict[int, int], int, int]:
        """Channels, schemas, metadata, counts and the time range: from the summary of a complete
        file, else from one pass over the data (a truncated file).
        """
        fast = self._summary()
        if fast is not None:
            return fast
        channels: dict[int, Channel] = {}
        schemas: dict[int, Schema] = {}
        metadata: dict[str, str] = {}
        counts: dict[int, int] = {}
        start, end = 0, 0
        n = 0
        with open(self.path, "rb") as f:
            for record in self._stream(f):
                if isinstance(record, Message):
                    counts[record.channel_id] = counts.get(record.channel_id, 0) + 1
                    start = record.log_time if n == 0 else min(start, record.log_time)
                    end = max(end, record.log_time)
                    n += 1
                elif isinstance(record, Channel):
                    channels[record.id] = record
                elif isinstance(record, Schema):
                    schemas[record.id] = record
                elif isinstance(record, Metadata) and record.name == METADATA_NAME:
                    metadata = dict(record.metadata)
        self.recovered = n
        return _Scan(channels, schemas, metadata), counts, start, end

    def topics(self) -> dict[str, str]:
        """The schema of every topic in the bag.

        Returns
        -------
        dict of str to str
            Topic -> schema id.

        Raises
        ------
        ValueError
            For a topic recorded with several schemas (a player could not give it one type).
        """
        scan, _, _, _ = self._scan()
        out: dict[str, str] = {}
        for ch in scan.channels.values():
            sid = scan.schemas[ch.schema_id].name if ch.schema_id in scan.schemas else ""
            if out.get(ch.topic, sid) != sid:
                raise ValueError(f"bag {self.path}: topic {ch.topic!r} holds two schemas ({out[ch.topic]}, {sid})")
            out[ch.topic] = sid
        return out

    def info(self) -> dict[str, Any]:
        """A summary of the bag.

        Returns
        -------
        dict of str to Any
            ``path``, ``size_bytes``, ``complete``, ``error``, ``messages`` (count), ``start_ns`` and
            ``end_ns`` (CLOCK_MONOTONIC of the recording host), ``duration_s``, ``topics`` (type,
            count), ``schemas`` (their stored descriptions) and ``metadata`` (of the recording).
        """
        scan, counts, start, end = self._scan()
        topics: dict[str, dict[str, Any]] = {}
        for cid, ch in sorted(scan.channels.items()):
            sch = scan.schemas.get(ch.schema_id)
            t = topics.setdefault(ch.topic, {"type": sch.name if sch else "", "count": 0})
            if sch and t["type"] != sch.name:
                t["type"] = f"{t['type']}, {sch.name}"
            t["count"] += counts.get(cid, 0)
        schemas = {}
        for sch in scan.schemas.values():
            try:
                schemas[sch.name] = json.loads(sch.data)
            except ValueError:
                schemas[sch.name] = {"schema": sch.name, "unreadable": True}
        n = sum(counts.values())
        return {
            "path": str(self.path),
            "size_bytes": self.path.stat().st_size,
            "complete": bool(self.complete),
            "error": self.error,
            "messages": n,
            "start_ns": start,
            "end_ns": end,
            "duration_s": (end - start) / 1e9 if n else 0.0,
            "topics": topics,
            "schemas": schemas,
            "metadata": scan.metadata,
        }


# ------------------------------------------------------------------------------ generic decode


def decode_fields(parts: Sequence[Any]) -> tuple[str, dict[str, Any]]:
    """Decode wire parts without the message class.

    Works for any bag, whatever was importable when it is read.

    Parameters
    ----------
    parts : sequence of buffers
        Wire parts ``[header, buffers...]``.

    Returns
    -------
    schema : str
        The schema id.
    fields : dict of str to Any
        The fields, with arrays in place (read-only views).

    Raises
    ------
    DecodeError
        For a malformed header or arrays that do not match it.
    """
    header = read_header(parts[0], DEFAULT_LIMITS)
    specs = header.get("a", [])
    if len(specs) != len(parts) - 1:
        raise DecodeError("bad_array", f"header names {len(specs)} arrays but {len(parts) - 1} buffers follow")
    arrays = []
    for i, (dt, shape) in enumerate(specs):
        dtype = np.dtype(dt)
        buf = memoryview(parts[i + 1]).cast("B")
        if buf.nbytes != dtype.itemsize * int(np.prod(shape, dtype=np.int64)):
            raise DecodeError("bad_array", f"array {i}: {buf.nbytes} bytes for {dtype}{shape}")
        arrays.append(np.frombuffer(buf, dtype=dtype).reshape(shape) if buf.nbytes else np.zeros(shape, dtype))

    def resolve(v: Any) -> Any:
        idx = array_index(v)
        if idx is not None:
            return arrays[idx]
        if isinstance(v, list):
            return [resolve(x) for x in v]
        if isinstance(v, dict):
            return {k: resolve(x) for k, x in v.items()}
        return v

    return header["s"], resolve(header["f"])


__all__ = [
    "BagWriter",
    "BagReader",
    "BagRecord",
    "pack_parts",
    "unpack_parts",
    "decode_fields",
    "schema_description",
    "ENCODING",
    "COMPRESSIONS",
]
