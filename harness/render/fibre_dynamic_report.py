"""The text `python -m harness hair` prints: a fibre's mapping to the dynamic model
(harness/core/hair_physics.py, docs/hair_physics.md) and the [fibre] table for a scene."""


def text(preset, fibre, m):
    """Lines of a fibre `fibre` mapped as `m` (a hair_physics.Mapped); `preset`: its name or None."""
    table = [f'preset = "{preset}"'] if preset else []
    if not preset or fibre.source.startswith("given"):
        table += [
            f"radius_um = {fibre.radius_um:.6g}",
            f"youngs_modulus_gpa = {fibre.youngs_gpa:.6g}",
            f"density = {fibre.density:.6g}",
        ]
    rows = [
        ("fibre", f"r = {fibre.radius_um:.4g} µm, E = {fibre.youngs_gpa:.4g} GPa, ρ = {fibre.density:.4g} g/cm³"),
        ("source", fibre.source or "—"),
        ("segment ℓ = L/(P − 1)", f"{m.segment:.6g} cm"),
        ("point mass m = ρ·πr²·ℓ", f"{m.mass:.6g} g (the binaries keep unit masses: compliances per unit mass)"),
        ("EA, EI = E·πr⁴/4", f"{m.ea:.6g} dyn, {m.ei:.6g} dyn·cm²"),
        ("rest curvature κ, turn θ₀ = 2·asin(ℓκ/2)", f"{m.curvature:.6g} /cm, {m.turn:.6g} rad"),
        ("k_s = EA/ℓ, k_b = EI/(ℓ³·sin²(θ₀/2))", f"{m.k_stretch:.6g} dyn/cm, {m.k_bend:.6g} dyn/cm"),
        ("α_s = m/k_s (--stretch-compliance)", f"{m.stretch_compliance:.6g} s²"),
        ("α_b = m/k_b (--bend-compliance)", f"{m.bend_compliance:.6g} s²"),
    ]
    width = max(len(k) for k, _ in rows)
    lines = [f"{k:<{width}}  {v}" for k, v in rows]
    return "\n".join([*lines, "", "in a scene (configs/scenes/physical.toml):", "[fibre]", *table])
