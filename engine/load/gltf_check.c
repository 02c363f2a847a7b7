/* gltf_check.c - a glTF file checked before assimp reads it
 * (assimp_import.h: assimp_check_gltf).
 *
 * Why, in two holes of assimp 5.2 (both found by fuzzing):
 *  - a file named .gltf or .glb is claimed by two importers (glTF 1 and 2);
 *    when both refuse it, assimp offers it to every importer by content, and
 *    some of those overrun their buffers on garbage (an OpenDDL parser read
 *    past a 148-byte file: tests/fuzz/corpus/gltf/crash-sniffed-by-others).
 *    So what the glTF 2 importer would refuse is refused here, with the
 *    reason: for .glb the header and chunk layout; for the JSON text, what
 *    its parser (rapidjson, strict) rejects and json-c might accept
 *    (comments, single quotes, trailing commas, NaN and infinities, raw
 *    control characters in strings, a lone high surrogate, a key given
 *    twice), then a root object whose "asset" has a "version" string "2...".
 *  - its base64 decoder allocates the output, then throws on a byte >= 0x80
 *    and never frees it (a leak per such buffer:
 *    tests/fuzz/corpus/gltf/crash-leak-base64-high-byte), and decodes any
 *    other character outside the alphabet as if it were one, giving wrong
 *    bytes without a word. A data URI payload holding anything but A-Z a-z
 *    0-9 + / and '=' is refused with its offset and the character.
 *  - its data URI parser keeps the offsets of the parts of "data:...,PAYLOAD"
 *    in the string's first bytes, as a (signed) char: a header of 127 bytes
 *    or more before the ',' makes the payload's offset negative or wrapped,
 *    so assimp decodes bytes from before the string (or the header itself)
 *    as the buffer, giving wrong data without a word, or a leak when they are
 *    not base64 (tests/fuzz/corpus/gltf/crash-leak-long-data-uri-header). A
 *    data URI whose payload would start past byte 127 is refused.
 *
 * The JSON text (a .gltf file, or the JSON chunk of a .glb) is read once as a
 * stream of bytes by a small lexer that knows strings and their escapes and
 * the few bytes JSON allows between them; a string whose decoded text starts
 * "data:" and whose part before the first ',' ends in ";base64" has its
 * payload checked. Then json_read's parser (syntax, keys given twice) builds
 * the tree the asset and number checks walk.
 *
 * Files not named .gltf or .glb pass unless their content is glTF (the magic
 * "glTF", or a JSON object): an .obj, .stl or .fbx is claimed by one importer
 * and never offered to others. */
#include "assimp_import.h"

#include <errno.h>
#include <json-c/json.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "engine/base/json_read.h"
#include "engine/base/path.h"

/* A .gltf's text may be as large as assimp reads (it refuses 4 GiB). */
#define GLTF_TEXT_MAX_BYTES ((size_t)UINT32_MAX - 1)

/* What the lexer carries from byte to byte. */
typedef struct gltf_lexer {
    const char *path;
    long long offset;      /* of the byte being read, in the file */
    bool in_string;
    int escape;            /* 0; 1 after '\'; 2..5 while reading \uXXXX's digits */
    unsigned escape_code;  /* \uXXXX's value so far */
    bool high_surrogate;   /* the last character was a \uD800-\uDBFF escape */
    long long string_at;   /* offset of the current string's opening quote */
    size_t decoded;        /* characters of the current string so far */
    size_t header_bytes;   /* UTF-8 bytes of the current string so far, as assimp counts them */
    char head[8];          /* its first 5 characters ("data:"?) */
    char tail[8];          /* the last 7 characters before the ',' (";base64"?) */
    enum { URI_OTHER, URI_HEADER, URI_PAYLOAD } state;
    unsigned char last;    /* the last byte outside strings that is not white space */
} gltf_lexer;

static bool is_base64(unsigned c)
{
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '+' || c == '/' ||
           c == '=';
}

/* The payload of a data URI must start at most this many bytes into the
 * string: assimp 5.2 stores the offset in a char (glTFCommon's ParseDataURI). */
#define DATA_URI_PAYLOAD_MAX_OFFSET 127

/* One decoded character `c` of the current string (a code point; values
 * >= 0x80 are whatever a multi-byte character or a \u escape made), which
 * is `bytes` bytes of the string assimp's parser sees (a raw byte: 1; a \u
 * escape: its UTF-8 length). */
