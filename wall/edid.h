/* edid.h - the identity of a monitor from its EDID block (VESA E-EDID 1.3/1.4,
 * base block of 128 bytes): manufacturer (3 letters), model and serial, as
 * wall configs name monitors (wall_config.h "edid"). */
#ifndef TESSERA_EDID_H
#define TESSERA_EDID_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct edid_identity {
    char manufacturer[4]; /* PNP id, e.g. "DEL" */
    char model[64];       /* the monitor name descriptor (0xFC), else the product code as "0x1234" */
    char serial[64];      /* the serial string descriptor (0xFF), else the serial number in decimal, else "" */
} edid_identity;

/* Parse the base block. False when the block is shorter than 128 bytes, its
 * header is wrong or its checksum does not add up (*out cleared). */
bool edid_parse(const uint8_t *data, size_t size, edid_identity *out);

#endif
