/* safe_write.c — see safe_write.h. */
#define _GNU_SOURCE /* program_invocation_short_name */
#include "safe_write.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
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

/* "<anything>.tmp.<pid>" with pid a number; returns the pid or 0. */
static long tmp_pid(const char *name)
{
    const char *t = strstr(name, ".tmp.");
    if (!t) return 0;
    while (strstr(t + 1, ".tmp.")) t = strstr(t + 1, ".tmp.");
    const char *d = t + 5;
    if (!*d) return 0;
    char *end;
    long pid = strtol(d, &end, 10);
    return (*end == '\0' && pid > 0) ? pid : 0;
}

/* A regular file of ours: empty (killed before HDF5 wrote) or starting with HDF5's signature. */
static int looks_ours(int dirfd, const char *name)
{
    struct stat st;
    if (fstatat(dirfd, name, &st, AT_SYMLINK_NOFOLLOW) != 0 || !S_ISREG(st.st_mode)) return 0;
    if (st.st_uid != geteuid()) return 0;
    if (st.st_size == 0) return 1;
    int fd = openat(dirfd, name, O_RDONLY | O_NOFOLLOW);
    if (fd < 0) return 0;
    unsigned char sig[8];
    int ok = read(fd, sig, 8) == 8 && memcmp(sig, "\211HDF\r\n\032\n", 8) == 0;
    close(fd);
    return ok;
}

static void clean_stale(const char *path)
{
    char dir[PATH_MAX];
    snprintf(dir, sizeof dir, "%s", path);
    char *slash = strrchr(dir, '/');
    if (slash == dir) dir[1] = '\0';
    else if (slash) *slash = '\0';
    else snprintf(dir, sizeof dir, ".");
    DIR *d = opendir(dir);
    if (!d) return;
    int n = 0;
    char first[256] = "";
    for (struct dirent *e; (e = readdir(d));) {
        long pid = tmp_pid(e->d_name);
        if (!pid || pid == (long)getpid()) continue;
        if (kill((pid_t)pid, 0) == 0 || errno != ESRCH) continue; /* alive, or not ours to judge */
        if (!looks_ours(dirfd(d), e->d_name)) continue;
        if (unlinkat(dirfd(d), e->d_name, 0) == 0 && n++ == 0) snprintf(first, sizeof first, "%s", e->d_name);
    }
    closedir(d);
    if (n)
        fprintf(stderr, "%s: note: removed %d stale temporary file%s of killed runs in %s (%s%s)\n",
                program_invocation_short_name, n, n > 1 ? "s" : "", dir, first, n > 1 ? ", …" : "");
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

int hb_safe_commit(const char *tmp, const char *path, char *err, size_t errlen)
{
    if (fsync_path(tmp, O_RDONLY) != 0) {
        snprintf(err, errlen, "--output %s: cannot fsync %s (%s)", path, tmp, strerror(errno));
        return -1;
    }
    if (refuse_special(path, err, errlen)) return -1; /* replaced while we ran */
    if (rename(tmp, path) != 0) {
        snprintf(err, errlen, "--output %s: cannot rename %s into place (%s)", path, tmp, strerror(errno));
        return -1;
    }
    hb_safe_forget();
    char dir[PATH_MAX];
    snprintf(dir, sizeof dir, "%s", path);
    char *slash = strrchr(dir, '/');
    if (slash == dir) dir[1] = '\0';
    else if (slash) *slash = '\0';
    else snprintf(dir, sizeof dir, ".");
    fsync_path(dir, O_RDONLY | O_DIRECTORY); /* best effort: the rename itself is durable */
    return 0;
}