static bool take_char(gltf_lexer *x, unsigned c, unsigned bytes, tess_error *err)
{
    size_t i = x->decoded++;
    size_t at_byte = x->header_bytes; /* where this character starts in assimp's string */
    x->header_bytes += bytes;
    switch (x->state) {
    case URI_OTHER:
        return true;
    case URI_HEADER:
        if (i < 5) {
            x->head[i] = (char)(c < 0x80 ? c : '?');
            if (i == 4 && memcmp(x->head, "data:", 5) != 0)
                x->state = URI_OTHER;
            return true;
        }
        if (c == ',') {
            if (at_byte + 1 > DATA_URI_PAYLOAD_MAX_OFFSET)
                return tess_error_set(err, "%s: byte %lld: the data URI (string at byte %lld) has %zu bytes before "
                                           "its ',' (at most %d: assimp's glTF reader misplaces the data after a "
                                           "longer media type and parameters)",
                                      x->path, x->offset, x->string_at, at_byte, DATA_URI_PAYLOAD_MAX_OFFSET - 1);
            x->state = memcmp(x->tail, ";base64", 7) == 0 ? URI_PAYLOAD : URI_OTHER;
            return true;
        }
        memmove(x->tail, x->tail + 1, 6);
        x->tail[6] = (char)(c < 0x80 ? c : '?');
        return true;
    case URI_PAYLOAD:
        if (c < 0x80 && is_base64(c))
            return true;
        if (c >= 0x20 && c < 0x7f)
            return tess_error_set(err, "%s: byte %lld: the base64 data URI (string at byte %lld) holds '%c', which is "
                                       "not a base64 character",
                                  x->path, x->offset, x->string_at, (int)c);
        return tess_error_set(err, "%s: byte %lld: the base64 data URI (string at byte %lld) holds character 0x%x, "
                                   "which is not a base64 character",
                              x->path, x->offset, x->string_at, c);
    }
    return true;
}

/* The end of a \uXXXX escape with value `code`. */
static bool take_escaped(gltf_lexer *x, unsigned code, tess_error *err)
{
    bool low = code >= 0xDC00 && code <= 0xDFFF;
    if (x->high_surrogate && !low)
        return tess_error_set(err, "%s: byte %lld: a \\u escape of a high surrogate is not followed by a low one "
                                   "(the glTF reader's JSON parser refuses it)",
                              x->path, x->offset);
    x->high_surrogate = code >= 0xD800 && code <= 0xDBFF;
    /* UTF-8 length; a low surrogate ends a pair, 4 bytes in all */
    unsigned bytes = code < 0x80 ? 1 : code < 0x800 ? 2 : low ? 4 : 3;
    return x->high_surrogate || take_char(x, code, bytes, err);
}

/* A byte between strings: JSON's structure, white space, numbers and the
 * letters of true, false and null; a ',' must not close a container. */
static bool take_outside(gltf_lexer *x, unsigned char b, tess_error *err)
{
    static const char allowed[] = " \t\r\n{}[]:,-+.0123456789eEtrufalsn";
    if (!b || !strchr(allowed, b)) {
        const char *what = b == '/' ? " (a comment?)" : b == '\'' ? " (a single-quoted string?)" : "";
        if (b >= 0x20 && b < 0x7f)
            return tess_error_set(err, "%s: byte %lld: '%c' outside a string is not JSON%s", x->path, x->offset,
                                  (int)b, what);
        return tess_error_set(err, "%s: byte %lld: byte 0x%02x outside a string is not JSON", x->path, x->offset, b);
    }
    if ((b == ']' || b == '}') && x->last == ',')
        return tess_error_set(err, "%s: byte %lld: a ',' before '%c' (a trailing comma is not JSON)", x->path,
                              x->offset, (int)b);
    if (!strchr(" \t\r\n", b))
        x->last = b;
    return true;
}

