/* fault_io.c - write failures on purpose: pwrite() and close() as our
 * objects call them (the Makefile's FAULT_WRAP) can be made to fail with a
 * chosen errno, as a dying disk (EIO) or a network file system reporting a
 * lost write at close does. See fault.h. */
#include "fault.h"

#include <errno.h>
#include <stdatomic.h>
#include <sys/types.h>
#include <unistd.h>

static atomic_int pwrite_errno;  /* 0: pass through */
static atomic_long pwrite_skip;  /* calls that still succeed before the failures start */
static atomic_int close_errno;   /* 0: pass through; else the next close fails (once) */

void fault_io_fail_pwrite(int errnum, long skip)
{
    atomic_store(&pwrite_skip, skip);
    atomic_store(&pwrite_errno, errnum);
}

void fault_io_fail_close(int errnum) { atomic_store(&close_errno, errnum); }

void fault_io_reset(void)
{
    atomic_store(&pwrite_errno, 0);
    atomic_store(&close_errno, 0);
}

ssize_t __real_pwrite(int fd, const void *buf, size_t n, off_t offset);
int __real_close(int fd);
ssize_t __wrap_pwrite(int fd, const void *buf, size_t n, off_t offset);
int __wrap_close(int fd);

ssize_t __wrap_pwrite(int fd, const void *buf, size_t n, off_t offset)
{
    int e = atomic_load(&pwrite_errno);
    if (e && atomic_fetch_sub(&pwrite_skip, 1) <= 0) {
        errno = e;
        return -1;
    }
    return __real_pwrite(fd, buf, n, offset);
}

/* The descriptor is closed all the same (as Linux does when close reports
 * an error): only the result says the data may be lost. */
int __wrap_close(int fd)
{
    int e = atomic_exchange(&close_errno, 0);
    int r = __real_close(fd);
    if (e && r == 0) {
        errno = e;
        return -1;
    }
    return r;
}
