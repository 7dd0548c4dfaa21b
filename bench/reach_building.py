"""Reach on ARCH-COMP Building BLDF01: BDS01 proved, BDU01 and BDU02 refuted, CPU time and memory.

Part of ``make bench`` (:func:`run`; Hylaa in the same run when the environment
variable ``HYBRID_BENCH_HYLAA`` names an interpreter with Hylaa installed), or
alone::

    OMP_NUM_THREADS=1 python -m bench.reach_building [--hylaa PYTHON] [--step H] [--instance BDU01] [--spec-dir DIR]

The instance is imported from ``../shared/external-models/arch/building`` with
:func:`hybrid.interchange.import_spaceex` (``--spec-dir`` takes a folder holding
``BDS01/``, ``BDU01/``, ``BDU02/`` with a ``sys.yaml`` each instead). For each
configuration it reports the verdict, the bound on x25 (the box hull of all 48
variables is computed for every set), and the CPU time of :func:`hybrid.reach`
in this process after a warm-up call (``time.process_time``, BLAS on one
thread, best of 3): the sets alone (``witness=False``), the verdict as a gate
asks for it (``refute_first=True``: a refuted entry is decided before any
flowpipe; a proof computes the whole one) and the default call (sets, then the
witness, whose run is simulated only when asked for), with the peak memory it
allocated (``tracemalloc``). Hylaa is given the same matrices and forbidden set
by ``bench/hylaa_driver.py`` in its own interpreter, at the same step; the ratio
is Hylaa's CPU time over reach's time to the verdict.
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

__all__ = ["FORBIDDEN", "load_instance", "main", "measure", "run"]

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


def _best(call: Any, repeats: int = 3) -> tuple[float, Any]:
    times, result = [], None
    for _ in range(repeats):
        started = time.process_time()
        result = call()
        times.append(time.process_time() - started)
    return min(times), result


def measure(model: Any, step: float, t_end: float) -> dict[str, Any]:
    """Verdict, x25 bound, CPU seconds and peak MiB of ``hybrid.reach`` on one instance."""
    hybrid.reach(model, 0.05, max_jumps=1, step=step, witness=False)  # warm-up (imports, caches)
    seconds, result = _best(
        lambda: hybrid.reach(model, t_end, max_jumps=1, step=step, witness=False)
    )
    gate, verdict = _best(
        lambda: hybrid.reach(model, t_end, max_jumps=1, step=step, refute_first=True)
    )
    tracemalloc.start()  # apart: tracing allocations slows numpy down
    hybrid.reach(model, t_end, max_jumps=1, step=step, witness=False)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    with_witness, full = _best(lambda: hybrid.reach(model, t_end, max_jumps=1, step=step), 1)
    x25 = list(result.variables).index("x25")
    lo, hi = result.hull()
    entry = full.properties[0]
    replayed = None
    if entry.witness is not None:  # the witness run, simulated (outside the timings)
        replayed = (float(entry.witness.t[-1]), float(entry.witness["x25"][-1]))
    return {
        "verdict": full.verdict,
        "gate_verdict": verdict.verdict,
        "x25": (float(lo[x25]), float(hi[x25])),
        "sets": len(result.sets),
        "seconds": seconds,
        "seconds_to_verdict": gate,
        "seconds_with_witness": with_witness,
        "peak_mib": peak / 2**20,
        "message": full.properties[0].message,
        "witness_end": replayed,
    }


FORBIDDEN: dict[str, list[tuple[dict[str, float], float]]] = {
    "BDS01": [({"x25": -1.0}, -0.0051)],
    "BDU01": [({"x25": -1.0}, -0.004)],
    "BDU02": [({"x25": 1.0}, -0.00078), ({"t_": -1.0}, -(20.0 - 1e-9))],
}
"""Each configuration's forbidden set as rows ``sum coef * var <= rhs`` for Hylaa (BDU02's
``t == 20`` read on the model's clock ``t_`` as ``t_ >= 20`` up to 1e-9: the horizon ends there)."""


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
    names = list(forms.variables)
    mat = np.zeros((len(FORBIDDEN[name]), keep))
    for i, (coefs, _) in enumerate(FORBIDDEN[name]):
        for var, coef in coefs.items():
            mat[i, names.index(var)] = coef
    rhs = np.array([r for _, r in FORBIDDEN[name]])
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
        mat=mat,
        rhs=rhs,
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


def run(hylaa_python: str | None = None, steps: tuple[float, ...] = (0.005,)) -> dict[str, Any]:
    """Every configuration at every step, with Hylaa's verdict and ratio when it is given."""
    rows = []
    for name in HORIZON:
        model = load_instance(name, None)
        for step in steps:
            row = {"instance": name, "step": step, **measure(model, step, HORIZON[name])}
            if hylaa_python:
                h = hylaa(model, name, step, hylaa_python)
                row["hylaa"] = h
                if "seconds" in h:
                    row["hylaa_ratio"] = h["seconds"] / row["seconds_to_verdict"]
            rows.append(row)
    return {"rows": rows, "hylaa": bool(hylaa_python)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spec-dir", type=Path, default=None)
    parser.add_argument("--step", type=float, action="append", default=None)
    parser.add_argument("--hylaa", metavar="PYTHON", help="an interpreter with hylaa installed")
    parser.add_argument("--instance", action="append", choices=list(HORIZON), default=None)
    args = parser.parse_args()
    steps = args.step or [0.005, 0.01]
    for name in args.instance or HORIZON:
        model = load_instance(name, args.spec_dir)
        for step in steps:
            m = measure(model, step, HORIZON[name])
            print(
                f"{name} step {step:g}: {m['verdict']:8s} x25 in [{m['x25'][0]:.6g}, "
                f"{m['x25'][1]:.6g}], {m['sets']} sets, {m['seconds']:.4f} s CPU for the sets, "
                f"{m['seconds_to_verdict']:.4f} s to the verdict ({m['gate_verdict']}), "
                f"{m['seconds_with_witness']:.3f} s with sets and witness, "
                f"peak {m['peak_mib']:.1f} MiB (best of 3)"
            )
            print(f"    {m['message']}; witness run ends at (t, x25) = {m['witness_end']}")
            if args.hylaa:
                h = hylaa(model, name, step, args.hylaa)
                if "error" in h:
                    print(f"    Hylaa: {h['error']}")
                else:
                    verdict = "unsafe" if h["unsafe"] else "safe at the step points"
                    print(
                        f"    Hylaa {verdict}: {h['seconds']:.3f} s CPU, "
                        f"{h['seconds'] / m['seconds_to_verdict']:.3g} times reach's time to "
                        f"its verdict, {h['seconds'] / m['seconds_with_witness']:.3g} times "
                        "reach with its sets and witness"
                    )


if __name__ == "__main__":
    main()