/* One byte of the JSON text. */
static bool take_byte(gltf_lexer *x, unsigned char b, tess_error *err)
{
    if (!x->in_string) {
        if (b != '"')
            return take_outside(x, b, err);
        x->in_string = true;
        x->string_at = x->offset;
        x->decoded = 0;
        x->header_bytes = 0;
        x->state = URI_HEADER;
        x->last = '"';
        memset(x->tail, 0, sizeof x->tail);
        return true;
    }
    if (x->escape == 1) {
        static const char simple[] = "\"\\/bfnrt", meaning[] = "\"\\/\b\f\n\r\t";
        const char *s = b ? strchr(simple, b) : NULL;
        if (b == 'u') {
            x->escape = 2;
            x->escape_code = 0;
            return true;
        }
        x->escape = 0;
        if (!s)
            return tess_error_set(err, "%s: byte %lld: '\\%c' is not a JSON escape", x->path, x->offset,
                                  b >= 0x20 && b < 0x7f ? (int)b : '?');
        if (x->high_surrogate)
            return take_escaped(x, (unsigned char)meaning[s - simple], err);
        return take_char(x, (unsigned char)meaning[s - simple], 1, err);
    }
    if (x->escape >= 2) {
        unsigned digit = b >= '0' && b <= '9'   ? b - 0x30u
                         : b >= 'a' && b <= 'f' ? b - 'a' + 10u
                         : b >= 'A' && b <= 'F' ? b - 'A' + 10u
                                                : 16u;
        if (digit == 16)
            return tess_error_set(err, "%s: byte %lld: a \\u escape needs four hexadecimal digits", x->path,
                                  x->offset);
        x->escape_code = x->escape_code << 4 | digit;
        if (++x->escape == 6) {
            x->escape = 0;
            return take_escaped(x, x->escape_code, err);
        }
        return true;
    }
    if (x->high_surrogate && b != '\\')
        return take_escaped(x, b, err); /* refused: not a low surrogate */
    if (b == '\\') {
        x->escape = 1;
        return true;
    }
    if (b == '"') {
        x->in_string = false;
        return true;
    }
    if (b < 0x20)
        return tess_error_set(err, "%s: byte %lld: control character 0x%02x inside a string (JSON needs it escaped)",
                              x->path, x->offset, b);
    return take_char(x, b, 1, err);
}

/* ---- the tree ------------------------------------------------------------ */

/* Every number in v is finite (the glTF reader's parser refuses 1e400, which
 * json-c reads as infinity). Depth is bounded by json-c's nesting limit. */
static bool numbers_finite(json_object *v)
{
    switch (json_object_get_type(v)) {
    case json_type_double:
        return isfinite(json_object_get_double(v));
    case json_type_array:
        for (size_t i = 0, n = json_object_array_length(v); i < n; i++)
            if (!numbers_finite(json_object_array_get_idx(v, i)))
                return false;
        return true;
    case json_type_object: {
        json_object_object_foreach(v, key, member) {
            (void)key;
            if (!numbers_finite(member))
                return false;
        }
        return true;
    }
    default:
        return true;
    }
}

/* The JSON text (`len` bytes at file offset `base`): the lexer, then the
 * parse and the tree's checks. */
static bool check_json_text(const char *path, const char *text, size_t len, long long base, tess_error *err)
{
    /* the glTF reader parses in place and stops at a NUL (a .glb's JSON
     * chunk may be padded with them): so does the check */
    len = strnlen(text, len);
    gltf_lexer x = {.path = path};
    for (size_t i = 0; i < len; i++) {
        x.offset = base + (long long)i;
        if (!take_byte(&x, (unsigned char)text[i], err))
            return false;
    }
    if (x.in_string)
        return tess_error_set(err, "%s: the string at byte %lld is not closed", path, x.string_at);
    json_object *root = NULL;
    if (!jr_parse(path, text, len, &root, err))
        return false;
    bool ok = true;
    json_object *asset = NULL, *version = NULL;
    const char *v = NULL;
    if (!json_object_is_type(root, json_type_object))
        ok = tess_error_set(err, "%s: not glTF: the JSON is %s, not an object", path, jr_kind(root));
    else if (!jr_get_member(root, "asset", &asset) || !json_object_is_type(asset, json_type_object))
        ok = tess_error_set(err, "%s: not glTF: no \"asset\" object", path);
    else if (!jr_get_member(asset, "version", &version) || !json_object_is_type(version, json_type_string))
        ok = tess_error_set(err, "%s: asset.version: missing or not a string (glTF 2.0 files say \"2.0\")", path);
    else if ((v = json_object_get_string(version))[0] != '2')
        ok = tess_error_set(err, "%s: asset.version is '%.20s': tessera reads glTF 2.0", path, v);
    else if (!numbers_finite(root))
        ok = tess_error_set(err, "%s: a number is out of range (beyond a double's)", path);
    json_object_put(root);
    return ok;
}

