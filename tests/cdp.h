/* cdp.h - a small Chrome DevTools Protocol client for the browser tests:
 * headless Chromium started with --remote-debugging-pipe reads commands
 * (JSON, each ended by a NUL byte) on its fd 3 and writes replies and
 * events the same way on its fd 4, so no WebSocket is needed. One page
 * (target) per cdp_page, attached with flatten sessions.
 *
 * Every wait has a cap; a Chromium that dies gives errors, never a hang.
 * Threading: one thread per browser. */
#ifndef TESSERA_TESTS_CDP_H
#define TESSERA_TESTS_CDP_H

#include <json-c/json.h>
#include <stdbool.h>
#include <stddef.h>

typedef struct cdp_browser cdp_browser;
typedef struct cdp_page cdp_page;

/* Start headless Chromium ($TESSERA_CHROMIUM, else `chromium` on PATH) with a
 * window of width x height CSS pixels. NULL with the reason in why when it
 * is not installed or does not answer. */
cdp_browser *cdp_launch(int width_px, int height_px, char *why, size_t why_bytes);
/* Close the browser, end its processes, remove its profile. NULL is fine. */
void cdp_close(cdp_browser *b);

/* A new page showing `url`, loaded (the load event came). NULL with why. */
cdp_page *cdp_open_page(cdp_browser *b, const char *url, char *why, size_t why_bytes);
/* The same, with `js_before` run in the page before any of its own scripts
 * (Page.addScriptToEvaluateOnNewDocument): a test's hooks. */
cdp_page *cdp_open_page_scripted(cdp_browser *b, const char *url, const char *js_before, char *why, size_t why_bytes);

/* Call `method` with `params` (taken; NULL: {}) in the page's session (page
 * NULL: the browser's), wait up to timeout_s for its reply. *result (may be
 * NULL) gets the reply's "result" (json_object_put it). False with why. */
bool cdp_call(cdp_browser *b, cdp_page *page, const char *method, json_object *params, json_object **result,
              double timeout_s, char *why, size_t why_bytes);

/* Evaluate JavaScript in the page (promises awaited) and return its value
 * (json_object_put it; NULL for undefined/null). False with why on an
 * exception or no reply. */
bool cdp_eval(cdp_page *page, const char *js, json_object **value, char *why, size_t why_bytes);
/* The value of a number / boolean expression; NAN / false when it fails. */
double cdp_eval_number(cdp_page *page, const char *js);
bool cdp_eval_bool(cdp_page *page, const char *js);

/* Wait, inside the page, until `js_condition` is true (checked every 10 ms of
 * page time), at most timeout_s. False (with why) when it never was. */
bool cdp_wait_js(cdp_page *page, const char *js_condition, double timeout_s, char *why, size_t why_bytes);

/* Input as a person gives it: Input.dispatchMouseEvent (type
 * "mousePressed" / "mouseMoved" / "mouseReleased", CSS pixels, button
 * "left" / "none"), Input.dispatchTouchEvent (type "touchStart" /
 * "touchMove" / "touchEnd", points as x0, y0, x1, y1, ...). */
bool cdp_mouse(cdp_page *page, const char *type, double x, double y, const char *button);
bool cdp_touch(cdp_page *page, const char *type, const double *xy, int points);

#endif
