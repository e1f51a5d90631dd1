/* input.c — see input.h. */
#include "runtime/input.h"

#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "runtime/safe_write.h"

/* The descriptor of `path` opened without blocking (a FIFO with no writer would), checked to
 * be a regular file of at least min_bytes; −1 with one line in err. */
static int open_regular(const char *flag, const char *path, const char *what, uint64_t min_bytes, uint64_t *size,
                        char *err, size_t errlen)
{
    if (path[0] == '\0') {
        snprintf(err, errlen, "%s needs a file name", flag);
        return -1;
    }
    const int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
    if (fd < 0) {
        if (errno == ENOENT) snprintf(err, errlen, "%s %s: no such file", flag, path);
        else snprintf(err, errlen, "%s %s: cannot read it (%s)", flag, path, strerror(errno));
        return -1;
    }
    struct stat st;
    if (fstat(fd, &st) != 0) {
        snprintf(err, errlen, "%s %s: cannot read it (%s)", flag, path, strerror(errno));
        close(fd);
        return -1;
    }
    if (!S_ISREG(st.st_mode)) {
        snprintf(err, errlen, "%s %s is %s; %s must be a regular file", flag, path, hb_file_kind(st.st_mode), flag);
        close(fd);
        return -1;
    }
    if (st.st_size == 0 || (uint64_t)st.st_size < min_bytes) {
        if (st.st_size == 0) snprintf(err, errlen, "%s %s is empty (%s)", flag, path, what);
        else
            snprintf(err, errlen, "%s %s is %lld bytes; %s has at least %llu", flag, path, (long long)st.st_size, what,
                     (unsigned long long)min_bytes);
        close(fd);
        return -1;
    }
    /* reads block as usual from here on */
    const int fl = fcntl(fd, F_GETFL);
    if (fl >= 0) fcntl(fd, F_SETFL, fl & ~O_NONBLOCK);
    if (size) *size = (uint64_t)st.st_size;
    return fd;
}

FILE *hb_input_fopen(const char *flag, const char *path, const char *what, uint64_t min_bytes, uint64_t *size,
                     char *err, size_t errlen)
{
    const int fd = open_regular(flag, path, what, min_bytes, size, err, errlen);
    if (fd < 0) return NULL;
    FILE *f = fdopen(fd, "rb");
    if (!f) {
        snprintf(err, errlen, "%s %s: cannot read it (%s)", flag, path, strerror(errno));
        close(fd);
    }
    return f;
}

int hb_input_check(const char *flag, const char *path, const char *what, uint64_t min_bytes, char *err, size_t errlen)
{
    const int fd = open_regular(flag, path, what, min_bytes, NULL, err, errlen);
    if (fd < 0) return -1;
    close(fd);
    return 0;
}
