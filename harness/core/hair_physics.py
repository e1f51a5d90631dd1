"""Physical hair → the dynamic model's compliances (docs/hair_physics.md).

A fibre (radius r, Young's modulus E, density ρ) on a strand of length L with P points maps,
for the segment length ℓ = L/(P − 1), to (cgs units: cm, g, s, dyn):

    A = π r²,  I = π r⁴/4,  m = ρ·A·ℓ            (each non-root point carries one segment)
    stretch:  k_s = E·A/ℓ                          (a segment as a bar)
    bend:     k_b = E·I/(ℓ³·sin²(θ₀/2))            (the rod's joint energy ½(EI/ℓ)δθ² equals the
              distance constraint's ½k_b·δd² across the joint, δd = ℓ·sin(θ₀/2)·δθ at a turn θ₀)
    θ₀ = 2·asin(ℓκ/2), the turn between successive segments of a strand of curvature κ

The binaries keep unit point masses (docs/model.md §3: gravity and drag are accelerations), so
the compliances passed are those per unit mass, α = m/k (XPBD with masses m and compliance 1/k
gives the same positions as unit masses with compliance m/k):

    α_s = ρ·ℓ²/E,   α_b = 4ρ·ℓ⁴·sin²(θ₀/2)/(E·r²)   (s²)

κ is the strand's curvature at rest where it bends: the helix's κ = a/(a² + c²) (a the curl
radius, c = pitch/2π) for the curly groom, 1/(R + h) (hair following the scalp) otherwise,
unless the scene gives it. A straight joint (κ = 0) has no first-order bend stiffness in a
distance constraint, so κ must be positive. Shape compliance is not a material property and
stays the scene's.
"""

import math
from dataclasses import dataclass

GPA = 1e10  # dyn/cm² per GPa
UM = 1e-4  # cm per µm


@dataclass(frozen=True)
class Fibre:
    radius_um: float
    youngs_gpa: float
    density: float  # g/cm³
    source: str = ""


# Presets (docs/hair_physics.md has the full citations): mean diameters from three measured
# groups, with one Young's modulus and one density, as measured values were found for those.
ROBBINS_E = "E = 3.89e10 dyn/cm² (Robbins, Chemical and Physical Behavior of Human Hair, appendix)"
DENSITY = "ρ = 1.32 g/cm³ (dry human hair, Robbins)"
PRESETS = {
    "fine": Fibre(57.1 / 2, 3.89, 1.32, f"d = 57.1 µm (Erik et al. 2008, Turkish subjects); {ROBBINS_E}; {DENSITY}"),
    "thick-straight": Fibre(
        85.9 / 2, 3.89, 1.32, f"d = 85.9 µm (Jeong et al. 2011, Korean occipital hair); {ROBBINS_E}; {DENSITY}"
    ),
    "coarse-curly": Fibre(
        122.0 / 2, 3.89, 1.32, f"d = 122 µm (Velasco et al. 2009, Afro-ethnic hair); {ROBBINS_E}; {DENSITY}"
    ),
}


def fibre(preset=None, radius_um=None, youngs_gpa=None, density=None, where="given"):
    """A preset (a PRESETS name or None) with the values given replacing its own; without a
    preset all three are needed. ValueError with one line otherwise."""
    base = PRESETS.get(preset) if preset else None
    if preset and base is None:
        raise ValueError(f"preset '{preset}' is not known (known: {', '.join(PRESETS)})")
    own = (radius_um, youngs_gpa, density)
    if base is None and None in own:
        raise ValueError("without a preset, the radius, Young's modulus and density are all needed")
    keys = ("radius_um", "youngs_gpa", "density")
    values = [v if v is not None else getattr(base, k) for v, k in zip(own, keys)]
    return Fibre(*values, source=base.source if base and own == (None, None, None) else f"{where}")


@dataclass(frozen=True)
class Mapped:
    """What a fibre gives on one strand (cgs)."""

    segment: float  # ℓ, cm
    mass: float  # m, g
    ea: float  # dyn
    ei: float  # dyn·cm²
    curvature: float  # κ, 1/cm
    turn: float  # θ₀, rad
    k_stretch: float  # dyn/cm
    k_bend: float  # dyn/cm
    stretch_compliance: float  # α_s per unit mass, s²
    bend_compliance: float  # α_b per unit mass, s²


def turn_angle(segment, curvature):
    """θ₀ = 2·asin(ℓκ/2): the turn between two chords of length ℓ on a circle of radius 1/κ."""
    x = segment * curvature / 2.0
    if not 0.0 < x <= 1.0:
        raise ValueError(
            f"a curvature of {curvature:g}/cm does not fit segments of {segment:g} cm (ℓκ must be in (0, 2])"
        )
    return 2.0 * math.asin(x)


def mapped(fibre, length_cm, points, curvature):
    """The stiffnesses and per-unit-mass compliances of `fibre` on a strand of `length_cm` and
    `points` points whose rest curvature where it bends is `curvature` (1/cm)."""
    r, e, rho = fibre.radius_um * UM, fibre.youngs_gpa * GPA, fibre.density
    ell = length_cm / (points - 1)
    area, inertia = math.pi * r * r, math.pi * r**4 / 4.0
    mass = rho * area * ell
    th = turn_angle(ell, curvature)
    k_s = e * area / ell
    k_b = e * inertia / (ell**3 * math.sin(th / 2.0) ** 2)
    return Mapped(ell, mass, e * area, e * inertia, curvature, th, k_s, k_b, mass / k_s, mass / k_b)


def helix_curvature(curl_radius, curl_pitch):
    """κ = a/(a² + c²) of a helix of radius a and pitch 2πc."""
    c = curl_pitch / (2.0 * math.pi)
    return curl_radius / (curl_radius**2 + c * c)
