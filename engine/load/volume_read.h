/* volume_read.h - a structured volume (engine/geometry/volume/volume.h)
 * from files: raw data with a text header, and NRRD.
 *
 * LOADING. volume_load picks the reader by name: ".nrrd" and ".nhdr" (or a
 * first line "NRRD000N") are NRRD, ".txt" is a raw file described by a
 * text header (the shape of /work/shared/data/volumes/), ".raw" looks for
 * the .txt header beside it. Raw data is memory-mapped when its byte order
 * and alignment are the host's (then loading costs the min/max scan), and
 * read and byte-swapped otherwise. Every size is checked against the data
 * file's size before anything is allocated, and the voxel count is capped
 * (VOLUME_MAX_VOXELS), so a broken header costs neither a crash nor memory.
 * A mapped file that is truncated by someone else while mapped raises
 * SIGBUS on access: the one thing the loader cannot check. */
#ifndef TESSERA_LOAD_VOLUME_READ_H
#define TESSERA_LOAD_VOLUME_READ_H

#include "engine/base/err.h"
#include "engine/geometry/volume/volume.h"

/* Load by name (see LOADING above). Errors are one line:
 *   "PATH:LINE: field 'dims': expected 'NX x NY x NZ', got '301 x 370'"
 *   "PATH: data file DATA: truncated: 1000 bytes, the header says 301*370*316 uint8 = 35192920"
 * (always starting with the path given, then the data file's when it is to blame).
 * The returned volume has its range computed. */
volume *volume_load(const char *path, tess_error *err);

/* The raw + text header reader. Fields "name: value", one a line; an
 * indented line continues the field above and is ignored, as is any field
 * not named here and a comment in parentheses after a value:
 *   dims:    NX x NY x NZ                required
 *   type:    uint8 | int16 | uint16 | float32 (also uchar, short, ushort,
 *            float), or a width "16-bit" with "signed"/"unsigned"; "read as
 *            TYPE" (or "read as signed") overrides; "little endian" or "big
 *            endian" (default little)            required
 *   file:    the raw file, relative to the header's directory   required
 *   bytes:   N (the data file's size; checked when given)
 *   spacing: SX SY SZ [unit]            default 1 1 1
 *   origin:  OX OY OZ [unit]            default 0 0 0 */
volume *volume_load_raw_txt(const char *header_path, tess_error *err);

/* The NRRD reader (http://teem.sourceforge.net/nrrd/format.html), NRRD0001
 * to NRRD0005: ".nhdr" with "data file:" (relative to the header's
 * directory) or ".nrrd" with the data after the header's blank line.
 * encoding raw only; dimension 3; type uchar/uint8/unsigned char,
 * short/int16, ushort/uint16, float; endian little or big (required for
 * more than one byte); "spacings" or axis-aligned "space directions" (a
 * positive diagonal); "space origin"; "byte skip" N >= 0 or -1 (data at the
 * end). Anything else that changes how the bytes are read (line skip,
 * gzip, a rotated or flipped axis, a data file list) is refused by name. */
volume *volume_load_nrrd(const char *path, tess_error *err);

#endif
