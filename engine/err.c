#include "err.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

bool tess_error_set(tess_error *err, const char *fmt, ...)
{
    if (!err || err->msg[0] != '\0')
        return false;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->msg, sizeof err->msg, fmt, ap);
    va_end(ap);
    return false;
}

void tess_error_prefix(tess_error *err, const char *fmt, ...)
{
    if (!err)
        return;
    char prefix[TESS_ERROR_MSG_BYTES];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(prefix, sizeof prefix, fmt, ap);
    va_end(ap);
    /* room for both; the result is cut to the message size */
    char joined[2 * TESS_ERROR_MSG_BYTES];
    snprintf(joined, sizeof joined, "%s%s", prefix, err->msg);
    memcpy(err->msg, joined, sizeof err->msg - 1);
    err->msg[sizeof err->msg - 1] = '\0';
}
