/* Scripted walks (walk.h): the script parser and the walker that steers the player along it. */
#include "walk.h"

#include "core/core.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

/* ---- errors ------------------------------------------------------------------------------------ */

/* "NAME:LINE: reason" (line 0: "NAME: reason") into the caller's error; returns false. */
static bool fail_at(core_error *error, core_error_code code, const char *name, int line, const char *fmt, ...)
    CORE_PRINTF(5, 6);
static bool fail_at(core_error *error, core_error_code code, const char *name, int line, const char *fmt, ...) {
    if (!error) return false;
    char reason[sizeof error->message];
    va_list args;
    va_start(args, fmt);
    vsnprintf(reason, sizeof reason, fmt, args);
    va_end(args);
    if (line > 0) return core_error_set(error, code, "%s:%d: %s", name, line, reason);
    return core_error_set(error, code, "%s: %s", name, reason);
}

/* ---- numbers ----------------------------------------------------------------------------------- */

/* A token, not NUL-terminated; messages quote at most its first 40 bytes. */
typedef struct token {
    const char *text;
    int size;
} token;

#define QUOTED(t) ((t).size > 40 ? 40 : (t).size), (t).text

/* Plain decimal numbers only ("12", "-3.5", "1e5"): strtod alone would also take hex, "inf",
 * "nan" and leading spaces, none of which a waypoint file should mean. */
static bool decimal(token t, double *value) {
    char copy[GAME_WALK_MAX_LINE + 1];
    bool digit = false;
    if (t.size <= 0 || t.size > GAME_WALK_MAX_LINE) return false;
    for (int i = 0; i < t.size; i++) {
        char c = t.text[i];
        if (c >= '0' && c <= '9') digit = true;
        else if (c != '+' && c != '-' && c != '.' && c != 'e' && c != 'E') return false;
    }
    if (!digit) return false;
    memcpy(copy, t.text, (size_t)t.size);
    copy[t.size] = '\0';
    char *end;
    *value = strtod(copy, &end);
    return end == copy + t.size;
}

/* ---- the waypoint file ------------------------------------------------------------------------- */

typedef struct parser {
    const char *name;
    int line;
    core_error *error;
    game_walk walk;
    size_t capacity;
    bool framed, radius_given;        /* relative/ahead and radius seen */
} parser;

/* FAIL for malformed lines, FAIL_RANGE for a value or a count past its limits. */
#define FAIL(p, ...) fail_at((p)->error, CORE_ERROR_FORMAT, (p)->name, (p)->line, __VA_ARGS__)
#define FAIL_RANGE(p, ...) fail_at((p)->error, CORE_ERROR_RANGE, (p)->name, (p)->line, __VA_ARGS__)

static bool next_token(const char **at, const char *end, token *t) {
    const char *s = *at;
    while (s < end && (*s == ' ' || *s == '\t')) s++;
    const char *start = s;
    while (s < end && *s != ' ' && *s != '\t') s++;
    *at = s;
    t->text = start;
    t->size = (int)(s - start);
    return t->size > 0;
}

static bool is(token t, const char *word) {
    return (size_t)t.size == strlen(word) && memcmp(t.text, word, (size_t)t.size) == 0;
}

static bool coordinate(parser *p, token t, const char *what, double *value) {
    if (!decimal(t, value)) return FAIL(p, "%s: '%.*s' is not a number", what, QUOTED(t));
    if (!(fabs(*value) <= GAME_WALK_MAX_COORD))
        return FAIL_RANGE(p, "%s: '%.*s' is out of range (-1e9 ... 1e9 m)", what, QUOTED(t));
    return true;
}

/* `relative`, `ahead`, `radius R`, `fly-over`. */
static bool directive(parser *p, token word, const char *rest, const char *end) {
    token extra;
    bool frame = is(word, "relative") || is(word, "ahead");
    if (!frame && !is(word, "radius") && !is(word, "fly-over"))
        return FAIL(p, "unknown directive '%.*s' (a line is X Z [words], relative, ahead, radius R or fly-over)",
                    QUOTED(word));
    if (p->walk.count > 0) return FAIL(p, "'%.*s' must come before the first waypoint", QUOTED(word));
    if (is(word, "fly-over")) {
        if (p->walk.fly_over) return FAIL(p, "fly-over given twice");
        if (next_token(&rest, end, &extra)) return FAIL(p, "'fly-over' takes nothing after it");
        p->walk.fly_over = true;
        return true;
    }
    if (frame) {
        if (p->framed) return FAIL(p, "only one of relative and ahead, once");
        if (next_token(&rest, end, &extra)) return FAIL(p, "'%.*s' takes nothing after it", QUOTED(word));
        p->framed = true;
        p->walk.frame = is(word, "relative") ? GAME_WALK_RELATIVE : GAME_WALK_AHEAD;
        return true;
    }
    if (p->radius_given) return FAIL(p, "radius given twice");
    token value;
    double radius;
    if (!next_token(&rest, end, &value) || next_token(&rest, end, &extra))
        return FAIL(p, "radius needs one number (metres)");
    if (!decimal(value, &radius)) return FAIL(p, "radius: '%.*s' is not a number", QUOTED(value));
    if (!(radius >= GAME_WALK_MIN_RADIUS && radius <= GAME_WALK_MAX_RADIUS))
        return FAIL_RANGE(p, "radius: '%.*s' is out of range (0.1 ... 1000 m)", QUOTED(value));
    p->radius_given = true;
    p->walk.radius = (float)radius;
    return true;
}

