/* gltf_uri_check.c - the base64 data URIs of a glTF file, checked before
 * assimp reads it (assimp_import.h: assimp_check_gltf_uris).
 *
 * Why: assimp 5.2's base64 decoder allocates the output, then throws on a
 * byte >= 0x80 and never frees it (a leak per such buffer, found by fuzzing,
 * tests/fuzz/corpus/gltf/crash-leak-base64-high-byte), and it decodes any
 * other character outside the alphabet as if it were one, giving a buffer of
 * wrong bytes without a word. A payload holding anything but A-Z a-z 0-9 + /
 * and '=' is refused here with the string's offset and the character.
 *
 * The JSON text (a .gltf file, or the first chunk of a .glb: the JSON chunk
 * of glTF 2.0, the content of glTF 1.0's binary format) is read once as a
 * stream of bytes by a small lexer that knows only strings and their
 * escapes; a string whose decoded text starts "data:" and whose part before
 * the first ',' ends in ";base64" has its payload checked. Nothing else in
 * the file is judged here: a file that is not JSON is assimp's to refuse.
 * assimp picks its glTF readers by content as well as by name, so any file
 * starting with the binary magic "glTF" or a '{' is read this way. */
#include "assimp_import.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

/* What the lexer carries from byte to byte. */
typedef struct uri_lexer {
    const char *path;
    long long offset;      /* of the byte being read, in the file */
    bool in_string;
    int escape;            /* 0; 1 after '\'; 2..5 while reading \uXXXX's digits */
    unsigned escape_code;  /* \uXXXX's value so far */
    long long string_at;   /* offset of the current string's opening quote */
    size_t decoded;        /* characters of the current string so far */
    char head[8];          /* its first 5 characters ("data:"?) */
    char tail[8];          /* the last 7 characters before the ',' (";base64"?) */
    enum { URI_OTHER, URI_HEADER, URI_PAYLOAD } state;
} uri_lexer;

static bool is_base64(int c)
{
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '+' || c == '/' ||
           c == '=';
}

/* One decoded character `c` of the current string (a code point; values
 * >= 0x80 are whatever a multi-byte character or a \u escape made). */
static bool take_char(uri_lexer *x, unsigned c, tess_error *err)
{
    size_t i = x->decoded++;
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
            x->state = memcmp(x->tail, ";base64", 7) == 0 ? URI_PAYLOAD : URI_OTHER;
            return true;
        }
        memmove(x->tail, x->tail + 1, 6);
        x->tail[6] = (char)(c < 0x80 ? c : '?');
        return true;
    case URI_PAYLOAD:
        if (c < 0x80 && is_base64((int)c))
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

/* One byte of the JSON text. */
static bool take_byte(uri_lexer *x, unsigned char b, tess_error *err)
{
    if (!x->in_string) {
        if (b == '"') {
            x->in_string = true;
            x->string_at = x->offset;
            x->decoded = 0;
            x->state = URI_HEADER;
            memset(x->tail, 0, sizeof x->tail);
        }
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
        /* an unknown escape is not JSON (assimp's parser refuses it); in a
         * payload it is refused here as its backslash */
        return take_char(x, s ? (unsigned char)meaning[s - simple] : '\\', err);
    }
    if (x->escape >= 2) {
        unsigned digit = b >= '0' && b <= '9'   ? b - 0x30u
                         : b >= 'a' && b <= 'f' ? b - 'a' + 10u
                         : b >= 'A' && b <= 'F' ? b - 'A' + 10u
                                                : 16u;
        if (digit == 16) { /* not JSON; the byte is read again as a string byte */
            x->escape = 0;
            if (!take_char(x, '\\', err))
                return false;
            return take_byte(x, b, err);
        }
        x->escape_code = x->escape_code << 4 | digit;
        if (++x->escape == 6) {
            x->escape = 0;
            return take_char(x, x->escape_code, err);
        }
        return true;
    }
    if (b == '\\') {
        x->escape = 1;
        return true;
    }
    if (b == '"') {
        x->in_string = false;
        return true;
    }
    return take_char(x, b, err);
}

/* Little-endian uint32 at p. */
static uint32_t le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

bool assimp_check_gltf_uris(const char *path, tess_error *err)
{
    FILE *file = fopen(path, "rb");
    if (!file) /* assimp names the file and the problem */
        return errno != ENOMEM || tess_error_set(err, "%s: out of memory opening it", path);
    uri_lexer x = {.path = path};
    unsigned char header[20];
    size_t got = fread(header, 1, sizeof header, file);
    long long limit = -1; /* bytes of JSON text after `offset`, -1: to the end of the file */
    if (got >= 4 && memcmp(header, "glTF", 4) == 0) {
        if (got < sizeof header) { /* too short for a chunk: assimp's to refuse */
            fclose(file);
            return true;
        }
        /* both binary formats: the JSON's length at byte 12, its text from 20 */
        limit = le32(header + 12);
        x.offset = (long long)sizeof header;
    } else {
        size_t first = 0; /* the first byte that is not JSON white space */
        while (first < got && strchr(" \t\r\n", header[first]))
            first++;
        if (first < got && header[first] != '{') { /* not a JSON object: not glTF */
            fclose(file);
            return true;
        }
        for (size_t i = 0; i < got; i++, x.offset++)
            if (!take_byte(&x, header[i], err)) {
                fclose(file);
                return false;
            }
    }
    unsigned char buf[1 << 16];
    bool ok = true;
    while (ok && limit != 0) {
        size_t want = limit < 0 || limit > (long long)sizeof buf ? sizeof buf : (size_t)limit;
        size_t n = fread(buf, 1, want, file);
        if (n == 0)
            break;
        if (limit > 0)
            limit -= (long long)n;
        for (size_t i = 0; ok && i < n; i++, x.offset++)
            ok = take_byte(&x, buf[i], err);
    }
    if (ok && ferror(file))
        ok = tess_error_set(err, "%s: read error at byte %lld", path, x.offset);
    fclose(file);
    return ok;
}
