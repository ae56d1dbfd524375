/* fuzz_walk — libFuzzer target for the waypoint file parser (game_walk_parse_text, game/walk.c)
 * and the walker that follows what it parsed.
 *
 *   tests/fuzz/run.sh 20     (builds every target with the engine's, modules' and game's sources)
 * Seeds: tests/fuzz/corpus/fuzz_walk/ (a file using every word and directive, CRLF and comments,
 * and one line of each kind of error).
 *
 * The input is the text, not NUL-terminated. Besides "no crash, no leak, no read out of bounds"
 * it traps when a result breaks the parser's contract. A success gives 1 … GAME_WALK_MAX_POINTS
 * waypoints, every number finite and within ±GAME_WALK_MAX_COORD, y= only with fly, never jump
 * with fly, a radius of 0 (the default) or within its range. A failure gives a zeroed walk and a
 * terminated, non-empty message that starts with the name and, where it names a line, a line
 * the input has. Then the walker is stepped for a few seconds with a stand-in player (moved by
 * the actions without terrain): its actions must be finite, move no longer than 1, turns within
 * the turn rate.
 */
#include "core/core.h"
#include "game/walk.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size);

static void check_walk(const game_walk *walk) {
    if (walk->count < 1 || walk->count > GAME_WALK_MAX_POINTS || !walk->points) __builtin_trap();
    if (walk->frame != GAME_WALK_ABSOLUTE && walk->frame != GAME_WALK_RELATIVE && walk->frame != GAME_WALK_AHEAD)
        __builtin_trap();
    if (walk->radius != 0.0f && !(walk->radius >= 0.0999f && walk->radius <= 1000.0f)) __builtin_trap();
    for (int i = 0; i < walk->count; i++) {
        const game_walk_point *p = &walk->points[i];
        if (!(fabs(p->x) <= GAME_WALK_MAX_COORD) || !(fabs(p->z) <= GAME_WALK_MAX_COORD)) __builtin_trap();
        if (p->has_y && (!p->fly || !(fabs(p->y) <= GAME_WALK_MAX_COORD))) __builtin_trap();
        if (!p->has_y && p->y != 0.0) __builtin_trap();
        if (p->jump && p->fly) __builtin_trap();
    }
}

static void check_error(const core_error *failure, const unsigned char *bytes, size_t size) {
    const char *error = failure->message;
    if (failure->code != CORE_ERROR_FORMAT && failure->code != CORE_ERROR_RANGE) __builtin_trap();
    if (error[0] == '\0' || memchr(error, '\0', sizeof failure->message) == NULL) __builtin_trap();
    if (strncmp(error, "fuzz:", 5) != 0) __builtin_trap();
    if (error[5] == ' ') return;                                   /* "fuzz: no waypoints …" */
    char *end;
    long line = strtol(error + 5, &end, 10);
    size_t lines = 1;
    for (size_t i = 0; i + 1 < size; i++) lines += bytes[i] == '\n';
    if (end == error + 5 || *end != ':' || line < 1 || (size_t)line > lines) __builtin_trap();
}

/* A stand-in player: turned and moved by the actions as player.c would on open ground. */
static void drive(const game_walk *walk) {
    game_player player;
    game_player_init(&player, NULL);
    player.position[0] = 0.5, player.position[2] = 0.5, player.on_ground = true;
    game_walker walker;
    game_walker_start(&walker, walk, &player);
    const float dt = 1.0f / 60.0f;
    for (int frame = 0; frame < 240 && !game_walker_done(&walker); frame++) {
        input_actions a = game_walker_step(&walker, &player, dt);
        if (!isfinite(a.move_x) || !isfinite(a.move_y) || !isfinite(a.look_x) || !isfinite(a.look_y)) __builtin_trap();
        if (a.move_x * a.move_x + a.move_y * a.move_y > 1.0f + 1e-5f) __builtin_trap();
        if (fabsf(a.look_x) > GAME_WALKER_TURN_RATE * dt * 1.0001f) __builtin_trap();
        if (a.pressed & INPUT_ACTION_BIT(INPUT_ACTION_TOGGLE_FLY)) player.flying = !player.flying;
        player.yaw = remainderf(player.yaw + a.look_x, 6.28318530718f);
        player.pitch += a.look_y;
        float speed = 8.0f * dt, s = sinf(player.yaw), c = cosf(player.yaw);
        player.position[0] += (double)((s * a.move_y + c * a.move_x) * speed);
        player.position[2] += (double)((-c * a.move_y + s * a.move_x) * speed);
        if (player.flying) player.position[1] += (a.down & INPUT_ACTION_BIT(INPUT_ACTION_JUMP)) ? speed : 0.0f;
    }
    if (walker.index < 0 || walker.index > walk->count || !(walker.walked >= 0.0) || !isfinite(walker.walked))
        __builtin_trap();
}

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size) {
    game_walk walk;
    core_error error = { 0 };
    if (game_walk_parse_text((const char *)bytes, size, "fuzz", &walk, &error)) {
        check_walk(&walk);
        drive(&walk);
    } else {
        check_error(&error, bytes, size);
        if (walk.count != 0 || walk.points != NULL) __builtin_trap();
    }
    game_walk_free(&walk);
    return 0;
}
