/* record.h - input transactions in a file (--record-input, --replay-input).
 *
 * FORMAT. Text, one transaction per line, after a header line; blank lines
 * and lines starting with '#' are skipped. Each line: TIME RECORD, TIME in
 * seconds since recording started (non-decreasing), RECORD a transaction
 * record in txn.h's text form (floats in C99 hexadecimal, %a, so a replay
 * reproduces every camera bit for bit). Two versions are read:
 *
 *   "tessera-input-record 2" (written now): RECORD is txn.h's TEXT FORM of
 *   any kind, e.g.
 *     T camera all EX EY EZ LX LY LZ UX UY UZ FOV    (or a channel number for all)
 *     T cursor ON SX SY          T status "TEXT"        T governor-status ON
 *     T hide FIRST COUNT         T show FIRST COUNT     T isolate FIRST COUNT
 *     T show-all                 T highlight FIRST COUNT ON
 *     T colour FIRST COUNT R G B | T colour FIRST COUNT reset
 *     T shadows ON               T renderer NAME        T threads N
 *     T channel-active CH ON     T tour ON              T quit
 *   "tessera-input-record 1" (written before; still replayed): the kinds
 *     T camera EX EY EZ LX LY LZ UX UY UZ FOV   the wall's camera (all channels)
 *     T cursor ON SX SY                         ON 0 or 1, plane coordinates
 *     T status "TEXT"                           \" \\ and \xHH escapes
 *     T hide GEOM_ID                            read as hide GEOM_ID 1
 *     T unhide-all                              read as show-all
 *     T tour ON
 *     T quit
 *     T governor-status ON
 * Errors name the file, the line and the problem.
 *
 * CUT OFF. A recording that ends mid-line (the kiosk killed or the power cut
 * while it wrote) still replays: tessera ends every line it writes with a
 * newline, so a last line without one may be the start of a longer line
 * ("0.5 hide 12 1" of "0.5 hide 123 1") and is left out, whether it parses or
 * not, with a warning naming the file and line; the complete lines before it
 * play. An operator wants the session back up to where the recording
 * stopped rather than nothing; a broken line anywhere else is an error. */
#ifndef TESSERA_INPUT_RECORD_H
#define TESSERA_INPUT_RECORD_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "engine/base/err.h"
#include "controller.h"

#define INPUT_RECORD_HEADER "tessera-input-record 2"    /* what input_sink writes */
#define INPUT_RECORD_HEADER_V1 "tessera-input-record 1" /* older recordings: read only */

typedef struct input_record_entry {
    double time_s;
    input_txn txn;
    size_t line;                 /* the file's line it was read from (0: not read from a file) */
} input_record_entry;

typedef struct input_record {
    input_record_entry *entries; /* malloc'ed */
    char *name;                  /* the file's name as given to input_record_parse (malloc'ed; NULL: none) */
    size_t count, capacity;
    size_t cut_line;             /* the last line, left out because it had no newline; 0: none */
    tess_error warning;          /* with cut_line: one line saying so (input_record_load logs it) */
} input_record;

/* Write one line (no header); false when the write failed. */
bool input_record_write(FILE *f, double time_s, const input_txn *t);

/* Read a whole record file. *out owns its entries (input_record_free). A
 * line cut off at the end is left out (see CUT OFF) and logged as a warning. */
bool input_record_load(const char *file, input_record *out, tess_error *err);
bool input_record_parse(const char *name, const char *text, size_t len, input_record *out, tess_error *err);
void input_record_free(input_record *r);

/* The name of a transaction kind as in the file ("camera", ...): txn_kind_name. */
const char *input_txn_kind_name(input_txn_kind k);

#endif
