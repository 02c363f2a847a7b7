/* edid.c - the base EDID block's identity fields. */
#include "edid.h"

#include <stdio.h>
#include <string.h>

#define EDID_BLOCK_BYTES 128
#define EDID_DESCRIPTOR_BYTES 18
#define EDID_FIRST_DESCRIPTOR 54
#define EDID_TAG_SERIAL 0xFF
#define EDID_TAG_NAME 0xFC

/* Descriptor text: up to 13 bytes, ended by a line feed, padded with spaces.
 * An empty (or all-blank) text leaves out as it is: the product code or the
 * serial number stands, never "" (which no wall file can name). */
static void descriptor_text(const uint8_t *d, char *out, size_t out_bytes)
{
    char text[EDID_DESCRIPTOR_BYTES];
    size_t n = 0;
    for (size_t i = 5; i < EDID_DESCRIPTOR_BYTES && d[i] != 0x0A; i++)
        text[n++] = (d[i] >= 0x20 && d[i] < 0x7F) ? (char)d[i] : '?';
    while (n > 0 && text[n - 1] == ' ')
        n--;
    text[n] = '\0';
    if (n > 0)
        snprintf(out, out_bytes, "%s", text);
}

bool edid_parse(const uint8_t *data, size_t size, edid_identity *out)
{
    static const uint8_t header[8] = {0x00, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x00};
    memset(out, 0, sizeof *out);
    if (!data || size < EDID_BLOCK_BYTES || memcmp(data, header, sizeof header) != 0)
        return false;
    uint8_t sum = 0;
    for (size_t i = 0; i < EDID_BLOCK_BYTES; i++)
        sum = (uint8_t)(sum + data[i]);
    if (sum != 0)
        return false;
    /* manufacturer: three 5-bit letters, 'A' = 1, big-endian in bytes 8-9 */
    unsigned id = (unsigned)data[8] << 8 | data[9];
    for (int k = 0; k < 3; k++) {
        unsigned letter = (id >> (10 - 5 * k)) & 0x1F;
        out->manufacturer[k] = letter >= 1 && letter <= 26 ? (char)('A' + letter - 1) : '?';
    }
    unsigned product = (unsigned)data[10] | (unsigned)data[11] << 8;
    uint32_t serial = (uint32_t)data[12] | (uint32_t)data[13] << 8 | (uint32_t)data[14] << 16 |
                      (uint32_t)data[15] << 24;
    snprintf(out->model, sizeof out->model, "0x%04X", product);
    if (serial)
        snprintf(out->serial, sizeof out->serial, "%u", serial);
    for (int k = 0; k < 4; k++) {
        const uint8_t *d = data + EDID_FIRST_DESCRIPTOR + k * EDID_DESCRIPTOR_BYTES;
        if (d[0] != 0 || d[1] != 0) /* a detailed timing, not a text descriptor */
            continue;
        if (d[3] == EDID_TAG_NAME)
            descriptor_text(d, out->model, sizeof out->model);
        else if (d[3] == EDID_TAG_SERIAL)
            descriptor_text(d, out->serial, sizeof out->serial);
    }
    return true;
}
