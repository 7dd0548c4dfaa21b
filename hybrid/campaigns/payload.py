"""A model sent to workers once, and each worker's copy of it.

A frozen model holds read-only mappings (``types.MappingProxyType``), which the
standard pickler refuses; :func:`pack` pickles them as plain dictionaries that
:func:`_mapping` turns back into read-only ones, with its own dispatch table (no
global change to pickling). A worker unpacks a payload once and keeps the model
(:func:`unpack`, keyed by the payload's digest), so the simulator's cache of
compiled models, kept per model object, serves every run of the worker.

Examples
--------
>>> import hybrid
>>> ball = hybrid.load("specs/bouncing_ball.yaml")
>>> payload = pack(ball)
>>> unpack(payload) == ball, unpack(payload) is unpack(payload)
(True, True)
"""

from __future__ import annotations

import copyreg
import hashlib
import io
import pickle
import threading
from collections import OrderedDict
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

from hybrid.compose import System
from hybrid.model import Automaton

__all__ = ["Payload", "pack", "unpack"]


@dataclass(frozen=True)
class Payload:
    """A pickled model and the digest that names it."""

    digest: str
    data: bytes


def _mapping(items: dict[str, Any]) -> Mapping[str, Any]:
    return MappingProxyType(items)


def _reduce_mapping(proxy: Mapping[str, Any]) -> tuple[Any, tuple[dict[str, Any]]]:
    return _mapping, (dict(proxy),)


def pack(model: Automaton | System) -> Payload:
    """``model`` pickled for workers."""
    buffer = io.BytesIO()
    pickler = pickle.Pickler(buffer, protocol=pickle.HIGHEST_PROTOCOL)
    table = copyreg.dispatch_table.copy()
    table[MappingProxyType] = _reduce_mapping
    pickler.dispatch_table = table
    pickler.dump(model)
    data = buffer.getvalue()
    return Payload(hashlib.sha256(data).hexdigest(), data)


_MODELS: OrderedDict[str, Automaton | System] = OrderedDict()
_LOCK = threading.Lock()
_KEEP = 4


def unpack(payload: Payload) -> Automaton | System:
    """The model of ``payload``, unpickled once per process (the same object after that)."""
    with _LOCK:
        model = _MODELS.get(payload.digest)
        if model is None:
            model = pickle.loads(payload.data)
            _MODELS[payload.digest] = model
            if len(_MODELS) > _KEEP:
                _MODELS.popitem(last=False)
        else:
            _MODELS.move_to_end(payload.digest)
        return model
