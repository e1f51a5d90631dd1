"""The analytic checks of docs/model.md §4 swept over the substep count S: Markdown tables.

    python -m harness.studies.analytic_table_dynamic [--binary build/hairsim-cpu] [--quick]

Runs the C reference (fp64, one thread) on the hand-made states of
harness/studies/analytic_runs_dynamic.py (the same runs tests/cpu/test_analytic.py makes, over more S)
and prints one table per check: solver, S, measured, expected, relative error, and what
shows the damping. docs/analytic.md holds its output. About 30 s on 2 cores.
"""

import argparse
import math
import sys
import tempfile
from pathlib import Path

from harness.studies import analytic_dynamic as an

ROOT = Path(__file__).resolve().parents[2]


def _support():
    from harness.studies import analytic_runs_dynamic as analytic_runs

    return analytic_runs


def _fmt(x, digits=7):
    return "—" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.{digits}g}"


def _order(s_values, errors, tail=3):
    """Observed order from the last `tail` points (least squares on log–log)."""
    s, e = s_values[-tail:], errors[-tail:]
    if any(not (v > 0) for v in e):
        return float("nan")
    return an.convergence_order(s, e)


def pendulum_tables(binary, work, sa, s_values):
    out = []
    for theta0 in (0.1, 2.0):
        out.append(f"### Pendulum, θ0 = {theta0} rad (P = 2, ℓ = 30 cm, 3 periods)\n")
        out.append(
            "| solver | S | T measured (s) | T expected (s) | rel. error | rel. error vs 2π√(ℓ/g) "
            "| amplitude in the 4th (last) period (rad) |"
        )
        out.append("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
        orders = []
        for solver in ("xpbd", "ftl"):
            errs = []
            for s in s_values:
                r = sa.run_pendulum(binary, work, solver, s, theta0)
                e = an.relative_error(r["measured"], r["expected"])
                errs.append(e)
                out.append(
                    f"| {solver} | {s} | {_fmt(r['measured'], 10)} | {_fmt(r['expected'], 10)} | {e:.2e} "
                    f"| {an.relative_error(r['measured'], r['small_angle']):.2e} "
                    f"| {_fmt(r['amplitude_end'], 4)} |"
                )
            orders.append(f"{solver} {_order(s_values, errs):.2f}")
        out.append(f"\nObserved order over the last three S: {', '.join(orders)}.\n")
    return out


WIND_CASES = ((250.0, 0.0, "0"), (981.0, 0.0, "0"), (3000.0, 0.0, "0"), (981.0, math.pi, "π"), (981.0, 0.5, "0.5"))


def wind_table(binary, work, sa, s_values):
    out = [
        "### Hanging particle in a steady wind (P = 2, c_d = 1/s, β = 10/s, 8 s)\n",
        "| solver | U (cm/s) | ψ | S | θ measured (rad) | θ expected (rad) | abs. error (rad) "
        "| change over the last second (rad) |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for solver in ("xpbd", "ftl"):
        for speed, psi, psi_label in WIND_CASES:
            for s in s_values:
                r = sa.run_wind(binary, work, solver, s, speed, wind_angle=psi)
                out.append(
                    f"| {solver} | {speed:g} | {psi_label} | {s} | {r['measured']:.15f} "
                    f"| {r['expected']:.15f} | {abs(r['measured'] - r['expected']):.1e} "
                    f"| {r['change_last_second']:.1e} |"
                )
    out.append("")
    return out


def chain_tables(binary, work, sa, s_values):
    out = []
    for points in (32, 64):
        w_disc = an.discrete_chain_omega1(points, 30.0, sa.G0)
        w_cont = an.chain_omega1(30.0, sa.G0)
        out.append(f"### Hanging chain, P = {points} (L = 30 cm, amplitude 0.3 cm, 4 periods)\n")
        out.append(
            f"Expected: the discrete chain's ω1 = {w_disc:.10g} rad/s; the continuum's "
            f"(j01/2)√(g/L) = {w_cont:.10g} rad/s (gap {an.relative_error(w_disc, w_cont):.2e}).\n"
        )
        out.append(
            "| solver | S | ω measured (rad/s) | rel. error vs discrete | rel. error vs continuum "
            "| tip FFT rel. error | tip amplitude in the last period / initial | max stretch |"
        )
        out.append("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
        orders = []
        for solver, s_ftl, label in (
            ("xpbd", None, "xpbd"),
            ("ftl", None, "ftl (s = 0.9)"),
            ("ftl", 1.0, "ftl (s = 1)"),
        ):
            errs = []
            for s in s_values:
                r = sa.run_chain(binary, work, solver, s, points, ftl_damping=s_ftl)
                e = an.relative_error(r["measured"], r["expected"])
                errs.append(e)
                out.append(
                    f"| {label} | {s} | {_fmt(r['measured'], 8)} | {e:.2e} "
                    f"| {an.relative_error(r['measured'], r['continuum']):.2e} "
                    f"| {an.relative_error(r['tip_fft'], r['expected']):.2e} "
                    f"| {r['amplitude_end']:.3f} | {r['stretch_max']:.1e} |"
                )
            orders.append(f"{label} {_order(s_values, errs):.2f}")
        out.append(f"\nObserved order over the last three S: {', '.join(orders)}.\n")
    return out


def fp32_tables(binary, work, sa, pend_s, wind_s, chain_s):
    """The same checks in fp32 (xpbd; ftl is the same at P = 2): rounding stops the convergence."""
    eps = 2.0**-24  # unit roundoff of float: half an ulp of 1
    out = [
        "### fp32: where rounding stops the convergence (xpbd)\n",
        "A substep moves a particle by about h²·|a| (a the acceleration); once that is a few ulps of "
        "a coordinate (ulp(30 cm) = 1.9e-6 cm in fp32, 3.6e-15 cm in fp64) the step cannot resolve "
        "it. The last column is u·ℓ/(h²·|a|), u the unit roundoff: the angle by which a resting "
        "particle can sit off its equilibrium because the restoring displacement rounds away.\n",
        "| check | S | measured | expected | rel. / abs. error | fp64 error at this S | u·ℓ/(h²·\\|a\\|) |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]

    def rel(r):
        return f"{an.relative_error(r['measured'], r['expected']):.2e}"

    def absolute(r):
        return f"{abs(r['measured'] - r['expected']):.1e}"

    checks = (  # (label, S values, run, value format, error, |a|)
        (
            "pendulum θ0 = 0.1, T (s)",
            pend_s,
            lambda s, **kw: sa.run_pendulum(binary, work, "xpbd", s, 0.1, **kw),
            lambda x: _fmt(x, 8),
            rel,
            sa.G0,
        ),
        (
            "wind U = 981, ψ = 0, θ (rad)",
            wind_s,
            lambda s, **kw: sa.run_wind(binary, work, "xpbd", s, 981.0, **kw),
            lambda x: f"{x:.7f}",
            absolute,
            math.hypot(sa.G0, 981.0),
        ),
        (
            "chain P = 32, ω (rad/s)",
            chain_s,
            lambda s, **kw: sa.run_chain(binary, work, "xpbd", s, 32, **kw),
            lambda x: _fmt(x, 8),
            rel,
            sa.G0,
        ),
    )
    for label, s_values, run, value, error, accel in checks:
        for s in s_values:
            r, r64 = run(s, precision="fp32"), run(s)
            h = sa.FRAME_DT / s
            out.append(
                f"| {label} | {s} | {value(r['measured'])} | {value(r['expected'])} | {error(r)} | {error(r64)} "
                f"| {eps * 30.0 / (h * h * accel):.1e} |"
            )
    out.append("")
    return out


def tables(binary, quick=False):
    """Every table, as Markdown lines (a temporary directory holds the runs)."""
    sa = _support()
    pend_s = (1, 2, 4) if quick else (1, 2, 4, 8, 16, 32, 64, 128)
    wind_s = (1,) if quick else (1, 8, 64)
    chain_s = (16, 64) if quick else (1, 4, 16, 64, 256, 1024)
    lines = []
    with tempfile.TemporaryDirectory(prefix="hb_analytic_") as work:
        lines += pendulum_tables(binary, work, sa, pend_s)
        lines += wind_table(binary, work, sa, wind_s)
        lines += chain_tables(binary, work, sa, chain_s)
        lines += fp32_tables(
            binary,
            work,
            sa,
            pend_s,
            (1, 8, 64, 256) if not quick else (1, 8),
            chain_s[1:] if not quick else chain_s,
        )
    return lines


def main(argv=None):
    p = argparse.ArgumentParser(
        prog="python -m harness.studies.analytic_table_dynamic", description=__doc__.splitlines()[0]
    )
    p.add_argument("--binary", default=str(ROOT / "build" / "hairsim-cpu"))
    p.add_argument("--quick", action="store_true", help="fewer S (a smoke run)")
    args = p.parse_args(argv)
    print("\n".join(tables(args.binary, args.quick)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
