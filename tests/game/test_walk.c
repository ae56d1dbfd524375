/* Scripted walks (game/walk.h): the script parser's results and messages, and the walker driving
 * the real player controller through hand-built worlds.
 *
 * The worlds are whole columns of bedrock (test_player.c explains the field they give: with σ = 1
 * the surface of flat ground at height g is exactly y = g, and walls are smoothed over a metre on
 * each side). Ground is at y = 0 everywhere; on it stand, depending on the world, nothing, a low
 * wall (2 m, 3 m thick: too steep to walk up, even at a sprint, but a 1.1 m jump clears it
 * because the smoothing turns its foot into a fillet the feet climb 0.5 m up, as in
 * test_player's 2 m step; at 1.5 m a sprint runs up it), a short tall wall (20 m high, 6 m long: no
 * jump clears it, so the walker must go round), or a closed box of 20 m walls.
 */
#include "../engine/test.h"
#include "game/walk.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* ---- parsing ---------------------------------------------------------------------------------- */

static bool parse(const char *text, game_walk *walk, core_error *error) {
    return game_walk_parse_text(text, strlen(text), "t.walk", walk, error);
}

/* The failure's kind is `code`, and its message starts where `example` (what a person reads)
 * starts: the file and line, up to the first space. */
static void expect_failure(const core_error *error, core_error_code code, const char *example, const char *input) {
    cr_expect_eq(error->code, code, "'%s': code %s, expected %s (%s)", input, core_error_code_name(error->code),
                 core_error_code_name(code), error->message);
    size_t where = strcspn(example, " ");
    cr_expect(strncmp(error->message, example, where) == 0, "'%s': '%s' is not at '%.*s'", input, error->message,
              (int)where, example);
}

Test(game_walk_parse, straight) {
    game_walk walk;
    core_error error = { 0 };
    cr_assert(game_walk_parse("straight:2000", &walk, &error), "%s", error.message);
    cr_expect_eq(walk.count, 1);
    cr_expect_eq(walk.frame, GAME_WALK_AHEAD);
    cr_expect_eq(walk.points[0].x, 0.0);
    cr_expect_eq(walk.points[0].z, 2000.0);
    cr_expect_not(walk.points[0].walk || walk.points[0].fly || walk.points[0].jump);
    game_walk_free(&walk);
    cr_expect_null(walk.points);
    cr_assert(game_walk_parse("straight:100000", &walk, &error), "%s", error.message);
    cr_expect_eq(walk.points[0].z, 100000.0);
    game_walk_free(&walk);
    cr_assert(game_walk_parse("straight:0.5", &walk, &error), "%s", error.message);
    cr_expect_eq(walk.points[0].z, 0.5);
    game_walk_free(&walk);
}

typedef struct bad_case {
    const char *input;
    core_error_code code;
    const char *message;              /* what a person reads; its place (up to the first space) is checked */
} bad_case;

static const char RANGE[] = ": the distance must be more than 0 and at most 100000 m";

Test(game_walk_parse, bad_straight_values_name_the_problem) {
    char range[8][96];
    const char *out_of_range[] = { "straight:0", "straight:-5", "straight:100000.5", "straight:1e999", "straight:-0" };
    for (int i = 0; i < 5; i++) snprintf(range[i], sizeof range[i], "%s%s", out_of_range[i], RANGE);
    const bad_case cases[] = {
        { "straight:", CORE_ERROR_FORMAT, "straight: needs a distance in metres (straight:2000)" },
        { "straight:abc", CORE_ERROR_FORMAT, "straight:abc: 'abc' is not a number of metres" },
        { "straight:12m", CORE_ERROR_FORMAT, "straight:12m: '12m' is not a number of metres" },
        { "straight: 5", CORE_ERROR_FORMAT, "straight: 5: ' 5' is not a number of metres" },
        { "straight:nan", CORE_ERROR_FORMAT, "straight:nan: 'nan' is not a number of metres" },
        { "straight:inf", CORE_ERROR_FORMAT, "straight:inf: 'inf' is not a number of metres" },
        { "straight:0x10", CORE_ERROR_FORMAT, "straight:0x10: '0x10' is not a number of metres" },
        { "straight:1.2.3", CORE_ERROR_FORMAT, "straight:1.2.3: '1.2.3' is not a number of metres" },
        { "straight:-", CORE_ERROR_FORMAT, "straight:-: '-' is not a number of metres" },
        { "", CORE_ERROR_ARGUMENT, "no walk given; a walk is " GAME_WALK_USAGE },
        { out_of_range[0], CORE_ERROR_RANGE, range[0] },
        { out_of_range[1], CORE_ERROR_RANGE, range[1] },
        { out_of_range[2], CORE_ERROR_RANGE, range[2] },
        { out_of_range[3], CORE_ERROR_RANGE, range[3] },
        { out_of_range[4], CORE_ERROR_RANGE, range[4] },
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        game_walk walk = { .count = 99 };
        core_error error = { 0 };
        cr_expect_not(game_walk_parse(cases[i].input, &walk, &error), "'%s' was taken", cases[i].input);
        expect_failure(&error, cases[i].code, cases[i].message, cases[i].input);
        cr_expect(walk.count == 0 && walk.points == NULL, "'%s': output not zeroed", cases[i].input);
        game_walk_free(&walk);
    }
    game_walk walk;
    cr_expect_not(game_walk_parse(NULL, &walk, NULL), "NULL spec, no error");
}

