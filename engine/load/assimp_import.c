/* assimp_import.c - what both assimp loaders share (assimp_import.h): the
 * checks that plug assimp 5.2's holes, the import under the one lock around
 * assimp's error string, and copying a triangle mesh into a tessera mesh.
 *
 * The holes (each found by tests or fuzzing, each checked here before or
 * instead of trusting assimp):
 *  - its OBJ parser drops a "v" line with a non-numeric coordinate ("v 1 abc 2")
 *    without a word, shifting every later vertex index, and reads "2abc" as 2;
 *    check_obj_numbers() reads the numbers of .obj files itself first;
 *  - its MTL reader dereferences a NULL material for a texture statement
 *    (map_Kd, bump, disp, norm, ...) before the first "newmtl" and crashes
 *    (found by fuzzing), and drops colours given there silently;
 *    check_mtllib() reads the material libraries an .obj names first;
 *  - an index of an element line out of range (vertex, texture coordinate
 *    or normal) after a second group ("g") makes it throw with the group's
 *    mesh half built and leak it; so does an "l" line of one corner. The
 *    check must therefore read every line as assimp does: assimp classifies a
 *    line by its first character without skipping blanks ("fx 1 2 5" is a
 *    face, an indented "  v 0 1 0" is skipped), drops a "v" line of 2, 5 or 7
 *    numbers (counting ".5" as none and a comment's numbers as the line's),
 *    reads a corner "-30-1" as two indices and a byte-order mark as
 *    text (each found by fuzzing, each a way an index got past the check):
 *    check_obj_line refuses what assimp would read differently, reads
 *    corners strictly, counts the data of each kind and checks every index;
 *  - aiProcess_JoinIdenticalVertices merges a vertex with a NaN coordinate into
 *    an unrelated one, so the NaN never reaches mesh_validate; the scene is
 *    therefore checked for non-finite values before that step runs;
 *  - a .gltf or .glb that both glTF importers refuse is offered to every
 *    other importer by content, some of which overrun buffers on garbage;
 *    its base64 decoder leaks the buffer of a data URI holding a byte >= 0x80
 *    (both found by fuzzing): assimp_check_gltf (gltf_check.c) reads glTF
 *    files first. */
#include "assimp_import.h"

#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "engine/geometry/triangles/mesh.h"
#include "engine/base/path.h"
#include "engine/base/progress.h"

/* ValidateDataStructure turns out-of-range indices into an import failure
 * instead of a scene we would have to distrust. JoinIdenticalVertices runs
 * afterwards, once the scene is known to be finite. */
#define BASE_FLAGS (aiProcess_Triangulate | aiProcess_SortByPType | aiProcess_ValidateDataStructure)
#define JOIN_FLAGS aiProcess_JoinIdenticalVertices

/* aiPrimitiveType bits that name a primitive (5.2 adds an n-gon encoding flag) */
#define PRIMITIVE_MASK                                                                                            \
    (aiPrimitiveType_POINT | aiPrimitiveType_LINE | aiPrimitiveType_TRIANGLE | aiPrimitiveType_POLYGON)

/* assimp's C API keeps the last import error in one process-wide string,
 * written inside a failing aiImportFile and read by aiGetErrorString. This lock
 * makes the pair atomic so concurrent loads report their own errors; it is the
 * only shared state of the assimp loaders and guards nothing else. */
static pthread_mutex_t import_lock = PTHREAD_MUTEX_INITIALIZER;

/* ---- OBJ numbers, checked before assimp sees them ---------------------- */

/* How many numbers an OBJ vertex-data line holds: the counts assimp 5.2's
 * reader takes; it drops a "v" line of any other count without a word
 * (shifting every later index) and throws on a "vt" line of another. */
static const struct obj_vertex_data {
    const char *keyword; /* first word of the line */
    unsigned counts;     /* bit n: n numbers are allowed */
    const char *allowed; /* the same, for messages */
} obj_vertex_data[] = {
    {"v", 1u << 3 | 1u << 4 | 1u << 6, "3, 4 or 6"}, /* x y z, x y z w, or x y z r g b (a common extension) */
    {"vn", 1u << 3, "3"},                           /* normal */
    {"vt", 1u << 2 | 1u << 3, "2 or 3"},            /* u v, optional w */
};

