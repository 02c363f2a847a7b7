/* particle_load.c - particle files into a particle set (particles.h):
 * PLY point sets (through engine/load/ply_read.h) and LAMMPS text dumps.
 *
 * PLY. The vertex element's x y z are the positions; every other scalar
 * vertex property is an attribute of its name, its value as a float (a uchar
 * red is 0..255). List properties of the vertex element and every other
 * element (faces, edges, ...) are read past. Messages cite the line in an
 * ascii body and the element index in a binary one.
 *
 * LAMMPS. A "dump custom" (or "dump atom") text file: ITEM sections
 * TIMESTEP, NUMBER OF ATOMS, BOX BOUNDS (3 lines of 2 numbers; 3 for a
 * triclinic "xy xz yz" box, 4 for a general "abc origin" one), optional
 * UNITS and TIME, then "ITEM: ATOMS col col ..." and one line per atom.
 * Positions come from x y z, else xu yu zu (unwrapped), else xs ys zs or
 * xsu ysu zsu (scaled by the orthogonal box: x = lo + xs * (hi - lo)); every
 * other column is an attribute of its name. Only the first snapshot is read:
 * the loader stops after its atom lines, whatever follows. Messages cite the
 * line.
 *
 * MEMORY. Both readers stream the file through ply_reader's bounded buffer,
 * and reserve storage only for as many particles as the file's remaining
 * bytes can hold (two characters a value in text, the record size in
 * binary), so a header claiming 2e9 particles in a small file is refused
 * (LAMMPS) or stops where the data ends (PLY) without a large allocation.
 *
 * Nothing here is global: loads run in parallel. */
#include "particle_load.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "ply_read.h"

/* a LAMMPS line longer than this is refused: even 67 columns of 24-character
 * numbers take under 2 KiB, and the bound keeps a file without newlines from
 * growing the buffer */
#define LAMMPS_LINE_MAX_BYTES ((size_t)1 << 20)
/* longest token quoted back in a message */
#define QUOTE_CHARS 40
/* a dump line has at most the three positions and every attribute; a
 * second position set (x and xu both written) counts as attributes */
#define LAMMPS_COLUMNS_MAX (3 + PARTICLE_MAX_ATTRIBUTES)

static const char *errno_text(int code, char *buf, size_t size)
{
    if (strerror_r(code, buf, size) != 0)
        snprintf(buf, size, "error %d", code);
    return buf;
}

/* A FIFO or device would block fopen or fread: refuse one before opening it
 * (a missing file is left to fopen, whose errno the message then gives). */
static bool is_regular_or_absent(const char *path, tess_error *err)
{
    struct stat st;
    if (stat(path, &st) == 0 && !S_ISREG(st.st_mode))
        return tess_error_set(err, "%s: cannot open: not a regular file", path);
    return true;
}

/* Grow every array of p to hold more particles, up to `limit` (the file's own
 * count): storage was reserved for what the file's size allows, so only a
 * file that grew while read gets here. */
static bool grow_particles(particle_set *p, uint32_t limit)
{
    uint64_t wanted = (uint64_t)p->capacity + p->capacity / 2 + 1024;
    return particle_set_reserve(p, wanted < limit ? (uint32_t)wanted : limit);
}

/* ======================================================================== */
/* PLY                                                                      */
/* ======================================================================== */

/* Roles of vertex properties (ply_property.role): the positions, and
 * ROLE_ATTRIBUTE + a for the property stored as attribute a. */
enum { ROLE_X = 1, ROLE_Y, ROLE_Z, ROLE_ATTRIBUTE };

static const char *const axis_names[3] = {"x", "y", "z"};

/* ply_property_hook: positions and attributes of the vertex element; the
 * attribute count so far is in *ctx (a uint32_t). */