Test(game_walk_parse, file_with_comments_blank_lines_crlf_and_words) {
    const char text[] = "\xef\xbb\xbf# a test walk\r\n"
                        "\r\n"
                        "relative   # offsets from the start\r\n"
                        "radius 3.5\r\n"
                        "   \t\r\n"
                        "12.5 -7 walk\r\n"
                        "\t-1e3\t+2e-1   jump # hop\r\n"
                        "100000 -100000 fly y=-12.25\r\n"
                        "0 0 sprint";                                      /* no line end at the end */
    game_walk walk;
    core_error error = { 0 };
    cr_assert(parse(text, &walk, &error), "%s", error.message);
    cr_assert_eq(walk.count, 4);
    cr_expect_eq(walk.frame, GAME_WALK_RELATIVE);
    cr_expect_eq(walk.radius, 3.5f);
    const game_walk_point *p = walk.points;
    cr_expect(p[0].x == 12.5 && p[0].z == -7.0 && p[0].walk && !p[0].jump && !p[0].fly && !p[0].has_y);
    cr_expect(p[1].x == -1000.0 && p[1].z == 0.2 && !p[1].walk && p[1].jump && !p[1].fly);
    cr_expect(p[2].x == 100000.0 && p[2].z == -100000.0 && p[2].fly && p[2].has_y && p[2].y == -12.25);
    cr_expect(p[3].x == 0.0 && p[3].z == 0.0 && !p[3].walk && !p[3].jump && !p[3].fly);
    game_walk_free(&walk);
    /* defaults: absolute, radius 0 (= 2 m); "ahead" */
    cr_assert(parse("5 6\n", &walk, &error), "%s", error.message);
    cr_expect(walk.frame == GAME_WALK_ABSOLUTE && walk.radius == 0.0f && walk.count == 1);
    game_walk_free(&walk);
    cr_assert(parse("ahead\n0 10\n", &walk, &error), "%s", error.message);
    cr_expect_eq(walk.frame, GAME_WALK_AHEAD);
    game_walk_free(&walk);
}

