/* motion_track.c — the head transform track of --head-motion track: its CSV file and its copy
 * in the HDF5 state (docs/interfaces.md, "Motion tracks"). */
#include "dynamic/motion_track.h"
#include "runtime/input.h"

#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define TRACK_COLUMNS 8
#define TRACK_MAX_SAMPLES 10000000
static const char *const QUAT_HEADER[TRACK_COLUMNS] = {"time", "qw", "qx", "qy", "qz", "tx", "ty", "tz"};
static const char *const AXIS_HEADER[TRACK_COLUMNS] = {"time", "axis_x", "axis_y", "axis_z", "angle", "tx", "ty", "tz"};

#define FAIL(...)                                                                                                      \
    do {                                                                                                               \
        snprintf(err, errlen, __VA_ARGS__);                                                                            \
        goto fail;                                                                                                     \
    } while (0)

void hb_track_free(hb_head_track *k)
{
    free(k->t);
    free(k->q);
    free(k->tr);
    memset(k, 0, sizeof *k);
}

static int grow(hb_head_track *k, int64_t cap)
{
    double *t = realloc(k->t, (size_t)cap * sizeof *t);
    if (t) k->t = t;
    double *q = realloc(k->q, (size_t)cap * 4 * sizeof *q);
    if (q) k->q = q;
    double *tr = realloc(k->tr, (size_t)cap * 3 * sizeof *tr);
    if (tr) k->tr = tr;
    return t && q && tr ? 0 : -1;
}

/* Splits `line` at commas into at most TRACK_COLUMNS fields, spaces around each trimmed. */
static int split(char *line, char **field)
{
    int n = 0;
    for (char *p = line; p; n++) {
        if (n == TRACK_COLUMNS) return n + 1;
        char *comma = strchr(p, ',');
        if (comma) *comma = '\0';
        while (*p == ' ' || *p == '\t') p++;
        char *end = p + strlen(p);
        while (end > p && (end[-1] == ' ' || end[-1] == '\t' || end[-1] == '\r' || end[-1] == '\n')) *--end = '\0';
        field[n] = p;
        p = comma ? comma + 1 : NULL;
    }
    return n;
}

/* A decimal number and nothing else ([+-]digits[.digits][e[+-]digits]), finite. */
static int number(const char *s, double *v)
{
    if (!*s || strspn(s, "0123456789+-.eE") != strlen(s)) return -1;
    char *end;
    *v = strtod(s, &end);
    return *end == '\0' && isfinite(*v) ? 0 : -1;
}

/* The quaternion of a row (w, x, y, z), normalised; −1 when it names no rotation. */
static int row_quaternion(const double *v, int axis_angle, double q[4])
{
    if (axis_angle) {
        const double n = sqrt(v[1] * v[1] + v[2] * v[2] + v[3] * v[3]);
        if (v[4] == 0.0) {
            q[0] = 1.0;
            q[1] = q[2] = q[3] = 0.0;
            return 0;
        }
        if (!(n > 0.0)) return -1;
        const double s = sin(0.5 * v[4]) / n;
        q[0] = cos(0.5 * v[4]);
        for (int c = 0; c < 3; c++) q[1 + c] = s * v[1 + c];
        return 0;
    }
    const double n = sqrt(v[1] * v[1] + v[2] * v[2] + v[3] * v[3] + v[4] * v[4]);
    if (!(n > 0.0) || !isfinite(n)) return -1;
    for (int c = 0; c < 4; c++) q[c] = v[1 + c] / n;
    return 0;
}

int hb_track_load_csv(const char *path, hb_head_track *k, char *err, size_t errlen)
{
    memset(k, 0, sizeof *k);
    FILE *f = hb_input_fopen("--motion-track", path, "a motion track: a CSV file", 1, NULL, err, errlen);
    if (!f) return -1;
    char *line = NULL, *field[TRACK_COLUMNS + 1];
    size_t cap = 0;
    int64_t lineno = 0, have = 0;
    int axis_angle = -1;
    while (getline(&line, &cap, f) >= 0) {
        lineno++;
        const char *p = line + strspn(line, " \t");
        if (*p == '#' || *p == '\n' || *p == '\r' || *p == '\0') continue;
        const int n = split(line, field);
        if (axis_angle < 0) { /* the header names the form */
            int quat = n == TRACK_COLUMNS, axis = n == TRACK_COLUMNS;
            for (int c = 0; c < TRACK_COLUMNS && c < n; c++) {
                quat &= strcmp(field[c], QUAT_HEADER[c]) == 0;
                axis &= strcmp(field[c], AXIS_HEADER[c]) == 0;
            }
            if (!quat && !axis)
                FAIL("--motion-track %s: line %lld: the header must be time,qw,qx,qy,qz,tx,ty,tz or "
                     "time,axis_x,axis_y,axis_z,angle,tx,ty,tz",
                     path, (long long)lineno);
            axis_angle = axis;
            continue;
        }
        if (n != TRACK_COLUMNS)
            FAIL("--motion-track %s: line %lld: %d fields, the header names %d", path, (long long)lineno, n,
                 TRACK_COLUMNS);
        double v[TRACK_COLUMNS];
        for (int c = 0; c < TRACK_COLUMNS; c++)
            if (number(field[c], &v[c]))
                FAIL("--motion-track %s: line %lld: %s '%s' is not a finite decimal number", path, (long long)lineno,
                     axis_angle ? AXIS_HEADER[c] : QUAT_HEADER[c], field[c]);
        if (v[5] != 0.0 || v[6] != 0.0 || v[7] != 0.0)
            FAIL("--motion-track %s: line %lld: head translation is not modelled yet (translation %g, %g, %g cm at "
                 "t = %g s; docs/model.md §3.2)",
                 path, (long long)lineno, v[5], v[6], v[7], v[0]);
        if (have > 0 && !(v[0] > k->t[have - 1]))
            FAIL("--motion-track %s: line %lld: time %.17g s does not follow %.17g s (times must increase)", path,
                 (long long)lineno, v[0], k->t[have - 1]);
        if (have == TRACK_MAX_SAMPLES) FAIL("--motion-track %s: more than %d samples", path, TRACK_MAX_SAMPLES);
        if (have == k->n) {
            const int64_t more = k->n ? 2 * k->n : 64;
            if (grow(k, more)) FAIL("--motion-track %s: out of host memory", path);
            k->n = more;
        }
        if (row_quaternion(v, axis_angle, k->q + 4 * have))
            FAIL("--motion-track %s: line %lld: %s", path, (long long)lineno,
                 axis_angle ? "the axis is zero for a non-zero angle" : "the quaternion is zero");
        k->t[have] = v[0];
        for (int c = 0; c < 3; c++) k->tr[3 * have + c] = v[5 + c];
        have++;
    }
    if (ferror(f)) FAIL("--motion-track %s: a read failed", path);
    if (axis_angle < 0) FAIL("--motion-track %s: no header line (time,qw,qx,qy,qz,tx,ty,tz)", path);
    if (have == 0) FAIL("--motion-track %s: no samples after the header", path);
    k->n = have;
    free(line);
    fclose(f);
    return 0;
fail:
    free(line);
    fclose(f);
    hb_track_free(k);
    return -1;
}

