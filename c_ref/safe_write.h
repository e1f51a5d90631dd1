/* safe_write.h — an --output that cannot hurt: refuse what is not a regular file, remove
 * our temporary file on every exit path (signals included), fsync before the rename, and
 * clean the stale temporaries of killed runs (docs/interfaces.md, "Writing the output"). */
#ifndef HB_SAFE_WRITE_H
#define HB_SAFE_WRITE_H

#include <stddef.h>

/* Before any work: refuse an --output that is a symlink or exists and is not a regular file
 * (with or without --force), or a regular file without --force; remove stale
 * "<name>.tmp.<pid>" files of dead runs in its directory (one line on stderr). 0 or −1. */
int hb_safe_output_check(const char *path, int force, char *err, size_t errlen);

/* The temporary file being written: removed on SIGINT/SIGTERM/SIGHUP and at exit() until
 * hb_safe_forget() (after the rename, or after the caller removed it itself). */
void hb_safe_track(const char *tmp);
void hb_safe_forget(void);

/* fsync tmp, check path again, rename tmp over path, fsync the directory. 0 or −1. */
int hb_safe_commit(const char *tmp, const char *path, char *err, size_t errlen);

#endif