static bool ply_vertex_role(ply_file *f, const ply_element *e, ply_property *p, void *ctx)
{
    uint32_t *attributes = ctx;
    p->role = PLY_ROLE_SKIP;
    if (e->kind != PLY_ELEMENT_VERTEX)
        return true;
    int axis = -1;
    for (int k = 0; k < 3; k++)
        if (strcmp(p->name, axis_names[k]) == 0)
            axis = k;
    if (p->count_type != PLY_NONE) { /* a list: read past, unless it claims to be a position */
        if (axis >= 0)
            return ply_fail(f, "vertex property '%s' must be a scalar, not a list", p->name);
        return true;
    }
    for (size_t i = 0; i < e->prop_count; i++)
        if (e->props[i].count_type == PLY_NONE && strcmp(e->props[i].name, p->name) == 0)
            return ply_fail(f, "vertex element has two '%s' properties", p->name);
    if (axis >= 0) {
        p->role = ROLE_X + axis;
        return true;
    }
    if (strlen(p->name) >= PARTICLE_NAME_BYTES)
        return ply_fail(f, "vertex property '%s': name longer than %d characters (the attribute limit)", p->name,
                        PARTICLE_NAME_BYTES - 1);
    if (*attributes >= PARTICLE_MAX_ATTRIBUTES)
        return ply_fail(f, "vertex property '%s': more than %d attributes (besides x y z)", p->name,
                        PARTICLE_MAX_ATTRIBUTES);
    p->role = ROLE_ATTRIBUTE + (int)(*attributes)++;
    return true;
}

/* Where property values go: &p->x, &p->y, &p->z or &attribute.values (the
 * arrays move as they grow; these pointers to them do not, as p does not). */
static float **ply_column(particle_set *p, int role)
{
    if (role == ROLE_X)
        return &p->x;
    if (role == ROLE_Y)
        return &p->y;
    if (role == ROLE_Z)
        return &p->z;
    return &p->attributes[role - ROLE_ATTRIBUTE].values;
}

/* A kept property of a fixed-size binary vertex record. */
typedef struct ply_field {
    size_t offset;      /* bytes from the start of the record */
    enum ply_type type; /* its type */
    float **column;     /* where its values go (ply_column) */
} ply_field;

/* Binary vertices of scalars only: each record one block from the reader,
 * its kept values decoded straight into the arrays. */
static bool ply_read_fixed(ply_file *f, const ply_element *e, particle_set *p, size_t record)
{
    ply_field fields[3 + PARTICLE_MAX_ATTRIBUTES];
    size_t field_count = 0, offset = 0;
    for (size_t i = 0; i < e->prop_count; i++) {
        const ply_property *pr = &e->props[i];
        if (pr->role != PLY_ROLE_SKIP)
            fields[field_count++] = (ply_field){offset, pr->type, ply_column(p, pr->role)};
        offset += ply_type_bytes(pr->type);
    }
    bool big = f->format == PLY_BINARY_BE;
    uint32_t total = (uint32_t)e->count; /* checked against PARTICLE_MAX_COUNT */
    for (uint32_t v = 0; v < total; v++) {
        const unsigned char *bytes = ply_take(&f->in, record);
        if (!bytes)
            return ply_fail_input(f, e, v, false);
        if (v == p->capacity && !grow_particles(p, total))
            return ply_fail(f, "out of memory for %" PRIu32 " particles", total);
        for (size_t k = 0; k < field_count; k++)
            (*fields[k].column)[v] = ply_to_float(ply_decode_number(bytes + fields[k].offset, fields[k].type, big));
        p->count = v + 1;
    }
    return true;
}

/* Any vertex element: value by value (ascii, or binary with list properties). */
static bool ply_read_records(ply_file *f, const ply_element *e, particle_set *p)
{
    uint32_t total = (uint32_t)e->count; /* checked against PARTICLE_MAX_COUNT */
    for (uint32_t v = 0; v < total; v++) {
        if (!ply_record_begin(f, e, v))
            return false;
        if (v == p->capacity && !grow_particles(p, total))
            return ply_fail(f, "out of memory for %" PRIu32 " particles", total);
        for (size_t i = 0; i < e->prop_count; i++) {
            const ply_property *pr = &e->props[i];
            if (pr->role == PLY_ROLE_SKIP) {
                if (!ply_skip_property(f, e, v, pr))
                    return false;
                continue;
            }
            double value;
            if (!ply_read_number(f, e, v, pr->name, pr->type, &value))
                return false;
            (*ply_column(p, pr->role))[v] = ply_to_float(value);
        }
        if (!ply_record_end(f, e, v))
            return false;
        p->count = v + 1;
    }
    return true;
}

