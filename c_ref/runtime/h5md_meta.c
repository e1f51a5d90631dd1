/* h5md_meta.c — see h5md_meta.h. */
#include "runtime/h5md_meta.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static hid_t fixed_str_type(size_t len)
{
    hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, len ? len : 1);
    H5Tset_strpad(t, H5T_STR_NULLTERM);
    H5Tset_cset(t, H5T_CSET_ASCII);
    return t;
}

int hb_h5md_str_array_attr(hid_t loc, const char *name, const char *const *values, int n)
{
    size_t len = 1;
    for (int i = 0; i < n; i++)
        if (strlen(values[i]) + 1 > len) len = strlen(values[i]) + 1;
    char *buf = calloc((size_t)n, len);
    if (!buf) return -1;
    for (int i = 0; i < n; i++) memcpy(buf + (size_t)i * len, values[i], strlen(values[i]));
    hid_t t = fixed_str_type(len);
    hsize_t dims = (hsize_t)n;
    hid_t sp = H5Screate_simple(1, &dims, NULL);
    hid_t a = H5Acreate2(loc, name, t, sp, H5P_DEFAULT, H5P_DEFAULT);
    herr_t rc = a < 0 ? -1 : H5Awrite(a, t, buf);
    if (a >= 0) H5Aclose(a);
    H5Sclose(sp);
    H5Tclose(t);
    free(buf);
    return rc < 0 ? -1 : 0;
}

int hb_h5md_str_attr(hid_t loc, const char *name, const char *value)
{
    const char *v = value ? value : "";
    size_t len = strlen(v) + 1;
    hid_t t = fixed_str_type(len), sp = H5Screate(H5S_SCALAR);
    hid_t a = H5Acreate2(loc, name, t, sp, H5P_DEFAULT, H5P_DEFAULT);
    herr_t rc = a < 0 ? -1 : H5Awrite(a, t, v);
    if (a >= 0) H5Aclose(a);
    H5Sclose(sp);
    H5Tclose(t);
    return rc < 0 ? -1 : 0;
}

int hb_h5md_unit(hid_t dataset, const char *unit)
{
    return hb_h5md_str_attr(dataset, "unit", unit);
}

static int unit_on(hid_t file, const char *path, const char *unit)
{
    hid_t d = H5Dopen2(file, path, H5P_DEFAULT);
    if (d < 0) return -1;
    int rc = hb_h5md_unit(d, unit);
    H5Dclose(d);
    return rc;
}

/* int32 strand ids, written a chunk at a time (no N·P buffer); compressed where HDF5 has
 * deflate, since the ids repeat P times. */
static int write_strand_ids(hid_t file, const hb_scene *s)
{
    const hsize_t rows = (hsize_t)s->n_strands * (hsize_t)s->points, step = (hsize_t)1 << 20;
    hsize_t chunk = rows < step ? rows : step;
    hid_t space = H5Screate_simple(1, &rows, NULL), dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(dcpl, 1, &chunk);
    if (H5Zfilter_avail(H5Z_FILTER_DEFLATE) > 0) {
        H5Pset_shuffle(dcpl);
        H5Pset_deflate(dcpl, 1);
    }
    hid_t d = H5Dcreate2(file, "particles/hair/strand", H5T_STD_I32LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    H5Pclose(dcpl);
    int32_t *buf = malloc(chunk * sizeof *buf);
    int bad = d < 0 || !buf;
    for (hsize_t start = 0; !bad && start < rows; start += chunk) {
        hsize_t count = rows - start < chunk ? rows - start : chunk;
        for (hsize_t r = 0; r < count; r++) buf[r] = (int32_t)((start + r) / (hsize_t)s->points);
        hid_t ms = H5Screate_simple(1, &count, NULL);
        H5Sselect_hyperslab(space, H5S_SELECT_SET, &start, NULL, &count, NULL);
        bad |= H5Dwrite(d, H5T_NATIVE_INT32, ms, space, H5P_DEFAULT, buf) < 0;
        H5Sclose(ms);
    }
    free(buf);
    if (d >= 0) {
        hb_h5md_str_attr(d, "description", "strand index of each particle: row i*P + k holds i");
        H5Dclose(d);
    }
    H5Sclose(space);
    return bad ? -1 : 0;
}

int hb_h5md_finish(hid_t file, const hb_scene *s)
{
    int bad = 0;
    hid_t modules = H5Gcreate2(file, "h5md/modules", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    hid_t units = modules < 0 ? -1 : H5Gcreate2(modules, "units", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    int32_t version[2] = {1, 0};
    hsize_t two = 2;
    hid_t sp = H5Screate_simple(1, &two, NULL);
    hid_t a = units < 0 ? -1 : H5Acreate2(units, "version", H5T_STD_I32LE, sp, H5P_DEFAULT, H5P_DEFAULT);
    bad |= a < 0 || H5Awrite(a, H5T_NATIVE_INT32, version) < 0;
    if (a >= 0) H5Aclose(a);
    H5Sclose(sp);
    bad |= units < 0 || hb_h5md_str_attr(units, "system", "SI") < 0; /* cm and s: SI prefixes and units */
    if (units >= 0) H5Gclose(units);
    if (modules >= 0) H5Gclose(modules);
    bad |= unit_on(file, "particles/hair/position/value", "cm") < 0;
    bad |= unit_on(file, "particles/hair/position/time", "s") < 0;
    bad |= write_strand_ids(file, s) < 0;
    return bad ? -1 : 0;
}
