/* drape_poles.c — runs the C reference's drape, collide and wind on hand-placed roots that
 * the RNG cannot produce (tests/test_stability.py::test_drape_at_the_slice_poles): the slice
 * centre (r0 = 0), θ0 = π, θ0 = −π/2, the top, and a root just below the horizon at the back.
 * Prints one line per point: precision strand stage k x y z (%a, exact). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "paper/model.h"

#define P 12

static const double roots[][3] = {
    {10.0, 0.0, 0.0},      /* r0 = 0: x = R */
    {-10.0, 0.0, 0.0},     /* r0 = 0: x = −R */
    {0.0, 0.0, -10.0},     /* θ0 = π: the clamped back pole */
    {6.0, 0.0, -8.0},      /* θ0 = π, smaller slice */
    {6.0, -8.0, 0.0},      /* θ0 = −π/2 (taken as 3π/2: hangs from the root) */
    {0.0, 10.0, 0.0},      /* top */
    {0.0, -1e-7, -10.0},   /* just past π */
    {9.99, 0.0, 0.447102}, /* tiny slice near the side */
};
#define NR (sizeof roots / sizeof roots[0])

static void print_f64(int i, const char *stage, const double *s)
{
    for (int k = 0; k < P; k++) printf("fp64 %d %s %d %a %a %a\n", i, stage, k, s[3 * k], s[3 * k + 1], s[3 * k + 2]);
}

static void print_f32(int i, const char *stage, const float *s)
{
    for (int k = 0; k < P; k++)
        printf("fp32 %d %s %d %a %a %a\n", i, stage, k, (double)s[3 * k], (double)s[3 * k + 1], (double)s[3 * k + 2]);
}

int main(int argc, char **argv)
{
    double L = argc > 1 ? atof(argv[1]) : 5.5; /* ℓ = L/(P−1) */
    double h = 0.1;
    hb_model_f64 m64 = {1, P, 10.0, h, 1.0, L / (P - 1), 1.0, M_PI};
    hb_model_f32 m32 = {1, P, 10.0f, (float)h, 1.0f, (float)(L / (P - 1)), 1.0f, (float)M_PI};
    for (size_t i = 0; i < NR; i++) {
        double s[3 * P] = {0};
        float f[3 * P] = {0};
        for (int c = 0; c < 3; c++) {
            s[c] = roots[i][c];
            f[c] = (float)roots[i][c];
        }
        hb_drape_strand_f64(&m64, s);
        hb_drape_strand_f32(&m32, f);
        print_f64((int)i, "drape", s);
        print_f32((int)i, "drape", f);
        hb_collide_strand_f64(&m64, s);
        hb_collide_strand_f32(&m32, f);
        print_f64((int)i, "collide", s);
        print_f32((int)i, "collide", f);
        hb_wind_strand_f64(&m64, s);
        hb_wind_strand_f32(&m32, f);
        hb_collide_strand_f64(&m64, s);
        hb_collide_strand_f32(&m32, f);
        print_f64((int)i, "windcollide", s);
        print_f32((int)i, "windcollide", f);
    }
    return 0;
}