/* The set for the vertex element: attributes in property order, storage for
 * as many particles as the file can hold. */
static particle_set *ply_prepare(ply_file *f, ply_element *vertex)
{
    for (int k = 0; k < 3; k++) {
        bool found = false;
        for (size_t i = 0; i < vertex->prop_count; i++)
            found = found || vertex->props[i].role == ROLE_X + k;
        if (!found) {
            ply_fail(f, "vertex element has no '%s' property", axis_names[k]);
            return NULL;
        }
    }
    if (vertex->count > PARTICLE_MAX_COUNT) {
        ply_fail(f, "%" PRIu64 " vertices: more than a particle set can hold (%" PRIu32 ")", vertex->count,
                 (uint32_t)PARTICLE_MAX_COUNT);
        return NULL;
    }
    uint64_t fit = ply_records_that_fit(f, vertex);
    uint32_t reserve = (uint32_t)(fit < vertex->count ? fit : vertex->count);
    particle_set *p = particle_set_create();
    bool ok = p && particle_set_reserve(p, reserve);
    for (size_t i = 0; ok && i < vertex->prop_count; i++)
        if (vertex->props[i].role >= ROLE_ATTRIBUTE)
            ok = particle_set_add_attribute(p, vertex->props[i].name) == vertex->props[i].role - ROLE_ATTRIBUTE;
    if (!ok) {
        ply_fail(f, "out of memory for %" PRIu32 " particles", reserve);
        particle_set_destroy(p);
        return NULL;
    }
    return p;
}

static particle_set *ply_load(ply_file *f, const char *path, tess_error *err)
{
    uint32_t attributes = 0;
    if (!ply_open(f, path, err, ply_vertex_role, &attributes))
        return NULL;
    ply_element *vertex = ply_find_element(f, PLY_ELEMENT_VERTEX);
    if (!vertex) {
        ply_fail(f, "no 'vertex' element");
        return NULL;
    }
    particle_set *p = ply_prepare(f, vertex);
    if (!p)
        return NULL;
    f->cite_line = f->format == PLY_ASCII;
    bool ok = true;
    for (size_t i = 0; ok && i < f->element_count; i++) {
        const ply_element *e = &f->elements[i];
        if (e != vertex || e->prop_count == 0) {
            ok = ply_skip_element(f, e);
            continue;
        }
        uint64_t record = f->format != PLY_ASCII ? ply_fixed_record_bytes(e) : 0;
        ok = record > 0 ? ply_read_fixed(f, e, p, (size_t)record) : ply_read_records(f, e, p);
    }
    f->cite_line = false;
    if (!ok || !particle_set_finish(p, path, err)) {
        particle_set_destroy(p);
        return NULL;
    }
    return p;
}

particle_set *particles_load_ply(const char *path, tess_error *err)
{
    ply_file f;
    particle_set *p = ply_load(&f, path, err);
    ply_close(&f);
    return p;
}

/* ======================================================================== */
/* LAMMPS                                                                   */
/* ======================================================================== */

/* How positions are written: the column names of each kind, in the order
 * they are looked for. */
enum position_kind { POSITION_PLAIN, POSITION_UNWRAPPED, POSITION_SCALED, POSITION_SCALED_UNWRAPPED };
static const char *const position_columns[4][3] = {
    {"x", "y", "z"}, {"xu", "yu", "zu"}, {"xs", "ys", "zs"}, {"xsu", "ysu", "zsu"}};

