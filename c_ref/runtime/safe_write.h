/* safe_write.h — an --output that cannot hurt: refuse what is not a regular file, write to a
 * temporary file only this program owns (a hidden name with the program's name, its pid and
 * a random part, and a marker in the file's user block), remove it on every exit path
 * (signals included), fsync before a rename that replaces nothing without --force, and clean
 * only the marked temporaries of dead runs (docs/interfaces.md, "Writing the output"). */
#ifndef HB_SAFE_WRITE_H
#define HB_SAFE_WRITE_H

#include <stddef.h>
#include <sys/types.h>

/* The temporary file's HDF5 user block (bytes) and the marker written at its start; the
 * harness (harness/core/tempfiles.py) keeps the same two. */
#define HB_TMP_USERBLOCK 512
#define HB_TMP_MARKER "HAIRSIM-TEMPORARY-OUTPUT\n"
#define HB_TMP_PREFIX ".hairsim-"
#define HB_TMP_SUFFIX ".tmp"

/* hb_safe_commit's return when --output appeared during the run (without --force). */
#define HB_SAFE_EXISTS (-2)

/* Before any work: refuse an --output that is a symlink or exists and is not a regular file
 * (with or without --force), or a regular file without --force; remove the stale marked
 * temporaries of dead runs in its directory (one line on stderr). 0 or −1. */
int hb_safe_output_check(const char *path, int force, char *err, size_t errlen);

/* "<dir of path>/.hairsim-<pid>-<16 hex digits>.tmp" into buf. 0, or −1 when it is too long. */
int hb_safe_tmp_name(const char *path, char *buf, size_t n);

/* Writes the marker at the start of tmp (inside its user block). 0 or −1. */
int hb_safe_mark(const char *tmp);

/* The temporary file being written: removed on SIGINT/SIGTERM/SIGHUP/SIGQUIT and at exit()
 * until hb_safe_forget() (after the rename, or after the caller removed it itself). */
void hb_safe_track(const char *tmp);
void hb_safe_forget(void);

/* Clear the marker, fsync tmp, check path again, move tmp to path (replacing a file there
 * only with force; atomically where the file system allows), fsync the directory.
 * 0, HB_SAFE_EXISTS, or −1. */
int hb_safe_commit(const char *tmp, const char *path, int force, char *err, size_t errlen);

/* "a directory", "a FIFO", … for a mode that is not a regular file. */
const char *hb_file_kind(mode_t m);

#endif
