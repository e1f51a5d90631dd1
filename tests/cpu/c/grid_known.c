/* grid_known.c — the hair–hair grid's per-point math (c_ref/dynamic/contact_impl.h, docs/model.md
 * §3.16) on hand-made clouds of points, in double: tests/cpu/test_hair_grid.py reads its lines
 * "name value" and checks them against their known answers. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dynamic/world.h"

#include "dynamic/precision_f64.h"
#include "dynamic/contact_impl.h"
#include "dynamic/precision_end.h"

#define N 5 /* nodes per axis: the box [0, 4]³, nodes at whole cm */
#define NODES (N * N * N)
#define MAXP 4096

static int64_t mass[NODES], mom[3 * NODES];
static double node_v[4 * NODES], node_a[4 * NODES], target[NODES];
static double ftab[1] = {1.0};

static hb_dyn_world_f64 world(int friction, int volume)
{
    hb_dyn_world_f64 w;
    memset(&w, 0, sizeof w);
    w.grid = 1, w.grid_friction = friction, w.grid_volume = volume, w.gn = N;
    for (int c = 0; c < 3; c++) w.glo[c] = 0.0, w.gsc[c] = 1.0;
    w.ftab = ftab, w.node_v = node_v, w.node_a = node_a;
    return w;
}

/* splat n points, then the node fields (volume: targets t everywhere, ρ̄₀ = rho0, K) */
static void build(const hb_dyn_world_f64 *w, int n, double (*x)[3], double (*v)[3], double t, double rho0, double kv)
{
    memset(mass, 0, sizeof mass);
    memset(mom, 0, sizeof mom);
    for (int i = 0; i < n; i++) {
        int64_t base, m[8], p[24];
        if (!hb_grid_splat_point_f64(NULL, w->glo, w->gsc, N, x[i], v[i], &base, m, p)) continue;
        for (int k = 0; k < 8; k++) {
            const int64_t j = hb_grid_corner_f64(base, N, k);
            mass[j] += m[k];
            for (int c = 0; c < 3; c++) mom[3 * j + c] += p[3 * k + c];
        }
    }
    for (int j = 0; j < NODES; j++) target[j] = t;
    for (int j = 0; j < NODES; j++)
        hb_grid_node_f64(j, N, mass, mom, target, 1.0 / rho0, -kv, w->gsc, NULL, w->grid_friction ? node_v : NULL,
                         w->grid_volume ? node_a : NULL);
}

static double x[MAXP][3], v[MAXP][3], v0[MAXP][3];

static double urand(unsigned *s)
{
    *s = *s * 1664525u + 1013904223u;
    return (double)(*s >> 8) / 16777216.0;
}

