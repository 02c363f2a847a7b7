/* thread_name.c - names for tessera's threads (thread_name.h). */
#define _GNU_SOURCE /* pthread_setname_np */
#include "thread_name.h"

#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>

#define THREAD_NAME_BYTES 16 /* the kernel's TASK_COMM_LEN, with the NUL */

void thread_name_set(const char *fmt, ...)
{
    char name[THREAD_NAME_BYTES];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(name, sizeof name, fmt, ap);
    va_end(ap);
    (void)pthread_setname_np(pthread_self(), name);
}
