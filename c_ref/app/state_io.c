/* state_io.c — HDF5 states, H5MD 1.1 shaped (layout in docs/interfaces.md). */
#include "app/state_io.h"
#include "runtime/safe_write.h"
#include "runtime/checked.h"
#include "runtime/cli.h" /* HB_COLLIDER_SWEEPS_MAX */
#include "runtime/h5md_meta.h"
#include "runtime/input.h"
#include "dynamic/motion_track.h"

#include <errno.h>
#include <stddef.h>
#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <sys/stat.h>
#include <unistd.h>

#define FAIL(...)                                                                                                      \
    do {                                                                                                               \
        snprintf(err, errlen, __VA_ARGS__);                                                                            \
        goto fail;                                                                                                     \
    } while (0)

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void quiet_hdf5(void)
{
    /* No clean-up of HDF5 at exit(): after a close that failed (a full disk), HDF5 1.10's
     * clean-up dies of SIGSEGV on that file (exit 139 for the 4 the error set). Every file is
     * closed explicitly; the process's end frees the rest. Takes effect before HDF5 starts. */
    H5dont_atexit();
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}

/* The exit status of a failure to create or write the temporary file: the user's path (2),
 * or the machine's fault (4: a full disk, an I/O error). */
static int create_status(int e)
{
    return e == ENOENT || e == ENOTDIR || e == EACCES || e == EPERM || e == EROFS || e == ENAMETOOLONG || e == ELOOP
               ? HB_EXIT_USAGE
               : HB_EXIT_RUNTIME;
}

static hid_t str_type(void)
{
    hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, H5T_VARIABLE);
    H5Tset_cset(t, H5T_CSET_UTF8);
    return t;
}

/* ---- small attribute / dataset writers: each returns < 0 on failure ------------------- */
static int attr_str(hid_t loc, const char *name, const char *v)
{
    hid_t t = str_type(), sp = H5Screate(H5S_SCALAR);
    hid_t a = H5Acreate2(loc, name, t, sp, H5P_DEFAULT, H5P_DEFAULT);
    const char *val = v ? v : "";
    herr_t rc = a < 0 ? -1 : H5Awrite(a, t, &val);
    if (a >= 0) H5Aclose(a);
    H5Sclose(sp);
    H5Tclose(t);
    return rc < 0 ? -1 : 0;
}

static int attr_num(hid_t loc, const char *name, hid_t file_type, hid_t mem_type, const void *v)
{
    hid_t sp = H5Screate(H5S_SCALAR);
    hid_t a = H5Acreate2(loc, name, file_type, sp, H5P_DEFAULT, H5P_DEFAULT);
    herr_t rc = a < 0 ? -1 : H5Awrite(a, mem_type, v);
    if (a >= 0) H5Aclose(a);
    H5Sclose(sp);
    return rc < 0 ? -1 : 0;
}

static int attr_f64(hid_t loc, const char *name, double v)
{
    return attr_num(loc, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &v);
}

static int attr_i64(hid_t loc, const char *name, int64_t v)
{
    return attr_num(loc, name, H5T_STD_I64LE, H5T_NATIVE_INT64, &v);
}

static int attr_vec3(hid_t loc, const char *name, const double v[3])
{
    const hsize_t n = 3;
    hid_t sp = H5Screate_simple(1, &n, NULL);
    hid_t a = sp < 0 ? -1 : H5Acreate2(loc, name, H5T_IEEE_F64LE, sp, H5P_DEFAULT, H5P_DEFAULT);
    herr_t rc = a < 0 ? -1 : H5Awrite(a, H5T_NATIVE_DOUBLE, v);
    if (a >= 0) H5Aclose(a);
    if (sp >= 0) H5Sclose(sp);
    return rc < 0 ? -1 : 0;
}

static int attr_f64v(hid_t loc, const char *name, const double *v, hsize_t n)
{
    hid_t sp = H5Screate_simple(1, &n, NULL);
    hid_t a = sp < 0 ? -1 : H5Acreate2(loc, name, H5T_IEEE_F64LE, sp, H5P_DEFAULT, H5P_DEFAULT);
    herr_t rc = a < 0 ? -1 : H5Awrite(a, H5T_NATIVE_DOUBLE, v);
    if (a >= 0) H5Aclose(a);
    if (sp >= 0) H5Sclose(sp);
    return rc < 0 ? -1 : 0;
}

