"""Responder model files: one ``.npz`` holding the model's arrays and a JSON metadata string.

Layout: arrays under their own names plus ``__meta__``, a JSON object::

    {"format": "counterpart.responder.model", "version": 4, "model": "dual-hmm",
     "config": {...constructor parameters and scalars...},
     "training": {"sequences": 36, "frames": 5123, "fps": 25.0, "labels": {...}, "seconds": 12.3}}

Loading a file of another format version raises :class:`ModelVersionError` naming the file, its
version and the version this code reads. Default models live in
``~/.cache/counterpart/models/responder-<model>.npz`` (``$COUNTERPART_MODELS`` overrides the folder)
and are trained from the simulator when missing (:func:`load_default`).
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from counterpart.messages import INTERACTION_MODELS

MODEL_FORMAT = "counterpart.responder.model"
MODEL_VERSION = 4  # 2: dual-hmm partner velocity, per-label state blocks, tracked placement;
# 3: dual-hmm time-ordered state blocks, states shared by phases, no inflation;
# 4: dual-hmm placement correction (cross-fitted forest arrays)
#: the kinds of model file: the contract's interaction models and the emotion model that styles them
MODEL_NAMES: tuple[str, ...] = (*INTERACTION_MODELS, "emotion")


class ModelVersionError(ValueError):
    """A model file written by another format version."""


class Storable(Protocol):
    name: str

    def get_state(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]: ...

    @classmethod
    def from_state(cls, arrays: dict[str, np.ndarray], config: dict[str, Any]) -> Storable: ...


def model_class(name: str) -> type:
    """The class of model ``name``.

    Parameters
    ----------
    name : str
        One of ``MODEL_NAMES``.

    Returns
    -------
    type
        The model class (imported on first use).

    Raises
    ------
    ValueError
        For an unknown model name.
    """
    if name == "dual-hmm":
        from .dual_hmm import DualHMM

        return DualHMM
    if name == "joint-shape":
        from .joint_shape import JointShapeModel

        return JointShapeModel
    if name == "listener":
        from .listener import ListenerModel

        return ListenerModel
    if name == "emotion":
        from .emotion import EmotionModel

        return EmotionModel
    if name == "video-texture":
        from .video_texture import VideoTexture

        return VideoTexture
    if name == "gpdm":
        from .gpdm import GPDM

        return GPDM
    raise ValueError(f"unknown responder model {name!r}; choose one of {', '.join(MODEL_NAMES)}")


def save_model(path: str | os.PathLike[str], model: Storable, training: dict[str, Any] | None = None) -> Path:
    """Write ``model`` to ``path``.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write (``.npz`` appended if missing; its folder is created).
    model : Storable
        The model (``name``, ``get_state``).
    training : dict or None, default=None
        Summary of the training data, stored in the metadata.

    Returns
    -------
    Path
        The path written.
    """
    path = Path(path)
    if path.suffix != ".npz":
        path = path.with_name(path.name + ".npz")
    arrays, config = model.get_state()
    meta = {
        "format": MODEL_FORMAT,
        "version": MODEL_VERSION,
        "model": model.name,
        "config": config,
        "training": training or {},
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp.npz")
    np.savez_compressed(tmp, __meta__=np.array(json.dumps(meta)), **arrays)
    os.replace(tmp, path)
    return path


def read_meta(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The metadata of a model file, checked for format and version.

    Parameters
    ----------
    path : str or os.PathLike
        The model file.

    Returns
    -------
    dict
        The metadata: format, version, model, config, training.

    Raises
    ------
    FileNotFoundError
        For a missing file.
    ModelVersionError
        For a file of another format version.
    ValueError
        For a file that is not a responder model.
    """
    return _open(path)[1]


