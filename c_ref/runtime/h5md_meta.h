/* h5md_meta.h — the H5MD 1.1 metadata of a state (docs/interfaces.md, "HDF5 state"):
 * fixed-length string attributes, units (cm, s), the per-particle strand id. */
#ifndef HB_H5MD_META_H
#define HB_H5MD_META_H

#include <hdf5.h>

#include "runtime/params.h"

/* A fixed-length, NUL-terminated ASCII string attribute: scalar, or n values. <0 on failure. */
int hb_h5md_str_attr(hid_t loc, const char *name, const char *value);
int hb_h5md_str_array_attr(hid_t loc, const char *name, const char *const *values, int n);

/* The H5MD units module's `unit` attribute on a dataset: a fixed-length ASCII string. */
int hb_h5md_unit(hid_t dataset, const char *unit);

/* At close: /h5md/modules/units (system "SI"), `unit` on position/value (cm) and position/time (s), and
 * /particles/hair/strand (int32 [N·P], row i·P + k holds i). <0 on failure. */
int hb_h5md_finish(hid_t file, const hb_scene *s);

#endif