/* `look=YAW,PITCH`'s value: degrees as --look (yaw any, wrapped to [0, 360); pitch within ±89). */
static bool look_word(parser *p, token value, game_walk_point *point) {
    const char *comma = memchr(value.text, ',', (size_t)value.size);
    if (!comma) return FAIL(p, "look=: '%.*s' is not YAW,PITCH (degrees)", QUOTED(value));
    token yaw_text = { value.text, (int)(comma - value.text) };
    token pitch_text = { comma + 1, value.size - (int)(comma - value.text) - 1 };
    double yaw, pitch;
    if (!decimal(yaw_text, &yaw) || !(fabs(yaw) <= 1e6)) return FAIL(p, "look=: yaw '%.*s' is not a number", QUOTED(yaw_text));
    if (!decimal(pitch_text, &pitch)) return FAIL(p, "look=: pitch '%.*s' is not a number", QUOTED(pitch_text));
    if (!(fabs(pitch) <= 89.0)) return FAIL_RANGE(p, "look=: pitch '%.*s' is out of range (-89 ... 89)", QUOTED(pitch_text));
    yaw = fmod(yaw, 360.0);
    point->look_yaw = (float)(yaw < 0.0 ? yaw + 360.0 : yaw);
    point->look_pitch = (float)pitch;
    point->has_look = true;
    return true;
}

/* The words after X Z. */
static bool point_words(parser *p, const char *rest, const char *end, game_walk_point *point) {
    token t;
    bool sprint = false;
    while (next_token(&rest, end, &t)) {
        bool *flag = is(t, "walk") ? &point->walk : is(t, "sprint") ? &sprint : is(t, "jump") ? &point->jump
                   : is(t, "fly") ? &point->fly : is(t, "shot") ? &point->shot : NULL;
        if (flag) {
            if (*flag) return FAIL(p, "'%.*s' given twice", QUOTED(t));
            *flag = true;
        } else if (t.size >= 5 && memcmp(t.text, "look=", 5) == 0) {
            if (point->has_look) return FAIL(p, "'look=' given twice");
            if (!look_word(p, (token){ t.text + 5, t.size - 5 }, point)) return false;
        } else if (t.size >= 2 && t.text[0] == 'y' && t.text[1] == '=') {
            if (point->has_y) return FAIL(p, "'y=' given twice");
            if (!coordinate(p, (token){ t.text + 2, t.size - 2 }, "y", &point->y)) return false;
            point->has_y = true;
        } else {
            return FAIL(p, "unknown word '%.*s' (walk, sprint, jump, fly, y=H, shot, look=YAW,PITCH)", QUOTED(t));
        }
    }
    if (point->walk && sprint) return FAIL(p, "walk and sprint together");
    if (point->jump && point->fly) return FAIL(p, "jump and fly together (flying, there is nothing to jump from)");
    if (point->has_y && !point->fly) return FAIL(p, "y=H needs fly (walking, the ground sets the height)");
    if (point->has_look && !point->shot) return FAIL(p, "look= needs shot (it is the picture's direction)");
    return true;
}

/* `cave R [words]`, `shore R [words]`, `rocks R [words]` or `cliff R [words]` (`kind`): resolved later
 * (game_walk_resolve_stops), so only shot may follow. */