int hb_track_write_h5(int64_t params, const hb_head_track *k)
{
    const hsize_t dims[2] = {(hsize_t)k->n, TRACK_COLUMNS};
    double *rows = malloc((size_t)k->n * TRACK_COLUMNS * sizeof *rows);
    if (!rows) return -1;
    for (int64_t i = 0; i < k->n; i++) {
        double *r = rows + TRACK_COLUMNS * i;
        r[0] = k->t[i];
        memcpy(r + 1, k->q + 4 * i, 4 * sizeof *r);
        memcpy(r + 5, k->tr + 3 * i, 3 * sizeof *r);
    }
    hid_t sp = H5Screate_simple(2, dims, NULL);
    hid_t ds =
        sp < 0 ? -1
               : H5Dcreate2((hid_t)params, "motion_track", H5T_IEEE_F64LE, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    int bad = ds < 0 || H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, rows) < 0;
    if (ds >= 0) H5Dclose(ds);
    if (sp >= 0) H5Sclose(sp);
    free(rows);
    return bad ? -1 : 0;
}

int hb_track_read_h5(int64_t file, const char *path, hb_head_track *k, char *err, size_t errlen)
{
    memset(k, 0, sizeof *k);
    double *rows = NULL;
    hsize_t dims[2] = {0, 0};
    hid_t ds = H5Lexists((hid_t)file, "parameters/motion_track", H5P_DEFAULT) > 0
                   ? H5Dopen2((hid_t)file, "parameters/motion_track", H5P_DEFAULT)
                   : -1;
    hid_t sp = ds < 0 ? -1 : H5Dget_space(ds);
    if (sp < 0 || H5Sget_simple_extent_ndims(sp) != 2 || H5Sget_simple_extent_dims(sp, dims, NULL) != 2 ||
        dims[1] != TRACK_COLUMNS || dims[0] < 1 || dims[0] > TRACK_MAX_SAMPLES) {
        snprintf(err, errlen, "--input %s: head_motion is 'track' but /parameters/motion_track [K][%d] is missing",
                 path, TRACK_COLUMNS);
        goto fail;
    }
    rows = malloc((size_t)dims[0] * TRACK_COLUMNS * sizeof *rows);
    if (!rows || H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, rows) < 0 || grow(k, (int64_t)dims[0])) {
        snprintf(err, errlen, "--input %s: cannot read /parameters/motion_track", path);
        goto fail;
    }
    k->n = (int64_t)dims[0];
    for (int64_t i = 0; i < k->n; i++) {
        const double *r = rows + TRACK_COLUMNS * i;
        int ok = 1;
        for (int c = 0; c < TRACK_COLUMNS; c++) ok &= isfinite(r[c]);
        const double n2 = r[1] * r[1] + r[2] * r[2] + r[3] * r[3] + r[4] * r[4];
        if (!ok || fabs(n2 - 1.0) > 1e-12 || (i > 0 && !(r[0] > rows[TRACK_COLUMNS * (i - 1)]))) {
            snprintf(err, errlen,
                     "--input %s: /parameters/motion_track row %lld is not a finite time after the one before with a "
                     "unit quaternion",
                     path, (long long)i);
            goto fail;
        }
        k->t[i] = r[0];
        memcpy(k->q + 4 * i, r + 1, 4 * sizeof *r);
        memcpy(k->tr + 3 * i, r + 5, 3 * sizeof *r);
    }
    free(rows);
    H5Sclose(sp);
    H5Dclose(ds);
    return 0;
fail:
    free(rows);
    if (sp >= 0) H5Sclose(sp);
    if (ds >= 0) H5Dclose(ds);
    hb_track_free(k);
    return -1;
}

int hb_track_same(const hb_head_track *a, const hb_head_track *b)
{
    return a->n == b->n && memcmp(a->t, b->t, (size_t)a->n * sizeof *a->t) == 0 &&
           memcmp(a->q, b->q, (size_t)a->n * 4 * sizeof *a->q) == 0 &&
           memcmp(a->tr, b->tr, (size_t)a->n * 3 * sizeof *a->tr) == 0;
}