/* What separates the words of an OBJ line for assimp's reader: blanks and
 * tabs only. A line "\vv 0 1 0" is no vertex to it (it skips the line), so
 * the check must not count one either (found by fuzzing: the vertex count
 * then disagreed and an index out of range reached assimp); other control
 * characters stay inside words, where the number and corner checks refuse
 * them. */
#define OBJ_SPACE " \t"

/* assimp's OBJ and MTL readers end a line at '\n', '\r', '\f' and '\0' alike
 * ("#\0mtllib x.mtl" names a library for them; found by fuzzing): the next
 * such line of the bytes from *p to `end` (as getline gave them),
 * NUL-terminated in place, or NULL after the last. */
static char *next_logical_line(char **p, char *end)
{
    if (*p >= end)
        return NULL;
    char *line = *p, *q = line;
    while (q < end && *q != '\n' && *q != '\r' && *q != '\f' && *q != '\0')
        q++;
    if (q < end)
        *q++ = '\0';
    *p = q;
    return line;
}

/* Every statement of material library `mtl_path` must follow a "newmtl" (see
 * the top of the file). A library that is not a regular file, or cannot be
 * read, is left to assimp (which goes on without its materials). */
static bool check_mtl_file(const char *mtl_path, const char *obj_path, unsigned long obj_line, tess_error *err)
{
    FILE *file = fopen(mtl_path, "r");
    if (!file) /* out of memory is no reason to skip the check (assimp would read it unchecked) */
        return errno != ENOMEM ||
               tess_error_set(err, "%s:%lu: material library %s: out of memory opening it", obj_path, obj_line,
                              mtl_path);
    struct stat st;
    bool ok = true;
    char *line = NULL;
    size_t capacity = 0;
    unsigned long line_no = 0;
    ssize_t got = 0;
    errno = 0;
    bool named = false; /* a "newmtl" was seen: the rest is assimp's */
    while (ok && !named && fstat(fileno(file), &st) == 0 && S_ISREG(st.st_mode) &&
           (got = getline(&line, &capacity, file)) >= 0) {
        line_no++;
        char *p = line, *part;
        while (ok && !named && (part = next_logical_line(&p, line + got))) {
            char *save;
            char *word = strtok_r(part, " \t\v", &save);
            if (!word || word[0] == '#')
                continue;
            named = strcmp(word, "newmtl") == 0;
            if (!named)
                ok = tess_error_set(err, "%s:%lu: material library %s:%lu: '%.40s' before any 'newmtl' (a "
                                         "material statement needs its material)",
                                    obj_path, obj_line, mtl_path, line_no, word);
        }
    }
    if (ok && got < 0 && !feof(file) && errno == ENOMEM) /* getline's -1 without the end: as in check_obj_numbers */
        ok = tess_error_set(err, "%s:%lu: material library %s:%lu: out of memory reading the line", obj_path, obj_line,
                            mtl_path, line_no + 1);
    free(line);
    fclose(file);
    return ok;
}

/* An "mtllib" line (`rest`: after the keyword). assimp 5.2 reads the first
 * name, relative to the .obj's directory unless absolute, and when that does
 * not exist, the .obj's own name with ".mtl" for ".obj". */
static bool check_mtllib(char *rest, const char *obj_path, unsigned long obj_line, tess_error *err)
{
    char *save;
    const char *name = strtok_r(rest, " \t\r\n\v\f", &save);
    if (!name)
        return true;
    char mtl[4096];
    const char *slash = strrchr(obj_path, '/');
    int dir_len = name[0] == '/' || !slash ? 0 : (int)(slash - obj_path + 1);
    if (snprintf(mtl, sizeof mtl, "%.*s%s", dir_len, obj_path, name) >= (int)sizeof mtl)
        return true;
    struct stat st;
    if (stat(mtl, &st) != 0) {
        size_t n = strlen(obj_path); /* ends in ".obj" */
        if (n + 1 > sizeof mtl)
            return true;
        snprintf(mtl, sizeof mtl, "%.*smtl", (int)(n - 3), obj_path);
    }
    return check_mtl_file(mtl, obj_path, obj_line, err);
}

/* The data an element line's corner indexes: "v", "vt", "vn" lines. */
enum { OBJ_VERTEX, OBJ_TEXCOORD, OBJ_NORMAL, OBJ_KINDS };
static const char *const obj_kind_name[OBJ_KINDS] = {"vertex", "texture coordinate", "normal"};
static const char *const obj_kind_plural[OBJ_KINDS] = {"vertices", "texture coordinates", "normals"};