static bool found_line(parser *p, const char *kind, const char *rest, const char *end) {
    game_walk_point point = { 0 };
    token value, word;
    double radius;
    if (!next_token(&rest, end, &value)) return FAIL(p, "%s needs a radius (metres)", kind);
    if (!decimal(value, &radius)) return FAIL(p, "%s: '%.*s' is not a number", kind, QUOTED(value));
    if (!(radius >= 1.0 && radius <= 1000.0))
        return FAIL_RANGE(p, "%s: '%.*s' is out of range (1 ... 1000 m)", kind, QUOTED(value));
    while (next_token(&rest, end, &word)) {
        if (!is(word, "shot"))
            return FAIL(p, "%s: unknown word '%.*s' (only shot; the flight and the view are found)", kind, QUOTED(word));
        if (point.shot) return FAIL(p, "'shot' given twice");
        point.shot = true;
    }
    if (strcmp(kind, "cave") == 0) point.cave_radius = (float)radius;
    else if (strcmp(kind, "shore") == 0) point.shore_radius = (float)radius;
    else if (strcmp(kind, "rocks") == 0) point.rocks_radius = (float)radius;
    else point.cliff_radius = (float)radius;
    if (p->walk.count >= GAME_WALK_MAX_POINTS) return FAIL_RANGE(p, "more than %d waypoints", GAME_WALK_MAX_POINTS);
    p->walk.points = core_grow(p->walk.points, &p->capacity, (size_t)p->walk.count + 1, sizeof point);
    p->walk.points[p->walk.count++] = point;
    return true;
}

static bool waypoint(parser *p, token first, const char *rest, const char *end) {
    game_walk_point point = { 0 };
    token second;
    if (!coordinate(p, first, "x", &point.x)) return false;
    if (!next_token(&rest, end, &second)) return FAIL(p, "a waypoint needs X and Z; Z is missing");
    if (!coordinate(p, second, "z", &point.z)) return false;
    if (!point_words(p, rest, end, &point)) return false;
    if (p->walk.count >= GAME_WALK_MAX_POINTS) return FAIL_RANGE(p, "more than %d waypoints", GAME_WALK_MAX_POINTS);
    p->walk.points = core_grow(p->walk.points, &p->capacity, (size_t)p->walk.count + 1, sizeof point);
    p->walk.points[p->walk.count++] = point;
    return true;
}

