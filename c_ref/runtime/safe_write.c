/* safe_write.c — see safe_write.h. */
#define _GNU_SOURCE /* program_invocation_short_name */
#include "runtime/safe_write.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <stdint.h>
#include <string.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

static char g_tmp[PATH_MAX];
static volatile sig_atomic_t g_armed;

static void on_signal(int sig)
{
    if (g_armed) unlink(g_tmp); /* async-signal-safe */
    signal(sig, SIG_DFL);
    raise(sig); /* die of the signal: the parent sees it, the status is non-zero */
}

static void at_exit(void)
{
    if (g_armed) unlink(g_tmp);
    g_armed = 0;
}

void hb_safe_track(const char *tmp)
{
    static int installed;
    if (!installed) {
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_signal;
        sigemptyset(&sa.sa_mask);
        int sigs[] = {SIGINT, SIGTERM, SIGHUP, SIGQUIT};
        for (size_t i = 0; i < sizeof sigs / sizeof sigs[0]; i++) sigaction(sigs[i], &sa, NULL);
        atexit(at_exit);
        installed = 1;
    }
    g_armed = 0;
    snprintf(g_tmp, sizeof g_tmp, "%s", tmp);
    g_armed = 1;
}

void hb_safe_forget(void)
{
    g_armed = 0;
}

static const char *kind_of(mode_t m)
{
    if (S_ISDIR(m)) return "a directory";
    if (S_ISCHR(m) || S_ISBLK(m)) return "a device";
    if (S_ISFIFO(m)) return "a FIFO";
    if (S_ISSOCK(m)) return "a socket";
    return "not a regular file";
}

/* 0 when path is absent or a regular file; else −1 with the reason in err. */
static int refuse_special(const char *path, char *err, size_t errlen)
{
    struct stat st;
    if (lstat(path, &st) != 0) return 0;
    if (S_ISLNK(st.st_mode)) {
        snprintf(err, errlen, "--output %s is a symbolic link; refusing to replace it (even with --force)", path);
        return -1;
    }
    if (!S_ISREG(st.st_mode)) {
        snprintf(err, errlen, "--output %s is %s; refusing to replace it (even with --force)", path,
                 kind_of(st.st_mode));
        return -1;
    }
    return 0;
}

/* ".hairsim-<pid>-<16 hex>.tmp": returns the pid, or 0 for any other name. */
static long tmp_pid(const char *name)
{
    const size_t np = strlen(HB_TMP_PREFIX), ns = strlen(HB_TMP_SUFFIX);
    if (strncmp(name, HB_TMP_PREFIX, np) != 0) return 0;
    const char *d = name + np;
    char *end;
    if (*d < '1' || *d > '9') return 0;
    long pid = strtol(d, &end, 10);
    if (*end != '-' || pid <= 0) return 0;
    const char *h = end + 1;
    for (int i = 0; i < 16; i++)
        if (!((h[i] >= '0' && h[i] <= '9') || (h[i] >= 'a' && h[i] <= 'f'))) return 0;
    return strcmp(h + 16, HB_TMP_SUFFIX) == 0 && strlen(h + 16) == ns ? pid : 0;
}

/* A regular file of this user that starts with the marker. */
static int marked(int dirfd, const char *name)
{
    struct stat st;
    if (fstatat(dirfd, name, &st, AT_SYMLINK_NOFOLLOW) != 0 || !S_ISREG(st.st_mode)) return 0;
    if (st.st_uid != geteuid()) return 0;
    int fd = openat(dirfd, name, O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) return 0;
    const size_t n = strlen(HB_TMP_MARKER);
    char buf[64];
    int ok = read(fd, buf, n) == (ssize_t)n && memcmp(buf, HB_TMP_MARKER, n) == 0;
    close(fd);
    return ok;
}

static void dir_of(const char *path, char *dir, size_t n)
{
    snprintf(dir, n, "%s", path);
    char *slash = strrchr(dir, '/');
    if (slash == dir) dir[1] = '\0';
    else if (slash) *slash = '\0';
    else snprintf(dir, n, ".");
}

static void clean_stale(const char *path)
{
    char dir[PATH_MAX];
    dir_of(path, dir, sizeof dir);
    DIR *d = opendir(dir);
    if (!d) return;
    int n = 0;
    char first[256] = "";
    for (struct dirent *e; (e = readdir(d));) {
        long pid = tmp_pid(e->d_name);
        if (!pid || pid == (long)getpid()) continue;
        if (kill((pid_t)pid, 0) == 0 || errno != ESRCH) continue; /* alive, or not ours to judge */
        if (!marked(dirfd(d), e->d_name)) continue;
        if (unlinkat(dirfd(d), e->d_name, 0) == 0 && n++ == 0) snprintf(first, sizeof first, "%s", e->d_name);
    }
    closedir(d);
    if (n)
        fprintf(stderr, "%s: note: removed %d stale temporary file%s of killed runs in %s (%s%s)\n",
                program_invocation_short_name, n, n > 1 ? "s" : "", dir, first, n > 1 ? ", …" : "");
}

