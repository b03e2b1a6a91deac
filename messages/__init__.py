"""The message contract: typed message classes, schema ids, the msgpack/raw-buffer codec, and the
names the controls allow (``INTERACTION_MODELS``, ``EMOTIONS``, ``SPEAKERS``, ``INTEREST_LEVELS``).
"""

from .camera import CameraInfo, Frame
from .codec import (
    DEFAULT_LIMITS,
    DecodeError,
    Limits,
    UntypedMessage,
    decode,
    decode_any,
    decode_frames,
    encode,
    encode_frames,
)
from .core import EMPTY, REGISTRY, by_name, describe, lookup, message, schema_id, struct
from .labeller import PersonSignals, SocialSignals
from .responder import EMOTIONS, INTERACTION_MODELS, INTEREST_LEVELS, SPEAKERS, Control, Partner
from .silhouette import PersonShape, Silhouettes
from .system import EndOfStream, NodeStats, TopicStats
from .tracker import Pose3D, TrackedBody

__all__ = [
    "EMPTY",
    "REGISTRY",
    "by_name",
    "describe",
    "lookup",
    "message",
    "schema_id",
    "struct",
    "DEFAULT_LIMITS",
    "DecodeError",
    "Limits",
    "UntypedMessage",
    "decode_any",
    "decode",
    "decode_frames",
    "encode",
    "encode_frames",
    "EndOfStream",
    "NodeStats",
    "TopicStats",
    "CameraInfo",
    "Frame",
    "PersonShape",
    "Silhouettes",
    "Pose3D",
    "TrackedBody",
    "PersonSignals",
    "SocialSignals",
    "Control",
    "Partner",
    "INTERACTION_MODELS",
    "EMOTIONS",
    "SPEAKERS",
    "INTEREST_LEVELS",
]