static bool line(parser *p, const char *begin, const char *end) {
    if (end - begin > GAME_WALK_MAX_LINE) return FAIL_RANGE(p, "line longer than %d bytes", GAME_WALK_MAX_LINE);
    if (end > begin && end[-1] == '\r') end--;          /* CRLF */
    const char *hash = memchr(begin, '#', (size_t)(end - begin));
    if (hash) end = hash;
    for (const char *c = begin; c < end; c++)
        if ((*c < ' ' || *c > '~') && *c != '\t')
            return FAIL(p, "unexpected byte 0x%02x in column %d", (unsigned char)*c, (int)(c - begin) + 1);
    const char *at = begin;
    token first;
    if (!next_token(&at, end, &first)) return true;     /* blank or a comment */
    char c = first.text[0];
    if ((c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.') return waypoint(p, first, at, end);
    if (is(first, "cave")) return found_line(p, "cave", at, end);
    if (is(first, "shore")) return found_line(p, "shore", at, end);
    if (is(first, "rocks")) return found_line(p, "rocks", at, end);
    if (is(first, "cliff")) return found_line(p, "cliff", at, end);
    return directive(p, first, at, end);
}

static void walk_release(game_walk *walk, size_t capacity) {
    if (walk->points) core_free(walk->points, capacity * sizeof *walk->points);
    memset(walk, 0, sizeof *walk);
}

bool game_walk_parse_text(const char *text, size_t size, const char *name, game_walk *out, core_error *error) {
    parser p = { .name = name ? name : "walk", .error = error };
    memset(out, 0, sizeof *out);
    const char *at = text, *end = text + size;
    if (size >= 3 && memcmp(text, "\xef\xbb\xbf", 3) == 0) at += 3;
    bool ok = true;
    while (ok && at < end) {
        if (p.line == INT_MAX) return walk_release(&p.walk, p.capacity), FAIL_RANGE(&p, "too many lines");
        p.line++;
        const char *newline = memchr(at, '\n', (size_t)(end - at));
        const char *line_end = newline ? newline : end;
        ok = line(&p, at, line_end);
        at = newline ? newline + 1 : end;
    }
    if (ok && p.walk.count == 0) {
        p.line = 0;
        ok = FAIL(&p, "no waypoints (a waypoint line is X Z)");
    }
    if (!ok) {
        walk_release(&p.walk, p.capacity);
        return false;
    }
    /* shrink to fit, so that game_walk_free knows the size from the count */
    p.walk.points = core_realloc(p.walk.points, p.capacity * sizeof *p.walk.points,
                                 (size_t)p.walk.count * sizeof *p.walk.points);
    *out = p.walk;
    return true;
}

void game_walk_copy(const game_walk *from, game_walk *to) {
    *to = *from;
    size_t size = (size_t)from->count * sizeof *from->points;
    to->points = size ? core_alloc(size) : NULL;
    if (size) memcpy(to->points, from->points, size);
}

void game_walk_free(game_walk *walk) {
    if (walk) walk_release(walk, (size_t)walk->count);
}

/* ---- the spec ---------------------------------------------------------------------------------- */

static bool parse_straight(const char *spec, game_walk *out, core_error *error) {
    const char *number = spec + strlen("straight:");
    double metres;
    if (!*number) return core_error_set(error, CORE_ERROR_FORMAT, "straight: needs a distance in metres (straight:2000)");
    size_t length = strlen(number);
    if (length > GAME_WALK_MAX_LINE || !decimal((token){ number, (int)length }, &metres))
        return core_error_set(error, CORE_ERROR_FORMAT, "%.60s: '%.40s' is not a number of metres", spec, number);
    if (!(metres > 0.0 && metres <= GAME_WALK_MAX_STRAIGHT))
        return core_error_set(error, CORE_ERROR_RANGE, "%.60s: the distance must be more than 0 and at most 100000 m",
                                 spec);
    out->points = core_calloc(1, sizeof *out->points);
    out->points[0].z = metres;
    out->count = 1;
    out->frame = GAME_WALK_AHEAD;
    return true;
}

/* The whole file, at most GAME_WALK_MAX_FILE bytes; NULL after a message. */
static char *read_file(const char *path, size_t *size, core_error *error) {
    FILE *file = fopen(path, "rb");
    if (!file) {
        core_error_set(error, CORE_ERROR_IO, "%s: cannot open (%s); a walk is " GAME_WALK_USAGE, path, strerror(errno));
        return NULL;
    }
    size_t capacity = 4096, used = 0;
    char *text = core_alloc(capacity);
    for (;;) {
        if (used == capacity) {
            if (capacity > GAME_WALK_MAX_FILE) break;
            text = core_realloc(text, capacity, capacity * 2);
            capacity *= 2;
        }
        size_t got = fread(text + used, 1, capacity - used, file);
        used += got;
        if (got == 0) break;
    }
    bool failed = ferror(file) != 0;
    int read_errno = errno;
    fclose(file);
    if (failed || used > GAME_WALK_MAX_FILE) {
        if (failed) core_error_set(error, CORE_ERROR_IO, "%s: cannot read (%s)", path, strerror(read_errno));
        else core_error_set(error, CORE_ERROR_RANGE, "%s: larger than %d MiB", path, GAME_WALK_MAX_FILE >> 20);
        core_free(text, capacity);
        return NULL;
    }
    text = core_realloc(text, capacity, used ? used : 1);
    *size = used;
    return text;
}

bool game_walk_parse(const char *spec, game_walk *out, core_error *error) {
    memset(out, 0, sizeof *out);
    if (!spec || !*spec) return core_error_set(error, CORE_ERROR_ARGUMENT, "no walk given; a walk is " GAME_WALK_USAGE);
    if (strncmp(spec, "straight:", strlen("straight:")) == 0) return parse_straight(spec, out, error);
    size_t size;
    char *text = read_file(spec, &size, error);
    if (!text) return false;
    bool ok = game_walk_parse_text(text, size, spec, out, error);
    core_free(text, size ? size : 1);
    return ok;
}

/* ---- the tour ---------------------------------------------------------------------------------- */

const char game_walk_tour[] =
    "ahead\n"
    "radius 3\n"
    "fly-over\n"
    "0 0 shot\n"                 /* where the player stands */
    "0 50 shot\n"                /* 50 m on */
    "cave 150 shot\n"            /* into the nearest cave or under the nearest arch */
    "shore 150 shot\n"           /* out over the nearest water from its shore */
    "rocks 150 shot\n"           /* down at the nearest pile of rocks, from its lit side */
    "0 60 fly y=120 shot\n";     /* back over the walk and up 120 m */

/* ---- cave stops -------------------------------------------------------------------------------- */

static void target(const game_walker *w, int i, double out[3]);

/* World point `world_xz` (and feet height y) as coordinates of the walk's frame, from the start
 * `origin` facing `yaw`: the inverse of the walker's target(). */
static void to_walk_frame(const game_walk *walk, const double origin[3], float yaw, const double world[3],
                          game_walk_point *point) {
    double dx = world[0] - origin[0], dz = world[2] - origin[2];
    switch (walk->frame) {
    case GAME_WALK_ABSOLUTE: point->x = world[0], point->y = world[1], point->z = world[2]; return;
    case GAME_WALK_RELATIVE: point->x = dx, point->y = world[1] - origin[1], point->z = dz; return;
    case GAME_WALK_AHEAD: {
        /* target() maps (X, Z) to o + X·(c, s) + Z·(s, −c); that matrix is its own inverse */
        double s = sin((double)yaw), c = cos((double)yaw);
        point->x = dx * c + dz * s;
        point->z = dx * s - dz * c;
        point->y = world[1] - origin[1];
        return;
    }
    }
}

/* The flight a found view asks for: its eye as a `fly y=H` waypoint in the walk's frame (the feet
 * an eye height under it), facing the view for the picture. */
static void view_point(const game_walk *walk, const game_walker *frame, const game_player *player, const double eye[3],
                       float yaw, float pitch, game_walk_point *point) {
    double feet[3] = { eye[0], eye[1] - (double)player->params.eye_height, eye[2] };
    to_walk_frame(walk, frame->origin, frame->origin_yaw, feet, point);
    point->fly = point->has_y = point->has_look = true;
    point->look_yaw = yaw, point->look_pitch = pitch;
    point->cave_radius = point->shore_radius = point->rocks_radius = point->cliff_radius = 0.0f;
}

/* A `cave R`, `shore R`, `rocks R` or `cliff R` point resolved against the world from `centre`; false (with a notice)
 * when there is nothing to see within R. */
static bool resolve_found(game_walk *walk, const game_walker *frame, terrain_world *world, const game_player *player,
                          const double centre[3], int index, game_walk_point *point) {
    if (point->cave_radius > 0.0f) {
        game_cave_view view;
        if (!game_find_cave_view(world, centre[0], centre[2], point->cave_radius, &view)) {
            core_info("walk", "no cave or arch within %.0f m of waypoint %d: that stop is skipped",
                      (double)point->cave_radius, index);
            return false;
        }
        view_point(walk, frame, player, view.eye, view.yaw, view.pitch, point);
        return true;
    }
    if (point->rocks_radius > 0.0f) {
        game_rocks_view view;
        if (!game_find_rocks_view(world, centre[0], centre[2], point->rocks_radius, &view)) {
            core_info("walk", "no pile of rocks within %.0f m of waypoint %d: that stop is skipped",
                      (double)point->rocks_radius, index);
            return false;
        }
        view_point(walk, frame, player, view.eye, view.yaw, view.pitch, point);
        point->has_look_at = true;
        for (int a = 0; a < 3; a++) point->look_at[a] = view.pile[a];
        return true;
    }
    if (point->cliff_radius > 0.0f) {
        game_cliff_view view;
        if (!game_find_cliff_view(world, centre[0], centre[2], point->cliff_radius, &view)) {
            core_info("walk", "no cliff within %.0f m of waypoint %d: that stop is skipped",
                      (double)point->cliff_radius, index);
            return false;
        }
        view_point(walk, frame, player, view.eye, view.yaw, view.pitch, point);
        point->has_look_at = true;
        for (int a = 0; a < 3; a++) point->look_at[a] = view.face[a];
        return true;
    }
    game_shore_view view;
    if (!game_find_shore_view(world, centre[0], centre[2], point->shore_radius, &view)) {
        core_info("walk", "no shore within %.0f m of waypoint %d: that stop is skipped", (double)point->shore_radius,
                  index);
        return false;
    }
    view_point(walk, frame, player, view.eye, view.yaw, view.pitch, point);
    return true;
}

game_walk_found game_walk_resolve_stops(game_walk *walk, terrain_world *world, const game_player *player) {
    game_walker frame = { .walk = walk, .origin_yaw = player->yaw };   /* target()'s frame */
    memcpy(frame.origin, player->position, sizeof frame.origin);
    game_walk_found found = { 0 };
    int kept = 0;
    double centre[3] = { player->position[0], player->position[1], player->position[2] };
    for (int i = 0; i < walk->count; i++) {
        game_walk_point point = walk->points[i];
        bool cave = point.cave_radius > 0.0f, shore = point.shore_radius > 0.0f, rocks = point.rocks_radius > 0.0f;
        bool cliff = point.cliff_radius > 0.0f;
        if (cave || shore || rocks || cliff) {
            if (!resolve_found(walk, &frame, world, player, centre, i, &point)) continue;
            found.caves += cave, found.shores += shore, found.rocks += rocks, found.cliffs += cliff;
        }
        walk->points[kept++] = point;
        frame.walk = walk;
        target(&frame, kept - 1, centre);
    }
    if (kept < walk->count) {   /* game_walk_free takes the array's size from the count */
        size_t old_size = (size_t)walk->count * sizeof *walk->points, new_size = (size_t)kept * sizeof *walk->points;
        if (kept == 0) core_free(walk->points, old_size), walk->points = NULL;
        else walk->points = core_realloc(walk->points, old_size, new_size);
        walk->count = kept;
    }
    return found;
}

int game_walk_resolve_caves(game_walk *walk, terrain_world *world, const game_player *player) {
    return game_walk_resolve_stops(walk, world, player).caves;
}

/* ---- the walker -------------------------------------------------------------------------------- */

#define STALL_WINDOW 0.5          /* seconds looked back to tell a stall */
#define STALL_FRACTION 0.5        /* stalled: covered less than this share of the gait's distance */
#define HISTORY_SPACING 0.02      /* seconds between kept positions: 64 of them span over 1.28 s */
#define STEER_ALIGNED 0.5         /* radians: facing the waypoint this closely counts as heading to it */
#define DETOUR_SECONDS 1.0
#define DETOURS_PER_SIDE 4
#define LEG_SLACK 5.0             /* seconds added to every leg's time limit */
#define PITCH_RATE 1.0f           /* radians a second: a gentle nod, not a snap */
#define BIT(name) INPUT_ACTION_BIT(INPUT_ACTION_##name)

static float walk_radius(const game_walk *walk) {
    return walk->radius > 0.0f ? walk->radius : GAME_WALK_DEFAULT_RADIUS;
}
static float clamp_abs(float value, float limit) { return fminf(fmaxf(value, -limit), limit); }

/* Waypoint i in world metres: x, the height to fly at, z. */
static void target(const game_walker *w, int i, double out[3]) {
    const game_walk_point *p = &w->walk->points[i];
    const double *o = w->origin;
    switch (w->walk->frame) {
    case GAME_WALK_ABSOLUTE: out[0] = p->x, out[1] = p->y, out[2] = p->z; break;
    case GAME_WALK_RELATIVE: out[0] = o[0] + p->x, out[1] = o[1] + p->y, out[2] = o[2] + p->z; break;
    case GAME_WALK_AHEAD: {
        /* yaw 0 looks along −z and positive turns right (player.h): ahead is (sin, −cos) in x, z,
         * right is (cos, sin) */
        double s = sin((double)w->origin_yaw), c = cos((double)w->origin_yaw);
        out[0] = o[0] + p->x * c + p->z * s;
        out[1] = o[1] + p->y;
        out[2] = o[2] + p->x * s - p->z * c;
        break;
    }
    }
}

/* What the player's speed is on this leg on dry land (player.c: sprint is a held button, fly has
 * its own). */
static float dry_gait_speed(const game_player *pl, const game_walk_point *p) {
    const game_player_desc *pr = &pl->params;
    if (p->fly) return p->walk ? pr->fly_speed : pr->fly_sprint_speed;
    return p->walk ? pr->walk_speed : pr->sprint_speed;
}

/* ... and where the player is now (player.h: wading walks slower and never sprints; swimming has
 * its own speeds; flying ignores water). */
static float gait_speed(const game_player *pl, const game_walk_point *p) {
    const game_player_desc *pr = &pl->params;
    if (p->fly || pl->flying || !pl->in_water) return dry_gait_speed(pl, p);
    if (pl->swimming) return p->walk ? pr->swim_speed : pr->swim_sprint_speed;
    return pr->walk_speed * game_player_wade_share(pr, pl->water_depth);
}

static bool unresolved(const game_walk_point *p) {
    return p->cave_radius > 0.0f || p->shore_radius > 0.0f || p->rocks_radius > 0.0f || p->cliff_radius > 0.0f;
}

/* Horizontally within the radius; also vertically for `fly y=H`. An unresolved `cave`, `shore`, `rocks` or `cliff` line
 * (game_walk_resolve_stops never ran) is passed over at once. */
static bool reached(const game_walker *w, const game_player *pl, int i) {
    if (unresolved(&w->walk->points[i])) return true;
    double t[3];
    target(w, i, t);
    double dx = t[0] - pl->position[0], dz = t[2] - pl->position[2], d2 = dx * dx + dz * dz;
    if (w->walk->points[i].has_y) d2 += (t[1] - pl->position[1]) * (t[1] - pl->position[1]);
    double r = walk_radius(w->walk);
    return d2 <= r * r;
}

/* A new leg towards w->index: its time limit is twice its length at the gait's speed plus slack. */
static void start_leg(game_walker *w, const game_player *pl) {
    w->leg_start = w->time;
    w->leg_stalls = 0;
    w->leg_flying_over = false;
    w->detour_until = w->time;
    w->history_count = 0;
    w->fly_height = pl->position[1];
    if (w->index >= w->walk->count) return;
    const game_walk_point *p = &w->walk->points[w->index];
    double t[3];
    target(w, w->index, t);
    double length = hypot(t[0] - pl->position[0], t[2] - pl->position[2]);
    if (p->has_y) length = hypot(length, t[1] - pl->position[1]);
    w->leg_limit = 2.0 * length / dry_gait_speed(pl, p) + LEG_SLACK;
}

void game_walker_start(game_walker *walker, const game_walk *walk, const game_player *player) {
    memset(walker, 0, sizeof *walker);
    walker->walk = walk;
    memcpy(walker->origin, player->position, sizeof walker->origin);
    walker->origin_yaw = player->yaw;
    walker->last[0] = player->position[0], walker->last[1] = player->position[2];
    start_leg(walker, player);
}

bool game_walker_done(const game_walker *walker) { return walker->done; }

void game_walker_resume(game_walker *walker, const game_player *player) {
    if (!walker->shot_due) return;
    walker->shot_due = false;
    walker->last[0] = player->position[0], walker->last[1] = player->position[2];
    start_leg(walker, player);            /* the hold does not count against the next leg */
}

/* Time, distances and the frame count, from where the player got to. */
static void progress(game_walker *w, const game_player *pl) {
    if (!pl->waiting) w->time += (double)w->last_dt;   /* a waiting frame did not walk */
    double dx = pl->position[0] - w->last[0], dz = pl->position[2] - w->last[1];
    w->walked += sqrt(dx * dx + dz * dz);
    w->last[0] = pl->position[0], w->last[1] = pl->position[2];
    w->from_start = hypot(pl->position[0] - w->origin[0], pl->position[2] - w->origin[2]);
    w->frames++;
}

/* Water slows the gait (wading, swimming): the time the last step lost to it, against the leg's
 * dry gait, is added to the leg's limit, so a leg across a lake is given the time its water
 * costs. A step in water at speed u instead of the dry U covers u·dt, which on land takes u·dt/U:
 * dt·(1 − u/U) was lost. */
static void water_allowance(game_walker *w, const game_player *pl) {
    if (w->index >= w->walk->count || pl->waiting) return;
    const game_walk_point *p = &w->walk->points[w->index];
    float dry = dry_gait_speed(pl, p), wet = gait_speed(pl, p);
    if (wet < dry) w->leg_limit += (double)w->last_dt * (1.0 - (double)wet / (double)dry);
}

/* Keeps the position every HISTORY_SPACING seconds at most, so the ring spans a stall window at
 * any frame rate. */
static void remember(game_walker *w, const game_player *pl) {
    if (w->history_count > 0) {
        int newest = (w->history_next + GAME_WALKER_HISTORY - 1) % GAME_WALKER_HISTORY;
        if (w->time - w->history[newest].time < HISTORY_SPACING) return;
    }
    w->history[w->history_next].time = w->time;
    w->history[w->history_next].x = pl->position[0];
    w->history[w->history_next].y = pl->position[1];
    w->history[w->history_next].z = pl->position[2];
    w->history_next = (w->history_next + 1) % GAME_WALKER_HISTORY;
    if (w->history_count < GAME_WALKER_HISTORY) w->history_count++;
}

/* Over the last STALL_WINDOW seconds (the newest kept position at least that old) the player
 * covered less than STALL_FRACTION of what `speed` would have. Flying, height counts too. */
static bool stalled(const game_walker *w, const game_player *pl, float speed, bool flying) {
    for (int k = 1; k <= w->history_count; k++) {
        int slot = (w->history_next + GAME_WALKER_HISTORY - k) % GAME_WALKER_HISTORY;
        double age = w->time - w->history[slot].time;
        if (age < STALL_WINDOW) continue;
        double dx = pl->position[0] - w->history[slot].x, dz = pl->position[2] - w->history[slot].z;
        double dy = flying ? pl->position[1] - w->history[slot].y : 0.0;
        return sqrt(dx * dx + dy * dy + dz * dz) < STALL_FRACTION * (double)speed * age;
    }
    return false;
}

/* Metres the player needs to stop from `speed` at the controller's easing (player.h); 0 when
 * it stops at once. */
static double braking(float speed, float accel) {
    return accel > 0.0f ? (double)speed * (double)speed / (2.0 * (double)accel) : 0.0;
}

/* The actions that head for waypoint w->index. */
static input_actions steer(game_walker *w, const game_player *pl, float dt) {
    const game_walk_point *p = &w->walk->points[w->index];
    input_actions a = { 0 };
    double t[3];
    target(w, w->index, t);
    double dx = t[0] - pl->position[0], dz = t[2] - pl->position[2], horizontal = hypot(dx, dz);

    bool flying = pl->flying;         /* as it will be in this frame's update */
    bool fly = p->fly || w->leg_flying_over;
    bool toggle = pl->flying != fly && !w->toggled;   /* one press, then see it took */
    if (toggle) a.pressed |= BIT(TOGGLE_FLY), flying = fly;
    w->toggled = toggle;

    /* yaw: forward is (sin yaw, −cos yaw), so the waypoint's bearing is atan2(dx, −dz) */
    float diff = (float)remainder(atan2(dx, -dz) - (double)pl->yaw, 2.0 * PI);
    a.look_x = clamp_abs(diff, GAME_WALKER_TURN_RATE * dt);
    float rest = diff - a.look_x;      /* the player turns before it moves */
    a.move_y = fmaxf(cosf(rest), 0.0f); /* facing away: turn on the spot, don't run off */
    float pitch = flying ? 0.0f : GAME_WALKER_PITCH;    /* level when flying: height is the buttons' */
    a.look_y = clamp_abs(pitch - pl->pitch, PITCH_RATE * dt);
    if (!p->walk) a.down |= BIT(SPRINT);
    if (flying) {
        /* up and down with jump and crouch, which fly mode moves by whatever the yaw, with a dead
         * band so it settles instead of bobbing */
        double radius = walk_radius(w->walk), dy = (p->has_y ? t[1] : w->fly_height) - pl->position[1];
        /* let go early enough that the easing stops it inside the dead band, not past it */
        float accel = pl->params.fly_accel, vy = pl->velocity[1];
        double rise = vy > 0.0f ? braking(vy, accel) : 0.0, fall = vy < 0.0f ? braking(vy, accel) : 0.0;
        if (dy > 0.5 * radius + rise) a.down |= BIT(JUMP);
        else if (dy < -0.5 * radius - fall) a.down |= BIT(CROUCH);
        double glide = braking(hypotf(pl->velocity[0], pl->velocity[2]), accel);
        if (horizontal < 0.5 * radius + glide) a.move_y = 0.0f;  /* above or below it: climb or sink */
    } else if (p->jump && pl->on_ground) {
        a.down |= BIT(JUMP), a.pressed |= BIT(JUMP);
    }
    if (fabsf(diff) > STEER_ALIGNED) w->history_count = 0;   /* turning is not stalling */
    remember(w, pl);

    bool detour = w->time < w->detour_until;
    if (!detour && fabsf(diff) <= STEER_ALIGNED && (pl->on_ground || flying || pl->swimming) &&
        stalled(w, pl, gait_speed(pl, p), flying)) {
        w->stalls++, w->leg_stalls++;
        w->detour_until = w->time + DETOUR_SECONDS;
        w->history_count = 0;
        detour = true;
        if (!flying) a.down |= BIT(JUMP), a.pressed |= BIT(JUMP);
        /* Sidesteps to one side did not get past: fly over it, this leg only. */
        if (!flying && w->walk->fly_over && w->leg_stalls > DETOURS_PER_SIDE) w->leg_flying_over = true;
    }
    if (detour) {
        /* sidestep while still heading for the waypoint: slides along a wall towards its end */
        float side = ((w->leg_stalls - 1) / DETOURS_PER_SIDE) % 2 ? -1.0f : 1.0f;
        a.move_x = side * 0.70710678f, a.move_y = 0.70710678f;     /* 45°, length 1 */
        if (flying) {
            a.down |= BIT(JUMP);                         /* and over it, */
            w->fly_height = fmax(w->fly_height, pl->position[1]);   /* keeping the height won */
        }
    }
    return a;
}

input_actions game_walker_step(game_walker *walker, const game_player *player, float dt) {
    input_actions idle = { 0 };
    if (walker->done) return idle;
    if (!(dt > 0.0f)) dt = 0.0f;
    if (dt > player->params.max_dt) dt = player->params.max_dt;   /* as the player clamps it */
    if (walker->shot_due) return idle;   /* holding still for the picture */
    progress(walker, player);
    water_allowance(walker, player);
    while (walker->index < walker->walk->count && reached(walker, player, walker->index)) {
        const game_walk_point *point = &walker->walk->points[walker->index];
        bool shot = point->shot && !unresolved(point);
        walker->index++;
        start_leg(walker, player);
        if (shot) {
            walker->shot_due = true;
            walker->shots++;
            return idle;
        }
    }
    if (walker->index >= walker->walk->count) {
        walker->done = true;
        return idle;
    }
    if (walker->time - walker->leg_start > walker->leg_limit) {
        walker->done = walker->stuck = true;
        return idle;
    }
    input_actions actions = steer(walker, player, dt);
    walker->last_dt = dt;
    return actions;
}
