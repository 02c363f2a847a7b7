/* fuzz_edid.c - EDID base blocks (wall/edid.c). Each input is parsed as it
 * is, and again with the 8-byte header and the checksum made right, so that
 * the fields behind the checksum are fuzzed too. The identity must be
 * terminated printable text. */
#include "fuzz.h"

#include <string.h>

#include "wall/edid.h"

#define EDID_BLOCK_BYTES 128

static void check_text(const char *s, size_t bytes, const char *what)
{
    const char *end = memchr(s, '\0', bytes);
    if (!end)
        fuzz_fail("edid: %s not terminated", what);
    for (; s < end; s++)
        if ((unsigned char)*s < 0x20 || (unsigned char)*s >= 0x7F)
            fuzz_fail("edid: %s has byte 0x%02X", what, (unsigned char)*s);
}

static void parse(const uint8_t *data, size_t size)
{
    edid_identity id;
    memset(&id, 0xA5, sizeof id);
    if (!edid_parse(data, size, &id)) {
        static const edid_identity zero;
        if (memcmp(&id, &zero, sizeof id) != 0)
            fuzz_fail("edid: a refused block left the identity set");
        return;
    }
    check_text(id.manufacturer, sizeof id.manufacturer, "manufacturer");
    check_text(id.model, sizeof id.model, "model");
    check_text(id.serial, sizeof id.serial, "serial");
    if (strlen(id.manufacturer) != 3 || !id.model[0])
        fuzz_fail("edid: manufacturer '%s', model '%s'", id.manufacturer, id.model);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    parse(data, size);
    if (size < EDID_BLOCK_BYTES)
        return 0;
    static const uint8_t header[8] = {0x00, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x00};
    uint8_t block[EDID_BLOCK_BYTES];
    memcpy(block, data, sizeof block);
    memcpy(block, header, sizeof header);
    uint8_t sum = 0;
    for (size_t i = 0; i + 1 < EDID_BLOCK_BYTES; i++)
        sum = (uint8_t)(sum + block[i]);
    block[EDID_BLOCK_BYTES - 1] = (uint8_t)(0x100 - sum);
    parse(block, sizeof block);
    return 0;
}