typedef struct lammps_loader {
    const char *path;           /* names the file in every message (not owned) */
    tess_error *err;            /* where the first failure goes; may be NULL */
    ply_reader in;              /* the file's lines */
    uint64_t file_bytes;        /* the file's size when opened */
    uint64_t line;              /* lines read so far: the number of the current line */
    int64_t timestep;           /* ITEM: TIMESTEP, -1 before it */
    bool have_count;            /* ITEM: NUMBER OF ATOMS was read */
    uint64_t atom_count;        /* its value */
    uint64_t count_line;        /* the line it was read from (messages about the count cite it) */
    bool have_box;              /* ITEM: BOX BOUNDS was read */
    bool triclinic;             /* the box is tilted ("xy xz yz" or "abc origin") */
    double box_lo[3], box_hi[3]; /* the first two numbers of each box line */
    particle_set *p;            /* the result, owned by the loader until returned */
} lammps_loader;

static bool lammps_fail(lammps_loader *ld, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static bool lammps_fail_at(lammps_loader *ld, uint64_t line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static bool fail_v(lammps_loader *ld, uint64_t line, const char *fmt, va_list ap)
{
    char what[TESS_ERROR_MSG_BYTES];
    vsnprintf(what, sizeof what, fmt, ap);
    return tess_error_set(ld->err, "%s:%" PRIu64 ": %s", ld->path, line, what);
}

/* Set "PATH:LINE: what" for the current line; returns false. */
static bool lammps_fail(lammps_loader *ld, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    bool r = fail_v(ld, ld->line, fmt, ap);
    va_end(ap);
    return r;
}

/* The same for an earlier line (the count's, when the atoms cannot be what it says). */
static bool lammps_fail_at(lammps_loader *ld, uint64_t line, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    bool r = fail_v(ld, line, fmt, ap);
    va_end(ap);
    return r;
}

static inline bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

static inline char *skip_blanks(char *s)
{
    while (is_blank(*s))
        s++;
    return s;
}

static inline char *token_end(char *s)
{
    while (*s != '\0' && !is_blank(*s))
        s++;
    return s;
}

/* The reader stopped on a failure (reported by lammps_line), not at the end. */
static bool reader_failed(const ply_reader *r) { return r->read_errno || r->out_of_memory || r->line_too_long; }

/* The next line, counted. False at the end of the file or on a failure,
 * which is then already reported (end of file is the caller's to word). */
static bool lammps_line(lammps_loader *ld, char **line)
{
    ld->line++;
    if (ply_reader_line(&ld->in, LAMMPS_LINE_MAX_BYTES, line))
        return true;
    if (ld->in.read_errno) {
        char text[128];
        return lammps_fail(ld, "read error: %s", errno_text(ld->in.read_errno, text, sizeof text));
    }
    if (ld->in.out_of_memory)
        return lammps_fail(ld, "out of memory");
    if (ld->in.line_too_long)
        return lammps_fail(ld, "line longer than %zu bytes", (size_t)LAMMPS_LINE_MAX_BYTES);
    return false;
}

/* The line after an ITEM line, which must exist. */
static bool lammps_item_line(lammps_loader *ld, const char *item, char **line)
{
    return lammps_line(ld, line) || lammps_fail(ld, "file ends after 'ITEM: %s'", item);
}

/* A line that is one token: it, NUL-terminated in place; NULL when the line
 * is blank or has more. */
static char *single_token(char *line)
{
    char *start = skip_blanks(line), *end = token_end(start);
    if (end == start || *skip_blanks(end) != '\0')
        return NULL;
    *end = '\0';
    return start;
}

static bool lammps_timestep(lammps_loader *ld)
{
    char *line, *end;
    if (!lammps_item_line(ld, "TIMESTEP", &line))
        return false;
    char *token = single_token(line);
    errno = 0;
    long long v = token ? strtoll(token, &end, 10) : 0;
    if (!token || *end != '\0' || errno == ERANGE || v < 0)
        return lammps_fail(ld, "ITEM: TIMESTEP: expected a time step (an integer >= 0), got '%.*s'", QUOTE_CHARS,
                           skip_blanks(line));
    ld->timestep = v;
    return true;
}

static bool lammps_atom_count(lammps_loader *ld)
{
    char *line;
    if (!lammps_item_line(ld, "NUMBER OF ATOMS", &line))
        return false;
    char *token = single_token(line);
    uint64_t v = 0;
    bool ok = token != NULL;
    for (const char *s = token; ok && *s; s++) {
        unsigned digit = (unsigned)(*s - '0');
        ok = digit <= 9 && v <= (UINT64_MAX - digit) / 10;
        v = 10 * v + digit;
    }
    if (!ok)
        return lammps_fail(ld, "ITEM: NUMBER OF ATOMS: expected a count, got '%.*s'", QUOTE_CHARS,
                           skip_blanks(line));
    if (v > PARTICLE_MAX_COUNT)
        return lammps_fail(ld, "NUMBER OF ATOMS %" PRIu64 ": more than a particle set can hold (%" PRIu32 ")", v,
                           (uint32_t)PARTICLE_MAX_COUNT);
    ld->atom_count = v;
    ld->count_line = ld->line;
    ld->have_count = true;
    return true;
}

/* `words`: what follows "BOX BOUNDS" (the boundary flags, after "xy xz yz"
 * for a triclinic box or "abc origin" for a general one). */
static bool lammps_box(lammps_loader *ld, const char *words)
{
    ld->triclinic = strstr(words, "xy") != NULL || strstr(words, "abc") != NULL;
    int expected = strstr(words, "abc") ? 4 : ld->triclinic ? 3 : 2;
    for (int axis = 0; axis < 3; axis++) {
        char *line;
        if (!lammps_item_line(ld, "BOX BOUNDS", &line))
            return false;
        double v[4];
        int n = 0;
        for (char *s = skip_blanks(line); *s != '\0'; s = skip_blanks(s)) {
            char *end = token_end(s), *parsed;
            if (n == expected)
                return lammps_fail(ld, "box bounds: expected %d numbers, got more", expected);
            v[n] = strtod(s, &parsed);
            if (parsed != end || !isfinite(v[n]))
                return lammps_fail(ld, "box bounds: expected a number, got '%.*s'",
                                   (int)(end - s < QUOTE_CHARS ? end - s : QUOTE_CHARS), s);
            n++;
            s = end;
        }
        if (n != expected)
            return lammps_fail(ld, "box bounds: expected %d numbers, got %d", expected, n);
        ld->box_lo[axis] = v[0];
        ld->box_hi[axis] = v[1];
    }
    ld->have_box = true;
    return true;
}

/* The columns of an "ITEM: ATOMS" line, and where each one's values go. */
typedef struct lammps_columns {
    char *names[LAMMPS_COLUMNS_MAX]; /* in the line, in order (pointing into the line) */
    size_t count;                    /* columns */
    enum position_kind kind;         /* which names are the positions */
    int axis[LAMMPS_COLUMNS_MAX];    /* 0..2 for a position column, -1 for an attribute */
} lammps_columns;

static int find_column(const lammps_columns *c, const char *name)
{
    for (size_t i = 0; i < c->count; i++)
        if (strcmp(c->names[i], name) == 0)
            return (int)i;
    return -1;
}

/* Split the ATOMS line's column names (in place) and choose the positions. */
static bool lammps_columns_parse(lammps_loader *ld, char *words, lammps_columns *c)
{
    c->count = 0;
    for (char *s = skip_blanks(words); *s != '\0'; s = skip_blanks(s)) {
        char *end = token_end(s);
        bool last = *end == '\0';
        *end = '\0';
        if (find_column(c, s) >= 0)
            return lammps_fail(ld, "ITEM: ATOMS: duplicate column '%.*s'", QUOTE_CHARS, s);
        if (c->count == LAMMPS_COLUMNS_MAX)
            return lammps_fail(ld, "ITEM: ATOMS: more than %d columns (x y z and %d attributes)", LAMMPS_COLUMNS_MAX,
                               PARTICLE_MAX_ATTRIBUTES);
        c->names[c->count++] = s;
        s = last ? end : end + 1;
    }
    if (c->count == 0)
        return lammps_fail(ld, "ITEM: ATOMS names no columns");
    /* the first complete set of x y z, xu yu zu, xs ys zs, xsu ysu zsu; the
     * columns of any other set present are attributes */
    int kind = 0, partial = -1;
    for (; kind < 4; kind++) {
        int found = 0;
        for (int k = 0; k < 3; k++)
            found += find_column(c, position_columns[kind][k]) >= 0;
        if (found == 3)
            break;
        if (found > 0 && partial < 0)
            partial = kind;
    }
    if (kind == 4 && partial < 0)
        return lammps_fail(ld, "ITEM: ATOMS has no position columns (x y z, xu yu zu, or xs ys zs)");
    if (kind == 4) {
        const char *const *axes = position_columns[partial];
        int k = 0;
        while (find_column(c, axes[k]) >= 0)
            k++;
        return lammps_fail(ld, "ITEM: ATOMS has no '%s' column (positions need all of '%s %s %s')", axes[k], axes[0],
                           axes[1], axes[2]);
    }
    c->kind = (enum position_kind)kind;
    const char *const *axes = position_columns[kind];
    for (size_t i = 0; i < c->count; i++) {
        c->axis[i] = -1;
        for (int k = 0; k < 3; k++)
            if (strcmp(c->names[i], axes[k]) == 0)
                c->axis[i] = k;
        if (c->axis[i] < 0 && strlen(c->names[i]) >= PARTICLE_NAME_BYTES)
            return lammps_fail(ld, "ITEM: ATOMS: column name '%.*s' longer than %d characters", QUOTE_CHARS,
                               c->names[i], PARTICLE_NAME_BYTES - 1);
    }
    if (kind >= POSITION_SCALED) {
        if (!ld->have_box)
            return lammps_fail(ld, "scaled coordinates (%s %s %s) need 'ITEM: BOX BOUNDS' before 'ITEM: ATOMS'",
                               axes[0], axes[1], axes[2]);
        if (ld->triclinic)
            return lammps_fail(ld,
                               "scaled coordinates (%s %s %s) in a triclinic box are not supported "
                               "(dump x y z or xu yu zu instead)",
                               axes[0], axes[1], axes[2]);
    }
    return true;
}

/* The set, with the attributes in column order and room for every atom,
 * after checking that the rest of the file can hold them: each atom line
 * has at least two characters per column (a digit and a separator). */
static bool lammps_prepare(lammps_loader *ld, const lammps_columns *c)
{
    uint64_t read = ld->in.base + ld->in.pos;
    uint64_t rest = ld->file_bytes > read ? ld->file_bytes - read : 0;
    uint64_t fit = (rest + 1) / (2 * (uint64_t)c->count); /* the last line may lack its newline */
    if (ld->atom_count > fit)
        return lammps_fail_at(ld, ld->count_line,
                              "NUMBER OF ATOMS %" PRIu64 ": the rest of the file after line %" PRIu64 " (%" PRIu64
                              " bytes) cannot hold that many lines of %zu columns",
                              ld->atom_count, ld->line, rest, c->count);
    ld->p = particle_set_create();
    if (!ld->p || !particle_set_reserve(ld->p, (uint32_t)ld->atom_count))
        return lammps_fail(ld, "out of memory for %" PRIu64 " atoms", ld->atom_count);
    for (size_t i = 0; i < c->count; i++)
        if (c->axis[i] < 0 && particle_set_add_attribute(ld->p, c->names[i]) < 0)
            return lammps_fail(ld, "out of memory for %" PRIu64 " atoms", ld->atom_count);
    return true;
}

/* Read the atom lines straight into the arrays. */
static bool lammps_atoms(lammps_loader *ld, const lammps_columns *c)
{
    particle_set *p = ld->p;
    float *const axis_arrays[3] = {p->x, p->y, p->z};
    float *columns[LAMMPS_COLUMNS_MAX]; /* where column i's values go; reserved above, never moved */
    uint32_t attribute = 0;
    for (size_t i = 0; i < c->count; i++)
        columns[i] = c->axis[i] >= 0 ? axis_arrays[c->axis[i]] : p->attributes[attribute++].values;
    bool scaled = c->kind >= POSITION_SCALED;
    double scale[3], offset[3];
    for (int k = 0; k < 3; k++) {
        offset[k] = ld->box_lo[k];
        scale[k] = ld->box_hi[k] - ld->box_lo[k];
    }
    uint32_t total = (uint32_t)ld->atom_count;
    for (uint32_t a = 0; a < total; a++) {
        char *line;
        if (!lammps_line(ld, &line)) {
            if (reader_failed(&ld->in))
                return false;
            return lammps_fail(ld, "file ends after %" PRIu32 " of %" PRIu32 " atoms", a, total);
        }
        char *s = skip_blanks(line);
        if (strncmp(s, "ITEM:", 5) == 0)
            return lammps_fail(ld, "'%.*s' after %" PRIu32 " of %" PRIu32 " atoms", QUOTE_CHARS, s, a, total);
        size_t col = 0;
        for (; *s != '\0'; s = skip_blanks(s), col++) {
            if (col == c->count) {
                size_t got = col;
                for (; *s != '\0'; s = skip_blanks(token_end(s)))
                    got++;
                return lammps_fail(ld, "atom %" PRIu32 ": expected %zu values (the columns of ITEM: ATOMS), got %zu",
                                   a, c->count, got);
            }
            char *end;
            int axis = c->axis[col];
            float v;
            if (scaled && axis >= 0) {
                double unit = strtod(s, &end);
                v = ply_to_float(offset[axis] + unit * scale[axis]);
            } else {
                v = strtof(s, &end);
            }
            if (end == s || (*end != '\0' && !is_blank(*end))) {
                char *stop = token_end(s);
                return lammps_fail(ld, "atom %" PRIu32 ": column '%s': expected a number, got '%.*s'", a,
                                   c->names[col], (int)(stop - s < QUOTE_CHARS ? stop - s : QUOTE_CHARS), s);
            }
            columns[col][a] = v;
            s = end;
        }
        if (col != c->count)
            return lammps_fail(ld, "atom %" PRIu32 ": expected %zu values (the columns of ITEM: ATOMS), got %zu", a,
                               c->count, col);
        p->count = a + 1;
    }
    return true;
}

/* "ITEM: NAME rest": NAME's words matched against `item` (words may be
 * separated by any blanks); the rest after it, or NULL when it is not that item. */
static char *item_is(char *text, const char *item)
{
    const char *w = item;
    char *s = text;
    while (*w != '\0') {
        if (*w == ' ') {
            if (!is_blank(*s))
                return NULL;
            s = skip_blanks(s);
            w++;
            continue;
        }
        if (*s++ != *w++)
            return NULL;
    }
    return *s == '\0' || is_blank(*s) ? s : NULL;
}

/* The sections up to and including ITEM: ATOMS and its atoms. */
static bool lammps_read(lammps_loader *ld)
{
    char *line;
    for (;;) {
        if (!lammps_line(ld, &line)) {
            if (reader_failed(&ld->in))
                return false;
            return lammps_fail(ld, ld->line == 1 ? "empty file (expected 'ITEM: TIMESTEP')"
                                                 : "file ends before 'ITEM: ATOMS'");
        }
        char *s = skip_blanks(line);
        if (*s == '\0')
            continue;
        if (strncmp(s, "ITEM:", 5) != 0)
            return lammps_fail(ld, "expected an 'ITEM:' line, got '%.*s'", QUOTE_CHARS, s);
        char *item = skip_blanks(s + 5), *rest;
        bool ok;
        if (item_is(item, "TIMESTEP"))
            ok = lammps_timestep(ld);
        else if (item_is(item, "NUMBER OF ATOMS"))
            ok = lammps_atom_count(ld);
        else if ((rest = item_is(item, "BOX BOUNDS")) != NULL)
            ok = lammps_box(ld, rest);
        else if (item_is(item, "UNITS") || item_is(item, "TIME"))
            ok = lammps_item_line(ld, item, &line); /* one line, not used */
        else if ((rest = item_is(item, "ATOMS")) != NULL) {
            if (!ld->have_count)
                return lammps_fail(ld, "'ITEM: ATOMS' before 'ITEM: NUMBER OF ATOMS'");
            lammps_columns c = {.count = 0};
            return lammps_columns_parse(ld, rest, &c) && lammps_prepare(ld, &c) && lammps_atoms(ld, &c);
        } else
            ok = lammps_fail(ld, "unknown section 'ITEM: %.*s' (expected TIMESTEP, NUMBER OF ATOMS, BOX BOUNDS or ATOMS)",
                             QUOTE_CHARS, item);
        if (!ok)
            return false;
    }
}

particle_set *particles_load_lammps(const char *path, tess_error *err)
{
    lammps_loader ld = {.path = path, .err = err, .timestep = -1};
    if (!is_regular_or_absent(path, err))
        return NULL;
    FILE *file = fopen(path, "rb");
    if (!file) {
        char text[128];
        tess_error_set(err, "%s: cannot open: %s", path, errno_text(errno, text, sizeof text));
        return NULL;
    }
    particle_set *result = NULL;
    struct stat st;
    if (fstat(fileno(file), &st) != 0 || !S_ISREG(st.st_mode)) {
        tess_error_set(err, "%s: cannot open: not a regular file", path);
    } else if (!ply_reader_init(&ld.in, file, (uint64_t)st.st_size)) {
        tess_error_set(err, "%s: out of memory", path);
    } else {
        ld.file_bytes = (uint64_t)st.st_size;
        if (lammps_read(&ld) && particle_set_finish(ld.p, path, err)) {
            ld.p->timestep = ld.timestep;
            result = ld.p;
            ld.p = NULL;
        }
    }
    particle_set_destroy(ld.p);
    ply_reader_finish(&ld.in);
    fclose(file);
    return result;
}

/* ======================================================================== */
/* by name or content                                                        */
/* ======================================================================== */

/* The path's extension (after the last '.' of its last component), or "". */
static const char *extension(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(slash ? slash + 1 : path, '.');
    return dot ? dot + 1 : "";
}

enum particle_format { FORMAT_UNKNOWN, FORMAT_PLY, FORMAT_LAMMPS };

/* By the first line: "ply", or an "ITEM:" line (LAMMPS starts with ITEM:
 * TIMESTEP, or ITEM: UNITS / ITEM: TIME before it). False when the file
 * cannot be opened (the error is set). */
static bool sniff(const char *path, enum particle_format *format, tess_error *err)
{
    if (!is_regular_or_absent(path, err))
        return false;
    FILE *file = fopen(path, "rb");
    if (!file) {
        char text[128];
        return tess_error_set(err, "%s: cannot open: %s", path, errno_text(errno, text, sizeof text));
    }
    char head[16] = {0};
    size_t n = fread(head, 1, sizeof head - 1, file);
    fclose(file);
    head[n] = '\0';
    if (strncmp(head, "ply\n", 4) == 0 || strncmp(head, "ply\r\n", 5) == 0)
        *format = FORMAT_PLY;
    else if (strncmp(head, "ITEM:", 5) == 0)
        *format = FORMAT_LAMMPS;
    else
        *format = FORMAT_UNKNOWN;
    return true;
}

particle_set *particles_load(const char *path, tess_error *err)
{
    const char *ext = extension(path);
    enum particle_format format = FORMAT_UNKNOWN;
    if (strcasecmp(ext, "ply") == 0)
        format = FORMAT_PLY;
    else if (strcasecmp(ext, "dump") == 0 || strcasecmp(ext, "lammpstrj") == 0)
        format = FORMAT_LAMMPS;
    else if (!sniff(path, &format, err))
        return NULL;
    if (format == FORMAT_PLY)
        return particles_load_ply(path, err);
    if (format == FORMAT_LAMMPS)
        return particles_load_lammps(path, err);
    tess_error_set(err,
                   "%s: not a particle file tessera reads (supported: PLY point sets '.ply'; LAMMPS text dumps "
                   "'.dump', '.lammpstrj' or any file starting 'ITEM: TIMESTEP')",
                   path);
    return NULL;
}
