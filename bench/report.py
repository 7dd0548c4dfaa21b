"""Render bench/results.json as the results section of docs/performance.md.

The section between the markers ``<!-- bench:results:start -->`` and
``<!-- bench:results:end -->`` is replaced; the rest of the page is prose kept by
hand. So the numbers in the docs are always those of one ``make bench`` run.
"""

from __future__ import annotations

import itertools
import json
from pathlib import Path
from typing import Any

__all__ = ["render", "update_docs"]

START, END = "<!-- bench:results:start -->", "<!-- bench:results:end -->"
DOC = Path(__file__).resolve().parent.parent / "docs" / "performance.md"


def render(report: dict[str, Any]) -> str:
    m = report["machine"]
    lines = [
        f"Measured on: {m['platform']}, {m['cpus']} CPUs ({m['processor']}), Python "
        f"{m['python']}, NumPy {m['numpy']}, SciPy {m['scipy']}; whole run "
        f"{report['total_s']:.0f} s.",
        "",
        "| benchmark | contender / baseline: median ratio | min | max | contender | baseline | notes |",
        "|---|---|---|---|---|---|---|",
    ]
    for c in report["comparisons"]:
        notes = ", ".join(f"{k} = {_fmt(v)}" for k, v in c["extra"].items())
        lines.append(
            f"| {c['name']} | **{c['ratio_median']:.3f}** | {c['ratio_min']:.3f} | "
            f"{c['ratio_max']:.3f} | {c['contender_median_s'] * 1e3:.3f} ms | "
            f"{c['baseline_median_s'] * 1e3:.3f} ms | {notes} |"
        )
    lines += [
        "",
        f"Each ratio: {report['comparisons'][0]['repeats']} (or more) alternating repeats of "
        "contender and baseline in the same process.",
        "",
        "Load, validate and check of generated automata (5 edges per location):",
        "",
        "| locations | file | load | load peak | check | check peak | load growth | check growth |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in report["scaling"]["rows"]:
        lines.append(
            f"| {r['locations']:,} | {r['bytes'] / 1e6:.2f} MB | {r['load_s']:.3f} s | "
            f"{r['load_peak_MiB']:.1f} MiB | {r['check_s']:.3f} s | {r['check_peak_MiB']:.1f} MiB | "
            f"{_fmt(r.get('load_s_growth_exponent', '-'))} | "
            f"{_fmt(r.get('check_s_growth_exponent', '-'))} |"
        )
    p = report["product_exploration"]
    lines += [
        "",
        "Growth exponent: log(t2/t1) / log(n2/n1) between consecutive sizes. Linear reads "
        "1; n log n from 1,000 to 10,000 reads 1 + log10(4/3) = 1.125.",
        "",
        "Product exploration (12 copies of a 3-location automaton):",
        "",
        "| " + " | ".join(p) + " |",
        "|" + "---|" * len(p),
        "| " + " | ".join(_fmt(v) for v in p.values()) + " |",
        "",
    ]
    compile_s = report.get("native_compile")
    if compile_s:
        lines += [
            "Compiled backend, compile and load times (fresh processes, one new cache directory):",
            "",
            "| first process: kernel | first process: model | new model (kernel cached) | cached: kernel + model + first run | cached: numba import | cached: whole process |",
            "|---|---|---|---|---|---|",
            f"| {compile_s['first_process_kernel_s']:.1f} s | {compile_s['first_process_model_s']:.2f} s | "
            f"{compile_s['new_model_compile_s']:.2f} s | {compile_s['cached_compiled_code_s']:.2f} s | "
            f"{compile_s['numba_import_s']:.2f} s | {compile_s['cached_process_total_s']:.2f} s |",
            "",
        ]
        if "first_process_kernel_and_model_s" in compile_s:
            lines += [
                f"A first process that asks for the thermostat at once (as `simulate` does) "
                f"compiles the kernel and the model in "
                f"{compile_s['first_process_kernel_and_model_s']:.1f} s (the kernel's pieces in "
                f"worker processes meanwhile, one per CPU)"
                + (
                    f"; with the whole compile in that one process "
                    f"(`HYBRID_NATIVE_COMPILE_PROCESSES=1`) it takes "
                    f"{compile_s['first_process_kernel_and_model_one_process_s']:.1f} s."
                    if "first_process_kernel_and_model_one_process_s" in compile_s
                    else "."
                ),
                "",
            ]
        if "uvms_mission_2_model_compile_s" in compile_s:
            lines += [
                f"UVMS mission 2 (library functions compiled): model compile "
                f"{compile_s['uvms_mission_2_model_compile_s']:.1f} s (kernel cached), cached "
                f"model load {compile_s['uvms_mission_2_cached_model_load_s']:.2f} s, cached "
                f"whole process {compile_s['uvms_mission_2_cached_process_total_s']:.2f} s.",
                "",
            ]
    lines += _choice(report.get("backend_choice"))
    lines += _reach(report.get("reach"))
    lines += _components(report.get("components"))
    lines += _ring(report.get("coupled_ring"))
    lines += _campaigns(report.get("campaigns"))
    lines += ["Peers:", ""]
    for name, info in report["peers"].items():
        state = "available" if info["available"] else "not available"
        lines.append(f"- **{name}**: {state}. {info['reason']}")
    return "\n".join(lines)


def _choice(c: dict[str, Any] | None) -> list[str]:
    """The default backend choice in whole processes (bench/backend_choice.py)."""
    if not c:
        return []
    lines = [
        f"The default backend choice, whole `hybrid` processes (CPU s of the process and its "
        f"children, median of {c['repeats']}; cold: an empty compiled cache each run; warm: a "
        f"filled one):",
        "",
        "| cache | simulate: default | auto | scipy | sweep of "
        f"{c['points']:,} points: default | scipy | compiled | default / faster | "
        "default / slower |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for state in ("cold", "warm"):
        cpu, ratio = c["cpu_s"][state], c[state]
        lines.append(
            f"| {state} | {cpu['simulate default']:.2f} | {cpu['simulate auto']:.2f} | "
            f"{cpu['simulate scipy']:.2f} | {cpu['sweep default']:.2f} | "
            f"{cpu['sweep scipy']:.2f} | {cpu['sweep compiled']:.2f} | "
            f"{ratio['sweep_default_over_best']:.2f} | {ratio['sweep_default_over_worst']:.2f} |"
        )
    return [*lines, ""]


def _reach(r: dict[str, Any] | None) -> list[str]:
    """Reach on ARCH-COMP Building (bench/reach_building.py), with Hylaa when it was given."""
    if not r:
        return []
    lines = [
        "Reach on ARCH-COMP Building BLDF01 (48 states, horizon 20 s; CPU time after a "
        "warm-up, best of 3; to the verdict: `refute_first=True`, a proof needs the whole "
        "flowpipe; see [reach](reach.md)):",
        "",
        "| instance | step | verdict | bound on x25 | CPU, sets | CPU, to the verdict | "
        "CPU, sets and witness | peak memory | Hylaa | Hylaa CPU | Hylaa / reach |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for row in r["rows"]:
        h = row.get("hylaa")
        if h is None:
            hylaa = ["not run", "", ""]
        elif "error" in h:
            hylaa = [f"failed: {h['error']}", "", ""]
        else:
            verdict = "unsafe" if h["unsafe"] else "safe at the step points"
            hylaa = [verdict, f"{h['seconds']:.3f} s", f"**{row['hylaa_ratio']:.3g}**"]
        lines.append(
            f"| {row['instance']} | {row['step']:g} | {row['verdict']} | "
            f"<= {row['x25'][1]:.6g} | {row['seconds']:.4f} s | "
            f"{row['seconds_to_verdict']:.4f} s | {row['seconds_with_witness']:.3f} s | "
            f"{row['peak_mib']:.1f} MiB | " + " | ".join(hylaa) + " |"
        )
    if not r["hylaa"]:
        lines += ["", "Hylaa: give `HYBRID_BENCH_HYLAA=PYTHON` (an interpreter with hylaa)."]
    return [*lines, ""]


def _campaigns(c: dict[str, Any] | None) -> list[str]:
    """Sweep throughput (bench/sweep_throughput.py), when the run has it."""
    if not c:
        return []
    lines = [
        f"Campaigns ({c['runs']} runs of the bouncing ball, {c['run_ms']:.1f} ms each in the "
        f"serial loop; load average {c['load_before'][0]:.2f} before, "
        f"{c['load_after'][0]:.2f} after, {c['cpus']} CPUs):",
        "",
        "| executor | runs/s | against the loop |",
        "|---|---|---|",
        f"| hand-written loop of `hybrid.simulate` | {c['serial_runs_per_s']:.1f} | 1 |",
        f"| sweep, 1 worker | {c['workers_1_runs_per_s']:.1f} | overhead per run "
        f"{c['overhead_per_run_1_worker']:+.1%} |",
        f"| sweep, 2 workers | {c['workers_2_runs_per_s']:.1f} | speed-up "
        f"{c['speedup_2_workers']:.2f} |",
        f"| Dask LocalCluster, 2 workers | {c['dask_2_runs_per_s']:.1f} | overhead per run "
        f"(1 worker) {c['dask_overhead_per_run_ms']:.2f} ms |",
        "",
    ]
    if "parallelism_control" in c:
        lines += [
            f"Parallelism control (pure Python on two processes against one after the other, "
            f"in the same repeats; 2.0 on two free cores): {c['parallelism_control']:.2f}; "
            f"the speed-up of two workers over it: {c['speedup_2_workers_of_available']:.2f}.",
            "",
        ]
    return [
        *lines,
        f"Monitoring one requirement on an oscillating run: {c['requirement_monitor_ratio']:.2f} "
        "times the run without it.",
        "",
    ]


def _components(c: dict[str, Any] | None) -> list[str]:
    """Many components (bench/scaling_components.py), when the run has it."""
    if not c:
        return []
    sim = c["simulate"]
    lines = [
        f"Many components: `simulate` of 50 and 200 independent thermostats to t = {sim['t_end']:g}: "
        f"{sim['median_s_50']:.2f} s and {sim['median_s_200']:.2f} s (median), growth exponent "
        f"**{sim['exponent']:.2f}** (min {sim['exponent_min']:.2f}, max {sim['exponent_max']:.2f}).",
        "",
        "| `check` case | time | peak memory | findings |",
        "|---|---|---|---|",
    ]
    for case in c["check"]:
        rules = sorted(set(case["findings"]))
        lines.append(
            f"| {case['case']} | {case['s']:.2f} s | {case['peak_rss_mb']:.0f} MB | "
            f"{', '.join(rules) or 'none'} |"
        )
    return [*lines, ""]


def _ring(c: dict[str, Any] | None) -> list[str]:
    """The coupled ring (bench/scaling_ring.py), when the run has it."""
    if not c:
        return []
    lines = [
        f"Coupled ring of n thermostats to t = {c['t_end']:g} (medians of {c['repeats']} fresh "
        "processes; CPU time; memory allocated during the call):",
        "",
        "| n | jumps | first `simulate` | of which full collections | second "
        "| of which full collections | peak memory, first | second | resident |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in c["rows"]:
        first_gc, second_gc = r.get("first_full_gc_s"), r.get("second_full_gc_s")
        lines.append(
            f"| {r['n']} | {r['jumps']} | {r['first_cpu_s']:.3f} s "
            f"| {'' if first_gc is None else f'{first_gc:.3f} s'} | {r['second_cpu_s']:.3f} s "
            f"| {'' if second_gc is None else f'{second_gc:.3f} s'} "
            f"| {r['first_peak_mb']:.1f} MB | {r['second_peak_mb']:.1f} MB "
            f"| {r['peak_rss_mb']:.0f} MB |"
        )
    sizes = [r["n"] for r in c["rows"]]
    steps = ", ".join(f"{a}->{b}" for a, b in itertools.pairwise(sizes))
    lines += [
        "",
        f"Growth exponents between consecutive sizes ({steps}; target <= {c['target']}):",
        "",
    ]
    for key, values in c["exponents"].items():
        lines.append(f"- {key.replace('_', ' ')}: {', '.join(f'{v:.2f}' for v in values)}")
    apart = c.get("exponents_without_full_collections")
    if apart:
        lines += ["", "The same, each call's full collections left out (a diagnostic, not the target):", ""]
        for key, values in apart.items():
            lines.append(f"- {key.replace('_', ' ')}: {', '.join(f'{v:.2f}' for v in values)}")
    return [*lines, ""]


def _fmt(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.3g}" if abs(value) < 1e4 else f"{value:,.0f}"
    return str(value)


def update_docs(report: dict[str, Any], doc: Path = DOC) -> None:
    text = doc.read_text()
    head, rest = text.split(START, 1)
    _, tail = rest.split(END, 1)
    doc.write_text(f"{head}{START}\n{render(report)}\n{END}{tail}")


if __name__ == "__main__":
    update_docs(json.loads((Path(__file__).resolve().parent / "results.json").read_text()))
