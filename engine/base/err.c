#include "err.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* Messages quote input (a PLY token, a record's word, a path) and must stay
 * one printable line: a tab becomes a space, any other control character or
 * DEL a '?'. Bytes from 0x80 up are left alone (UTF-8 file names). */
static void one_line(char *msg)
{
    for (unsigned char *p = (unsigned char *)msg; *p; p++)
        if (*p == '\t')
            *p = ' ';
        else if (*p < 0x20 || *p == 0x7F)
            *p = '?';
}

bool tess_error_set(tess_error *err, const char *fmt, ...)
{
    if (!err || err->msg[0] != '\0')
        return false;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->msg, sizeof err->msg, fmt, ap);
    va_end(ap);
    one_line(err->msg);
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
    one_line(err->msg);
}
