"""The analytic checks of the dynamic model (studies/analytic_table_dynamic.py measures them) as
Markdown tables: solver, S, measured, expected, relative error, and what shows the damping.
docs/analytic.md holds them (`python -m harness analytic`); the accuracy page embeds them."""

import math

FP32_LABELS = {  # a check's fp32 row label, from its case
    "pendulum": lambda r: f"pendulum θ0 = {r['theta0']:g}, T (s)",
    "wind": lambda r: f"wind U = {r['speed']:g}, ψ = {_angle(r['psi'])}, θ (rad)",
    "chain": lambda r: f"chain P = {r['points']}, ω (rad/s)",
}


def _fmt(x, digits=7):
    return "—" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.{digits}g}"


def _angle(psi):
    return "π" if psi == math.pi else f"{psi:g}"


def _orders(orders):
    return f"\nObserved order over the last three S: {', '.join(f'{k} {v:.2f}' for k, v in orders.items())}.\n"


def _table(header, rows):
    """A Markdown table: the first column left-aligned, the others right."""
    return [
        "| " + " | ".join(header) + " |",
        "| --- |" + " ---: |" * (len(header) - 1),
        *("| " + " | ".join(cells) + " |" for cells in rows),
    ]


PENDULUM_HEADER = ("solver", "S", "T measured (s)", "T expected (s)", "rel. error", "rel. error vs 2π√(ℓ/g)")
PENDULUM_HEADER += ("amplitude in the 4th (last) period (rad)",)
WIND_HEADER = ("solver", "U (cm/s)", "ψ", "S", "θ measured (rad)", "θ expected (rad)", "abs. error (rad)")
WIND_HEADER += ("change over the last second (rad)",)
CHAIN_HEADER = ("solver", "S", "ω measured (rad/s)", "rel. error vs discrete", "rel. error vs continuum")
CHAIN_HEADER += ("tip FFT rel. error", "tip amplitude in the last period / initial", "max stretch")
FP32_HEADER = ("check", "S", "measured", "expected", "rel. / abs. error", "fp64 error at this S", "u·ℓ/(h²·\\|a\\|)")


def pendulum_tables(sweeps):
    out = []
    for case in sweeps:
        out.append(f"### Pendulum, θ0 = {case['theta0']} rad (P = 2, ℓ = 30 cm, 3 periods)\n")
        out += _table(
            PENDULUM_HEADER,
            (
                (r["solver"], str(r["S"]), _fmt(r["measured"], 10), _fmt(r["expected"], 10), f"{r['rel_error']:.2e}")
                + (f"{r['rel_error_small_angle']:.2e}", _fmt(r["amplitude_end"], 4))
                for r in case["rows"]
            ),
        )
        out.append(_orders(case["orders"]))
    return out


def wind_table(rows):
    cells = (
        (r["solver"], f"{r['speed']:g}", _angle(r["psi"]), str(r["S"]), f"{r['measured']:.15f}")
        + (f"{r['expected']:.15f}", f"{r['abs_error']:.1e}", f"{r['change_last_second']:.1e}")
        for r in rows
    )
    return [
        "### Hanging particle in a steady wind (P = 2, c_d = 1/s, β = 10/s, 8 s)\n",
        *_table(WIND_HEADER, cells),
        "",
    ]


def chain_tables(sweeps):
    out = []
    for case in sweeps:
        out.append(f"### Hanging chain, P = {case['points']} (L = 30 cm, amplitude 0.3 cm, 4 periods)\n")
        out.append(
            f"Expected: the discrete chain's ω1 = {case['omega_discrete']:.10g} rad/s; the continuum's "
            f"(j01/2)√(g/L) = {case['omega_continuum']:.10g} rad/s (gap {case['gap']:.2e}).\n"
        )
        out += _table(
            CHAIN_HEADER,
            (
                (r["label"], str(r["S"]), _fmt(r["measured"], 8), f"{r['rel_error']:.2e}")
                + (f"{r['rel_error_continuum']:.2e}", f"{r['tip_fft_rel_error']:.2e}")
                + (f"{r['amplitude_end']:.3f}", f"{r['stretch_max']:.1e}")
                for r in case["rows"]
            ),
        )
        out.append(_orders(case["orders"]))
    return out


def fp32_table(rows):
    def value(r, x):
        return f"{x:.7f}" if r["check"] == "wind" else _fmt(x, 8)

    def error(r, x):
        return f"{x:.2e}" if r["error_kind"] == "relative" else f"{x:.1e}"

    cells = (
        (FP32_LABELS[r["check"]](r), str(r["S"]), value(r, r["measured"]), value(r, r["expected"]))
        + (error(r, r["error"]), error(r, r["error_fp64"]), f"{r['rounding_angle']:.1e}")
        for r in rows
    )
    return [
        "### fp32: where rounding stops the convergence (xpbd)\n",
        "A substep moves a particle by about h²·|a| (a the acceleration); once that is a few ulps of "
        "a coordinate (ulp(30 cm) = 1.9e-6 cm in fp32, 3.6e-15 cm in fp64) the step cannot resolve "
        "it. The last column is u·ℓ/(h²·|a|), u the unit roundoff: the angle by which a resting "
        "particle can sit off its equilibrium because the restoring displacement rounds away.\n",
        *_table(FP32_HEADER, cells),
        "",
    ]


def lines(sweeps):
    """Every table of studies/analytic_table_dynamic.measure's data, as Markdown lines."""
    return [
        *pendulum_tables(sweeps["pendulum"]),
        *wind_table(sweeps["wind"]),
        *chain_tables(sweeps["chain"]),
        *fp32_table(sweeps["fp32"]),
    ]
