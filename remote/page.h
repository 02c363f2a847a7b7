/* page.h (remote) - the remote view's page (remote/page.html: HTML, CSS and
 * JavaScript in one file), built into the binary: the Makefile generates
 * $(BUILD)/remote/page_html.c from it, so the kiosk serves it without files
 * beside it. */
#ifndef TESSERA_REMOTE_PAGE_H
#define TESSERA_REMOTE_PAGE_H

#include <stddef.h>

extern const char remote_page_html[];     /* the page's bytes (NUL-terminated too) */
extern const size_t remote_page_html_bytes; /* without the NUL */

#endif
