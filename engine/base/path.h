/* path.h - what the file readers ask of a file's path: its extension and its
 * last component. Text only: nothing here touches the file system. */
#ifndef TESSERA_BASE_PATH_H
#define TESSERA_BASE_PATH_H

#include <stdbool.h>
#include <string.h>
#include <strings.h>

/* Whether `path` ends with `ext` (".ply"), compared without case. */
static inline bool path_has_extension(const char *path, const char *ext)
{
    size_t n = strlen(path), e = strlen(ext);
    return n >= e && strcasecmp(path + n - e, ext) == 0;
}

/* The last component of `path` (after its last '/'), within `path`. */
static inline const char *path_basename(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

#endif
