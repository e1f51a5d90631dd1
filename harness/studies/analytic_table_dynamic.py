"""The analytic checks of docs/model.md §4 swept over the substep count S, as data
(render/analytic_dynamic_report.py writes them as tables; `python -m harness analytic`).

Runs the C reference (fp64, one thread) on the hand-made states of
harness/studies/analytic_runs_dynamic.py (the same runs tests/cpu/test_analytic.py makes, over more S).
`measure` returns what JSON holds (the accuracy study keeps it as analytic.json):

    pendulum  [{theta0, orders: {solver: order}, rows: [{solver, S, measured, expected, rel_error,
               rel_error_small_angle, amplitude_end}]}]
    wind      [{solver, speed, psi, S, measured, expected, abs_error, change_last_second}]
    chain     [{points, omega_discrete, omega_continuum, gap, orders: {label: order}, rows: [{label, S,
               measured, rel_error, rel_error_continuum, tip_fft_rel_error, amplitude_end, stretch_max}]}]
    fp32      [{check, its case (theta0 | speed, psi | points), S, measured, expected, error, error_kind,
               error_fp64, rounding_angle}]

An order is the observed order of convergence over the last three S; docs/analytic.md holds the
tables. About 10 s on 2 cores.
"""

import math
import tempfile

from harness.studies import analytic_dynamic as an

PENDULUM_ANGLES = (0.1, 2.0)  # θ0 (rad)
WIND_CASES = ((250.0, 0.0), (981.0, 0.0), (3000.0, 0.0), (981.0, math.pi), (981.0, 0.5))  # (U cm/s, ψ rad)
CHAIN_POINTS = (32, 64)
CHAIN_SOLVERS = (("xpbd", None, "xpbd"), ("ftl", None, "ftl (s = 0.9)"), ("ftl", 1.0, "ftl (s = 1)"))
UNIT_ROUNDOFF_FP32 = 2.0**-24  # half an ulp of 1


def _support():
    from harness.studies import analytic_runs_dynamic as analytic_runs

    return analytic_runs


def _order(s_values, errors, tail=3):
    """Observed order from the last `tail` points (least squares on log–log)."""
    s, e = s_values[-tail:], errors[-tail:]
    if any(not (v > 0) for v in e):
        return float("nan")
    return an.convergence_order(s, e)


def pendulum(binary, work, sa, s_values):
    out = []
    for theta0 in PENDULUM_ANGLES:
        rows, orders = [], {}
        for solver in ("xpbd", "ftl"):
            errs = []
            for s in s_values:
                r = sa.run_pendulum(binary, work, solver, s, theta0)
                e = an.relative_error(r["measured"], r["expected"])
                errs.append(e)
                rows.append(
                    dict(solver=solver, S=s, measured=r["measured"], expected=r["expected"], rel_error=e)
                    | dict(rel_error_small_angle=an.relative_error(r["measured"], r["small_angle"]))
                    | dict(amplitude_end=r["amplitude_end"])
                )
            orders[solver] = _order(s_values, errs)
        out.append(dict(theta0=theta0, orders=orders, rows=rows))
    return out


def wind(binary, work, sa, s_values):
    out = []
    for solver in ("xpbd", "ftl"):
        for speed, psi in WIND_CASES:
            for s in s_values:
                r = sa.run_wind(binary, work, solver, s, speed, wind_angle=psi)
                out.append(
                    dict(solver=solver, speed=speed, psi=psi, S=s, measured=r["measured"], expected=r["expected"])
                    | dict(abs_error=abs(r["measured"] - r["expected"]), change_last_second=r["change_last_second"])
                )
    return out


def chain(binary, work, sa, s_values):
    out = []
    for points in CHAIN_POINTS:
        w_disc = an.discrete_chain_omega1(points, 30.0, sa.G0)
        w_cont = an.chain_omega1(30.0, sa.G0)
        rows, orders = [], {}
        for solver, s_ftl, label in CHAIN_SOLVERS:
            errs = []
            for s in s_values:
                r = sa.run_chain(binary, work, solver, s, points, ftl_damping=s_ftl)
                e = an.relative_error(r["measured"], r["expected"])
                errs.append(e)
                rows.append(
                    dict(label=label, S=s, measured=r["measured"], rel_error=e)
                    | dict(rel_error_continuum=an.relative_error(r["measured"], r["continuum"]))
                    | dict(tip_fft_rel_error=an.relative_error(r["tip_fft"], r["expected"]))
                    | dict(amplitude_end=r["amplitude_end"], stretch_max=r["stretch_max"])
                )
            orders[label] = _order(s_values, errs)
        gap = an.relative_error(w_disc, w_cont)
        out.append(dict(points=points, omega_discrete=w_disc, omega_continuum=w_cont, gap=gap))
        out[-1] |= dict(orders=orders, rows=rows)
    return out


def fp32(binary, work, sa, pend_s, wind_s, chain_s):
    """The same checks in fp32 (xpbd; ftl is the same at P = 2): rounding stops the convergence.
    rounding_angle is u·ℓ/(h²·|a|): the angle by which a resting particle can sit off its
    equilibrium because the restoring displacement rounds away."""
    checks = (  # (check, its case, S values, run)
        ("pendulum", dict(theta0=0.1), pend_s, lambda s, **kw: sa.run_pendulum(binary, work, "xpbd", s, 0.1, **kw)),
        ("wind", dict(speed=981.0, psi=0.0), wind_s, lambda s, **kw: sa.run_wind(binary, work, "xpbd", s, 981.0, **kw)),
        ("chain", dict(points=32), chain_s, lambda s, **kw: sa.run_chain(binary, work, "xpbd", s, 32, **kw)),
    )
    kinds = dict(pendulum="relative", wind="absolute", chain="relative")
    accels = dict(pendulum=sa.G0, wind=math.hypot(sa.G0, 981.0), chain=sa.G0)

    def error(r, kind):
        if kind == "relative":
            return an.relative_error(r["measured"], r["expected"])
        return abs(r["measured"] - r["expected"])

    out = []
    for check, case, s_values, run in checks:
        kind, accel = kinds[check], accels[check]
        for s in s_values:
            r, r64 = run(s, precision="fp32"), run(s)
            h = sa.FRAME_DT / s
            out.append(
                dict(check=check, **case, S=s, measured=r["measured"], expected=r["expected"])
                | dict(error=error(r, kind), error_kind=kind, error_fp64=error(r64, kind))
                | dict(rounding_angle=UNIT_ROUNDOFF_FP32 * 30.0 / (h * h * accel))
            )
    return out


def measure(binary, quick=False):
    """Every sweep, as data (a temporary directory holds the runs)."""
    sa = _support()
    pend_s = (1, 2, 4) if quick else (1, 2, 4, 8, 16, 32, 64, 128)
    wind_s = (1,) if quick else (1, 8, 64)
    chain_s = (16, 64) if quick else (1, 4, 16, 64, 256, 1024)
    with tempfile.TemporaryDirectory(prefix="hb_analytic_") as work:
        return dict(
            pendulum=pendulum(binary, work, sa, pend_s),
            wind=wind(binary, work, sa, wind_s),
            chain=chain(binary, work, sa, chain_s),
            fp32=fp32(
                binary,
                work,
                sa,
                pend_s,
                (1, 8, 64, 256) if not quick else (1, 8),
                chain_s[1:] if not quick else chain_s,
            ),
        )
