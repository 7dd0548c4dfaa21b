"""Reach on ARCH-COMP Building BLDF01: BDS01 proved, BDU01 and BDU02 refuted, CPU time and memory.

Run it alone (not part of ``make bench`` nor of the tests)::

    OMP_NUM_THREADS=1 python -m bench.reach_building [--spec-dir DIR]

The instance is imported from ``../shared/external-models/arch/building`` with
:func:`hybrid.interchange.import_spaceex` (``--spec-dir`` takes a folder holding
``BDS01/``, ``BDU01/``, ``BDU02/`` with a ``sys.yaml`` each instead, for a
checkout whose importer does not take Building yet). For each configuration it
reports the verdict, the bound on x25 (the box hull of all 48 variables is
computed for every set), the CPU time of :func:`hybrid.reach` in this process
after a warm-up call (``time.process_time``, BLAS on one thread) and the peak
memory it allocated (``tracemalloc``). The issue's bar: BDS01 proved, sound in
continuous time, in at most 0.5 s of CPU at step 0.005.
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import tempfile
import time
import tracemalloc
from pathlib import Path
from typing import Any

import hybrid
from hybrid.interchange import import_spaceex

__all__ = ["load_instance", "main", "measure"]

BUILDING = Path(__file__).resolve().parents[2] / "shared" / "external-models" / "arch" / "building"
if not BUILDING.exists():
    BUILDING = Path("/work/shared/external-models/arch/building")
HORIZON = {"BDS01": 20.0, "BDU01": 20.0, "BDU02": 20.0}


def load_instance(name: str, spec_dir: Path | None) -> Any:
    """The model of configuration ``name``, imported (or read from ``spec_dir/name/sys.yaml``)."""
    if spec_dir is not None:
        return hybrid.load(spec_dir / name / "sys.yaml")
    result = import_spaceex(BUILDING / "BLDF01.xml", BUILDING / f"BLDF01-{name}.cfg")
    folder = Path(tempfile.mkdtemp(prefix=f"reach-{name}-"))
    for file, text in result.files.items():
        (folder / file).write_text(text)
    return hybrid.load(folder / result.top)


def measure(model: Any, step: float, t_end: float) -> dict[str, Any]:
    """Verdict, x25 bound, CPU seconds and peak MiB of one ``hybrid.reach`` call."""
    hybrid.reach(model, 0.05, max_jumps=1, step=step, witness=False)  # warm-up (imports, caches)
    runs = []
    for _ in range(3):
        started = time.process_time()
        result = hybrid.reach(model, t_end, max_jumps=1, step=step, witness=False)
        runs.append(time.process_time() - started)
    seconds = min(runs)
    tracemalloc.start()  # apart: tracing allocations slows numpy down
    hybrid.reach(model, t_end, max_jumps=1, step=step, witness=False)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    started = time.process_time()
    full = hybrid.reach(model, t_end, max_jumps=1, step=step, witness=True)
    with_witness = time.process_time() - started
    x25 = list(result.variables).index("x25")
    lo, hi = result.hull()
    return {
        "verdict": full.verdict,
        "x25": (float(lo[x25]), float(hi[x25])),
        "sets": len(result.sets),
        "seconds": seconds,
        "seconds_with_witness": with_witness,
        "peak_mib": peak / 2**20,
        "message": full.properties[0].message,
    }


THRESHOLD = {"BDS01": 0.0051, "BDU01": 0.004}
"""The forbidden ``x25 >= r`` of the configurations Hylaa is given (BDU02's needs ``t == 20``)."""


def hylaa(model: Any, name: str, step: float, python: str) -> dict[str, Any]:
    """Hylaa on the same instance, in its own interpreter (``bench/hylaa_driver.py``)."""
    import json
    import subprocess

    import numpy as np

    from hybrid.reach.affine import Forms
    from hybrid.reach.engine import initial_boxes

    forms = Forms(model)
    mode, x_lo, x_hi = initial_boxes(forms)[0]
    a, b, c = forms.flow(mode)
    keep = len(forms.variables) - 1  # our own time coordinate is left out
    a, b, c = a[:keep, :keep], b[:keep], c[:keep]
    b = np.column_stack([b, c])  # the constant term as an input held at 1
    row = np.zeros(keep)
    row[list(forms.variables).index("x25")] = 1.0
    folder = Path(tempfile.mkdtemp(prefix="hylaa-"))
    instance = folder / f"{name}.npz"
    np.savez(
        instance,
        a=a,
        b=b,
        u_lo=np.append(forms.u_lo, 1.0),
        u_hi=np.append(forms.u_hi, 1.0),
        x_lo=x_lo[:keep],
        x_hi=x_hi[:keep],
        row=row,
        rhs=THRESHOLD[name],
        step=step,
        t_end=HORIZON[name],
    )
    driver = Path(__file__).with_name("hylaa_driver.py")
    done = subprocess.run(
        [python, str(driver), str(instance)],
        capture_output=True,
        text=True,
        check=False,
        env={**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"},
    )
    if done.returncode != 0:
        return {"error": done.stderr.strip().splitlines()[-1] if done.stderr else "failed"}
    result: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spec-dir", type=Path, default=None)
    parser.add_argument("--step", type=float, action="append", default=None)
    parser.add_argument("--hylaa", metavar="PYTHON", help="an interpreter with hylaa installed")
    args = parser.parse_args()
    steps = args.step or [0.005, 0.01]
    for name in HORIZON:
        model = load_instance(name, args.spec_dir)
        for step in steps:
            m = measure(model, step, HORIZON[name])
            print(
                f"{name} step {step:g}: {m['verdict']:8s} x25 in [{m['x25'][0]:.6g}, "
                f"{m['x25'][1]:.6g}], {m['sets']} sets, {m['seconds']:.3f} s CPU "
                f"(sets only, best of 3), {m['seconds_with_witness']:.2f} s with the witness search, "
                f"peak {m['peak_mib']:.1f} MiB"
            )
            print(f"    {m['message']}")
            if args.hylaa and name in THRESHOLD:
                h = hylaa(model, name, step, args.hylaa)
                if "error" in h:
                    print(f"    Hylaa: {h['error']}")
                else:
                    verdict = "unsafe" if h["unsafe"] else "safe at the step points"
                    print(
                        f"    Hylaa {verdict}: {h['seconds']:.2f} s CPU, "
                        f"{h['seconds'] / m['seconds']:.3g} times reach's sets, "
                        f"{h['seconds'] / m['seconds_with_witness']:.3g} times reach with its witness"
                    )


if __name__ == "__main__":
    main()