/* Every error with the number of the line it is on: good, blank and comment lines come first. */
Test(game_walk_parse, every_error_names_its_line) {
    const bad_case cases[] = {
        { "1 2\n\n# c\nfoo 3\n", CORE_ERROR_FORMAT,
          "t.walk:4: unknown directive 'foo' (a line is X Z [words], relative, ahead, radius R or fly-over)" },
        { "1 2\n3\n", CORE_ERROR_FORMAT, "t.walk:2: a waypoint needs X and Z; Z is missing" },
        { "\n\n1.2.3 4\n", CORE_ERROR_FORMAT, "t.walk:3: x: '1.2.3' is not a number" },
        { "1 abc\n", CORE_ERROR_FORMAT, "t.walk:1: z: 'abc' is not a number" },
        { "1 2\n3 0x4\n", CORE_ERROR_FORMAT, "t.walk:2: z: '0x4' is not a number" },
        { "-inf 2\n", CORE_ERROR_FORMAT, "t.walk:1: x: '-inf' is not a number" },
        { "1 2\r\n3 1e999\r\n", CORE_ERROR_RANGE, "t.walk:2: z: '1e999' is out of range (-1e9 ... 1e9 m)" },
        { "# x\n1000000001 0\n", CORE_ERROR_RANGE, "t.walk:2: x: '1000000001' is out of range (-1e9 ... 1e9 m)" },
        { "1 2 sprnt\n", CORE_ERROR_FORMAT, "t.walk:1: unknown word 'sprnt' (walk, sprint, jump, fly, y=H, shot, look=YAW,PITCH)" },
        { "1 2 shot shot\n", CORE_ERROR_FORMAT, "t.walk:1: 'shot' given twice" },
        { "fly-over\nfly-over\n1 2\n", CORE_ERROR_FORMAT, "t.walk:2: fly-over given twice" },
        { "fly-over now\n", CORE_ERROR_FORMAT, "t.walk:1: 'fly-over' takes nothing after it" },
        { "1 2\nfly-over\n", CORE_ERROR_FORMAT, "t.walk:2: 'fly-over' must come before the first waypoint" },
        { "1 2\n1 2 walk sprint\n", CORE_ERROR_FORMAT, "t.walk:2: walk and sprint together" },
        { "1 2 jump jump\n", CORE_ERROR_FORMAT, "t.walk:1: 'jump' given twice" },
        { "1 2 fly jump\n", CORE_ERROR_FORMAT, "t.walk:1: jump and fly together (flying, there is nothing to jump from)" },
        { "1 2 y=3\n", CORE_ERROR_FORMAT, "t.walk:1: y=H needs fly (walking, the ground sets the height)" },
        { "1 2 fly y=\n", CORE_ERROR_FORMAT, "t.walk:1: y: '' is not a number" },
        { "1 2 fly y=high\n", CORE_ERROR_FORMAT, "t.walk:1: y: 'high' is not a number" },
        { "1 2 fly y=2e9\n", CORE_ERROR_RANGE, "t.walk:1: y: '2e9' is out of range (-1e9 ... 1e9 m)" },
        { "1 2 fly y=1 y=2\n", CORE_ERROR_FORMAT, "t.walk:1: 'y=' given twice" },
        { "1 2\nrelative\n", CORE_ERROR_FORMAT, "t.walk:2: 'relative' must come before the first waypoint" },
        { "relative\nahead\n1 2\n", CORE_ERROR_FORMAT, "t.walk:2: only one of relative and ahead, once" },
        { "relative now\n", CORE_ERROR_FORMAT, "t.walk:1: 'relative' takes nothing after it" },
        { "radius\n", CORE_ERROR_FORMAT, "t.walk:1: radius needs one number (metres)" },
        { "radius 1 2\n", CORE_ERROR_FORMAT, "t.walk:1: radius needs one number (metres)" },
        { "radius big\n", CORE_ERROR_FORMAT, "t.walk:1: radius: 'big' is not a number" },
        { "radius 0.09\n", CORE_ERROR_RANGE, "t.walk:1: radius: '0.09' is out of range (0.1 ... 1000 m)" },
        { "radius 1000.5\n", CORE_ERROR_RANGE, "t.walk:1: radius: '1000.5' is out of range (0.1 ... 1000 m)" },
        { "radius 2\nradius 3\n", CORE_ERROR_FORMAT, "t.walk:2: radius given twice" },
        { "1 2\n3 4 \x01\n", CORE_ERROR_FORMAT, "t.walk:2: unexpected byte 0x01 in column 5" },
        { "1 2\r3 4\n", CORE_ERROR_FORMAT, "t.walk:1: unexpected byte 0x0d in column 4" },
        { "1\t2 \xc3\xa9\n", CORE_ERROR_FORMAT, "t.walk:1: unexpected byte 0xc3 in column 5" },
        { "", CORE_ERROR_FORMAT, "t.walk: no waypoints (a waypoint line is X Z)" },
        { "# only a comment\n\nrelative\n", CORE_ERROR_FORMAT, "t.walk: no waypoints (a waypoint line is X Z)" },
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        game_walk walk;
        core_error error = { 0 };
        cr_expect_not(parse(cases[i].input, &walk, &error), "case %zu was taken", i);
        expect_failure(&error, cases[i].code, cases[i].message, cases[i].input);
        cr_expect(walk.count == 0 && walk.points == NULL, "case %zu: output not zeroed", i);
    }
    /* a NUL byte inside the text (the size says where it ends, not the NUL) */
    game_walk walk;
    core_error error = { 0 };
    cr_expect_not(game_walk_parse_text("1 2\n3\0 4\n", 9, "t.walk", &walk, &error));
    expect_failure(&error, CORE_ERROR_FORMAT, "t.walk:2: unexpected byte 0x00 in column 2", "NUL");
    /* comments may hold anything but a line end */
    cr_expect(game_walk_parse_text("1 2 # \xc3\xa9\x01\0\n", 11, "t.walk", &walk, &error), "%s", error.message);
    game_walk_free(&walk);
    /* a name too long for the message is cut, still terminated */
    char name[400];
    memset(name, 'n', sizeof name - 1);
    name[sizeof name - 1] = '\0';
    cr_expect_not(game_walk_parse_text("1 2\n3\n", 6, name, &walk, &error));
    cr_expect_eq(strlen(error.message), sizeof error.message - 1);
}

/* Writes `text` to a temporary file; returns its path (free with free()). */
static char *temporary_file(const char *text, size_t size) {
    char *path = strdup("/tmp/test_walk_XXXXXX");
    int fd = mkstemp(path);
    cr_assert_geq(fd, 0);
    cr_assert_eq(write(fd, text, size), (ssize_t)size);
    close(fd);
    return path;
}

Test(game_walk_parse, files_by_path) {
    game_walk walk;
    core_error error = { 0 };
    char expected[512];
    /* A file that cannot be opened or read: the message names it (and how a walk is spelt). */
    cr_expect_not(game_walk_parse("/nonexistent/dir/lap.walk", &walk, &error));
    expect_failure(&error, CORE_ERROR_IO, "/nonexistent/dir/lap.walk: cannot open", "missing");
    cr_expect_not(game_walk_parse("straigt:100", &walk, &error), "a misspelt spec is a missing file");
    expect_failure(&error, CORE_ERROR_IO, "straigt:100: cannot open", "misspelt");
    cr_expect_not_null(strstr(error.message, GAME_WALK_USAGE), "says how a walk is spelt: %s", error.message);
    cr_expect_not(game_walk_parse("/tmp", &walk, &error));
    expect_failure(&error, CORE_ERROR_IO, "/tmp: cannot read", "a folder");

    char *good = temporary_file("relative\n10 0\n10 10 walk\n", 25);
    cr_assert(game_walk_parse(good, &walk, &error), "%s", error.message);
    cr_expect(walk.count == 2 && walk.frame == GAME_WALK_RELATIVE && walk.points[1].z == 10.0 && walk.points[1].walk);
    game_walk_free(&walk);
    char *bad = temporary_file("10 0\n\n10 ten\n", 13);
    cr_expect_not(game_walk_parse(bad, &walk, &error));
    snprintf(expected, sizeof expected, "%s:3: z: 'ten' is not a number", bad);
    expect_failure(&error, CORE_ERROR_FORMAT, expected, bad);
    char *empty = temporary_file("", 0);
    cr_expect_not(game_walk_parse(empty, &walk, &error));
    snprintf(expected, sizeof expected, "%s: no waypoints (a waypoint line is X Z)", empty);
    expect_failure(&error, CORE_ERROR_FORMAT, expected, empty);
    /* over the size limit: rejected before parsing (its lines, one waypoint and blank ones, would be fine) */
    size_t huge_size = (size_t)GAME_WALK_MAX_FILE + 1;
    char *huge_text = malloc(huge_size);
    memset(huge_text, '\n', huge_size);
    memcpy(huge_text, "1 2", 3);
    char *huge = temporary_file(huge_text, huge_size);
    cr_expect_not(game_walk_parse(huge, &walk, &error));
    snprintf(expected, sizeof expected, "%s: larger than 16 MiB", huge);
    expect_failure(&error, CORE_ERROR_RANGE, expected, huge);
    char *limit = temporary_file(huge_text, huge_size - 1);                 /* exactly 16 MiB */
    cr_expect(game_walk_parse(limit, &walk, &error), "%s", error.message);
    game_walk_free(&walk);
    char *paths[] = { good, bad, empty, huge, limit };
    for (int i = 0; i < 5; i++) unlink(paths[i]), free(paths[i]);
    free(huge_text);
}

