"""A damaged compiled-model cache is discarded and rebuilt, with one note, never blamed on the model.

The kernel and the bouncing ball's model are compiled (or loaded) in this
process, their cache folders copied into a fresh cache, and the ball's files
there damaged as a disk or a careless copy would: a machine-code file truncated
(the manifest :func:`~hybrid.simulation.native.cache.seal` wrote no longer
matches) or, with no manifest to hold them to, numba's index truncated (the load
itself fails). ``hybrid simulate --backend compiled`` must then exit 0 with the
ball's bounces where the closed form puts them, say once that it rebuilt the
cache, and leave a cache the next process loads silently.
"""

from __future__ import annotations

import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from support import SPECS, assert_no_traceback, read_json, run_cli

import hybrid
from hybrid.compose import as_system
from hybrid.simulation.native.cache import CACHE_ENV, MANIFEST

pytest.importorskip("numba")

G, E, H0 = 9.81, 0.8, 10.0


def bounce_times(count: int) -> list[float]:
    """The ball dropped from H0 at rest: t1 = sqrt(2 H0 / g), then gaps 2 e^k v1 / g."""
    v = math.sqrt(2 * G * H0)
    times = [v / G]
    for _ in range(count - 1):
        v *= E
        times.append(times[-1] + 2 * v / G)
    return times


@pytest.fixture(scope="module")
def compiled_folders(ball: hybrid.Automaton) -> tuple[Path, Path]:
    """The cache folders of the kernel and of the ball's model, compiled whole."""
    from hybrid.simulation.native.engine import compiled_native

    hybrid.simulate(ball, t_end=1.0, backend="compiled")
    compiled = compiled_native(as_system(ball))
    kernel_file, model_file = compiled.kernel.__file__, compiled.module.__file__
    assert kernel_file and model_file
    return Path(kernel_file).parent, Path(model_file).parent


def _fresh_cache(tmp_path: Path, folders: tuple[Path, Path]) -> tuple[Path, Path]:
    cache = tmp_path / "cache"
    for folder in folders:
        shutil.copytree(folder, cache / folder.name)
    return cache, cache / folders[1].name


def _simulate(cache: Path, tmp_path: Path) -> tuple[int, str, list[float]]:
    events = tmp_path / "events.json"
    env_before = os.environ.get(CACHE_ENV)
    os.environ[CACHE_ENV] = str(cache)
    try:
        done = run_cli("simulate", SPECS / "bouncing_ball.yaml", "--t-end", "5", "--backend",
                       "compiled", "--events", events, timeout=600)  # fmt: skip
    finally:
        if env_before is None:
            del os.environ[CACHE_ENV]
        else:
            os.environ[CACHE_ENV] = env_before
    assert_no_traceback(done.stderr)
    jumps = [j["t"] for j in read_json(events)["jumps"]] if events.exists() else []
    return done.returncode, done.stderr, jumps


@pytest.mark.parametrize("damage", ["machine-code-truncated", "index-truncated-no-manifest"])
def test_a_damaged_cache_is_rebuilt_with_one_note(
    damage: str, compiled_folders: tuple[Path, Path], tmp_path: Path
) -> None:
    cache, model = _fresh_cache(tmp_path, compiled_folders)
    assert (model / MANIFEST).is_file()  # sealed when it compiled whole
    if damage == "machine-code-truncated":
        victim = sorted((model / "__pycache__").glob("*.nbc"))[0]  # any: the manifest holds all
        victim.write_bytes(victim.read_bytes()[:100])
        says = "has changed"
    else:
        (model / MANIFEST).unlink()
        (victim,) = (model / "__pycache__").glob("*.model-*.nbi")  # the one a load reads
        victim.write_bytes(victim.read_bytes()[:10])
        says = "pickle data was truncated"
    code, stderr, jumps = _simulate(cache, tmp_path)
    assert code == 0, stderr
    notes = [line for line in stderr.splitlines() if line.startswith("hybrid: note: ")]
    assert len(notes) == 1, stderr
    assert "was damaged" in notes[0] and says in notes[0] and "compiling again" in notes[0]
    assert str(model) in notes[0]
    expected = [t for t in bounce_times(12) if t <= 5.0]
    assert jumps == pytest.approx(expected, abs=1e-6)
    # rebuilt whole and sealed again: the next process loads it without a word
    assert (model / MANIFEST).is_file()
    again, stderr, jumps_again = _simulate(cache, tmp_path)
    assert again == 0 and "note" not in stderr, stderr
    assert jumps_again == jumps


def test_an_intact_cache_says_nothing(compiled_folders: tuple[Path, Path], tmp_path: Path) -> None:
    cache, _ = _fresh_cache(tmp_path, compiled_folders)
    code, stderr, jumps = _simulate(cache, tmp_path)
    assert code == 0 and "note" not in stderr, stderr
    assert len(jumps) == len([t for t in bounce_times(12) if t <= 5.0])


def test_the_ensemble_loop_is_sealed_and_stays_so(tmp_path: Path) -> None:
    """The ensemble loop's files are held to a manifest once loaded, and a later process's
    runs change none of them (a manifest that numba's first calls outdated would report
    damage that is not there)."""
    import json

    from hybrid.simulation.native.cache import _digests
    from hybrid.simulation.native.engine import kernel

    thermostat = hybrid.load(SPECS / "thermostat.yaml")
    hybrid.simulate_many(thermostat, t_end=30.0, parameters={"a": [0.08, 0.1, 0.12]})
    folder = Path(kernel(parallel=True).__file__).parent
    sealed = json.loads((folder / MANIFEST).read_text())
    assert sealed == _digests(folder) and any(name.endswith(".nbc") for name in sealed)
    script = tmp_path / "many.py"
    script.write_text(
        "import hybrid\n"
        f"m = hybrid.load({str(SPECS / 'thermostat.yaml')!r})\n"
        "runs = hybrid.simulate_many(m, t_end=30.0, parameters={'a': [0.09, 0.11]})\n"
        "print(len(runs))\n"
    )
    done = subprocess.run([sys.executable, "-W", "always", str(script)], capture_output=True,
                          text=True, timeout=600, check=False)  # fmt: skip
    assert done.returncode == 0 and done.stdout.split() == ["2"], done.stderr
    assert "damaged" not in done.stderr, done.stderr
    assert json.loads((folder / MANIFEST).read_text()) == sealed == _digests(folder)


def test_the_note_points_at_the_users_call(tmp_path: Path) -> None:
    from hybrid.simulation.native.cache import CompiledCacheNote, _discard

    (tmp_path / "model.py").write_text("")
    with pytest.warns(CompiledCacheNote, match="was damaged [(]a test[)]") as notes:
        _discard(tmp_path, "a test")
    assert [note.filename for note in notes] == [__file__]
    assert not (tmp_path / "model.py").exists()  # discarded: compiled again on the next load