static int ds_1d(hid_t loc, const char *name, hid_t file_type, hid_t mem_type, hsize_t n, const void *v)
{
    hid_t sp = H5Screate_simple(1, &n, NULL);
    hid_t d = H5Dcreate2(loc, name, file_type, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    herr_t rc = d < 0 ? -1 : (n ? H5Dwrite(d, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) : 0);
    if (d >= 0) H5Dclose(d);
    H5Sclose(sp);
    return rc < 0 ? -1 : 0;
}

static int ds_str(hid_t loc, const char *name, hsize_t n, const char **v)
{
    hid_t t = str_type();
    int rc = ds_1d(loc, name, t, t, n, v);
    H5Tclose(t);
    return rc;
}

static hid_t make_group(hid_t loc, const char *name)
{
    return H5Gcreate2(loc, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
}

/* ---- writer ------------------------------------------------------------------------- */
struct hb_writer {
    char *path, *tmp;
    int force; /* --force: the rename may replace a file that appeared during the run */
    hid_t file, value;
    hb_scene scene;           /* points: the written ones (P_r with --render-points) */
    int64_t simulated_points; /* P_s */
    uint64_t rows;            /* N·P */
    int n_frames, cap;
    hb_frame_meta *frames;
    double seconds;
    /* the dynamic model */
    hid_t velocity; /* velocity/value, created by the first velocity frame */
    int n_vel, vel_cap;
    int64_t *vel_step;
    double *vel_time;
    int n_obs, obs_cap;
    hb_observables *obs;
    int64_t *obs_step;
    double *obs_time;
};

double hb_writer_seconds(const hb_writer *w)
{
    return w->seconds;
}

static void writer_free(hb_writer *w)
{
    if (!w) return;
    free(w->path);
    free(w->tmp);
    free(w->frames);
    free(w->vel_step);
    free(w->vel_time);
    free(w->obs);
    free(w->obs_step);
    free(w->obs_time);
    free(w);
}

void hb_writer_abort(hb_writer *w)
{
    if (!w) return;
    if (w->velocity >= 0) H5Dclose(w->velocity);
    if (w->value >= 0) H5Dclose(w->value);
    if (w->file >= 0) H5Fclose(w->file);
    if (w->tmp && w->tmp[0]) unlink(w->tmp);
    hb_safe_forget();
    writer_free(w);
}

hb_writer *hb_writer_open(const char *path, int force, const hb_scene *scene, int *status, char *err, size_t errlen)
{
    quiet_hdf5();
    *status = HB_EXIT_USAGE;
    double t0 = now_s();
    hb_writer *w = calloc(1, sizeof *w);
    if (!w) {
        snprintf(err, errlen, "out of host memory");
        return NULL;
    }
    w->file = w->value = w->velocity = -1;
    w->scene = *scene;
    w->simulated_points = scene->points;
    if (scene->dyn.render_points) w->scene.points = scene->dyn.render_points; /* §3.14: the rendered points */
    if (hb_mul_u64((uint64_t)scene->n_strands, (uint64_t)w->scene.points, &w->rows)) {
        snprintf(err, errlen, "--strands x --points is too large to address");
        free(w);
        return NULL;
    }
    if (hb_safe_output_check(path, force, err, errlen)) goto fail;
    w->force = force;
    w->path = strdup(path);
    size_t n = strlen(path) + 64;
    w->tmp = calloc(n, 1); /* "" until named: the abort path unlinks nothing */
    if (!w->path || !w->tmp) FAIL("out of host memory");
    if (hb_safe_tmp_name(path, w->tmp, n)) {
        w->tmp[0] = '\0';
        FAIL("--output %s: the path is too long", path);
    }
    /* the user block holds the marker that makes the temporary file ours (safe_write.h) */
    hid_t fcpl = H5Pcreate(H5P_FILE_CREATE);
    H5Pset_userblock(fcpl, HB_TMP_USERBLOCK);
    hb_safe_track(w->tmp); /* removed on a signal or exit() from here on */
    w->file = H5Fcreate(w->tmp, H5F_ACC_EXCL, fcpl, H5P_DEFAULT);
    H5Pclose(fcpl);
    if (w->file < 0) {
        const int e = errno;
        *status = create_status(e);
        hb_safe_forget();
        if (e != EEXIST) unlink(w->tmp); /* its random name is this run's: a full disk leaves it empty */
        errno = e;
        snprintf(err, errlen, "--output %s: cannot create %s (%s)", path, w->tmp, strerror(errno));
        free(w->tmp);
        w->tmp = NULL;
        goto fail;
    }
    if (hb_safe_mark(w->tmp)) {
        *status = create_status(errno);
        FAIL("--output %s: cannot write %s (%s)", path, w->tmp, strerror(errno));
    }
    *status = HB_EXIT_RUNTIME; /* the path is good: what fails from here on is the machine's */

    /* /h5md: version, author, creator (H5MD 1.1 §"H5MD metadata") */
    hid_t h5md = make_group(w->file, "h5md");
    int32_t version[2] = {1, 1};
    hsize_t two = 2;
    hid_t sp2 = H5Screate_simple(1, &two, NULL);
    hid_t av = H5Acreate2(h5md, "version", H5T_STD_I32LE, sp2, H5P_DEFAULT, H5P_DEFAULT);
    int bad = av < 0 || H5Awrite(av, H5T_NATIVE_INT32, version) < 0;
    if (av >= 0) H5Aclose(av);
    H5Sclose(sp2);
    hid_t author = make_group(h5md, "author");
    bad |= hb_h5md_str_attr(author, "name", "hairbench") < 0;
    hid_t creator = make_group(h5md, "creator");
    bad |= hb_h5md_str_attr(creator, "name", "hairbench") < 0;
    bad |= hb_h5md_str_attr(creator, "version", HB_VERSION) < 0;
    H5Gclose(creator);
    H5Gclose(author);
    H5Gclose(h5md);

    /* /particles/hair/{box,position} */
    hid_t particles = make_group(w->file, "particles");
    hid_t hair = make_group(particles, "hair");
    hid_t box = make_group(hair, "box");
    int32_t dim = 3;
    bad |= attr_num(box, "dimension", H5T_STD_I32LE, H5T_NATIVE_INT32, &dim) < 0;
    {
        const char *boundary[3] = {"none", "none", "none"};
        bad |= hb_h5md_str_array_attr(box, "boundary", boundary, 3) < 0;
    }
    H5Gclose(box);
    hid_t position = make_group(hair, "position");
    hsize_t dims[3] = {0, w->rows, 3}, maxdims[3] = {H5S_UNLIMITED, w->rows, 3};
    hsize_t chunk[3] = {1, w->rows < (1u << 20) ? w->rows : (1u << 20), 3};
    hid_t space = H5Screate_simple(3, dims, maxdims);
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(dcpl, 3, chunk);
    hid_t ftype = scene->precision == HB_FP64 ? H5T_IEEE_F64LE : H5T_IEEE_F32LE;
    w->value = H5Dcreate2(position, "value", ftype, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    H5Pclose(dcpl);
    H5Sclose(space);
    H5Gclose(position);
    H5Gclose(hair);
    H5Gclose(particles);
    if (bad || w->value < 0) FAIL("--output %s: HDF5 could not create the layout", path);
    w->seconds += now_s() - t0;
    return w;
fail:
    hb_writer_abort(w);
    return NULL;
}

/* Resizes *a to `cap` entries of `size` bytes; −1 (and *a unchanged) when out of memory. */
static int resize(void **a, int cap, size_t size)
{
    uint64_t bytes;
    if (cap < 0 || hb_mul_u64((uint64_t)cap, size, &bytes)) return -1;
    void *p = realloc(*a, (size_t)bytes);
    if (!p) return -1;
    *a = p;
    return 0;
}

/* An extendible [frames][rows][3] dataset, one chunk row per frame (or 2^20 rows). */
static hid_t create_frames_ds(hid_t loc, const char *name, uint64_t rows, hb_precision prec)
{
    hsize_t dims[3] = {0, rows, 3}, maxdims[3] = {H5S_UNLIMITED, rows, 3};
    hsize_t chunk[3] = {1, rows < (1u << 20) ? rows : (1u << 20), 3};
    hid_t space = H5Screate_simple(3, dims, maxdims);
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(dcpl, 3, chunk);
    hid_t d =
        H5Dcreate2(loc, name, prec == HB_FP64 ? H5T_IEEE_F64LE : H5T_IEEE_F32LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    H5Pclose(dcpl);
    H5Sclose(space);
    return d;
}

/* Writes frame `index` of a [frames][rows][3] dataset, extending it by one. */
static herr_t write_frame_row(hid_t ds, int index, uint64_t rows, hb_precision prec, const void *frame)
{
    hsize_t dims[3] = {(hsize_t)index + 1, rows, 3};
    if (H5Dset_extent(ds, dims) < 0) return -1;
    hid_t fs = H5Dget_space(ds);
    hsize_t start[3] = {(hsize_t)index, 0, 0}, count[3] = {1, rows, 3};
    H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, count, NULL);
    hid_t ms = H5Screate_simple(3, count, NULL);
    herr_t rc = H5Dwrite(ds, prec == HB_FP64 ? H5T_NATIVE_DOUBLE : H5T_NATIVE_FLOAT, ms, fs, H5P_DEFAULT, frame);
    H5Sclose(ms);
    H5Sclose(fs);
    return rc;
}

int hb_writer_rest(hb_writer *w, const void *rest, char *err, size_t errlen)
{
    double t0 = now_s();
    hsize_t dims[2] = {w->rows, 3};
    hid_t hair = H5Gopen2(w->file, "particles/hair", H5P_DEFAULT);
    hid_t sp = H5Screate_simple(2, dims, NULL);
    const int f64 = w->scene.precision == HB_FP64;
    hid_t d = H5Dcreate2(hair, "rest_position", f64 ? H5T_IEEE_F64LE : H5T_IEEE_F32LE, sp, H5P_DEFAULT, H5P_DEFAULT,
                         H5P_DEFAULT);
    herr_t rc =
        d < 0 ? -1 : H5Dwrite(d, f64 ? H5T_NATIVE_DOUBLE : H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, rest);
    if (rc >= 0 && hb_h5md_unit(d, "cm") < 0) rc = -1;
    if (d >= 0) H5Dclose(d);
    H5Sclose(sp);
    H5Gclose(hair);
    w->seconds += now_s() - t0;
    if (rc < 0) {
        snprintf(err, errlen, "--output %s: HDF5 could not write the rest shape (disk full?)", w->path);
        return -1;
    }
    return 0;
}

int hb_writer_velocity(hb_writer *w, const void *v, int64_t step, double time, char *err, size_t errlen)
{
    double t0 = now_s();
    if (w->velocity < 0) {
        hid_t hair = H5Gopen2(w->file, "particles/hair", H5P_DEFAULT);
        hid_t g = make_group(hair, "velocity");
        w->velocity = g < 0 ? -1 : create_frames_ds(g, "value", w->rows, w->scene.precision);
        if (w->velocity >= 0 && hb_h5md_unit(w->velocity, "cm s-1") < 0) {
            H5Dclose(w->velocity);
            w->velocity = -1;
        }
        if (g >= 0) H5Gclose(g);
        H5Gclose(hair);
        if (w->velocity < 0) {
            snprintf(err, errlen, "--output %s: HDF5 could not create the velocity dataset", w->path);
            return -1;
        }
    }
    if (w->n_vel == w->vel_cap) {
        int cap = w->vel_cap ? 2 * w->vel_cap : 8;
        if (resize((void **)&w->vel_step, cap, sizeof *w->vel_step) < 0 ||
            resize((void **)&w->vel_time, cap, sizeof *w->vel_time) < 0)
            goto oom;
        w->vel_cap = cap;
    }
    if (write_frame_row(w->velocity, w->n_vel, w->rows, w->scene.precision, v) < 0) {
        snprintf(err, errlen, "--output %s: HDF5 write of velocity frame %d failed (disk full?)", w->path, w->n_vel);
        return -1;
    }
    w->vel_step[w->n_vel] = step;
    w->vel_time[w->n_vel] = time;
    w->n_vel++;
    w->seconds += now_s() - t0;
    return 0;
oom:
    snprintf(err, errlen, "out of host memory");
    return -1;
}

int hb_writer_observables(hb_writer *w, const hb_observables *o, int64_t step, double time, char *err, size_t errlen)
{
    if (w->n_obs == w->obs_cap) {
        int cap = w->obs_cap ? 2 * w->obs_cap : 8;
        if (resize((void **)&w->obs, cap, sizeof *w->obs) < 0 ||
            resize((void **)&w->obs_step, cap, sizeof *w->obs_step) < 0 ||
            resize((void **)&w->obs_time, cap, sizeof *w->obs_time) < 0)
            goto oom;
        w->obs_cap = cap;
    }
    w->obs[w->n_obs] = *o;
    w->obs_step[w->n_obs] = step;
    w->obs_time[w->n_obs] = time;
    w->n_obs++;
    return 0;
oom:
    snprintf(err, errlen, "out of host memory");
    return -1;
}

int hb_writer_append(hb_writer *w, const void *frame, const hb_frame_meta *fm, char *err, size_t errlen)
{
    double t0 = now_s();
    if (w->n_frames == w->cap) {
        int cap = w->cap ? 2 * w->cap : 8;
        hb_frame_meta *f = realloc(w->frames, (size_t)cap * sizeof *f);
        if (!f) {
            snprintf(err, errlen, "out of host memory");
            return -1;
        }
        w->frames = f;
        w->cap = cap;
    }
    hsize_t dims[3] = {(hsize_t)w->n_frames + 1, w->rows, 3};
    if (H5Dset_extent(w->value, dims) < 0) {
        snprintf(err, errlen, "--output %s: HDF5 could not extend the frame dataset", w->path);
        return -1;
    }
    hid_t fs = H5Dget_space(w->value);
    hsize_t start[3] = {(hsize_t)w->n_frames, 0, 0}, count[3] = {1, w->rows, 3};
    H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, count, NULL);
    hid_t ms = H5Screate_simple(3, count, NULL);
    hid_t mt = w->scene.precision == HB_FP64 ? H5T_NATIVE_DOUBLE : H5T_NATIVE_FLOAT;
    herr_t rc = H5Dwrite(w->value, mt, ms, fs, H5P_DEFAULT, frame);
    H5Sclose(ms);
    H5Sclose(fs);
    if (rc < 0) {
        snprintf(err, errlen, "--output %s: HDF5 write of frame %d failed (disk full?)", w->path, w->n_frames);
        return -1;
    }
    w->frames[w->n_frames++] = *fm;
    w->seconds += now_s() - t0;
    return 0;
}

/* One observable's series: /observables/NAME/{value, step, time} (H5MD observables). */
static int write_series(hid_t obs, const char *name, hid_t ftype, hid_t mtype, const void *value, const hb_writer *w,
                        const char *unit)
{
    hid_t g = make_group(obs, name);
    if (g < 0) return -1;
    hsize_t n = (hsize_t)w->n_obs;
    int bad = ds_1d(g, "value", ftype, mtype, n, value) < 0;
    bad |= ds_1d(g, "step", H5T_STD_I64LE, H5T_NATIVE_INT64, n, w->obs_step) < 0;
    bad |= ds_1d(g, "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, n, w->obs_time) < 0;
    if (!bad && unit) {
        hid_t d = H5Dopen2(g, "value", H5P_DEFAULT);
        bad |= d < 0 || hb_h5md_unit(d, unit) < 0;
        if (d >= 0) H5Dclose(d);
    }
    if (!bad) {
        hid_t d = H5Dopen2(g, "time", H5P_DEFAULT);
        bad |= d < 0 || hb_h5md_unit(d, "s") < 0;
        if (d >= 0) H5Dclose(d);
    }
    H5Gclose(g);
    return bad ? -1 : 0;
}

/* Simulated-point LOD (docs/model.md §3.14): the point counts, and which rows are simulated
 * points (row i·P_r + k·m is simulated point k of strand i, m = (P_r − 1)/(P_s − 1)). */
static int write_lod(hb_writer *w, hid_t p)
{
    const int64_t pr = w->scene.dyn.render_points, ps = w->simulated_points, m = (pr - 1) / (ps - 1);
    int bad = attr_i64(p, "render_points", pr) < 0;
    bad |= attr_i64(p, "simulated_points", ps) < 0;
    int8_t *mark = malloc((size_t)w->rows);
    if (!mark) return -1;
    for (uint64_t r = 0; r < w->rows; r++) mark[r] = (int8_t)((int64_t)(r % (uint64_t)pr) % m == 0);
    hid_t hair = H5Gopen2(w->file, "particles/hair", H5P_DEFAULT);
    bad |= hair < 0 || ds_1d(hair, "simulated", H5T_STD_I8LE, H5T_NATIVE_INT8, (hsize_t)w->rows, mark) < 0;
    if (hair >= 0) H5Gclose(hair);
    free(mark);
    return bad ? -1 : 0;
}

/* §3.16 the grid's and §3.17 the colliders' parameters (docs/interfaces.md): attributes, and the
 * colliders as /parameters/colliders [n][HB_COLLIDER_ROW] with each mesh's SDF beside it. */
#define HB_COLLIDER_ROW 13 /* kind, frame, g[7], mu_s, mu_k, sdf_n, band */
static int write_world(hid_t p, const hb_dynamics *d)
{
    int bad = attr_i64(p, "grid", d->grid) < 0;
    if (d->grid) {
        bad |= attr_i64(p, "grid_n", d->grid_n) < 0;
        bad |= attr_str(p, "grid_rebuild",
                        d->grid_rebuild == HB_GRID_SUBSTEP ? "substep"
                        : d->grid_rebuild == HB_GRID_HELD  ? "held"
                                                           : "frame") < 0;
        bad |= attr_i64(p, "grid_box_given", d->grid_box_given) < 0;
        bad |= attr_f64v(p, "grid_box", d->grid_box, 6) < 0;
        bad |= attr_f64(p, "grid_padding", d->grid_padding) < 0;
        bad |= attr_i64(p, "grid_friction_declared", d->grid_friction_declared) < 0;
        bad |= attr_f64v(p, "grid_friction", d->grid_friction, 2) < 0;
        bad |= attr_i64(p, "grid_volume_declared", d->grid_volume_declared) < 0;
        bad |= attr_f64(p, "grid_volume", d->grid_volume) < 0;
    }
    bad |= attr_i64(p, "friction_declared", d->friction_declared) < 0;
    bad |= attr_f64v(p, "friction", d->friction, 2) < 0;
    bad |= attr_i64(p, "depenetration_declared", d->depen_declared) < 0;
    bad |= attr_f64(p, "depenetration_speed", d->depen_speed) < 0;
    bad |= attr_i64(p, "collider_sweeps", d->collider_sweeps) < 0;
    bad |= attr_i64(p, "planes_declared", d->planes_declared) < 0;
    bad |= attr_f64(p, "contact_margin", d->contact_margin) < 0;
    bad |= attr_i64(p, "collide_once", d->collide_once) < 0;
    bad |= attr_str(p, "body_motion",
                    d->body_motion == HB_BODY_SWAY   ? "sway"
                    : d->body_motion == HB_BODY_RISE ? "rise"
                                                     : "still") < 0;
    bad |= attr_f64(p, "body_amplitude", d->body_amplitude) < 0;
    bad |= attr_f64(p, "body_frequency", d->body_frequency) < 0;
    const hb_colliders *c = d->cols;
    bad |= attr_i64(p, "colliders", c ? c->n : 0) < 0;
    if (!c || c->n == 0 || bad) return bad ? -1 : 0;
    if (d->colliders_path) bad |= attr_str(p, "colliders_file", d->colliders_path) < 0;
    double rows[HB_MAX_COLLIDERS * HB_COLLIDER_ROW];
    for (int i = 0; i < c->n; i++) {
        const hb_collider *k = &c->c[i];
        double *r = rows + i * HB_COLLIDER_ROW;
        r[0] = k->kind, r[1] = k->frame;
        memcpy(r + 2, k->g, 7 * sizeof *r);
        r[9] = k->mu_s, r[10] = k->mu_k, r[11] = (double)k->sdf_n, r[12] = (double)k->band;
    }
    const hsize_t dims[2] = {(hsize_t)c->n, HB_COLLIDER_ROW};
    hid_t sp = H5Screate_simple(2, dims, NULL);
    hid_t ds = sp < 0 ? -1 : H5Dcreate2(p, "colliders", H5T_IEEE_F64LE, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    bad |= ds < 0 || H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, rows) < 0;
    if (ds >= 0) H5Dclose(ds);
    if (sp >= 0) H5Sclose(sp);
    for (int i = 0; i < c->n && !bad; i++) {
        const hb_collider *k = &c->c[i];
        if (!k->sdf) continue;
        char name[64];
        snprintf(name, sizeof name, "collider_sdf_%d", i);
        const hsize_t n = (hsize_t)(k->sdf_n * k->sdf_n * k->sdf_n);
        bad |= ds_1d(p, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, n, k->sdf) < 0;
        hid_t a = bad ? -1 : H5Dopen2(p, name, H5P_DEFAULT);
        bad |= a < 0 || attr_vec3(a, "lo", k->sdf_lo) < 0 || attr_f64(a, "spacing", k->sdf_h) < 0 ||
               attr_str(a, "source", k->source) < 0;
        if (a >= 0) H5Dclose(a);
    }
    return bad ? -1 : 0;
}

/* The dynamic model's datasets and parameters (docs/interfaces.md, "dynamic files"). */
static int write_dynamic(hb_writer *w, hid_t p, const hb_run_meta *rm)
{
    const hb_dynamics *d = &w->scene.dyn;
    int bad = 0;
    bad |= attr_str(p, "model", "dynamic") < 0;
    bad |= attr_str(p, "solver", hb_solver_name(d->solver)) < 0;
    bad |= attr_str(p, "head_motion", hb_motion_name(d->motion)) < 0;
    bad |= attr_str(p, "features", rm->features) < 0;
    bad |= attr_i64(p, "paper_frames", rm->paper_frames) < 0;
    bad |= attr_i64(p, "simulated_frames", rm->simulated_frames) < 0;
    bad |= attr_i64(p, "output_every", rm->output_every) < 0;
    bad |= attr_i64(p, "substeps", d->substeps) < 0;
    bad |= attr_i64(p, "iterations", d->iterations) < 0;
    bad |= attr_i64(p, "bend", d->bend) < 0;
    bad |= attr_i64(p, "shape", d->shape) < 0;
    bad |= attr_i64(p, "collider", d->collider) < 0;
    bad |= attr_i64(p, "drag_declared", d->drag_declared) < 0;
    bad |= attr_i64(p, "guided", d->guided) < 0; /* §3.13 */
    bad |= attr_i64(p, "lra", d->lra) < 0;
    bad |= attr_i64(p, "sag_free", d->sag_free) < 0;
    bad |= attr_i64(p, "per_segment", d->per_segment) < 0; /* §3.15 */
    if (d->render_points) bad |= write_lod(w, p) < 0;
    if (d->motion == HB_MOTION_TRACK && d->track) bad |= hb_track_write_h5(p, d->track) < 0;
    if (d->guided) bad |= attr_str(p, "follow", hb_follow_name(d->follow)) < 0;
    bad |= write_world(p, d) < 0; /* §3.16, §3.17 */
    const struct {
        const char *name;
        double v;
    } num[] = {
        {"frame_dt", d->frame_dt},
        {"gravity", d->gravity},
        {"drag", d->drag},
        {"damping", d->damping},
        {"stretch_compliance", d->stretch_compliance},
        {"bend_compliance", d->bend_compliance},
        {"shape_compliance", d->shape_compliance},
        {"shape_range", d->shape_range},
        {"ftl_damping", d->ftl_damping},
        {"collision_margin", d->collision_margin},
        {"wind_speed", d->wind_speed},
        {"gust_amplitude", d->gust_amplitude},
        {"gust_frequency", d->gust_frequency},
        {"gust_wavelength", d->gust_wavelength},
        {"motion_amplitude", d->motion_amplitude},
        {"motion_frequency", d->motion_frequency},
        {"guides", d->guides},
        {"lra_scale", d->lra_scale},
    };
    for (size_t i = 0; i < sizeof num / sizeof num[0]; i++) bad |= attr_f64(p, num[i].name, num[i].v) < 0;

    if (w->velocity >= 0) {
        hid_t g = H5Gopen2(w->file, "particles/hair/velocity", H5P_DEFAULT);
        bad |= g < 0;
        if (g >= 0) {
            bad |= ds_1d(g, "step", H5T_STD_I64LE, H5T_NATIVE_INT64, (hsize_t)w->n_vel, w->vel_step) < 0;
            bad |= ds_1d(g, "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, (hsize_t)w->n_vel, w->vel_time) < 0;
            hid_t t = bad ? -1 : H5Dopen2(g, "time", H5P_DEFAULT);
            bad |= t < 0 || hb_h5md_unit(t, "s") < 0;
            if (t >= 0) H5Dclose(t);
            H5Gclose(g);
        }
    }
    hid_t obs = make_group(w->file, "observables");
    if (obs < 0) return -1;
    const int n = w->n_obs;
    double *v = calloc((size_t)n + 1, sizeof *v);
    int64_t *c = calloc((size_t)n + 1, sizeof *c);
    int8_t *b = calloc((size_t)n + 1, sizeof *b);
    if (!v || !c || !b) bad = 1;
    else {
        for (int i = 0; i < n; i++) v[i] = w->obs[i].stretch_max;
        bad |= write_series(obs, "stretch_max", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, v, w, NULL) < 0;
        for (int i = 0; i < n; i++) v[i] = w->obs[i].penetration_max;
        bad |= write_series(obs, "penetration_max", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, v, w, "cm") < 0;
        for (int i = 0; i < n; i++) v[i] = w->obs[i].kinetic_energy;
        bad |= write_series(obs, "kinetic_energy", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, v, w, "cm+2 s-2") < 0;
        for (int i = 0; i < n; i++) c[i] = w->obs[i].blown_up_strands;
        bad |= write_series(obs, "blown_up_strands", H5T_STD_I64LE, H5T_NATIVE_INT64, c, w, NULL) < 0;
        for (int i = 0; i < n; i++) b[i] = (int8_t)hb_obs_blown_up(&w->obs[i]);
        bad |= write_series(obs, "blown_up", H5T_STD_I8LE, H5T_NATIVE_INT8, b, w, NULL) < 0;
    }
    free(v);
    free(c);
    free(b);
    H5Gclose(obs);
    return bad ? -1 : 0;
}

int hb_writer_close(hb_writer *w, const hb_run_meta *rm, char *err, size_t errlen)
{
    double t0 = now_s();
    const hb_scene *s = &w->scene;
    int F = w->n_frames, bad = 0;
    int64_t *i64 = calloc((size_t)F + 1, sizeof *i64);
    double *f64 = calloc((size_t)F + 1, sizeof *f64);
    int8_t *i8 = calloc((size_t)F + 1, sizeof *i8);
    const char **str = calloc((size_t)F + 1, sizeof *str);
    if (!i64 || !f64 || !i8 || !str) {
        snprintf(err, errlen, "out of host memory");
        bad = 1;
        goto out;
    }

    {
        hid_t pos = H5Gopen2(w->file, "particles/hair/position", H5P_DEFAULT);
        /* step and time from each frame's record: paper frames at t = 0 (docs/interfaces.md) */
        for (int f = 0; f < F; f++) {
            i64[f] = w->frames[f].step;
            f64[f] = w->frames[f].time;
        }
        bad |= ds_1d(pos, "step", H5T_STD_I64LE, H5T_NATIVE_INT64, (hsize_t)F, i64) < 0;
        bad |= ds_1d(pos, "time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, (hsize_t)F, f64) < 0;
        H5Gclose(pos);
        bad |= hb_h5md_finish(w->file, s) < 0; /* units, strand ids (h5md_meta.c) */
    }

    hid_t p = make_group(w->file, "parameters");
    bad |= p < 0;
    bad |= attr_f64(p, "head_radius", s->head_radius) < 0;
    bad |= attr_f64(p, "hair_offset", s->hair_offset) < 0;
    bad |= attr_f64(p, "hair_length", s->hair_length) < 0;
    bad |= attr_f64(p, "face_margin", s->face_margin) < 0;
    bad |= attr_f64(p, "wind_strength", s->wind_strength) < 0;
    bad |= attr_f64(p, "wind_angle", s->wind_angle) < 0;
    bad |= attr_f64(p, "segment_length", hb_segment_length(s)) < 0;
    bad |= attr_num(p, "seed", H5T_STD_U64LE, H5T_NATIVE_UINT64, &s->seed) < 0;
    bad |= attr_i64(p, "n_strands", s->n_strands) < 0;
    bad |= attr_i64(p, "points_per_strand", s->points) < 0;
    bad |= attr_str(p, "precision", hb_precision_name(s->precision)) < 0;
    bad |= attr_str(p, "backend", rm->backend) < 0;
    bad |= attr_str(p, "variant", rm->variant) < 0;
    bad |= attr_i64(p, "threads", rm->threads) < 0;
    bad |= attr_i64(p, "block_size", rm->block_size) < 0;
    bad |= attr_i64(p, "repeat", rm->repeat) < 0;
    bad |= attr_i64(p, "warmup", rm->warmup) < 0;
    bad |= attr_str(p, "git_revision", rm->git_revision) < 0;
    bad |= attr_str(p, "compiler", rm->compiler) < 0;
    bad |= attr_str(p, "flags", rm->flags) < 0;
    bad |= attr_str(p, "device", rm->device) < 0;
    bad |= attr_str(p, "driver", rm->driver) < 0;
    bad |= attr_str(p, "version", HB_VERSION) < 0;
    bad |= attr_f64(p, "end_to_end_ms", rm->end_to_end_ms) < 0;
    if (rm->groom_head) { /* §3.15: a groom file's head sphere, fitted or given */
        bad |= attr_str(p, "groom_head", rm->groom_head) < 0;
        bad |= attr_vec3(p, "groom_head_center", rm->groom_head_center) < 0;
    }

    for (int f = 0; f < F; f++) str[f] = w->frames[f].stage;
    bad |= ds_str(p, "stage", (hsize_t)F, str) < 0;
    for (int f = 0; f < F; f++) str[f] = w->frames[f].fused;
    bad |= ds_str(p, "fused", (hsize_t)F, str) < 0;
    for (int f = 0; f < F; f++) str[f] = w->frames[f].backend;
    bad |= ds_str(p, "frame_backend", (hsize_t)F, str) < 0;
    for (int f = 0; f < F; f++) i8[f] = (int8_t)w->frames[f].skipped;
    bad |= ds_1d(p, "skipped", H5T_STD_I8LE, H5T_NATIVE_INT8, (hsize_t)F, i8) < 0;
    for (int f = 0; f < F; f++) i64[f] = w->frames[f].moved_points;
    bad |= ds_1d(p, "moved_points", H5T_STD_I64LE, H5T_NATIVE_INT64, (hsize_t)F, i64) < 0;
#define FRAME_F64(field)                                                                                               \
    for (int f = 0; f < F; f++) f64[f] = w->frames[f].field;                                                           \
    bad |= ds_1d(p, #field, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, (hsize_t)F, f64) < 0;
    FRAME_F64(wind_strength)
    FRAME_F64(wind_angle)
#undef FRAME_F64
    for (int f = 0; f < F; f++) f64[f] = w->frames[f].median_ms;
    bad |= ds_1d(p, "stage_median_ms", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, (hsize_t)F, f64) < 0;
    for (int f = 0; f < F; f++) f64[f] = w->frames[f].min_ms;
    bad |= ds_1d(p, "stage_min_ms", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, (hsize_t)F, f64) < 0;
    for (int f = 0; f < F; f++) f64[f] = w->frames[f].max_ms;
    bad |= ds_1d(p, "stage_max_ms", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, (hsize_t)F, f64) < 0;
    if (rm->dynamic) bad |= write_dynamic(w, p, rm) < 0;
    /* the write time so far, frames included; the closing itself is not counted */
    bad |= attr_f64(p, "hdf5_write_ms", 1e3 * (w->seconds + now_s() - t0)) < 0;
    if (p >= 0) H5Gclose(p);
    if (bad) snprintf(err, errlen, "--output %s: HDF5 could not write /parameters", w->path);
out:
    free(i64);
    free(f64);
    free(i8);
    free(str);
    if (bad) {
        hb_writer_abort(w);
        return -1;
    }
    H5Dclose(w->value);
    w->value = -1;
    if (w->velocity >= 0) H5Dclose(w->velocity);
    w->velocity = -1;
    herr_t rc = H5Fclose(w->file);
    w->file = -1;
    if (rc < 0) {
        snprintf(err, errlen, "--output %s: HDF5 could not close the file (disk full?)", w->path);
        hb_writer_abort(w);
        return -1;
    }
    const int rc_commit = hb_safe_commit(w->tmp, w->path, w->force, err, errlen);
    if (rc_commit != 0) {
        hb_writer_abort(w);
        return rc_commit;
    }
    w->seconds += now_s() - t0;
    writer_free(w);
    return 0;
}

/* ---- reader ------------------------------------------------------------------------- */
static int has_path(hid_t file, const char *path)
{
    /* H5Lexists checks one link at a time: walk the path. */
    char buf[256];
    snprintf(buf, sizeof buf, "%s", path);
    char partial[256] = "";
    char *save = NULL;
    for (char *tok = strtok_r(buf, "/", &save); tok; tok = strtok_r(NULL, "/", &save)) {
        strncat(partial, "/", sizeof partial - strlen(partial) - 1);
        strncat(partial, tok, sizeof partial - strlen(partial) - 1);
        if (H5Lexists(file, partial, H5P_DEFAULT) <= 0) return 0;
    }
    return 1;
}

static int read_attr(hid_t loc, const char *name, hid_t mem_type, void *v)
{
    if (H5Aexists(loc, name) <= 0) return -1;
    hid_t a = H5Aopen(loc, name, H5P_DEFAULT);
    if (a < 0) return -1;
    hid_t sp = H5Aget_space(a);
    int ok = H5Sget_simple_extent_npoints(sp) == 1 && H5Aread(a, mem_type, v) >= 0;
    H5Sclose(sp);
    H5Aclose(a);
    return ok ? 0 : -1;
}

static int read_attr_str(hid_t loc, const char *name, char *out, size_t n)
{
    if (H5Aexists(loc, name) <= 0) return -1;
    hid_t a = H5Aopen(loc, name, H5P_DEFAULT);
    hid_t t = H5Aget_type(a);
    int rc = -1;
    if (H5Tget_class(t) == H5T_STRING) {
        if (H5Tis_variable_str(t) > 0) {
            char *s = NULL;
            hid_t mt = str_type();
            if (H5Aread(a, mt, &s) >= 0 && s) {
                snprintf(out, n, "%s", s);
                H5free_memory(s);
                rc = 0;
            }
            H5Tclose(mt);
        } else {
            size_t sz = H5Tget_size(t);
            char *buf = calloc(sz + 1, 1);
            if (buf && H5Aread(a, t, buf) >= 0) {
                snprintf(out, n, "%s", buf);
                rc = 0;
            }
            free(buf);
        }
    }
    H5Tclose(t);
    H5Aclose(a);
    return rc;
}

/* Reads a 1-D dataset of length F under /parameters into mem_type; missing → −1. */
static int read_frames_ds(hid_t p, const char *name, hid_t mem_type, hsize_t F, void *v)
{
    if (H5Lexists(p, name, H5P_DEFAULT) <= 0) return -1;
    hid_t d = H5Dopen2(p, name, H5P_DEFAULT);
    if (d < 0) return -1;
    hid_t sp = H5Dget_space(d);
    hsize_t n = 0;
    int ok = H5Sget_simple_extent_ndims(sp) == 1 && H5Sget_simple_extent_dims(sp, &n, NULL) == 1 && n == F;
    ok = ok && H5Dread(d, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) >= 0;
    H5Sclose(sp);
    H5Dclose(d);
    return ok ? 0 : -1;
}

static int read_frames_str(hid_t p, const char *name, hsize_t F, hb_frame_meta *fm, size_t offset, size_t width)
{
    char **s = calloc(F ? F : 1, sizeof *s);
    if (!s) return -1;
    hid_t t = str_type();
    int rc = read_frames_ds(p, name, t, F, s);
    if (rc == 0) {
        for (hsize_t f = 0; f < F; f++) snprintf((char *)&fm[f] + offset, width, "%s", s[f] ? s[f] : "");
        for (hsize_t f = 0; f < F; f++) H5free_memory(s[f]);
    }
    H5Tclose(t);
    free(s);
    return rc;
}

void hb_input_close(hb_input *in)
{
    hb_colliders_free(&in->cols);
    if (in->hid > 0) H5Fclose((hid_t)in->hid);
    in->hid = 0;
    free(in->frames);
    free(in->vel_step);
    free(in->vel_time);
    free(in->obs);
    free(in->obs_step);
    free(in->obs_time);
    in->frames = NULL;
    in->vel_step = in->obs_step = NULL;
    in->vel_time = in->obs_time = NULL;
    in->obs = NULL;
    hb_track_free(&in->track);
}

/* Reads a 1-D dataset at `path` of any length into a new array; its length in *n. */
static void *read_1d(hid_t f, const char *path, hid_t mem_type, size_t size, hsize_t *n)
{
    *n = 0;
    if (!has_path(f, path)) return NULL;
    hid_t d = H5Dopen2(f, path, H5P_DEFAULT);
    if (d < 0) return NULL;
    hid_t sp = H5Dget_space(d);
    void *v = NULL;
    if (H5Sget_simple_extent_ndims(sp) == 1 && H5Sget_simple_extent_dims(sp, n, NULL) == 1) {
        v = calloc(*n ? *n : 1, size);
        if (v && H5Dread(d, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) < 0) {
            free(v);
            v = NULL;
        }
    }
    H5Sclose(sp);
    H5Dclose(d);
    return v;
}

/* Checks a [frames?][rows][3] float dataset of the file's precision; its frame count in *frames. */
static int check_rows(hid_t f, const char *path, int rank, uint64_t rows, hb_precision prec, hsize_t *frames)
{
    hid_t d = H5Dopen2(f, path, H5P_DEFAULT);
    if (d < 0) return -1;
    hid_t sp = H5Dget_space(d), t = H5Dget_type(d);
    hsize_t dims[3] = {0, 0, 0};
    int ok = H5Sget_simple_extent_ndims(sp) == rank && H5Sget_simple_extent_dims(sp, dims, NULL) == rank;
    ok = ok && H5Tget_class(t) == H5T_FLOAT && H5Tget_size(t) == hb_real_size(prec);
    if (ok && rank == 3) ok = dims[1] == rows && dims[2] == 3;
    if (ok && rank == 2) ok = dims[0] == rows && dims[1] == 3;
    if (frames) *frames = rank == 3 ? dims[0] : 1;
    H5Tclose(t);
    H5Sclose(sp);
    H5Dclose(d);
    return ok ? 0 : -1;
}

static int read_attr_f64v(hid_t loc, const char *name, double *v, hssize_t n)
{
    if (H5Aexists(loc, name) <= 0) return -1;
    hid_t a = H5Aopen(loc, name, H5P_DEFAULT);
    if (a < 0) return -1;
    hid_t sp = H5Aget_space(a);
    int ok = H5Sget_simple_extent_npoints(sp) == n && H5Aread(a, H5T_NATIVE_DOUBLE, v) >= 0;
    H5Sclose(sp);
    H5Aclose(a);
    return ok ? 0 : -1;
}

/* §3.16–3.17 from an --input file (absent in files written before them: none). */
static int input_world(hb_input *in, const char *path, hid_t p, char *err, size_t errlen)
{
    hb_dynamics *d = &in->scene.dyn;
    int64_t v = 0, nc = 0;
    char word[16] = "";
#define BAD(what) return snprintf(err, errlen, "--input %s: /parameters has a bad or missing %s", path, what), -1
    if (read_attr(p, "grid", H5T_NATIVE_INT64, &v) == 0 && v) {
        d->grid = 1;
        int64_t given = 0, fr = 0, vol = 0;
        if (read_attr(p, "grid_n", H5T_NATIVE_INT64, &d->grid_n) < 0) BAD("grid_n");
        if (read_attr_str(p, "grid_rebuild", word, sizeof word) < 0 ||
            (strcmp(word, "frame") != 0 && strcmp(word, "substep") != 0 && strcmp(word, "held") != 0))
            BAD("grid_rebuild");
        d->grid_rebuild = strcmp(word, "substep") == 0 ? HB_GRID_SUBSTEP
                          : strcmp(word, "held") == 0  ? HB_GRID_HELD
                                                       : HB_GRID_FRAME;
        if (read_attr(p, "grid_box_given", H5T_NATIVE_INT64, &given) < 0 ||
            read_attr_f64v(p, "grid_box", d->grid_box, 6) < 0 ||
            read_attr(p, "grid_padding", H5T_NATIVE_DOUBLE, &d->grid_padding) < 0)
            BAD("grid box");
        if (read_attr(p, "grid_friction_declared", H5T_NATIVE_INT64, &fr) < 0 ||
            read_attr_f64v(p, "grid_friction", d->grid_friction, 2) < 0 ||
            read_attr(p, "grid_volume_declared", H5T_NATIVE_INT64, &vol) < 0 ||
            read_attr(p, "grid_volume", H5T_NATIVE_DOUBLE, &d->grid_volume) < 0)
            BAD("grid friction or volume");
        d->grid_box_given = given != 0, d->grid_friction_declared = fr != 0, d->grid_volume_declared = vol != 0;
    }
    if (read_attr(p, "friction_declared", H5T_NATIVE_INT64, &v) == 0 && v) {
        d->friction_declared = 1;
        if (read_attr_f64v(p, "friction", d->friction, 2) < 0) BAD("friction");
    }
    if (read_attr(p, "depenetration_declared", H5T_NATIVE_INT64, &v) == 0 && v) {
        d->depen_declared = 1;
        if (read_attr(p, "depenetration_speed", H5T_NATIVE_DOUBLE, &d->depen_speed) < 0) BAD("depenetration_speed");
    }
    d->collider_sweeps = 1; /* absent in files written before sweeps: one */
    if (read_attr(p, "collider_sweeps", H5T_NATIVE_INT64, &d->collider_sweeps) == 0 &&
        !(d->collider_sweeps >= 1 && d->collider_sweeps <= HB_COLLIDER_SWEEPS_MAX))
        BAD("collider_sweeps");
    if (read_attr(p, "planes_declared", H5T_NATIVE_INT64, &v) == 0 && v) { /* absent in older files: exact */
        d->planes_declared = 1;
        if (read_attr(p, "contact_margin", H5T_NATIVE_DOUBLE, &d->contact_margin) < 0 || !(d->contact_margin > 0.0))
            BAD("contact_margin");
    }
    if (read_attr(p, "collide_once", H5T_NATIVE_INT64, &v) == 0) /* absent in older files: every iteration */
        d->collide_once = v != 0;
    if (read_attr_str(p, "body_motion", word, sizeof word) == 0) {
        if (strcmp(word, "sway") == 0) d->body_motion = HB_BODY_SWAY;
        else if (strcmp(word, "rise") == 0) d->body_motion = HB_BODY_RISE;
        else if (strcmp(word, "still") != 0) BAD("body_motion");
        if (read_attr(p, "body_amplitude", H5T_NATIVE_DOUBLE, &d->body_amplitude) < 0 ||
            read_attr(p, "body_frequency", H5T_NATIVE_DOUBLE, &d->body_frequency) < 0)
            BAD("body sway");
    }
    if (read_attr(p, "colliders", H5T_NATIVE_INT64, &nc) < 0 || nc == 0) return 0;
    if (nc < 0 || nc > HB_MAX_COLLIDERS) BAD("colliders count");
    double rows[HB_MAX_COLLIDERS * HB_COLLIDER_ROW];
    hid_t ds = H5Dopen2(p, "colliders", H5P_DEFAULT);
    hid_t sp = ds < 0 ? -1 : H5Dget_space(ds);
    hsize_t dims[2] = {0, 0};
    const int ok = sp >= 0 && H5Sget_simple_extent_ndims(sp) == 2 && H5Sget_simple_extent_dims(sp, dims, NULL) == 2 &&
                   dims[0] == (hsize_t)nc && dims[1] == HB_COLLIDER_ROW &&
                   H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, rows) >= 0;
    if (sp >= 0) H5Sclose(sp);
    if (ds >= 0) H5Dclose(ds);
    if (!ok) BAD("colliders dataset");
    hb_colliders *c = &in->cols;
    for (int i = 0; i < (int)nc; i++) {
        hb_collider *k = &c->c[i];
        const double *r = rows + i * HB_COLLIDER_ROW;
        memset(k, 0, sizeof *k);
        k->kind = (int)r[0], k->frame = (int)r[1];
        memcpy(k->g, r + 2, 7 * sizeof *r);
        k->mu_s = r[9], k->mu_k = r[10], k->sdf_n = (int64_t)r[11], k->band = (int64_t)r[12];
        c->n = i + 1;
        if (!(k->kind >= HB_COL_SPHERE && k->kind <= HB_COL_MESH && (k->frame == 0 || k->frame == 1) &&
              k->mu_s >= 0.0 && k->mu_k >= 0.0 && k->mu_k <= k->mu_s))
            BAD("collider row");
        if (k->kind != HB_COL_MESH) continue;
        char name[64];
        snprintf(name, sizeof name, "collider_sdf_%d", i);
        if (!(k->sdf_n >= 8 && k->sdf_n <= 512)) BAD("mesh SDF size");
        const int64_t n3 = k->sdf_n * k->sdf_n * k->sdf_n;
        hid_t m = H5Dopen2(p, name, H5P_DEFAULT);
        hid_t ms = m < 0 ? -1 : H5Dget_space(m);
        k->sdf = malloc((size_t)n3 * sizeof *k->sdf);
        const int good = ms >= 0 && k->sdf && H5Sget_simple_extent_npoints(ms) == n3 &&
                         H5Dread(m, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, k->sdf) >= 0 &&
                         read_attr_f64v(m, "lo", k->sdf_lo, 3) == 0 &&
                         read_attr(m, "spacing", H5T_NATIVE_DOUBLE, &k->sdf_h) == 0 &&
                         read_attr_str(m, "source", k->source, sizeof k->source) == 0;
        if (ms >= 0) H5Sclose(ms);
        if (m >= 0) H5Dclose(m);
        if (!good || !(k->sdf_h > 0.0)) BAD(name);
        for (int64_t j = 0; j < n3; j++)
            if (!isfinite(k->sdf[j])) BAD(name);
    }
    if (read_attr_str(p, "colliders_file", in->colliders_file, sizeof in->colliders_file) < 0)
        snprintf(in->colliders_file, sizeof in->colliders_file, "%s", path);
    d->cols = c;
    d->colliders_path = in->colliders_file;
#undef BAD
    return 0;
}

/* A dynamic file's arrays: the rest shape, the velocities where stored, the observables. */
static int input_dynamic_arrays(hb_input *in, const char *path, char *err, size_t errlen)
{
    hid_t f = (hid_t)in->hid;
    const uint64_t rows = (uint64_t)in->scene.n_strands * (uint64_t)in->scene.points;
    if (!has_path(f, "particles/hair/rest_position") ||
        check_rows(f, "particles/hair/rest_position", 2, rows, in->scene.precision, NULL) < 0)
        return snprintf(err, errlen, "--input %s: a dynamic file needs /particles/hair/rest_position [%llu][3] in %s",
                        path, (unsigned long long)rows, hb_precision_name(in->scene.precision)),
               -1;
    hsize_t nv = 0, ns = 0, nt = 0;
    if (has_path(f, "particles/hair/velocity/value")) {
        if (check_rows(f, "particles/hair/velocity/value", 3, rows, in->scene.precision, &nv) < 0)
            return snprintf(err, errlen, "--input %s: velocity/value must be [frames][%llu][3] in %s", path,
                            (unsigned long long)rows, hb_precision_name(in->scene.precision)),
                   -1;
        in->vel_step = read_1d(f, "particles/hair/velocity/step", H5T_NATIVE_INT64, sizeof(int64_t), &ns);
        in->vel_time = read_1d(f, "particles/hair/velocity/time", H5T_NATIVE_DOUBLE, sizeof(double), &nt);
        if (!in->vel_step || !in->vel_time || ns != nv || nt != nv)
            return snprintf(err, errlen,
                            "--input %s: velocity/step and velocity/time need one entry per velocity "
                            "frame (%llu)",
                            path, (unsigned long long)nv),
                   -1;
        in->n_vel = (int)nv;
    }
    /* observables: copied into the output when present and consistent */
    hsize_t n1 = 0, n2 = 0, n3 = 0, n4 = 0, n5 = 0;
    double *sm = read_1d(f, "observables/stretch_max/value", H5T_NATIVE_DOUBLE, sizeof(double), &n1);
    double *pm = read_1d(f, "observables/penetration_max/value", H5T_NATIVE_DOUBLE, sizeof(double), &n2);
    double *ke = read_1d(f, "observables/kinetic_energy/value", H5T_NATIVE_DOUBLE, sizeof(double), &n3);
    int64_t *bs = read_1d(f, "observables/blown_up_strands/value", H5T_NATIVE_INT64, sizeof(int64_t), &n4);
    in->obs_step = read_1d(f, "observables/stretch_max/step", H5T_NATIVE_INT64, sizeof(int64_t), &n5);
    in->obs_time = read_1d(f, "observables/stretch_max/time", H5T_NATIVE_DOUBLE, sizeof(double), &ns);
    int ok = sm && pm && ke && bs && in->obs_step && in->obs_time && n2 == n1 && n3 == n1 && n4 == n1 && n5 == n1 &&
             ns == n1;
    if (ok) {
        in->obs = calloc(n1 ? n1 : 1, sizeof *in->obs);
        ok = in->obs != NULL;
        for (hsize_t i = 0; ok && i < n1; i++) in->obs[i] = (hb_observables){sm[i], pm[i], ke[i], bs[i]};
        in->n_obs = (int)n1;
    }
    free(sm);
    free(pm);
    free(ke);
    free(bs);
    if (!ok)
        return snprintf(err, errlen,
                        "--input %s: /observables must hold stretch_max, penetration_max, kinetic_energy "
                        "and blown_up_strands with one value, step and time each",
                        path),
               -1;
    return 0;
}

/* The dynamic part of an --input file (docs/interfaces.md, "dynamic files"). */
static int input_dynamic(hb_input *in, const char *path, hid_t p, char *err, size_t errlen)
{
    hid_t f = (hid_t)in->hid;
    hb_dynamics *d = &in->scene.dyn;
    char model[32] = "", solver[16] = "", motion[16] = "";
    if (read_attr_str(p, "model", model, sizeof model) < 0 || strcmp(model, "dynamic") != 0) {
        if (has_path(f, "particles/hair/rest_position") || has_path(f, "particles/hair/velocity"))
            return snprintf(err, errlen,
                            "--input %s holds a rest shape or velocities but /parameters/model is not "
                            "'dynamic'",
                            path),
                   -1;
        return 0;
    }
    in->dynamic = 1;
    const char *missing = NULL;
    int64_t bend = 0, shape = 0, collider = 1, drag_declared = 0;
#define NEED(call, name)                                                                                               \
    if (!missing && (call) < 0) missing = name
    NEED(read_attr_str(p, "solver", solver, sizeof solver), "solver");
    NEED(read_attr_str(p, "head_motion", motion, sizeof motion), "head_motion");
    NEED(read_attr(p, "paper_frames", H5T_NATIVE_INT64, &in->paper_frames), "paper_frames");
    NEED(read_attr(p, "substeps", H5T_NATIVE_INT64, &d->substeps), "substeps");
    NEED(read_attr(p, "iterations", H5T_NATIVE_INT64, &d->iterations), "iterations");
    NEED(read_attr(p, "bend", H5T_NATIVE_INT64, &bend), "bend");
    NEED(read_attr(p, "shape", H5T_NATIVE_INT64, &shape), "shape");
    NEED(read_attr(p, "collider", H5T_NATIVE_INT64, &collider), "collider");
    NEED(read_attr(p, "drag_declared", H5T_NATIVE_INT64, &drag_declared), "drag_declared");
    const struct {
        const char *name;
        double *v;
    } num[] = {
        {"frame_dt", &d->frame_dt},
        {"gravity", &d->gravity},
        {"drag", &d->drag},
        {"damping", &d->damping},
        {"stretch_compliance", &d->stretch_compliance},
        {"bend_compliance", &d->bend_compliance},
        {"shape_compliance", &d->shape_compliance},
        {"shape_range", &d->shape_range},
        {"ftl_damping", &d->ftl_damping},
        {"collision_margin", &d->collision_margin},
        {"wind_speed", &d->wind_speed},
        {"gust_amplitude", &d->gust_amplitude},
        {"gust_frequency", &d->gust_frequency},
        {"gust_wavelength", &d->gust_wavelength},
        {"motion_amplitude", &d->motion_amplitude},
        {"motion_frequency", &d->motion_frequency},
    };
    for (size_t i = 0; i < sizeof num / sizeof num[0]; i++)
        NEED(read_attr(p, num[i].name, H5T_NATIVE_DOUBLE, num[i].v), num[i].name);
#undef NEED
    if (missing) return snprintf(err, errlen, "--input %s: /parameters lacks the attribute '%s'", path, missing), -1;
    /* §3.13's features, absent from files written before them: not declared */
    int64_t guided = 0, lra = 0;
    char follow[16] = "blend3";
    d->follow = HB_FOLLOW_BLEND3;
    d->lra_scale = 1.0;
    if (read_attr(p, "guided", H5T_NATIVE_INT64, &guided) == 0 && guided) {
        if (read_attr(p, "guides", H5T_NATIVE_DOUBLE, &d->guides) < 0 ||
            read_attr_str(p, "follow", follow, sizeof follow) < 0)
            return snprintf(err, errlen, "--input %s: /parameters has guided = 1 but lacks guides or follow", path), -1;
        d->guided = 1;
        if (strcmp(follow, "one") == 0) d->follow = HB_FOLLOW_ONE;
        else if (strcmp(follow, "blend3") == 0) d->follow = HB_FOLLOW_BLEND3;
        else return snprintf(err, errlen, "--input %s: unknown follow scheme '%s'", path, follow), -1;
    }
    int64_t sag_free = 0;
    if (read_attr(p, "sag_free", H5T_NATIVE_INT64, &sag_free) == 0) d->sag_free = sag_free != 0;
    int64_t per_segment = 0;
    if (read_attr(p, "per_segment", H5T_NATIVE_INT64, &per_segment) == 0) d->per_segment = per_segment != 0;
    if (read_attr(p, "lra", H5T_NATIVE_INT64, &lra) == 0 && lra) {
        if (read_attr(p, "lra_scale", H5T_NATIVE_DOUBLE, &d->lra_scale) < 0)
            return snprintf(err, errlen, "--input %s: /parameters has lra = 1 but lacks lra_scale", path), -1;
        d->lra = 1;
    }
    if (input_world(in, path, p, err, errlen)) return -1;
    d->bend = bend != 0;
    d->shape = shape != 0;
    d->collider = collider != 0;
    d->drag_declared = drag_declared != 0;
    if (strcmp(solver, "xpbd") == 0) d->solver = HB_SOLVER_XPBD;
    else if (strcmp(solver, "ftl") == 0) d->solver = HB_SOLVER_FTL;
    else if (strcmp(solver, "rigid") == 0) d->solver = HB_SOLVER_RIGID;
    else return snprintf(err, errlen, "--input %s: unknown solver '%s'", path, solver), -1;
    if (strcmp(motion, "still") == 0) d->motion = HB_MOTION_STILL;
    else if (strcmp(motion, "nod") == 0) d->motion = HB_MOTION_NOD;
    else if (strcmp(motion, "shake") == 0) d->motion = HB_MOTION_SHAKE;
    else if (strcmp(motion, "tilt") == 0) d->motion = HB_MOTION_TILT;
    else if (strcmp(motion, "track") == 0) d->motion = HB_MOTION_TRACK;
    else return snprintf(err, errlen, "--input %s: unknown head motion '%s'", path, motion), -1;
    if (d->motion == HB_MOTION_TRACK) {
        if (hb_track_read_h5(f, path, &in->track, err, errlen)) return -1;
        d->track = &in->track;
    }
    char why[HB_ERRLEN];
    if (hb_dynamics_validate(d, why, sizeof why) != 0)
        return snprintf(err, errlen, "--input %s holds invalid dynamic parameters: %s", path, why), -1;
    if (in->paper_frames < 1 || in->paper_frames > in->n_frames)
        return snprintf(err, errlen, "--input %s: paper_frames = %lld does not fit its %d frames", path,
                        (long long)in->paper_frames, in->n_frames),
               -1;
    return input_dynamic_arrays(in, path, err, errlen);
}

/* The first of n reals in buf that is NaN or ±Inf, or −1 when all are finite. */
static int64_t first_nonfinite(const void *buf, uint64_t n, hb_precision prec)
{
    for (uint64_t i = 0; i < n; i++) {
        double v = prec == HB_FP64 ? ((const double *)buf)[i] : (double)((const float *)buf)[i];
        if (!isfinite(v)) return (int64_t)i;
    }
    return -1;
}

int hb_input_read_rest(hb_input *in, void *buf, char *err, size_t errlen)
{
    hid_t d = H5Dopen2((hid_t)in->hid, "particles/hair/rest_position", H5P_DEFAULT);
    herr_t rc = d < 0 ? -1
                      : H5Dread(d, in->scene.precision == HB_FP64 ? H5T_NATIVE_DOUBLE : H5T_NATIVE_FLOAT, H5S_ALL,
                                H5S_ALL, H5P_DEFAULT, buf);
    if (d >= 0) H5Dclose(d);
    if (rc < 0) {
        snprintf(err, errlen, "--input: HDF5 could not read the rest shape (truncated file?)");
        return -1;
    }
    const int64_t bad =
        first_nonfinite(buf, (uint64_t)in->scene.n_strands * (uint64_t)in->scene.points * 3u, in->scene.precision);
    if (bad >= 0) {
        snprintf(err, errlen, "--input: the rest shape holds a NaN or Inf at point %lld", (long long)(bad / 3));
        return -1;
    }
    return 0;
}

int hb_input_read_velocity(hb_input *in, int index, void *buf, char *err, size_t errlen)
{
    const uint64_t rows = (uint64_t)in->scene.n_strands * (uint64_t)in->scene.points;
    hid_t d = H5Dopen2((hid_t)in->hid, "particles/hair/velocity/value", H5P_DEFAULT);
    if (d < 0) {
        snprintf(err, errlen, "--input: HDF5 could not open the velocities");
        return -1;
    }
    hid_t fs = H5Dget_space(d);
    hsize_t start[3] = {(hsize_t)index, 0, 0}, count[3] = {1, rows, 3};
    H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, count, NULL);
    hid_t ms = H5Screate_simple(3, count, NULL);
    herr_t rc =
        H5Dread(d, in->scene.precision == HB_FP64 ? H5T_NATIVE_DOUBLE : H5T_NATIVE_FLOAT, ms, fs, H5P_DEFAULT, buf);
    H5Sclose(ms);
    H5Sclose(fs);
    H5Dclose(d);
    if (rc < 0) {
        snprintf(err, errlen, "--input: HDF5 could not read velocity frame %d (truncated file?)", index);
        return -1;
    }
    const int64_t bad = first_nonfinite(buf, rows * 3u, in->scene.precision);
    if (bad >= 0) {
        snprintf(err, errlen, "--input: velocity frame %d holds a NaN or Inf at point %lld", index,
                 (long long)(bad / 3));
        return -1;
    }
    return 0;
}

#undef FAIL
#define FAIL(...)                                                                                                      \
    do {                                                                                                               \
        snprintf(err, errlen, __VA_ARGS__);                                                                            \
        hb_input_close(in);                                                                                            \
        return -1;                                                                                                     \
    } while (0)

int hb_input_open(const char *path, hb_input *in, char *err, size_t errlen)
{
    quiet_hdf5();
    memset(in, 0, sizeof *in);
    /* a FIFO or device would block or never end: a regular file, at least HDF5's superblock */
    if (hb_input_check("--input", path, "an HDF5 file", 8, err, errlen)) return -1;
    if (H5Fis_hdf5(path) <= 0) FAIL("--input %s is not an HDF5 file", path);
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (f < 0) FAIL("--input %s: HDF5 cannot open it (truncated or damaged?)", path);
    in->hid = f;
    if (!has_path(f, "h5md") || !has_path(f, "particles/hair/position/value") || !has_path(f, "parameters"))
        FAIL("--input %s is not a hairbench state: it lacks /h5md, /particles/hair/position/value or /parameters",
             path);

    hid_t p = H5Gopen2(f, "parameters", H5P_DEFAULT);
    hb_scene *s = &in->scene;
    char prec[16] = "";
    int bad = 0;
    const char *missing = NULL;
#define NEED(call, name)                                                                                               \
    if (!missing && (call) < 0) missing = name
    NEED(read_attr(p, "n_strands", H5T_NATIVE_INT64, &s->n_strands), "n_strands");
    NEED(read_attr(p, "points_per_strand", H5T_NATIVE_INT64, &s->points), "points_per_strand");
    NEED(read_attr(p, "seed", H5T_NATIVE_UINT64, &s->seed), "seed");
    NEED(read_attr(p, "head_radius", H5T_NATIVE_DOUBLE, &s->head_radius), "head_radius");
    NEED(read_attr(p, "hair_offset", H5T_NATIVE_DOUBLE, &s->hair_offset), "hair_offset");
    NEED(read_attr(p, "hair_length", H5T_NATIVE_DOUBLE, &s->hair_length), "hair_length");
    NEED(read_attr(p, "face_margin", H5T_NATIVE_DOUBLE, &s->face_margin), "face_margin");
    NEED(read_attr(p, "wind_strength", H5T_NATIVE_DOUBLE, &s->wind_strength), "wind_strength");
    NEED(read_attr(p, "wind_angle", H5T_NATIVE_DOUBLE, &s->wind_angle), "wind_angle");
    NEED(read_attr_str(p, "precision", prec, sizeof prec), "precision");
#undef NEED
    if (missing) {
        H5Gclose(p);
        FAIL("--input %s: /parameters lacks the attribute '%s'", path, missing);
    }
    int64_t rendered = 0; /* §3.14: its points are a spline's, not a state */
    if (read_attr(p, "render_points", H5T_NATIVE_INT64, &rendered) == 0 && rendered > 0) {
        H5Gclose(p);
        FAIL("--input %s was written with --render-points: its points are rendered, not simulated, so it cannot be "
             "resumed or simulated from (use a file written without it)",
             path);
    }
    if (strcmp(prec, "fp32") == 0) s->precision = HB_FP32;
    else if (strcmp(prec, "fp64") == 0) s->precision = HB_FP64;
    else {
        H5Gclose(p);
        FAIL("--input %s: unknown precision '%s'", path, prec);
    }
    char why[HB_ERRLEN];
    if (hb_scene_validate(s, why, sizeof why) != 0) {
        H5Gclose(p);
        FAIL("--input %s holds an invalid scene: %s", path, why);
    }

    hid_t d = H5Dopen2(f, "particles/hair/position/value", H5P_DEFAULT);
    hid_t sp = H5Dget_space(d);
    hid_t t = H5Dget_type(d);
    hsize_t dims[3] = {0, 0, 0};
    int rank = H5Sget_simple_extent_ndims(sp);
    if (rank == 3) H5Sget_simple_extent_dims(sp, dims, NULL);
    size_t tsize = H5Tget_size(t);
    int is_float = H5Tget_class(t) == H5T_FLOAT;
    H5Tclose(t);
    H5Sclose(sp);
    H5Dclose(d);
    uint64_t rows = (uint64_t)s->n_strands * (uint64_t)s->points;
    if (rank != 3 || dims[2] != 3)
        bad = snprintf(err, errlen, "--input %s: position/value must be [frames][N*P][3] (rank %d)", path, rank);
    else if (dims[1] != rows)
        bad =
            snprintf(err, errlen, "--input %s: position/value has %llu rows, but n_strands x points_per_strand = %llu",
                     path, (unsigned long long)dims[1], (unsigned long long)rows);
    else if (!is_float || tsize != hb_real_size(s->precision))
        bad = snprintf(err, errlen, "--input %s: position/value is not %s floating point as /parameters says", path,
                       prec);
    else if (dims[0] < 1) bad = snprintf(err, errlen, "--input %s has no frames", path);
    if (bad) {
        H5Gclose(p);
        hb_input_close(in);
        return -1;
    }
    in->n_frames = (int)dims[0];
    hsize_t F = dims[0];
    in->frames = calloc(F, sizeof *in->frames);
    if (!in->frames) {
        H5Gclose(p);
        FAIL("out of host memory");
    }
    for (hsize_t i = 0; i < F; i++) {
        in->frames[i].moved_points = -1;
        in->frames[i].wind_strength = in->frames[i].wind_angle = NAN;
        in->frames[i].median_ms = in->frames[i].min_ms = in->frames[i].max_ms = NAN;
    }
    if (read_frames_str(p, "stage", F, in->frames, offsetof(hb_frame_meta, stage), sizeof in->frames[0].stage) < 0) {
        H5Gclose(p);
        FAIL("--input %s: /parameters/stage is missing or does not have one entry per frame (%llu)", path,
             (unsigned long long)F);
    }
    /* The rest of the per-frame record is copied when present. */
    read_frames_str(p, "fused", F, in->frames, offsetof(hb_frame_meta, fused), sizeof in->frames[0].fused);
    read_frames_str(p, "frame_backend", F, in->frames, offsetof(hb_frame_meta, backend), sizeof in->frames[0].backend);
    {
        int8_t *sk = calloc(F, 1);
        int64_t *mv = calloc(F, sizeof *mv);
        double *v = calloc(F, sizeof *v);
        if (sk && read_frames_ds(p, "skipped", H5T_NATIVE_INT8, F, sk) == 0)
            for (hsize_t i = 0; i < F; i++) in->frames[i].skipped = sk[i];
        if (mv && read_frames_ds(p, "moved_points", H5T_NATIVE_INT64, F, mv) == 0)
            for (hsize_t i = 0; i < F; i++) in->frames[i].moved_points = mv[i];
#define COPY_F64(name, field)                                                                                          \
    if (v && read_frames_ds(p, name, H5T_NATIVE_DOUBLE, F, v) == 0)                                                    \
        for (hsize_t i = 0; i < F; i++) in->frames[i].field = v[i];
        COPY_F64("wind_strength", wind_strength)
        COPY_F64("wind_angle", wind_angle)
        COPY_F64("stage_median_ms", median_ms)
        COPY_F64("stage_min_ms", min_ms)
        COPY_F64("stage_max_ms", max_ms)
#undef COPY_F64
        free(sk);
        free(mv);
        free(v);
    }
    {
        hsize_t ns = 0, nt = 0;
        int64_t *st = read_1d(f, "particles/hair/position/step", H5T_NATIVE_INT64, sizeof(int64_t), &ns);
        double *tm = read_1d(f, "particles/hair/position/time", H5T_NATIVE_DOUBLE, sizeof(double), &nt);
        for (hsize_t i = 0; i < F; i++) {
            in->frames[i].step = st && ns == F ? st[i] : (int64_t)i;
            in->frames[i].time = tm && nt == F ? tm[i] : 0.0;
        }
        free(st);
        free(tm);
    }
    if (input_dynamic(in, path, p, err, errlen) < 0) {
        H5Gclose(p);
        hb_input_close(in);
        return -1;
    }
    H5Gclose(p);
    return 0;
}

int hb_input_read_frame(hb_input *in, int fidx, void *buf, char *err, size_t errlen)
{
    const hb_scene *s = &in->scene;
    hsize_t rows = (hsize_t)s->n_strands * (hsize_t)s->points;
    hid_t d = H5Dopen2((hid_t)in->hid, "particles/hair/position/value", H5P_DEFAULT);
    hid_t fs = H5Dget_space(d);
    hsize_t start[3] = {(hsize_t)fidx, 0, 0}, count[3] = {1, rows, 3};
    H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, count, NULL);
    hid_t ms = H5Screate_simple(3, count, NULL);
    hid_t mt = s->precision == HB_FP64 ? H5T_NATIVE_DOUBLE : H5T_NATIVE_FLOAT;
    herr_t rc = H5Dread(d, mt, ms, fs, H5P_DEFAULT, buf);
    H5Sclose(ms);
    H5Sclose(fs);
    H5Dclose(d);
    if (rc < 0) {
        snprintf(err, errlen, "--input: HDF5 could not read frame %d (truncated file?)", fidx);
        return -1;
    }
    const int64_t bad = first_nonfinite(buf, (uint64_t)rows * 3u, s->precision);
    if (bad >= 0) {
        snprintf(err, errlen, "--input: frame %d holds a NaN or Inf at point %lld", fidx, (long long)(bad / 3));
        return -1;
    }
    return 0;
}