/* What the check carries from line to line: the data of each kind is
 * counted, and of the positive indices of each kind (which may point
 * forward) the largest is kept, to be checked against the count at the end. */
typedef struct obj_check {
    const char *path;
    tess_error *err;
    unsigned long line_no;              /* the current line, from 1 */
    long long count[OBJ_KINDS];         /* "v", "vt", "vn" lines so far */
    long long max_index[OBJ_KINDS];     /* largest positive index so far, 0 if none */
    unsigned long max_line[OBJ_KINDS];  /* where it was */
    bool past_start;                    /* the file's first line was seen */
} obj_check;

/* An index as the check accepts it: an optional '-', then 1 to 15 digits.
 * Advances *p past it; false (with *p unchanged) when there is none. */
static bool read_obj_index(const char **p, long long *out)
{
    const char *q = *p;
    bool negative = *q == '-';
    q += negative;
    long long value = 0;
    int digits = 0;
    for (; *q >= '0' && *q <= '9'; q++, digits++) {
        if (digits == 15)
            return false;
        value = value * 10 + (*q - '0');
    }
    if (!digits)
        return false;
    *out = negative ? -value : value;
    *p = q;
    return true;
}

/* One index of kind k on the current line: a negative one counts back from
 * the data so far and must land on one, a positive one is remembered for the
 * check at the end; 0 is assimp's to refuse (it does, while parsing, before
 * any mesh is built: "Invalid face index"). */
static bool check_obj_index(obj_check *c, const char *keyword, int k, long long index)
{
    if (index < 0 && -index > c->count[k])
        return tess_error_set(c->err, "%s:%lu: '%s' line: %s index %lld is before the first %s (%lld so far)", c->path,
                              c->line_no, keyword, obj_kind_name[k], index, obj_kind_name[k], c->count[k]);
    if (index > c->max_index[k]) {
        c->max_index[k] = index;
        c->max_line[k] = c->line_no;
    }
    return true;
}

/* The corners of an element line ("f 1/2/3 -1//4 ...", "l 1/2 3/4", "p 1"),
 * each v, v/vt, v//vn or v/vt/vn. They are read strictly: assimp 5.2 reads
 * other spellings its own way ("-30-1" as two indices, "+5" twice) and
 * throws on an index out of range with a group's mesh half built (a leak), so
 * a corner it could misread is refused here with the reason. So is an "l"
 * line of fewer than two corners: after a second group assimp 5.2 leaks the
 * group's mesh on one (found by fuzzing). */
static bool check_obj_indices(obj_check *c, const char *keyword, char **save)
{
    int corners = 0;
    for (char *token; (token = strtok_r(NULL, OBJ_SPACE, save)) && token[0] != '#';) {
        const char *p = token;
        long long index[OBJ_KINDS];
        bool present[OBJ_KINDS] = {false, false, false};
        bool ok = present[OBJ_VERTEX] = read_obj_index(&p, &index[OBJ_VERTEX]);
        if (ok && *p == '/') {
            p++;
            if (*p != '/')
                ok = present[OBJ_TEXCOORD] = read_obj_index(&p, &index[OBJ_TEXCOORD]);
            if (ok && *p == '/') {
                p++;
                ok = present[OBJ_NORMAL] = read_obj_index(&p, &index[OBJ_NORMAL]);
            }
        }
        if (!ok || *p != '\0')
            return tess_error_set(c->err,
                                  "%s:%lu: '%s' line: expected a corner like 1, 1/2, 1//3 or 1/2/3 (an index may be "
                                  "negative), got '%.40s'",
                                  c->path, c->line_no, keyword, token);
        for (int k = 0; k < OBJ_KINDS; k++)
            if (present[k] && !check_obj_index(c, keyword, k, index[k]))
                return false;
        corners++;
    }
    if (strcmp(keyword, "l") == 0 && corners < 2)
        return tess_error_set(c->err, "%s:%lu: 'l' line: a line needs 2 or more corners, got %d", c->path, c->line_no,
                              corners);
    return true;
}