/* n lines "i 0\n" */
static char *many_waypoints(int n, size_t *size) {
    char *text = malloc((size_t)n * 10 + 1);
    size_t used = 0;
    for (int i = 0; i < n; i++) used += (size_t)sprintf(text + used, "%d 0\n", i % 100000);
    *size = used;
    return text;
}

Test(game_walk_parse, limits) {
    game_walk walk;
    core_error error = { 0 };
    size_t size;
    char *text = many_waypoints(GAME_WALK_MAX_POINTS, &size);
    cr_assert(game_walk_parse_text(text, size, "t.walk", &walk, &error), "%s", error.message);
    cr_expect_eq(walk.count, 100000);
    cr_expect_eq(walk.points[99999].x, 99999.0);
    game_walk_free(&walk);
    free(text);
    text = many_waypoints(GAME_WALK_MAX_POINTS + 1, &size);
    cr_expect_not(game_walk_parse_text(text, size, "t.walk", &walk, &error));
    expect_failure(&error, CORE_ERROR_RANGE, "t.walk:100001: more than 100000 waypoints", "100001 waypoints");
    free(text);

    /* 1024 bytes before the line end are fine (CR included), 1025 are not, comments too */
    char line[1100];
    memset(line, ' ', sizeof line);
    memcpy(line, "1 2 #", 5);
    line[1024] = '\n';
    cr_expect(game_walk_parse_text(line, 1025, "t.walk", &walk, &error), "%s", error.message);
    game_walk_free(&walk);
    line[1023] = '\r';
    cr_expect(game_walk_parse_text(line, 1025, "t.walk", &walk, &error), "%s", error.message);
    game_walk_free(&walk);
    line[1023] = ' ', line[1024] = ' ', line[1025] = '\n';
    cr_expect_not(game_walk_parse_text(line, 1026, "t.walk", &walk, &error));
    expect_failure(&error, CORE_ERROR_RANGE, "t.walk:1: line longer than 1024 bytes", "1025 bytes");

    cr_expect(parse("1e9 -1e9\n-1000000000 1000000000 fly y=1e9\n", &walk, &error), "%s", error.message);
    game_walk_free(&walk);
    cr_expect(parse("radius 0.1\n0 0\n", &walk, &error), "%s", error.message);
    game_walk_free(&walk);
    cr_expect(parse("radius 1000\n0 0\n", &walk, &error), "%s", error.message);
    game_walk_free(&walk);
    cr_expect_not(parse("1000000000.0001 0\n", &walk, &error));
    expect_failure(&error, CORE_ERROR_RANGE, "t.walk:1: x: '1000000000.0001' is out of range (-1e9 ... 1e9 m)", "x");
}

/* ---- worlds ------------------------------------------------------------------------------------ */

typedef enum world_kind { FLAT, LOW_WALL, SHORT_TALL_WALL, BOX } world_kind;

typedef struct hand_world {
    world_kind kind;
    int64_t shift_chunks;             /* the whole world moved by this many chunks in x and z */
} hand_world;

/* Height of column (x, z) above the ground at y = 0. */
static double hand_height(world_kind kind, int64_t x, int64_t z) {
    switch (kind) {
    case FLAT: return 0.0;
    case LOW_WALL: return x >= 10 && x < 13 ? 2.0 : 0.0;                     /* across every z */
    case SHORT_TALL_WALL: return x >= 10 && x < 12 && z >= -3 && z < 3 ? 20.0 : 0.0;
    case BOX: {                                                              /* inside [20, 30) × [−5, 5) */
        bool outer = x >= 18 && x < 32 && z >= -7 && z < 7, inner = x >= 20 && x < 30 && z >= -5 && z < 5;
        return outer && !inner ? 20.0 : 0.0;
    }
    }
    return 0.0;
}

