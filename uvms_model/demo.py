"""``make demo``: check every spec, run both missions, write figures and a summary to out/.

Run as ``python -m uvms_model.demo [OUT_DIR]``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import hybrid
from hybrid.export.trajectory import write_csv, write_events
from hybrid.version import install_hint
from uvms_model.missions import ABLATIONS, MISSIONS, run_mission, specs_dir

__all__ = ["main"]


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    out = Path(args[0] if args else "out")
    out.mkdir(parents=True, exist_ok=True)
    status = 0
    print("== specs ==")
    for path in sorted(specs_dir().glob("*.yaml")):
        try:
            model = hybrid.load(path)
        except hybrid.SpecError as exc:
            print(exc, file=sys.stderr)
            status = 2
            continue
        report = _check(model)
        print(f"{path.name}: valid; {report}")
    print("\n== missions ==")
    for name in MISSIONS:
        result = run_mission(name, dense=True)
        write_csv(result.run, out / f"{name}.csv")
        write_events(result.run, out / f"{name}.events.json")
        try:
            from uvms_model.figures import write_figures

            figures = write_figures(result, out, name)
        except ImportError:
            figures = []
            print(f"  (matplotlib missing: no figures; {install_hint('plot')})")
        print(result.summary())
        for fig in figures:
            print(f"  figure: {fig}")
        if not result.run.termination.ok:
            status = max(status, 1)
    print("\n== ablations (mission 2) ==")
    lines = [
        "| variant | end | min gamma | uvms locations | max tracking error [mm] |",
        "|---|---|---|---|---|",
    ]
    for label, overrides in ABLATIONS.items():
        result = run_mission("uvms_mission_2", overrides)
        locations = " ".join(dict.fromkeys(loc for loc, _ in result.visited))
        lines.append(
            f"| {label} | {result.run.termination.cause} at {result.run.termination.t:.1f} s "
            f"| {result.min_gamma:.3f} | {locations} | {result.max_tracking_error * 1e3:.1e} |"
        )
    table = "\n".join(lines)
    print(table)
    (out / "ablations.md").write_text(table + "\n")
    print(f"\noutputs in {out}/")
    return status


def _check(model: hybrid.Automaton | hybrid.System) -> str:
    try:
        from hybrid.analysis import check
    except ImportError:
        return "checks unavailable"
    report = check(model)
    return "checks pass" if report.ok else f"{len(report.findings)} findings"


if __name__ == "__main__":
    raise SystemExit(main())