/* Why assimp 5.2's reader would read number `token` of a vertex-data line
 * differently from strtod, or NULL when both read it alike. The spellings
 * both read alike: an optional sign, digits with an optional point and
 * fraction (or, after a sign, a point and a fraction), an optional exponent.
 * assimp differs on the others, each checked against it:
 *  - it does not count ".5" as a number when it counts a line's numbers, so
 *    "v .5 0 0" holds 2 to it and the vertex is dropped, shifting every later
 *    index (found by fuzzing: an index then got past the count check and
 *    assimp leaked a half-built mesh on it); "-.5" and "+.5" it counts;
 *  - it reads "0x10" as 0 and "1,5" as 1.5 (strtod: 16, 1);
 *  - it reads the digits before the point into a 64-bit integer without an
 *    overflow check: 21 digits come out wrong by a factor;
 *  - the words "nan" and "inf" are strtod's: refused as not finite later.
 * Past its 15th fraction digit assimp drops the rest: "0.0000000000000001"
 * is 0 to it, an error of 1e-16 at most that no scene of floats can see. */
static const char *obj_number_problem(const char *token)
{
    const char *p = token;
    const bool sign = *p == '-' || *p == '+';
    p += sign;
    if (p[0] == 'n' || p[0] == 'N' || p[0] == 'i' || p[0] == 'I') {
        char *end;
        double v = strtod(token, &end);
        /* nan, inf, infinity: refused as not finite, with their own message */
        return end > token && *end == '\0' && !isfinite(v) ? NULL : "expected a number";
    }
    const char *digits = p;
    while (*p >= '0' && *p <= '9')
        p++;
    const char *point = p;
    if (*p == '.') {
        p++;
        while (*p >= '0' && *p <= '9')
            p++;
    }
    const bool fraction = p > point + 1;
    if (point == digits && !fraction)
        return "expected a number";
    if (*p == 'e' || *p == 'E') {
        p++;
        p += *p == '-' || *p == '+';
        const char *exponent = p;
        while (*p >= '0' && *p <= '9')
            p++;
        if (p == exponent)
            return "expected a number";
    }
    if (*p != '\0')
        return "expected a number";
    if (point == digits && !sign)
        return "a number needs a digit before its point (assimp's reader does not count '.5' as a number and "
               "drops the line: write 0.5)";
    while (digits < point && *digits == '0')
        digits++;
    if (point - digits > 19)
        return "more than 19 digits before the point (assimp's reader overflows on them: write it with an "
               "exponent, like 1.5e20)";
    return NULL;
}

/* Check one line as assimp 5.2's OBJ reader will read it: it classifies a
 * line by its first character alone, without skipping blanks ('v' then a
 * blank, 't' or 'n': vertex data; 'f', 'l', 'p': an element, whatever the
 * rest of the word), and skips a line it does not know. So:
 *  - a data or element line indented by blanks is skipped by assimp, which
 *    loses the data silently: refused;
 *  - a word assimp would read as another ("vtx", "foo") is refused;
 *  - a vertex-data line must carry only finite numbers, as many as its
 *    keyword takes; it counts towards its kind;
 *  - an element line's corners must be in range (check_obj_indices);
 *  - "mtllib" has its libraries checked (check_mtllib); "cstype" (free-form
 *    geometry, whose lines assimp skips) is refused.
 * Other lines are assimp's business. Found by fuzzing: every disagreement
 * between this check and assimp about what a line is let an index out of
 * range through, and assimp leaks a half-built mesh on one. */