/* ---- the file ------------------------------------------------------------ */

static uint32_t le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

#define GLB_JSON 0x4E4F534Au /* "JSON" */
#define GLB_BIN 0x004E4942u  /* "BIN\0" */

/* A .glb: its header, the JSON chunk and, when the header's length leaves
 * room for one, the BIN chunk's header; then the JSON text. */
static bool check_glb(const char *path, FILE *file, long long file_size, tess_error *err)
{
    unsigned char header[20];
    if (fread(header, 1, sizeof header, file) != sizeof header)
        return tess_error_set(err, "%s: a .glb needs a 20-byte header and chunk header, the file has %lld bytes", path,
                              file_size);
    if (memcmp(header, "glTF", 4) != 0)
        return tess_error_set(err, "%s: not binary glTF: the file does not start with \"glTF\"", path);
    if (le32(header + 4) != 2)
        return tess_error_set(err, "%s: binary glTF version %u: tessera reads glTF 2.0", path, le32(header + 4));
    uint32_t json_len = le32(header + 12), declared = le32(header + 8);
    if (le32(header + 16) != GLB_JSON)
        return tess_error_set(err, "%s: the first chunk is not JSON (type 0x%08x)", path, le32(header + 16));
    if (json_len < 2 || (long long)json_len > file_size - 20)
        return tess_error_set(err, "%s: the JSON chunk's length %u does not fit the file (%lld bytes)", path,
                              json_len, file_size);
    long long padded = ((long long)json_len + 3) & ~3LL, bin_at = 20 + padded;
    if ((long long)declared >= bin_at + 8) { /* as the reader: then a BIN chunk must follow */
        unsigned char bin[8];
        if (fseek(file, (long)bin_at, SEEK_SET) != 0 || fread(bin, 1, sizeof bin, file) != sizeof bin)
            return tess_error_set(err, "%s: the header's length %u promises a BIN chunk at byte %lld past the end",
                                  path, declared, bin_at);
        if (le32(bin + 4) != GLB_BIN)
            return tess_error_set(err, "%s: byte %lld: the second chunk is not BIN (type 0x%08x)", path, bin_at,
                                  le32(bin + 4));
    }
    char *text = malloc((size_t)json_len + 1);
    if (!text)
        return tess_error_set(err, "%s: out of memory for the %u-byte JSON chunk", path, json_len);
    bool ok = fseek(file, 20, SEEK_SET) == 0 && fread(text, 1, json_len, file) == json_len;
    if (!ok)
        tess_error_set(err, "%s: read error in the JSON chunk", path);
    text[json_len] = '\0';
    ok = ok && check_json_text(path, text, json_len, 20, err);
    free(text);
    return ok;
}

bool assimp_check_gltf(const char *path, tess_error *err)
{
    bool named_gltf = path_has_extension(path, ".gltf"), named_glb = path_has_extension(path, ".glb");
    FILE *file = fopen(path, "rb");
    if (!file) /* assimp names the file and the problem */
        return errno != ENOMEM || tess_error_set(err, "%s: out of memory opening it", path);
    struct stat st;
    unsigned char first[4] = {0};
    size_t got = fstat(fileno(file), &st) == 0 && S_ISREG(st.st_mode) ? fread(first, 1, sizeof first, file) : 0;
    bool binary = got == 4 && memcmp(first, "glTF", 4) == 0;
    size_t lead = 0;
    while (lead < got && strchr(" \t\r\n", first[lead]))
        lead++;
    bool text = !binary && (named_gltf || (lead < got && first[lead] == '{'));
    if (!binary && named_glb)
        binary = true; /* refused below with the reason */
    bool ok = true;
    if (binary) {
        rewind(file);
        ok = check_glb(path, file, (long long)st.st_size, err);
    } else if (text) {
        size_t len = 0;
        char *json = jr_read_file(path, GLTF_TEXT_MAX_BYTES, "a glTF file", &len, err);
        ok = json && check_json_text(path, json, len, 0, err);
        free(json);
    }
    fclose(file);
    return ok;
}