int main(void)
{
    unsigned seed = 12345u;
    /* 1. every point on the node (2, 2, 2), friction 1: every velocity becomes the mean */
    hb_dyn_world_f64 w = world(1, 0);
    const int n1 = 200;
    double mean[3] = {0, 0, 0};
    for (int i = 0; i < n1; i++)
        for (int c = 0; c < 3; c++) {
            x[i][c] = 2.0;
            v[i][c] = v0[i][c] = 100.0 * (urand(&seed) - 0.5);
            mean[c] += v[i][c] / n1;
        }
    build(&w, n1, x, v, 0, 1, 0);
    double worst = 0.0, mom_before[3] = {0, 0, 0}, mom_after[3] = {0, 0, 0};
    for (int i = 0; i < n1; i++) {
        for (int c = 0; c < 3; c++) mom_before[c] += v[i][c];
        hb_grid_correct_f64(&w, NULL, 0.01, 0, x[i], v[i]);
        for (int c = 0; c < 3; c++) {
            mom_after[c] += v[i][c];
            worst = fmax(worst, fabs(v[i][c] - mean[c]));
        }
    }
    printf("one_node_mean_error %.17g\n", worst);
    printf("one_node_momentum_error %.17g\n",
           fmax(fabs(mom_after[0] - mom_before[0]),
                fmax(fabs(mom_after[1] - mom_before[1]), fabs(mom_after[2] - mom_before[2]))));

    /* 2. a cloud spread over the grid, friction 1, the grid from the same state: momentum kept */
    const int n2 = 2000;
    for (int i = 0; i < n2; i++)
        for (int c = 0; c < 3; c++) {
            x[i][c] = 0.2 + 3.6 * urand(&seed);
            v[i][c] = v0[i][c] = 50.0 * (urand(&seed) - 0.5);
        }
    build(&w, n2, x, v, 0, 1, 0);
    for (int c = 0; c < 3; c++) mom_before[c] = mom_after[c] = 0.0;
    for (int i = 0; i < n2; i++) {
        for (int c = 0; c < 3; c++) mom_before[c] += v[i][c];
        hb_grid_correct_f64(&w, NULL, 0.01, 0, x[i], v[i]);
        for (int c = 0; c < 3; c++) mom_after[c] += v[i][c];
    }
    printf("cloud_momentum_error %.17g\n",
           fmax(fabs(mom_after[0] - mom_before[0]),
                fmax(fabs(mom_after[1] - mom_before[1]), fabs(mom_after[2] - mom_before[2]))));
    printf("cloud_momentum_scale %.17g\n", fabs(mom_before[0]) + fabs(mom_before[1]) + fabs(mom_before[2]) + n2);

    /* 3. a uniform velocity passes unchanged */
    for (int i = 0; i < n2; i++)
        for (int c = 0; c < 3; c++) v[i][c] = c == 0 ? 12.5 : c == 1 ? -3.25 : 0.5;
    build(&w, n2, x, v, 0, 1, 0);
    worst = 0.0;
    for (int i = 0; i < n2; i++) {
        hb_grid_correct_f64(&w, NULL, 0.01, 0, x[i], v[i]);
        worst = fmax(worst, fmax(fabs(v[i][0] - 12.5), fmax(fabs(v[i][1] + 3.25), fabs(v[i][2] - 0.5))));
    }
    printf("uniform_change %.17g\n", worst);

    /* 4. Galilean: friction 0.3 on v and on v + u commute (the results differ by u) */
    ftab[0] = 0.3;
    static double va[MAXP][3], vb[MAXP][3];
    const double u[3] = {40.0, -25.0, 7.0};
    for (int i = 0; i < n2; i++)
        for (int c = 0; c < 3; c++) va[i][c] = v0[i][c], vb[i][c] = v0[i][c] + u[c];
    build(&w, n2, x, va, 0, 1, 0);
    for (int i = 0; i < n2; i++) hb_grid_correct_f64(&w, NULL, 0.01, 0, x[i], va[i]);
    build(&w, n2, x, vb, 0, 1, 0);
    for (int i = 0; i < n2; i++) hb_grid_correct_f64(&w, NULL, 0.01, 0, x[i], vb[i]);
    worst = 0.0;
    for (int i = 0; i < n2; i++)
        for (int c = 0; c < 3; c++) worst = fmax(worst, fabs((vb[i][c] - va[i][c]) - u[c]));
    printf("galilean_error %.17g\n", worst);
    ftab[0] = 1.0;

    /* 5. volume: a cloud at or below the target density feels nothing */
    w = world(0, 1);
    const int n5 = 500; /* 500 points over 64 cells: about 8 a node, target 10 */
    for (int i = 0; i < n5; i++)
        for (int c = 0; c < 3; c++) {
            x[i][c] = 0.01 + 3.98 * urand(&seed);
            v[i][c] = 0.0;
        }
    build(&w, n5, x, v, 10.0, 10.0, 1000.0);
    worst = 0.0;
    for (int i = 0; i < n5; i++) {
        hb_grid_correct_f64(&w, NULL, 0.01, 1, x[i], v[i]);
        for (int c = 0; c < 3; c++) worst = fmax(worst, fabs(v[i][c]));
    }
    printf("below_target_change %.17g\n", worst);

    /* 6. volume: two overlapping clumps about x = 1.8 and x = 2.2 are pushed apart */
    const int n6 = 2000;
    for (int i = 0; i < n6; i++) {
        const double cx = i < n6 / 2 ? 1.8 : 2.2;
        x[i][0] = cx + 0.3 * (urand(&seed) - 0.5);
        x[i][1] = 2.0 + 0.6 * (urand(&seed) - 0.5);
        x[i][2] = 2.0 + 0.6 * (urand(&seed) - 0.5);
        v[i][0] = v[i][1] = v[i][2] = 0.0;
    }
    build(&w, n6, x, v, 1.0, 1.0, 1000.0);
    double va0 = 0.0, vb0 = 0.0;
    for (int i = 0; i < n6; i++) {
        hb_grid_correct_f64(&w, NULL, 0.01, 1, x[i], v[i]);
        if (i < n6 / 2) va0 += v[i][0] / (n6 / 2);
        else vb0 += v[i][0] / (n6 / 2);
    }
    printf("clump_left_vx %.17g\nclump_right_vx %.17g\n", va0, vb0);
    return 0;
}
