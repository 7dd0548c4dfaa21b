"""Where compiled models are kept when the configured folder cannot be written.

The fallback is a folder of a predictable name in the shared temporary directory,
and the cache holds code the process runs: it is used only if it is this user's and
private. It was used whoever had made it, left 0o755, and never announced, so the
first-compile notice, ``hybrid compile`` and ``backend="auto"`` looked in the
configured folder while the models were in the fallback.
"""

from __future__ import annotations

import os
import stat
import warnings
from pathlib import Path

import pytest

from hybrid.simulation.native import cache


@pytest.fixture
def unwritable(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Path:
    """A configured cache folder inside a regular file (it cannot be created), and a
    temporary directory of the test's own; every choice made again."""
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("")
    monkeypatch.setenv(cache.CACHE_ENV, str(blocker / "native"))
    temp = tmp_path / "tmp"
    temp.mkdir()
    monkeypatch.setattr(cache.tempfile, "gettempdir", lambda: str(temp))
    monkeypatch.setattr(cache, "_ROOTS", {})
    return temp / f"hybrid-native-{os.getuid()}"


def test_an_unwritable_folder_falls_back_to_a_private_one_and_says_so(unwritable: Path) -> None:
    with pytest.warns(cache.CompiledCacheNote, match="cannot be written: compiled models are kept in"):
        root = cache.cache_root()
    assert root == unwritable
    assert stat.S_IMODE(os.lstat(root).st_mode) == 0o700
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert cache.cache_root() == root  # decided once: no second note
        assert cache._writable_directory("k1") == root / "k1"


def test_a_fallback_of_ours_left_open_is_made_private(unwritable: Path) -> None:
    unwritable.mkdir(mode=0o755)
    os.chmod(unwritable, 0o777)
    with pytest.warns(cache.CompiledCacheNote):
        assert cache.cache_root() == unwritable
    assert stat.S_IMODE(os.lstat(unwritable).st_mode) == 0o700


def test_a_fallback_someone_else_made_is_not_used(unwritable: Path) -> None:
    if os.getuid() != 0:
        pytest.skip("giving the folder to another user needs root")
    unwritable.mkdir(mode=0o777)
    os.chown(unwritable, 65534, 65534)  # nobody's
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no note: nothing to fall back on
        root = cache.cache_root()
    assert root != unwritable
    with pytest.raises(cache.UsageError, match="no writable cache directory for compiled models"):
        cache._writable_directory("k1")


def test_a_link_in_place_of_the_fallback_is_not_followed(unwritable: Path, tmp_path: Path) -> None:
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir(mode=0o700)
    unwritable.symlink_to(elsewhere)
    assert cache.cache_root() != unwritable
    assert list(elsewhere.iterdir()) == []