static void hand_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    const hand_world *hand = user;
    int64_t shift = hand->shift_chunks * TERRAIN_CHUNK_COLUMNS;
    double height = hand_height(hand->kind, x - shift, z - shift);
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, (float)(height - TERRAIN_FLOOR_Y));
}

static terrain_stacks *hand_generate(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, hand_column, user);
}

static terrain_world *hand_world_create(hand_world *hand) {
    return terrain_world_create(&(terrain_world_desc){ .generate = hand_generate, .generate_user = hand });
}

/* Stands the player on the ground at (x, 0, z), looking along yaw. */
static void place(game_player *pl, double x, double z, float yaw) {
    game_player_init(pl, NULL);
    pl->position[0] = x, pl->position[1] = 0.0, pl->position[2] = z;
    pl->yaw = yaw;
    pl->on_ground = true;
}

/* ---- running a walk ---------------------------------------------------------------------------- */

#define MAX_FRAMES 20000
#define TRACKED 8

typedef struct walk_run {
    float dt;                         /* 0 = 1/60 s */
    double (*trajectory)[3];          /* optional, MAX_FRAMES rows: position − start */
    /* out */
    double passed[TRACKED][3];        /* where the player was when waypoint i was counted reached */
    double highest;                   /* feet above the start */
    int frames, flying_frames, airborne_frames;
} walk_run;

static void run_walk(terrain_world *world, game_player *pl, const game_walk *walk, game_walker *w, walk_run *r) {
    float dt = r->dt > 0.0f ? r->dt : 1.0f / 60.0f;
    double start[3];
    memcpy(start, pl->position, sizeof start);
    r->highest = 0.0;
    game_walker_start(w, walk, pl);
    for (r->frames = 0; r->frames < MAX_FRAMES; r->frames++) {
        int before = w->index;
        input_actions a = game_walker_step(w, pl, dt);
        /* what input.h promises of actions, and the walker of its turns */
        cr_assert_leq(a.move_x * a.move_x + a.move_y * a.move_y, 1.0f + 1e-6f, "frame %d", r->frames);
        cr_assert_leq(fabsf(a.look_x), GAME_WALKER_TURN_RATE * dt * 1.000001f, "frame %d", r->frames);
        for (int i = before; i < w->index && i < TRACKED; i++) memcpy(r->passed[i], pl->position, sizeof r->passed[i]);
        if (game_walker_done(w)) break;
        game_player_update(pl, world, &a, dt);
        if (r->trajectory)
            for (int k = 0; k < 3; k++) r->trajectory[r->frames][k] = pl->position[k] - start[k];
        r->highest = fmax(r->highest, pl->position[1] - start[1]);
        r->flying_frames += pl->flying;
        r->airborne_frames += !pl->flying && !pl->on_ground;
    }
}

static game_walk parsed(const char *text) {
    game_walk walk;
    core_error error = { 0 };
    cr_assert(parse(text, &walk, &error), "%s", error.message);
    return walk;
}

static const char SQUARE[] = "relative\n30 0\n30 30\n0 30\n0 0\n";

static void walk_square(float dt) {
    hand_world hand = { .kind = FLAT };
    terrain_world *world = hand_world_create(&hand);
    game_walk walk = parsed(SQUARE);
    game_player pl;
    place(&pl, 0.5, 0.5, 0.0f);                       /* facing −z: the first waypoint is a quarter turn right */
    game_walker w;
    walk_run r = { .dt = dt };
    run_walk(world, &pl, &walk, &w, &r);
    cr_assert(game_walker_done(&w), "dt %g: not done after %d frames", dt, r.frames);
    cr_expect_not(w.stuck, "dt %g: stuck at waypoint %d", dt, w.index);
    cr_expect_eq(w.index, 4);
    const double corners[4][2] = { { 30.5, 0.5 }, { 30.5, 30.5 }, { 0.5, 30.5 }, { 0.5, 0.5 } };
    for (int i = 0; i < 4; i++) {
        double d = hypot(r.passed[i][0] - corners[i][0], r.passed[i][2] - corners[i][1]);
        cr_expect_leq(d, 2.0, "dt %g: waypoint %d passed %f m from it", dt, i, d);
    }
    double final = hypot(pl.position[0] - 0.5, pl.position[2] - 0.5);
    cr_expect_leq(final, 2.0, "dt %g: ended %f m from the last waypoint", dt, final);
    /* the legs are 30, 30, 30 and 28 m to within the radius, cut short by at most the radius at
     * each corner; the turns (6 rad/s, slowed while facing away) add little */
    cr_expect(w.walked > 4 * 30 - 4 * 2.0 - 1.0 && w.walked < 4 * 30 + 6.0, "dt %g: walked %f m", dt, w.walked);
    cr_expect_float_eq(w.from_start, final, 1e-9);
    /* at a sprint (8 m/s) 120 m takes 15 s: plus turning, well under 20 s */
    cr_expect_lt(w.time, 20.0, "dt %g: took %f s", dt, w.time);
    cr_expect_eq(w.stalls, 0, "dt %g: stalled on flat ground", dt);
    cr_expect_eq(w.frames, r.frames + 1);
    cr_expect_float_eq(pl.position[1], 0.0, 1e-3);
    game_walk_free(&walk);
    terrain_world_destroy(world);
}