static bool check_obj_line(obj_check *c, char *line)
{
    const char *path = c->path;
    unsigned long line_no = c->line_no;
    tess_error *err = c->err;
    if (!c->past_start && strncmp(line, "\xEF\xBB\xBF", 3) == 0) /* assimp 5.2 reads it as the line's first character */
        return tess_error_set(err, "%s:1: a UTF-8 byte-order mark (assimp's reader would lose the first line: save "
                                   "the file without it)",
                              path);
    c->past_start = true;
    if (line[0] == ' ' || line[0] == '\t') {
        const char *q = line + strspn(line, OBJ_SPACE);
        if (*q == 'v' || *q == 'f' || *q == 'l' || *q == 'p' || strncmp(q, "mtllib", 6) == 0)
            return tess_error_set(err, "%s:%lu: '%.40s': an indented line (assimp's reader skips a line that starts "
                                       "with a blank, and its data would be lost)",
                                  path, line_no, q);
        return true;
    }
    char *save;
    char *word = strtok_r(line, OBJ_SPACE, &save);
    if (!word)
        return true;
    if (strcmp(word, "mtllib") == 0)
        return check_mtllib(save, path, line_no, err);
    if (strcmp(word, "cstype") == 0)
        return tess_error_set(err, "%s:%lu: free-form geometry ('cstype') is not supported", path, line_no);
    const bool element = word[0] == 'f' || word[0] == 'l' || word[0] == 'p';
    const bool data = word[0] == 'v' && (word[1] == '\0' || word[1] == 't' || word[1] == 'n');
    if ((element && word[1] != '\0') || (data && word[1] != '\0' && word[2] != '\0'))
        return tess_error_set(err, "%s:%lu: unknown keyword '%.40s' (assimp would read it as '%.*s')", path, line_no,
                              word, element ? 1 : 2, word);
    if (element)
        return check_obj_indices(c, word, &save);
    if (!data)
        return true;
    const int k = word[1] == 't' ? OBJ_TEXCOORD : word[1] == 'n' ? OBJ_NORMAL : OBJ_VERTEX;
    const struct obj_vertex_data *kind = &obj_vertex_data[k == OBJ_VERTEX ? 0 : k == OBJ_NORMAL ? 1 : 2];
    c->count[k]++;
    int count = 0;
    double value[4] = {0, 0, 0, 1};
    char *token;
    for (; (token = strtok_r(NULL, OBJ_SPACE, &save)) && token[0] != '#'; count++) {
        const char *problem = obj_number_problem(token);
        if (problem)
            return tess_error_set(err, "%s:%lu: '%s' line: %s, got '%.40s'", path, line_no, kind->keyword, problem,
                                  token);
        double v = strtod(token, NULL);
        if (!isfinite(v))
            return tess_error_set(err, "%s:%lu: '%s' line: value %d is %.40s (must be finite)", path, line_no,
                                  kind->keyword, count + 1, token);
        if (fabs(v) > FLT_MAX)
            return tess_error_set(err, "%s:%lu: '%s' line: value %d is %.40s, beyond a float's range (must be at "
                                       "most %g in magnitude)",
                                  path, line_no, kind->keyword, count + 1, token, (double)FLT_MAX);
        if (count < 4)
            value[count] = v;
    }
    /* assimp counts the numbers of a "v" or "vt" line to the line's end, a
     * comment's too: "v 1 2 3 # 4" holds 4 to it, and it then fails on the
     * '#' (a "vn" line it reads as 3 numbers without counting) */
    for (; token && k != OBJ_NORMAL; token = strtok_r(NULL, OBJ_SPACE, &save))
        if ((token[0] >= '0' && token[0] <= '9') || token[0] == '-' || token[0] == '+' ||
            strncasecmp(token, "nan", 3) == 0 || strncasecmp(token, "inf", 3) == 0)
            return tess_error_set(err, "%s:%lu: '%s' line: a number in the comment ('%.40s'; assimp's reader counts "
                                       "it with the line's numbers)",
                                  path, line_no, kind->keyword, token);
    if (count > 30 || !(kind->counts >> count & 1u))
        return tess_error_set(err, "%s:%lu: '%s' line: expected %s numbers, got %d", path, line_no, kind->keyword,
                              kind->allowed, count);
    /* x y z w: assimp divides x, y and z by w, in floats */
    if (k == OBJ_VERTEX && count == 4) {
        const float w = (float)value[3];
        for (int i = 0; i < 3; i++)
            if (w == 0.f || !isfinite((float)value[i] / w))
                return tess_error_set(err, "%s:%lu: 'v' line: x y z w with w = %g: x, y and z divided by w "
                                           "(as assimp's reader does) are not finite floats",
                                      path, line_no, value[3]);
    }
    return true;
}

static bool check_obj_numbers(const char *path, tess_error *err)
{
    FILE *file = fopen(path, "r");
    if (!file) {
        char text[128];
        if (strerror_r(errno, text, sizeof text) != 0)
            snprintf(text, sizeof text, "error %d", errno);
        return tess_error_set(err, "%s: cannot open: %s", path, text);
    }
    char *line = NULL;
    size_t capacity = 0;
    obj_check c = {.path = path, .err = err};
    bool ok = true;
    errno = 0;
    ssize_t got;
    while (ok && (got = getline(&line, &capacity, file)) >= 0) {
        c.line_no++;
        char *p = line, *part;
        while (ok && (part = next_logical_line(&p, line + got)))
            ok = check_obj_line(&c, part);
        errno = 0;
    }
    unsigned long line_no = c.line_no;
    /* getline's -1 is the end, a read error, or (without the error flag)
     * no memory for a longer line: anything but the end stops the load */
    if (ok && !feof(file)) {
        int e = errno ? errno : EIO;
        char text[128];
        if (strerror_r(e, text, sizeof text) != 0)
            snprintf(text, sizeof text, "error %d", e);
        ok = e == ENOMEM ? tess_error_set(err, "%s:%lu: out of memory reading the line", path, line_no + 1)
                         : tess_error_set(err, "%s: read error: %s", path, text);
    }
    for (int k = 0; ok && k < OBJ_KINDS; k++)
        if (c.max_index[k] > c.count[k])
            ok = tess_error_set(err, "%s:%lu: %s index %lld out of range (the file has %lld %s)", path, c.max_line[k],
                                obj_kind_name[k], c.max_index[k], c.count[k], obj_kind_plural[k]);
    free(line);
    fclose(file);
    return ok;
}