def _open(path: str | os.PathLike[str]) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    p = os.fspath(path)
    if not os.path.exists(p):
        hint = f"; for the default model, default:{p}" if p in MODEL_NAMES else ""
        raise FileNotFoundError(f"{p}: no such model file (train one with 'counterpart learn responder'{hint})")
    try:
        with np.load(p, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
    except (OSError, ValueError) as e:
        raise ValueError(f"{p}: not a responder model file ({e})") from None
    if "__meta__" not in arrays:
        raise ValueError(f"{p}: not a responder model file (no metadata)")
    meta = json.loads(str(arrays.pop("__meta__")))
    if meta.get("format") != MODEL_FORMAT:
        raise ValueError(f"{p}: format {meta.get('format')!r} is not a responder model ({MODEL_FORMAT!r})")
    if meta.get("version") != MODEL_VERSION:
        raise ModelVersionError(
            f"{p}: model file version {meta.get('version')!r}, but this counterpart reads "
            f"version {MODEL_VERSION}; retrain it with 'counterpart learn responder "
            f"--model {meta.get('model', 'M')} ...'"
        )
    return arrays, meta


def load_model(path: str | os.PathLike[str], expected: str | None = None) -> Any:
    """Load a model file.

    Parameters
    ----------
    path : str or os.PathLike
        The model file.
    expected : str or None, default=None
        A model name checked against the file's model (None: any).

    Returns
    -------
    object
        The model, its ``training_`` set from the metadata.

    Raises
    ------
    FileNotFoundError
        For a missing file.
    ModelVersionError
        For a file of another format version.
    ValueError
        For a file that is not a responder model, or holds another model than ``expected``.
    """
    arrays, meta = _open(path)
    name = meta.get("model")
    if expected is not None and name != expected:
        raise ValueError(f"{os.fspath(path)}: holds a {name!r} model, expected {expected!r}")
    model = model_class(name).from_state(arrays, meta.get("config", {}))
    model.training_ = meta.get("training", {})
    return model


def models_dir() -> Path:
    """Folder of the default models: ``$COUNTERPART_MODELS`` or ``~/.cache/counterpart/models``.

    Returns
    -------
    Path
        The folder (it may not exist yet).
    """
    env = os.environ.get("COUNTERPART_MODELS")
    return Path(env) if env else Path.home() / ".cache" / "counterpart" / "models"


def default_model_path(name: str) -> Path:
    """Where the default model ``name`` lives (it may not exist yet).

    Parameters
    ----------
    name : str
        One of ``MODEL_NAMES``.

    Returns
    -------
    Path
        ``models_dir() / responder-NAME.npz``.

    Raises
    ------
    ValueError
        For an unknown model name.
    """
    model_class(name)  # validates the name
    return models_dir() / f"responder-{name}.npz"


def build_default(name: str, progress: Callable[[str], None] | None = None) -> tuple[Any, dict[str, Any]]:
    """Train model ``name`` on its default simulator data.

    Parameters
    ----------
    name : str
        One of ``MODEL_NAMES``.
    progress : callable or None, default=None
        Called with a line of progress text.

    Returns
    -------
    model : object
        The trained model.
    training : dict
        Training summary.
    """
    from .data import summary
    from .training import default_training_data, train

    t0 = time.perf_counter()
    if name == "video-texture":  # an avatar learns from a recording of a person, not trajectories
        from .avatar_default import build_default_avatar

        return build_default_avatar(progress)
    data = default_training_data(name, progress)
    model = train(name, data, progress)
    training = dict(summary(data), source="sim (default)", seconds=round(time.perf_counter() - t0, 2))
    return model, training


def load_default(name: str, progress: Callable[[str], None] | None = None) -> Any:
    """The default model ``name``: loaded from :func:`default_model_path`, built from the simulator
    and saved there first when missing or of an older version.

    Parameters
    ----------
    name : str
        One of ``MODEL_NAMES``.
    progress : callable or None, default=None
        Called with a line of progress text.

    Returns
    -------
    object
        The model.
    """
    path = default_model_path(name)
    if path.exists():
        try:
            return load_model(path, expected=name)
        except ModelVersionError:
            pass  # an old default: rebuild it
    model, training = build_default(name, progress)
    save_model(path, model, training)
    model.training_ = training
    return model