Test(game_walker, walks_a_square_on_flat_ground_at_60hz) { walk_square(1.0f / 60.0f); }
Test(game_walker, walks_a_square_on_flat_ground_at_30hz) { walk_square(1.0f / 30.0f); }
Test(game_walker, walks_a_square_on_flat_ground_at_144hz) { walk_square(1.0f / 144.0f); }

static double trajectory_a[MAX_FRAMES][3], trajectory_b[MAX_FRAMES][3];

/* A walk with everything in it: a jump over the low wall, walking, hops back over it, a flight
 * (at fly speed, 12 m/s) and a landing, and the wall again. */
static const char EVERYTHING[] = "relative\n20 0\n20 10 walk\n5 10 jump\n5 -10 fly y=8 walk\n25 -10\n";

static void walk_everything(int64_t shift_chunks, double (*trajectory)[3], game_player *pl, game_walker *w,
                            walk_run *r) {
    hand_world hand = { .kind = LOW_WALL, .shift_chunks = shift_chunks };
    terrain_world *world = hand_world_create(&hand);
    game_walk walk = parsed(EVERYTHING);
    double shift = (double)(shift_chunks * TERRAIN_CHUNK_COLUMNS);
    place(pl, 3.5 + shift, 0.5 + shift, 1.0f);
    *r = (walk_run){ .trajectory = trajectory };
    run_walk(world, pl, &walk, w, r);
    game_walk_free(&walk);
    terrain_world_destroy(world);
}

Test(game_walker, deterministic_bit_for_bit) {
    game_player a, b;
    game_walker wa, wb;
    walk_run ra, rb;
    memset(trajectory_a, 0, sizeof trajectory_a), memset(trajectory_b, 0, sizeof trajectory_b);
    walk_everything(0, trajectory_a, &a, &wa, &ra);
    walk_everything(0, trajectory_b, &b, &wb, &rb);
    cr_expect(wa.done && !wa.stuck, "the walk did not arrive (waypoint %d)", wa.index);
    cr_expect_eq(ra.frames, rb.frames);
    cr_expect(memcmp(trajectory_a, trajectory_b, sizeof trajectory_a) == 0, "trajectories differ");
    cr_expect(memcmp(a.position, b.position, sizeof a.position) == 0);
    cr_expect(memcmp(&wa.walked, &wb.walked, sizeof wa.walked) == 0 && memcmp(&wa.time, &wb.time, sizeof wa.time) == 0);
    cr_expect(wa.frames == wb.frames && wa.stalls == wb.stalls && wa.index == wb.index);
    /* it did what the script says */
    cr_expect_gt(ra.flying_frames, 60);
    cr_expect_gt(ra.highest, 7.0, "flew only %f m high", ra.highest);
    cr_expect_gt(ra.airborne_frames, 60, "no hops");
    cr_expect_not(a.flying, "still flying after the last (walking) leg");
    cr_expect(a.on_ground);
}

/* The same relative walk at the origin and 100 km out (the world shifted by whole chunks): every
 * position the walker reads and every target it computes is a double near the player, and the
 * differences it steers by are exact in double there (both operands are within a factor of two, or
 * are integers plus floats with at most 17 + 24 significant bits together), so the walker's inputs
 * to the player are the same; the player itself keeps to 1e-6 m 100 km out (test_player.c). */
Test(game_walker, the_same_relative_walk_100km_out) {
    game_player a, far;
    game_walker wa, wfar;
    walk_run ra, rfar;
    memset(trajectory_a, 0, sizeof trajectory_a), memset(trajectory_b, 0, sizeof trajectory_b);
    walk_everything(0, trajectory_a, &a, &wa, &ra);
    walk_everything(100000 / TERRAIN_CHUNK_COLUMNS, trajectory_b, &far, &wfar, &rfar);
    cr_expect(wfar.done && !wfar.stuck, "100 km out the walk did not arrive (waypoint %d)", wfar.index);
    cr_expect_eq(ra.frames, rfar.frames);
    double worst = 0.0;
    for (int f = 0; f < ra.frames; f++)
        for (int k = 0; k < 3; k++) worst = fmax(worst, fabs(trajectory_a[f][k] - trajectory_b[f][k]));
    cr_expect_leq(worst, 1e-6, "100 km out the displacement differs by %g m", worst);
    cr_expect_float_eq(wa.walked, wfar.walked, 1e-6);
    cr_expect_float_eq(wa.from_start, wfar.from_start, 1e-6);
}

Test(game_walker, jumps_a_low_wall) {
    hand_world hand = { .kind = LOW_WALL };
    terrain_world *world = hand_world_create(&hand);
    game_walk walk = parsed("20 0.5\n");
    game_player pl;
    place(&pl, 3.5, 0.5, 0.0f);
    game_walker w;
    walk_run r = { 0 };
    run_walk(world, &pl, &walk, &w, &r);
    cr_expect(w.done && !w.stuck, "stuck at x = %f", pl.position[0]);
    cr_expect_geq(w.stalls, 1, "never stalled: the wall should have stopped it once");
    cr_expect_gt(r.highest, 1.4, "never got on top of the wall (%f)", r.highest);
    cr_expect_leq(hypot(pl.position[0] - 20.0, pl.position[2] - 0.5), 2.0);
    game_walk_free(&walk);
    terrain_world_destroy(world);
}