/* ---- the scene ---------------------------------------------------------- */

static const struct aiScene *import_scene(const char *path, unsigned flags, tess_error *err)
{
    pthread_mutex_lock(&import_lock);
    const struct aiScene *scene = aiImportFile(path, flags);
    if (!scene)
        tess_error_set(err, "%s: assimp: %s", path, aiGetErrorString());
    pthread_mutex_unlock(&import_lock);
    return scene;
}

bool assimp_is_triangle_mesh(const struct aiMesh *am)
{
    return (am->mPrimitiveTypes & PRIMITIVE_MASK) == aiPrimitiveType_TRIANGLE && am->mNumFaces > 0 &&
           am->mNumVertices > 0;
}

/* Where a vector array first holds a non-finite component. */
typedef struct nonfinite {
    unsigned index; /* which vector */
    int axis;       /* 0, 1, 2 for x, y, z */
    float value;    /* NaN or an infinity */
} nonfinite;

static bool vectors_finite(const struct aiVector3D *v, unsigned n, nonfinite *bad)
{
    for (unsigned i = 0; i < n; i++) {
        const float c[3] = {v[i].x, v[i].y, v[i].z};
        for (int k = 0; k < 3; k++)
            if (!isfinite(c[k])) {
                *bad = (nonfinite){i, k, c[k]};
                return false;
            }
    }
    return true;
}

/* Every position and normal of every triangle mesh is finite (before
 * JoinIdenticalVertices can hide a NaN by merging it away). */
static bool check_scene_finite(const struct aiScene *scene, const char *path, tess_error *err)
{
    nonfinite bad;
    for (unsigned i = 0; i < scene->mNumMeshes; i++) {
        const struct aiMesh *am = scene->mMeshes[i];
        if (!assimp_is_triangle_mesh(am))
            continue;
        if (!vectors_finite(am->mVertices, am->mNumVertices, &bad))
            return tess_error_set(err, "%s: mesh %u ('%s') vertex %u: coordinate '%c' is %g (must be finite)", path,
                                  i, am->mName.data, bad.index, "xyz"[bad.axis], (double)bad.value);
        if (am->mNormals && !vectors_finite(am->mNormals, am->mNumVertices, &bad))
            return tess_error_set(err, "%s: mesh %u ('%s') vertex %u: normal component '%c' is not finite", path, i,
                                  am->mName.data, bad.index, "xyz"[bad.axis]);
    }
    return true;
}

static inline float clamp_unit(float v) { return v < 0.f ? 0.f : v > 1.f ? 1.f : v; } /* NaN passes through */

/* Append one triangle mesh's vertices (and attributes) at m->vertex_count. */
void assimp_append_vertices(mesh *m, const struct aiMesh *am)
{
    size_t base = 3 * (size_t)m->vertex_count;
    for (unsigned v = 0; v < am->mNumVertices; v++) {
        float *p = m->positions + base + 3 * (size_t)v;
        p[0] = am->mVertices[v].x;
        p[1] = am->mVertices[v].y;
        p[2] = am->mVertices[v].z;
        if (m->normals) {
            float *n = m->normals + base + 3 * (size_t)v;
            n[0] = am->mNormals[v].x;
            n[1] = am->mNormals[v].y;
            n[2] = am->mNormals[v].z;
        }
        if (m->colors) {
            float *c = m->colors + base + 3 * (size_t)v;
            c[0] = clamp_unit(am->mColors[0][v].r);
            c[1] = clamp_unit(am->mColors[0][v].g);
            c[2] = clamp_unit(am->mColors[0][v].b);
        }
    }
}

