/* fuzz_record.c - input record files (input/record.c) through
 * input_record_parse. A record that parses must have non-decreasing times and
 * known kinds, and writing its entries back (input_record_write) then parsing
 * that must give the same entries bit for bit (the replay promise). */
#define _GNU_SOURCE /* open_memstream */
#include "fuzz.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "input/record.h"

static bool same_txn(const input_txn *a, const input_txn *b)
{
    /* the reader zeroes each record before filling it in: records compare byte for byte */
    return memcmp(a, b, sizeof *a) == 0;
}

/* Times are written with %.6f (a replay needs microseconds, not bits), and
 * the reader takes words of up to 63 bytes: the round trip is checked for
 * times a recording can reach, below a million years. */
#define ROUND_TRIP_MAX_S 3e13

static double written_time(double t)
{
    char text[64];
    snprintf(text, sizeof text, "%.6f", t);
    return strtod(text, NULL);
}

static void check_record(const input_record *r, const char *name)
{
    for (size_t i = 0; i < r->count; i++) {
        const input_record_entry *e = &r->entries[i];
        if (!isfinite(e->time_s) || e->time_s < 0.0 || (i > 0 && e->time_s < r->entries[i - 1].time_s))
            fuzz_fail("%s: entry %zu: time %a out of order", name, i, e->time_s);
        if ((unsigned)e->txn.kind >= TXN_KIND_COUNT)
            fuzz_fail("%s: entry %zu: kind %d", name, i, (int)e->txn.kind);
        tess_error err = {{0}};
        if (!txn_validate(&e->txn, &err))
            fuzz_fail("%s: entry %zu: an invalid record was read: %s", name, i, err.msg);
    }
    if (r->count > 0 && !(r->entries[r->count - 1].time_s < ROUND_TRIP_MAX_S))
        return;
    char *text = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&text, &len);
    if (!f)
        fuzz_fail("harness: open_memstream failed");
    fprintf(f, "%s\n", INPUT_RECORD_HEADER);
    for (size_t i = 0; i < r->count; i++)
        if (!input_record_write(f, r->entries[i].time_s, &r->entries[i].txn))
            fuzz_fail("harness: input_record_write failed");
    fclose(f);
    input_record back = {0};
    tess_error err = {{0}};
    if (!input_record_parse("written", text, len, &back, &err))
        fuzz_fail("%s: its entries written back do not parse: %s\n%s", name, err.msg, text);
    if (back.count != r->count)
        fuzz_fail("%s: %zu entries written back as %zu", name, r->count, back.count);
    for (size_t i = 0; i < r->count; i++)
        if (back.entries[i].time_s != written_time(r->entries[i].time_s) || !same_txn(&back.entries[i].txn, &r->entries[i].txn))
            fuzz_fail("%s: entry %zu changed when written back", name, i);
    input_record_free(&back);
    free(text);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *name = "input.rec";
    input_record r = {0};
    tess_error err = {{0}};
    if (input_record_parse(name, (const char *)data, size, &r, &err))
        check_record(&r, name);
    else
        fuzz_check_error(&err, name);
    input_record_free(&r);
    return 0;
}