Test(game_walker, goes_round_a_short_tall_wall) {
    hand_world hand = { .kind = SHORT_TALL_WALL };
    terrain_world *world = hand_world_create(&hand);
    game_walk walk = parsed("20 0.5\n");
    game_player pl;
    place(&pl, 3.5, 0.5, 1.57079632679f);
    game_walker w;
    walk_run r = { 0 };
    run_walk(world, &pl, &walk, &w, &r);
    cr_expect(w.done && !w.stuck, "stuck at (%f, %f)", pl.position[0], pl.position[2]);
    cr_expect_geq(w.stalls, 1);
    cr_expect_lt(r.highest, 2.0, "climbed the wall (%f)", r.highest);
    cr_expect_leq(hypot(pl.position[0] - 20.0, pl.position[2] - 0.5), 2.0);
    game_walk_free(&walk);
    terrain_world_destroy(world);
}

/* The waypoint is inside a box of 20 m walls, 20.6 m away: the leg's limit is 2·20.6/8 + 5 s, and
 * the walk must end there, stuck, not run on. */
Test(game_walker, an_unreachable_waypoint_ends_stuck_at_the_time_limit) {
    hand_world hand = { .kind = BOX };
    terrain_world *world = hand_world_create(&hand);
    game_walk walk = parsed("25 0\n");
    game_player pl;
    place(&pl, 4.5, 0.5, 0.0f);
    game_walker w;
    walk_run r = { 0 };
    run_walk(world, &pl, &walk, &w, &r);
    cr_assert(w.done, "still walking after %d frames", r.frames);
    cr_expect(w.stuck);
    cr_expect_eq(w.index, 0);
    double limit = 2.0 * hypot(20.5, 0.5) / 8.0 + 5.0;
    cr_expect(w.time > limit && w.time <= limit + 1.0 / 60.0 + 1e-9, "gave up after %f s, limit %f s", w.time, limit);
    cr_expect_geq(w.stalls, 3, "it should have tried");
    cr_expect_lt(r.highest, 2.0, "climbed the box (%f)", r.highest);
    /* done stays done and asks for nothing */
    input_actions a = game_walker_step(&w, &pl, 1.0f / 60.0f);
    cr_expect(a.move_x == 0.0f && a.move_y == 0.0f && a.look_x == 0.0f && a.down == 0 && a.pressed == 0);
    game_walk_free(&walk);
    terrain_world_destroy(world);
}

/* The same box with `fly-over`: sidestepping one way fails, so the leg flies, climbs the 20 m
 * walls and reaches the waypoint inside instead of ending stuck. */
Test(game_walker, fly_over_clears_what_it_cannot_walk_round) {
    hand_world hand = { .kind = BOX };
    terrain_world *world = hand_world_create(&hand);
    game_walk walk = parsed("fly-over\n25 0\n");
    game_player pl;
    place(&pl, 4.5, 0.5, 0.0f);
    game_walker w;
    walk_run r = { 0 };
    run_walk(world, &pl, &walk, &w, &r);
    cr_assert(w.done, "still walking after %d frames", r.frames);
    cr_expect(!w.stuck, "stuck at (%f, %f)", pl.position[0], pl.position[2]);
    cr_expect_eq(w.index, 1);
    cr_expect_gt(r.highest, 20.0, "flew over the 20 m walls (%f)", r.highest);
    cr_expect_gt(r.flying_frames, 0);
    cr_expect_leq(hypot(pl.position[0] - 25.0, pl.position[2]), 3.0, "ended at (%f, %f)", pl.position[0],
                  pl.position[2]);
    game_walk_free(&walk);
    terrain_world_destroy(world);
}

/* Flying 10 m ahead while climbing 120 m at sprint-fly speed (48 m/s), with the controller's
 * easing (120 m/s²: 9.6 m to stop): the walker lets go early, horizontally and vertically, so
 * the player stops over the waypoint instead of overshooting and circling it until the leg runs
 * out of time (which the tour did before the walker knew about braking). */
Test(game_walker, a_fast_climb_stops_at_its_height) {
    hand_world hand = { .kind = FLAT };
    terrain_world *world = hand_world_create(&hand);
    game_walk walk = parsed("relative\nradius 3\n0 -10 fly y=120\n");   /* 10 m ahead, as the tour */
    game_player pl;
    place(&pl, 0.5, 0.5, 0.0f);
    game_walker w;
    walk_run r = { 0 };
    run_walk(world, &pl, &walk, &w, &r);
    cr_expect(w.done && !w.stuck, "stuck at height %f after %f s", pl.position[1], w.time);
    cr_expect_lt(w.time, 120.0 / 48.0 + 1.5, "took %f s", w.time);
    cr_expect_lt(r.highest, 120.0 + 3.0, "overshot to %f", r.highest);
    game_walk_free(&walk);
    terrain_world_destroy(world);
}