/* Append one triangle mesh's faces, offset by its first vertex. */
bool assimp_append_triangles(mesh *m, const struct aiMesh *am, uint32_t first_vertex, uint32_t material,
                             const char *path, tess_error *err)
{
    for (unsigned f = 0; f < am->mNumFaces; f++) {
        const struct aiFace *face = &am->mFaces[f];
        if (face->mNumIndices != 3) /* SortByPType promises triangles; trust, but check */
            return tess_error_set(err, "%s: mesh '%s' face %u has %u indices after triangulation", path,
                                  am->mName.data, f, face->mNumIndices);
        uint32_t *t = m->indices + 3 * (size_t)m->triangle_count;
        for (int k = 0; k < 3; k++)
            t[k] = first_vertex + face->mIndices[k];
        if (m->triangle_material)
            m->triangle_material[m->triangle_count] = material;
        m->triangle_count++;
    }
    return true;
}

/* ---- on a deep stack ------------------------------------------------------ */

/* assimp walks and frees the node tree recursively (the glTF importer,
 * ValidateDataStructure, aiNode's destructor), 400 to 800 bytes of stack a
 * level: a glTF file of 0.5 MB nesting 20,000 nodes overflows a main thread's
 * 8 MiB and crashes. Importing and releasing run on a thread of their own
 * with this much stack (address space: pages are only backed as they are
 * touched), over a million levels; when such a thread cannot be made they
 * run on the caller's. */
#define DEEP_STACK_BYTES ((size_t)1 << 30)

/* Run fn(arg) on a thread with DEEP_STACK_BYTES of stack and wait for it. */
static void run_deep(void *(*fn)(void *), void *arg)
{
    pthread_attr_t attr;
    pthread_t thread;
    bool made = false;
    if (pthread_attr_init(&attr) == 0) {
        made = pthread_attr_setstacksize(&attr, DEEP_STACK_BYTES) == 0 &&
               pthread_create(&thread, &attr, fn, arg) == 0;
        pthread_attr_destroy(&attr);
    }
    if (made)
        pthread_join(thread, NULL);
    else
        fn(arg);
}

/* One import: its arguments and result. */
typedef struct import_job {
    const char *path;
    unsigned flags;
    tess_error *err;
    const struct aiScene *scene; /* the result, NULL on failure */
} import_job;

static void *import_on_deep_stack(void *arg)
{
    import_job *job = arg;
    const char *path = job->path;
    tess_error *err = job->err;
    if (path_has_extension(path, ".obj") ? !check_obj_numbers(path, err) : !assimp_check_gltf(path, err))
        return NULL;
    const struct aiScene *scene = import_scene(path, BASE_FLAGS | job->flags, err);
    if (!scene)
        return NULL;
    if (!check_scene_finite(scene, path, err)) {
        aiReleaseImport(scene);
        return NULL;
    }
    /* on failure aiApplyPostProcessing releases the scene itself */
    scene = aiApplyPostProcessing(scene, JOIN_FLAGS);
    if (!scene)
        tess_error_set(err, "%s: assimp: joining identical vertices failed", path);
    job->scene = scene;
    return NULL;
}

/* Progress (engine/base/progress.h): assimp's C API has no progress callback (its
 * ProgressHandler is C++ only, set on an Assimp::Importer), so a long import
 * shows nothing until it ends, then its summary: bytes of the file named (not
 * of the .mtl or .bin files it pulls in) and the time. */
const struct aiScene *assimp_import_file(const char *path, unsigned flags, tess_error *err)
{
    struct stat st;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) {
        tess_error_set(err, "%s: is a directory, not a file", path);
        return NULL;
    }
    const char *slash = strrchr(path, '/');
    const char *name = slash ? slash + 1 : path;
    char what[PROGRESS_WHAT_BYTES];
    snprintf(what, sizeof what, "loading %s", name ? name : "");
    progress bytes;
    progress_begin(&bytes, what, stat(path, &st) == 0 ? (uint64_t)st.st_size : 0, "B");
    import_job job = {.path = path, .flags = flags, .err = err};
    run_deep(import_on_deep_stack, &job);
    if (job.scene)
        progress_set(&bytes, bytes.total);
    progress_end(&bytes);
    return job.scene;
}

static void *release_on_deep_stack(void *scene)
{
    aiReleaseImport(scene);
    return NULL;
}

void assimp_release(const struct aiScene *scene)
{
    if (scene)
        run_deep(release_on_deep_stack, (void *)scene);
}
