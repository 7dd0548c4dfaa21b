"""``make demo``: check every spec, run both missions, write figures and a summary to out/.

Run as ``python -m uvms_model.demo [OUT_DIR]``. The missions are recorded on a 2 ms
grid, on which the peak accelerations (the budget) are read; the summary also lists the ablations of mission 2, the vehicle's effort
against the always-on vehicle of the paper's section 3.2 (``V = alpha E``), and the
comparison's headline (the strategy against two classical resolutions).
"""

from __future__ import annotations

import sys
from pathlib import Path

import hybrid
from hybrid.export.trajectory import write_csv, write_events
from hybrid.version import install_hint
from uvms_model.missions import (
    ABLATIONS,
    ALWAYS_ON,
    MISSIONS,
    MissionResult,
    run_mission,
    specs_dir,
)

__all__ = ["DEMO_DT", "ablation_table", "effort_table", "main"]

DEMO_DT = 0.002
"""Recording grid of the demo's missions, s."""


def ablation_table(mission: str = "uvms_mission_2") -> str:
    """Markdown table of the ablations of ``mission`` (one run each)."""
    lines = [
        "| variant | end | switches | min abs(gamma) | max vehicle speed [m/s] |",
        "|---|---|---|---|---|",
    ]
    for label, overrides in ABLATIONS.items():
        r = run_mission(mission, overrides)
        term = r.run.termination
        lines.append(
            f"| {label} | {term.cause} at {term.t:.1f} s | {len(r.switches)} "
            f"| {r.min_abs_gamma:.3f} | {r.max_vehicle_speed:.3f} |"
        )
    return "\n".join(lines)


def effort_table(results: dict[str, MissionResult]) -> str:
    """Markdown table: vehicle travel time and energy, strategy vs always-on vehicle."""
    lines = [
        "| mission | vehicle | moving [s] | energy int v^2 dt [m^2/s] | max speed [m/s] "
        "| min abs(gamma) |",
        "|---|---|---|---|---|---|",
    ]
    for name, strategy in results.items():
        always = run_mission(name, ALWAYS_ON)
        for label, r in (("the strategy", strategy), ("always on (s = 1)", always)):
            lines.append(
                f"| {name} | {label} | {r.vehicle_travel_time:.1f} | {r.vehicle_energy:.3f} "
                f"| {r.max_vehicle_speed:.3f} | {r.min_abs_gamma:.3f} |"
            )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    out = Path(args[0] if args else "out")
    missing = [name for name in MISSIONS if not (specs_dir() / f"{name}.yaml").is_file()]
    if missing:
        print(
            f"uvms_model.demo: the missions' specs are not in {specs_dir()} "
            f"(missing: {', '.join(f'{m}.yaml' for m in missing)}); run the demo from a "
            "checkout of the repository (`make demo`, or `python -m uvms_model.demo OUT` "
            "from its root)",
            file=sys.stderr,
        )
        return 2
    out.mkdir(parents=True, exist_ok=True)
    status = 0
    shown: list[str] = []

    def say(text: str) -> None:  # the summary: on stdout, and kept for out/summary.txt
        print(text)
        shown.append(text)

    say("== specs ==")
    for path in sorted(specs_dir().glob("*.yaml")):
        try:
            model = hybrid.load(path)
        except hybrid.SpecError as exc:
            print(exc, file=sys.stderr)
            status = 2
            continue
        report = _check(model)
        say(f"{path.name}: valid; {report}")
    say("\n== missions ==")
    results: dict[str, MissionResult] = {}
    for name in MISSIONS:
        result = run_mission(name, dt=DEMO_DT)
        results[name] = result
        write_csv(result.run, out / f"{name}.csv")
        write_events(result.run, out / f"{name}.events.json")
        try:
            from uvms_model.figures import write_figures

            figures = write_figures(result, out, name)
        except ImportError:
            figures = []
            say(f"  (matplotlib missing: no figures; {install_hint('plot')})")
        say(result.summary())
        for fig in figures:
            say(f"  figure: {fig}")
        if not result.run.termination.ok:
            status = max(status, 1)
    say("\n== vehicle effort: the strategy vs an always-on vehicle ==")
    effort = effort_table(results)
    say(effort)
    say("\n== ablations (mission 2) ==")
    table = ablation_table()
    say(table)
    say("\n== the comparison's headline (mission 2; python -m uvms_model.compare: all) ==")
    from uvms_model.compare import headline

    head = headline()
    say(head)
    (out / "ablations.md").write_text(table + "\n\n" + effort + "\n\n" + head + "\n")
    say(f"\noutputs in {out}/ (this summary: {out / 'summary.txt'})")
    (out / "summary.txt").write_text("\n".join(shown) + "\n")
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
