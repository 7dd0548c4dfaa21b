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
cannot be written, ``hybrid-native-<uid>`` under the system's temporary
directory, used only if it is this user's and no one else's (a note says so).
Delete it to reclaim the space; nothing else refers to it. Like numba's own
cache, it is trusted: keep it private to the user (it is created ``0o700``).

**A damaged cache is rebuilt, not blamed on the model.** Once a model or the
kernel has compiled and loaded, :func:`seal` writes ``manifest.json`` beside
its module: the SHA-256 of every file of that key. Before the next load, a file
listed there that is missing or no longer matches (a truncated copy, a disk
error, a hand edit) makes the whole key's files be discarded and compiled again,
with a :class:`CompiledCacheNote` saying so (the command line prints it as one
``hybrid: note:`` line). Files no manifest covers yet (a compile that was
interrupted, another process's) are guarded the other way: a load from the cache
that fails (numba's pickles truncated, machine code LLVM cannot read) discards
them and compiles once more, with the same note.

Examples
--------
>>> cache_root().name
'native'
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.util
import json
import os
import platform
import shutil
import stat
import sys
import tempfile
import threading
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from types import ModuleType

from hybrid.errors import Note, UsageError, users_stacklevel
from hybrid.files import atomic_write
from hybrid.frames import with_frame_room
from hybrid.held import HeldCache
from hybrid.simulation.native.kernel_text import Generated
from hybrid.version import install_hint

__all__ = [
    "CACHE_ENV",
    "MANIFEST",
    "CompiledCacheNote",
    "cache_key",
    "cache_root",
    "compiling",
    "exclusive",
    "key_state",
    "load_generated",
    "require_numba",
    "seal",
]

CACHE_ENV = "HYBRID_NATIVE_CACHE"
MANIFEST = "manifest.json"
"""The file beside a compiled module that lists the SHA-256 of each of its cache files."""


class CompiledCacheNote(Note):
    """About the compiled-model cache: a damaged one discarded and rebuilt, or one that
    cannot be written replaced by the user's private temporary folder."""

_LOADED: dict[str, ModuleType] = {}
_SEALED: set[str] = set()
"""The compiled modules this process has sealed (their files do not change after)."""
_LOCK = threading.Lock()


def require_numba() -> ModuleType:
    """numba, or a :class:`~hybrid.errors.UsageError` with the install command (or, for a
    numba that is installed but does not import, why)."""
    try:
        import numba
    except ImportError as exc:
        if importlib.util.find_spec("numba") is not None:  # installed, broken (a numpy clash)
            raise UsageError(
                f"the compiled backend needs numba, which is installed but does not import: "
                f"{exc}; reinstall it ({install_hint('fast')}) or use the scipy backend"
            ) from None
        raise UsageError(
            f"the compiled backend needs numba, which is not installed: {install_hint('fast')}"
        ) from None
    return numba


def cache_root() -> Path:
    """The directory compiled models are kept in (see the module docstring).

    Decided once per process for each setting of the environment: the configured
    directory if it can be written, else the user's private folder of the temporary
    directory (a :class:`CompiledCacheNote` says so), so that what is looked up, said
    and chosen (the first-compile notice, ``hybrid compile``, ``backend="auto"``)
    is where the models are written.
    """
    configured = os.environ.get(CACHE_ENV)
    xdg = os.environ.get("XDG_CACHE_HOME")
    setting = (configured, xdg, os.environ.get("HOME"))
    found = _ROOTS.get(setting)
    if found is None:
        if configured:
            wanted = Path(configured)
        else:
            wanted = Path(xdg or str(Path.home() / ".cache")) / "hybrid" / "native"
        found = _ROOTS[setting] = _usable(wanted)
    return found


_ROOTS: dict[tuple[str | None, ...], Path] = {}


def _usable(wanted: Path) -> Path:
    """``wanted`` if a file can be created in it, else the private fallback (when there is one)."""
    if _can_write(wanted):
        return wanted
    fallback = Path(tempfile.gettempdir()) / f"hybrid-native-{os.getuid()}"
    if not _private_folder(fallback):
        return wanted  # nothing to fall back on: writing fails later, naming the setting
    warnings.warn(
        CompiledCacheNote(
            f"the cache folder {wanted} cannot be written: compiled models are kept in "
            f"{fallback} (set {CACHE_ENV} to choose another)"
        ),
        stacklevel=users_stacklevel(),
    )
    return fallback


def _can_write(folder: Path) -> bool:
    """Whether ``folder`` could hold new files: a file can be made in it, or in its nearest
    existing ancestor (nothing is left behind, and no folder is created)."""
    existing = folder
    while not existing.exists():
        if existing.parent == existing:
            return False
        existing = existing.parent
    if not existing.is_dir():
        return False
    probe = existing / f".hybrid-probe-{os.getpid()}"
    try:
        probe.touch()
        probe.unlink()
    except OSError:
        return False
    return True


def _private_folder(folder: Path) -> bool:
    """Whether ``folder`` is (or is now made) a directory of this user only, not a link.

    The cache holds code this process runs: a folder of a predictable name in a
    shared temporary directory that someone else created, or can write, is not used.
    """
    try:
        folder.mkdir(mode=0o700)
    except FileExistsError:
        pass
    except OSError:
        return False
    try:
        status = os.lstat(folder)
        if not stat.S_ISDIR(status.st_mode) or status.st_uid != os.getuid():
            return False
        if status.st_mode & 0o077:
            os.chmod(folder, 0o700)  # ours, made by an older version without the mode
    except OSError:
        return False
    return _can_write(folder)


def cache_key(generated: Generated, numba_version: str) -> str:
    """The hex key of a generated module (see the module docstring), computed once per
    generated module and numba version in a process (the choice, the notice, the lock and
    the load each ask; a library's package is read from disk for it)."""
    key = (id(generated), numba_version)
    return _KEYS.get(key, generated, lambda: _cache_key(generated, numba_version))


_KEYS = HeldCache[str](64)


def _cache_key(generated: Generated, numba_version: str) -> str:
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
    directory = cache_root() / key
    with contextlib.suppress(OSError):
        directory.mkdir(parents=True, exist_ok=True, mode=0o700)
    if not (directory.is_dir() and _can_write(directory)):
        raise UsageError(
            f"no writable cache directory for compiled models: {directory.parent} cannot be "
            f"written (set {CACHE_ENV})"
        )
    return directory


def _write_once(path: Path, text: str) -> None:
    """Write ``text`` unless ``path`` holds it already (atomically, safe across processes;
    an unchanged file keeps its time stamp, which numba's cache index is keyed by)."""
    try:
        if path.read_text(encoding="utf-8") == text:
            return
    except OSError:
        pass
    with atomic_write(path) as stream:
        stream.write(text.encode("utf-8"))


def _digests(directory: Path) -> dict[str, str]:
    """SHA-256 of the module and of numba's files of one key (temporary files left out)."""
    found: dict[str, str] = {}
    for path in sorted([*directory.glob("*.py"), *directory.glob("__pycache__/*")]):
        if path.is_file() and ".tmp" not in path.name:
            found[str(path.relative_to(directory))] = hashlib.sha256(path.read_bytes()).hexdigest()
    return found


def _damage(directory: Path) -> str | None:
    """The first file the manifest lists that is missing or changed, or None."""
    try:
        listed = json.loads((directory / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None  # no manifest (or one being replaced): nothing to hold the files to
    if not isinstance(listed, dict):
        return MANIFEST
    for name, digest in listed.items():
        path = directory / str(name)
        try:
            if hashlib.sha256(path.read_bytes()).hexdigest() != digest:
                return f"{name} has changed"
        except OSError:
            return f"{name} is missing"
    return None


def _discard(directory: Path, why: str) -> None:
    """Remove a key's compiled files (the module is written again) and say so."""
    warnings.warn(
        f"the compiled-model cache in {directory} was damaged ({why}); discarded, compiling again",
        CompiledCacheNote,
        stacklevel=users_stacklevel(),
    )
    shutil.rmtree(directory / "__pycache__", ignore_errors=True)
    for name in (MANIFEST, *(p.name for p in directory.glob("*.py"))):
        with contextlib.suppress(OSError):
            os.unlink(directory / name)


def seal(module: ModuleType) -> None:
    """Record the SHA-256 of the compiled ``module``'s cache files (see the module docstring).

    Called once a module has compiled and loaded whole; a manifest that already
    lists the same files is left as it is.
    """
    origin = getattr(module, "__file__", None)
    if not origin or origin in _SEALED:  # the kernel: once a process, not once a model
        return
    _SEALED.add(origin)
    directory = Path(origin).parent
    digests = _digests(directory)
    try:
        if json.loads((directory / MANIFEST).read_text(encoding="utf-8")) == digests:
            return
    except (OSError, ValueError):
        pass
    with contextlib.suppress(OSError):  # a cache that cannot be written is only not guarded
        _write_once(directory / MANIFEST, json.dumps(digests, indent=1, sort_keys=True))


def _import(name: str, path: Path) -> ModuleType:
    """The generated module at ``path``, imported (which does no work), then built (its
    ``build()`` compiles it or loads it from numba's cache, with room for numba's recursion:
    :mod:`~hybrid.frames`)."""
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # numba's cache re-imports the module by name
    try:
        spec.loader.exec_module(module)
        with_frame_room(module.build)
    except BaseException:
        sys.modules.pop(name, None)
        raise
    return module


def key_state(key: str) -> str:
    """Where the compiled module of ``key`` is: ``"loaded"`` in this process, ``"cached"``
    (sealed on disk by :func:`seal`) or ``"missing"`` (to compile; files no manifest
    covers are checked by loading them)."""
    if key in _LOADED:
        return "loaded"
    return "cached" if (cache_root() / key / MANIFEST).is_file() else "missing"


LOCK_FILE = ".compile.lock"
"""In a key's directory: held (``flock``) by the process compiling that key."""


@contextlib.contextmanager
def compiling(
    *generated: Generated, waiting: Callable[[], None] | None = None
) -> Iterator[None]:
    """Held while this process compiles ``generated``: another process about to compile one
    of them at once waits until it is done, then loads it from the cache (calling
    ``waiting()`` once, before it waits).

    Two processes started together on an empty cache (two pytest workers, two runs of
    a make file) each compiled the kernel, twice the CPU for the same files. Only keys
    neither loaded here nor sealed on disk are locked, each in its directory, in the
    order of their keys (two processes never wait for each other); a lock is released
    when its process ends, however it ends. Where ``fcntl`` is missing or a directory
    cannot be written, nothing is locked.
    """
    numba = require_numba()
    keys = sorted({cache_key(g, numba.__version__) for g in generated})
    said = [waiting]

    def wait_once() -> None:
        if said[0] is not None:
            said[0]()
            said[0] = None

    with contextlib.ExitStack() as held:
        for key in keys:
            if key_state(key) != "missing":
                continue
            directory = cache_root() / key
            try:
                directory.mkdir(parents=True, exist_ok=True, mode=0o700)
            except OSError:
                continue  # the compile goes on unlocked (a cache elsewhere, say)
            held.enter_context(exclusive(directory / LOCK_FILE, wait_once))
        yield


@contextlib.contextmanager
def exclusive(path: Path, waiting: Callable[[], None] | None = None) -> Iterator[None]:
    """Within, no other process is within ``exclusive`` of the same ``path`` (``flock`` on it,
    created if missing; ``waiting()`` is called before waiting for another process that
    holds it). A lock is released when its process ends, however it ends. Where ``fcntl``
    is missing or ``path`` cannot be opened, nothing is locked."""
    try:
        import fcntl
    except ImportError:  # not POSIX: unlocked
        yield
        return
    try:
        handle = os.open(path, os.O_RDWR | os.O_CREAT, 0o600)
    except OSError:
        yield
        return
    try:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:  # another process holds it
            if waiting is not None:
                waiting()
            fcntl.flock(handle, fcntl.LOCK_EX)  # a Ctrl-C while waiting stops the wait
        yield
    finally:
        os.close(handle)  # closing releases the lock


def load_generated(generated: Generated) -> ModuleType:
    """The imported module of ``generated`` (numba compiles or loads it on first call)."""
    numba = require_numba()
    key = cache_key(generated, numba.__version__)
    with _LOCK:
        module = _LOADED.get(key)
        if module is not None:
            return module
        name = f"hybrid_native_{key}"
        directory = _writable_directory(key)
        damage = _damage(directory)
        if damage is not None:
            _discard(directory, damage)
        path = directory / f"{name}.py"
        _write_once(path, generated.source)
        cached = any((directory / "__pycache__").glob("*.nb*"))
        try:
            module = _import(name, path)
        except Exception as exc:
            if not cached:
                raise  # compiled from nothing: the model's own failure
            lines = [line for line in str(exc).splitlines() if line.strip()]
            _discard(directory, f"{type(exc).__name__}: {lines[0] if lines else 'no message'}")
            _write_once(path, generated.source)
            module = _import(name, path)
        _LOADED[key] = module
        return module
