/* test_edid.c - the EDID identity parser on synthetic base blocks. */
#include <criterion/criterion.h>
#include <string.h>

#include "wall/edid.h"

/* A valid base block: header, manufacturer, product, serial, descriptors, checksum. */
static void make_block(uint8_t b[128], const char *pnp, unsigned product, uint32_t serial, const char *name,
                       const char *serial_text)
{
    static const uint8_t header[8] = {0x00, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x00};
    memset(b, 0, 128);
    memcpy(b, header, 8);
    unsigned id = (unsigned)(pnp[0] - 'A' + 1) << 10 | (unsigned)(pnp[1] - 'A' + 1) << 5 | (unsigned)(pnp[2] - 'A' + 1);
    b[8] = (uint8_t)(id >> 8), b[9] = (uint8_t)id;
    b[10] = (uint8_t)product, b[11] = (uint8_t)(product >> 8);
    for (int k = 0; k < 4; k++)
        b[12 + k] = (uint8_t)(serial >> (8 * k));
    b[54] = 0x01; /* descriptor 0: a detailed timing (non-zero pixel clock) */
    const char *texts[2] = {name, serial_text};
    const uint8_t tags[2] = {0xFC, 0xFF};
    for (int t = 0; t < 2; t++) {
        if (!texts[t])
            continue;
        uint8_t *d = b + 72 + 18 * t;
        d[3] = tags[t];
        size_t n = strlen(texts[t]);
        for (size_t i = 0; i < 13; i++)
            d[5 + i] = i < n ? (uint8_t)texts[t][i] : i == n ? 0x0A : 0x20;
    }
    uint8_t sum = 0;
    for (int i = 0; i < 127; i++)
        sum = (uint8_t)(sum + b[i]);
    b[127] = (uint8_t)(256 - sum);
}

Test(edid, identity_from_descriptors)
{
    uint8_t b[128];
    edid_identity id;
    make_block(b, "DEL", 0x40B5, 12345, "DELL U2415", "7MT0167B0Y3L");
    cr_assert(edid_parse(b, sizeof b, &id));
    cr_expect_str_eq(id.manufacturer, "DEL");
    cr_expect_str_eq(id.model, "DELL U2415");
    cr_expect_str_eq(id.serial, "7MT0167B0Y3L");
}

Test(edid, product_code_and_numeric_serial_without_descriptors)
{
    uint8_t b[128];
    edid_identity id;
    make_block(b, "RHT", 0x1234, 987654, NULL, NULL);
    cr_assert(edid_parse(b, sizeof b, &id));
    cr_expect_str_eq(id.manufacturer, "RHT");
    cr_expect_str_eq(id.model, "0x1234");
    cr_expect_str_eq(id.serial, "987654");
    make_block(b, "RHT", 0x1234, 0, NULL, NULL);
    cr_assert(edid_parse(b, sizeof b, &id));
    cr_expect_str_eq(id.serial, "", "no serial at all");
}

/* Found by fuzzing (tests/fuzz/corpus/edid/crash-empty-name): an empty or
 * all-blank name or serial descriptor used to give model "" (no wall file can
 * name it); the product code and the serial number stand instead. */
Test(edid, empty_text_descriptors_keep_the_numbers)
{
    uint8_t b[128];
    edid_identity id;
    make_block(b, "DEL", 0xA0C4, 4242, "", "  ");
    cr_assert(edid_parse(b, sizeof b, &id));
    cr_expect_str_eq(id.model, "0xA0C4");
    cr_expect_str_eq(id.serial, "4242");
    make_block(b, "DEL", 0xA0C4, 0, "   ", "");
    cr_assert(edid_parse(b, sizeof b, &id));
    cr_expect_str_eq(id.model, "0xA0C4");
    cr_expect_str_eq(id.serial, "", "no serial at all");
}

Test(edid, broken_blocks_are_refused)
{
    uint8_t b[128];
    edid_identity id;
    make_block(b, "DEL", 1, 1, "X", NULL);
    cr_expect_not(edid_parse(b, 127, &id), "short block");
    b[100] ^= 0x40;
    cr_expect_not(edid_parse(b, sizeof b, &id), "bad checksum");
    make_block(b, "DEL", 1, 1, "X", NULL);
    b[0] = 0x12;
    cr_expect_not(edid_parse(b, sizeof b, &id), "bad header");
    cr_expect_not(edid_parse(NULL, 128, &id));
    cr_expect_str_eq(id.manufacturer, "", "cleared on failure");
}