int hb_safe_tmp_name(const char *path, char *buf, size_t n)
{
    uint64_t r = 0;
    if (getrandom(&r, sizeof r, GRND_NONBLOCK) != (ssize_t)sizeof r) {
        struct timespec ts; /* no entropy yet: the clock and the address space still differ */
        clock_gettime(CLOCK_REALTIME, &ts);
        r = ((uint64_t)ts.tv_nsec << 20) ^ (uint64_t)ts.tv_sec ^ (uint64_t)(uintptr_t)&r;
    }
    char dir[PATH_MAX];
    dir_of(path, dir, sizeof dir);
    int len = snprintf(buf, n, "%s/%s%ld-%016llx%s", dir, HB_TMP_PREFIX, (long)getpid(), (unsigned long long)r,
                       HB_TMP_SUFFIX);
    return len < 0 || (size_t)len >= n ? -1 : 0;
}

/* Writes len bytes of src at offset 0 of path, then fsyncs; 0 or −1. */
static int write_head(const char *path, const void *src, size_t len)
{
    int fd = open(path, O_WRONLY | O_NOFOLLOW | O_CLOEXEC);
    if (fd < 0) return -1;
    int rc = pwrite(fd, src, len, 0) == (ssize_t)len ? 0 : -1;
    close(fd);
    return rc;
}

int hb_safe_mark(const char *tmp)
{
    return write_head(tmp, HB_TMP_MARKER, strlen(HB_TMP_MARKER));
}

const char *hb_file_kind(mode_t m)
{
    return kind_of(m);
}

int hb_safe_output_check(const char *path, int force, char *err, size_t errlen)
{
    if (refuse_special(path, err, errlen)) return -1;
    if (!force && access(path, F_OK) == 0) {
        snprintf(err, errlen, "--output %s exists; choose another name or pass --force to replace it", path);
        return -1;
    }
    clean_stale(path);
    return 0;
}

static int fsync_path(const char *p, int flags)
{
    int fd = open(p, flags | O_CLOEXEC);
    if (fd < 0) return -1;
    int rc = fsync(fd);
    close(fd);
    return rc;
}

/* Moves tmp to path unless something is there: renameat2(RENAME_NOREPLACE), else (a file
 * system without it) link + unlink, both atomic; else (no hard links either) a last check
 * and rename, which leaves a window of a few instructions. −1 with errno (EEXIST). */
static int move_noreplace(const char *tmp, const char *path)
{
    if (renameat2(AT_FDCWD, tmp, AT_FDCWD, path, RENAME_NOREPLACE) == 0) return 0;
    if (errno != EINVAL && errno != ENOSYS && errno != EOPNOTSUPP) return -1;
    if (link(tmp, path) == 0) {
        unlink(tmp);
        return 0;
    }
    if (errno != EPERM && errno != EOPNOTSUPP && errno != ENOSYS) return -1;
    if (access(path, F_OK) == 0) {
        errno = EEXIST;
        return -1;
    }
    return rename(tmp, path);
}

int hb_safe_commit(const char *tmp, const char *path, int force, char *err, size_t errlen)
{
    static const char zeros[sizeof HB_TMP_MARKER] = {0};
    if (write_head(tmp, zeros, strlen(HB_TMP_MARKER)) != 0 || fsync_path(tmp, O_RDONLY) != 0) {
        snprintf(err, errlen, "--output %s: cannot finish %s (%s)", path, tmp, strerror(errno));
        return -1;
    }
    if (refuse_special(path, err, errlen)) return -1; /* replaced while we ran */
    if ((force ? rename(tmp, path) : move_noreplace(tmp, path)) != 0) {
        if (errno == EEXIST) {
            snprintf(err, errlen,
                     "--output %s was created by someone else during this run; not replacing it without --force "
                     "(this run's result is discarded)",
                     path);
            return HB_SAFE_EXISTS;
        }
        snprintf(err, errlen, "--output %s: cannot move %s into place (%s)", path, tmp, strerror(errno));
        return -1;
    }
    hb_safe_forget();
    char dir[PATH_MAX];
    dir_of(path, dir, sizeof dir);
    fsync_path(dir, O_RDONLY | O_DIRECTORY); /* best effort: the rename itself is durable */
    return 0;
}
