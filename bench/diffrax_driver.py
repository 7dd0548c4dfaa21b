"""diffrax's ``vmap`` ensemble of the thermostat: run by ``bench.diffrax_peer`` in an
interpreter with ``jax`` and ``diffrax`` (CPU).

Needs none of hybrid. Each run is 20 switches of the thermostat (``specs/
thermostat.yaml``: ``T' = -a (T - T_out)`` off, ``a (T_heat - T)`` on,
switching at ``T_low`` and ``T_high``) from its initial temperature, ended as
hybrid's ``max_jumps=20`` ends it, at the 21st switch located: a
``lax.scan`` of 21 ``diffeqsolve`` calls (Dopri5, the PID step controller at
the given ``rtol``/``atol``), each ended by a ``diffrax.Event`` on the guard's
level with Newton's root finder (``optimistix``) to ``1e-12``, the next started
from the event's state in the other mode: the same hybrid run as hybrid's, by
hand, ``jax.vmap``-ed over the initial temperatures and compiled once
(``jax.jit``; the compile is not timed). It prints one JSON line: CPU seconds
per run (median of ``repeats``, the process's CPU time over all XLA threads),
the compile's seconds, and the largest error of an event time against the
closed form (``t = ln((T - T_out) / (T_low - T_out)) / a`` off, likewise on).

    python bench/diffrax_driver.py N REPEATS
"""

from __future__ import annotations

import json
import math
import statistics
import sys
import time

import numpy as np

A, T_OUT, T_HEAT, T_LOW, T_HIGH = 0.1, 10.0, 30.0, 18.0, 22.0
SWITCHES = 20
STAYS = SWITCHES + 1
"""A run of ``max_jumps=SWITCHES`` flows on to the next switch and ends there."""
RTOL, ATOL = 1e-10, 1e-12


def closed_form(start: float, switches: int = SWITCHES) -> list[float]:
    """The switching instants of the run from ``start`` (off, above ``T_low``)."""
    t, temp, on, times = 0.0, start, False, []
    for _ in range(switches):
        if on:
            t += math.log((T_HEAT - temp) / (T_HEAT - T_HIGH)) / A
            temp = T_HIGH
        else:
            t += math.log((temp - T_OUT) / (T_LOW - T_OUT)) / A
            temp = T_LOW
        on = not on
        times.append(t)
    return times


def main(n: int, repeats: int) -> None:
    import diffrax
    import jax
    import jax.numpy as jnp
    import optimistix

    jax.config.update("jax_enable_x64", True)

    def field(t: float, y: jax.Array, on: jax.Array) -> jax.Array:
        return jnp.where(on, A * (T_HEAT - y), -A * (y - T_OUT))

    def level(t: float, y: jax.Array, args: jax.Array, **kwargs: object) -> jax.Array:
        return jnp.where(args, y[0] - T_HIGH, y[0] - T_LOW)

    term = diffrax.ODETerm(field)
    event = diffrax.Event(level, optimistix.Newton(rtol=1e-12, atol=1e-12))
    controller = diffrax.PIDController(rtol=RTOL, atol=ATOL)

    def one_run(start: jax.Array) -> jax.Array:
        def segment(
            carry: tuple[jax.Array, jax.Array, jax.Array], _: None
        ) -> tuple[tuple[jax.Array, jax.Array, jax.Array], jax.Array]:
            t0, y0, on = carry
            sol = diffrax.diffeqsolve(
                term, diffrax.Dopri5(), t0, t0 + 1e3, None, y0, args=on,
                stepsize_controller=controller, event=event, max_steps=100_000,
                saveat=diffrax.SaveAt(t1=True),
            )  # fmt: skip
            t1, y1 = sol.ts[-1], sol.ys[-1]
            return (t1, y1, jnp.logical_not(on)), t1

        _, times = jax.lax.scan(
            segment, (jnp.float64(0.0), jnp.array([start]), jnp.bool_(False)), None, STAYS
        )
        return times

    ensemble = jax.jit(jax.vmap(one_run))
    starts = jnp.asarray(np.linspace(18.5, 21.5, n))
    begun = time.process_time()
    times = np.asarray(ensemble(starts).block_until_ready())
    compile_s = time.process_time() - begun
    seconds = []
    for _ in range(repeats):
        begun = time.process_time()
        ensemble(starts).block_until_ready()
        seconds.append((time.process_time() - begun) / n)
    truth = np.array([closed_form(float(s), STAYS) for s in np.asarray(starts)])
    print(
        json.dumps(
            {
                "tool": f"diffrax {diffrax.__version__}, jax {jax.__version__} (CPU)",
                "runs": n,
                "per_run_s": statistics.median(seconds),
                "per_run_all_s": seconds,
                "first_call_s": compile_s,
                "max_event_time_error_s": float(np.max(np.abs(times - truth))),
            }
        )
    )


if __name__ == "__main__":
    main(int(sys.argv[1]), int(sys.argv[2]))
