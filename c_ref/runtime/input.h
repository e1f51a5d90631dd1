/* input.h — the one way the binaries open a file they read (--input, --groom, --batch):
 * a regular file only (a FIFO with no writer would block, a directory or a device never
 * ends), of at least `min_bytes`, readable; every refusal one line naming the flag and the
 * path as the user gave it (docs/interfaces.md, "Reading the inputs"). */
#ifndef HB_INPUT_H
#define HB_INPUT_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Opens `path` for reading; *size (when not NULL) gets its size in bytes. NULL with one line
 * in err: "<flag> <path>: no such file", "… is a FIFO; <flag> must be a regular file",
 * "… is empty", "… is N bytes; a … needs at least M". The stream is positioned at 0. */
FILE *hb_input_fopen(const char *flag, const char *path, const char *what, uint64_t min_bytes, uint64_t *size,
                     char *err, size_t errlen);

/* The same checks for a reader that opens the path itself (HDF5): 0, or −1 with one line. */
int hb_input_check(const char *flag, const char *path, const char *what, uint64_t min_bytes, char *err, size_t errlen);

#ifdef __cplusplus
}
#endif
#endif
