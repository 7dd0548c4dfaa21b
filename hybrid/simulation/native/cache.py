"""Compiled models on disk: the cache key, the generated file, and loading it.

**The key** is the SHA-256 of the generated source (which holds the model's
structure and the whole kernel, but no parameter values or names), the numba,
Python and machine versions, and the text of every module of each package whose
compiled library functions the model calls (numba does not notice when a function called from
cached code changes; the key does). The generated module is written once, as
``<cache>/<key>/hybrid_native_<key>.py``, and imported from there; numba
(``cache=True``) keeps the machine code beside it in ``__pycache__``, indexed
by that file's path, modification time and size. A second process generates
the same source, finds the same file, leaves it untouched (rewriting it would
invalidate numba's index) and loads the machine code instead of compiling.

**The cache directory** is ``$HYBRID_NATIVE_CACHE`` if set, else
``$XDG_CACHE_HOME/hybrid/native``, else ``~/.cache/hybrid/native``; if it
cannot be written, a directory under the system's temporary directory. Delete
it to reclaim the space; nothing else refers to it. Like numba's own cache,
it is trusted: keep it private to the user (it is created ``0o700``).

Examples
--------
>>> cache_root().name
'native'
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import platform
import sys
import tempfile
import threading
from pathlib import Path
from types import ModuleType

from hybrid.errors import UsageError
from hybrid.simulation.native.kernel_text import Generated
from hybrid.version import install_hint

__all__ = ["CACHE_ENV", "cache_key", "cache_root", "load_generated", "require_numba"]

CACHE_ENV = "HYBRID_NATIVE_CACHE"

_LOADED: dict[str, ModuleType] = {}
_LOCK = threading.Lock()


def require_numba() -> ModuleType:
    """numba, or a :class:`~hybrid.errors.UsageError` with the install command."""
    try:
        import numba
    except ImportError:
        raise UsageError(
            f"the compiled backend needs numba, which is not installed: {install_hint('fast')}"
        ) from None
    return numba


def cache_root() -> Path:
    """The directory compiled models are kept in (see the module docstring)."""
    configured = os.environ.get(CACHE_ENV)
    if configured:
        return Path(configured)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "hybrid" / "native"


def cache_key(generated: Generated, numba_version: str) -> str:
    """The hex key of a generated module (see the module docstring)."""
    digest = hashlib.sha256()
    for part in (numba_version, sys.version, platform.machine(), generated.source):
        digest.update(part.encode())
        digest.update(b"\0")
    for module in generated.library_modules:
        digest.update(module.encode())
        for source in _library_sources(module):
            digest.update(source.read_bytes())
    return digest.hexdigest()[:24]


def _library_sources(module: str) -> list[Path]:
    """The module's file and the other modules of its package (a compiled form calls them)."""
    spec = importlib.util.find_spec(module)
    origin = spec.origin if spec is not None else None
    if not (origin and os.path.isfile(origin)):
        return []
    top = importlib.util.find_spec(module.partition(".")[0])
    folders = list(top.submodule_search_locations or []) if top is not None else []
    siblings = sorted(p for folder in folders for p in Path(folder).rglob("*.py"))
    return siblings if Path(origin) in siblings else [Path(origin)]


def _writable_directory(key: str) -> Path:
    for root in (cache_root(), Path(tempfile.gettempdir()) / f"hybrid-native-{os.getuid()}"):
        directory = root / key
        try:
            directory.mkdir(parents=True, exist_ok=True, mode=0o700)
            probe = directory / ".probe"
            probe.touch()
            probe.unlink()
        except OSError:
            continue
        return directory
    raise UsageError(f"no writable cache directory for compiled models (set {CACHE_ENV})")


def _write_once(path: Path, text: str) -> None:
    """Write ``text`` unless ``path`` holds it already (atomically, safe across processes)."""
    try:
        if path.read_text(encoding="utf-8") == text:
            return
    except OSError:
        pass
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=".", suffix=".tmp")
    with os.fdopen(handle, "w", encoding="utf-8") as stream:
        stream.write(text)
    os.replace(temporary, path)


def load_generated(generated: Generated) -> ModuleType:
    """The imported module of ``generated`` (numba compiles or loads it on first call)."""
    numba = require_numba()
    key = cache_key(generated, numba.__version__)
    with _LOCK:
        module = _LOADED.get(key)
        if module is not None:
            return module
        name = f"hybrid_native_{key}"
        path = _writable_directory(key) / f"{name}.py"
        _write_once(path, generated.source)
        spec = importlib.util.spec_from_file_location(name, path)
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module  # numba's cache re-imports the module by name
        spec.loader.exec_module(module)
        _LOADED[key] = module
        return module