/* A `shot` waypoint: the walker holds still (no input, no time) until resumed, then goes on. */
Test(game_walker, a_shot_holds_until_resumed) {
    hand_world hand = { .kind = FLAT };
    terrain_world *world = hand_world_create(&hand);
    game_walk walk = parsed("ahead\n0 10 shot\n0 20\n");
    game_player pl;
    place(&pl, 0.5, 0.5, 0.0f);
    game_walker w;
    game_walker_start(&w, &walk, &pl);
    float dt = 1.0f / 60.0f;
    int frame = 0;
    for (; frame < 2000 && !w.shot_due; frame++) {
        input_actions a = game_walker_step(&w, &pl, dt);
        game_player_update(&pl, world, &a, dt);
    }
    cr_assert(w.shot_due, "no hold after %d frames", frame);
    cr_expect_eq(w.shots, 1);
    cr_expect_leq(hypot(pl.position[0] - 0.5, pl.position[2] - (0.5 - 10.0)), GAME_WALK_DEFAULT_RADIUS + 1e-9);
    double time = w.time;
    for (int hold = 0; hold < 100; hold++) {
        input_actions a = game_walker_step(&w, &pl, dt);
        cr_assert(a.move_x == 0.0f && a.move_y == 0.0f && a.look_x == 0.0f && a.down == 0 && a.pressed == 0,
                  "input while holding (frame %d)", hold);
        game_player_update(&pl, world, &a, dt);
    }
    cr_expect_eq(w.time, time, "the hold counts against no leg");
    cr_expect(!game_walker_done(&w));
    game_walker_resume(&w, &pl);
    cr_expect(!w.shot_due);
    for (; frame < 4000 && !game_walker_done(&w); frame++) {
        input_actions a = game_walker_step(&w, &pl, dt);
        game_player_update(&pl, world, &a, dt);
    }
    cr_expect(w.done && !w.stuck);
    cr_expect_eq(w.shots, 1);
    cr_expect_leq(hypot(pl.position[0] - 0.5, pl.position[2] - (0.5 - 20.0)), GAME_WALK_DEFAULT_RADIUS + 0.5);
    game_walk_free(&walk);
    terrain_world_destroy(world);
}

Test(game_walker, straight_walks_ahead_of_the_start) {
    hand_world hand = { .kind = FLAT };
    terrain_world *world = hand_world_create(&hand);
    game_walk walk;
    core_error error = { 0 };
    cr_assert(game_walk_parse("straight:50", &walk, &error), "%s", error.message);
    game_player pl;
    float yaw = 2.5f;
    place(&pl, -7.25, 3.5, yaw);
    game_walker w;
    walk_run r = { 0 };
    run_walk(world, &pl, &walk, &w, &r);
    cr_expect(w.done && !w.stuck);
    /* forward is (sin yaw, −cos yaw) */
    double ex = -7.25 + 50.0 * sin(yaw), ez = 3.5 - 50.0 * cos(yaw);
    cr_expect_leq(hypot(pl.position[0] - ex, pl.position[2] - ez), 2.0, "ended at (%f, %f), expected (%f, %f)",
                  pl.position[0], pl.position[2], ex, ez);
    cr_expect(w.from_start > 48.0 - 1e-3 && w.from_start <= 50.0, "%f m from the start", w.from_start);
    cr_expect_float_eq(w.walked, w.from_start, 1e-3, "not straight: walked %f m", w.walked);
    cr_expect_float_eq(pl.yaw, yaw, 1e-6, "turned");
    cr_expect_float_eq(pl.pitch, GAME_WALKER_PITCH, 1e-6, "pitch %f", pl.pitch);
    game_walk_free(&walk);

    /* ahead, X to the right: facing +x, the right is +z */
    walk = parsed("ahead\n10 0\n");
    place(&pl, 3.5, -4.5, 1.57079632679f);
    run_walk(world, &pl, &walk, &w, &r);
    cr_expect(w.done && !w.stuck);
    cr_expect_leq(hypot(pl.position[0] - 3.5, pl.position[2] - 5.5), 2.0, "ended at (%f, %f)", pl.position[0],
                  pl.position[2]);
    game_walk_free(&walk);
    terrain_world_destroy(world);
}

Test(game_walker, waiting_frames_do_not_count_against_the_limit) {
    game_walk walk = parsed("100 0\n");
    game_player pl;
    place(&pl, 0.5, 0.5, 0.0f);
    pl.waiting = true;
    game_walker w;
    game_walker_start(&w, &walk, &pl);
    for (int i = 0; i < 10000; i++) game_walker_step(&w, &pl, 1.0f / 60.0f);
    cr_expect_not(game_walker_done(&w));
    cr_expect_eq(w.time, 0.0);
    cr_expect_eq(w.frames, 10000);
    pl.waiting = false;                               /* it never moves: now the limit runs */
    for (int i = 0; i < 10000 && !game_walker_done(&w); i++) game_walker_step(&w, &pl, 1.0f / 60.0f);
    cr_expect(game_walker_done(&w) && w.stuck);
    game_walk_free(&walk);
}

Test(game_walker, an_empty_walk_is_done_at_once) {
    game_walk walk = { 0 };
    game_player pl;
    place(&pl, 0.5, 0.5, 0.0f);
    game_walker w;
    game_walker_start(&w, &walk, &pl);
    input_actions a = game_walker_step(&w, &pl, 1.0f / 60.0f);
    cr_expect(game_walker_done(&w) && !w.stuck && a.move_y == 0.0f);
}
