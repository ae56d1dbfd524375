/* walk_test.h — what the walk-stop tests share (test_walk_cave.c, test_walk_cliff.c,
 * test_walk_rocks.c, test_walk_shore.c): a walk parsed from text, the test failing on a parse
 * error, and a player standing at a place, looking along +z. Include after test.h.
 */
#ifndef TESTS_GAME_WALK_TEST_H
#define TESTS_GAME_WALK_TEST_H

#include "core/core.h"
#include "game/player.h"
#include "game/walk.h"

#include <string.h>

static inline game_walk walk_test_parsed(const char *text) {
    game_walk walk;
    core_error error = { 0 };
    cr_assert(game_walk_parse_text(text, strlen(text), "t.walk", &walk, &error), "%s", error.message);
    return walk;
}

static inline void walk_test_place(game_player *pl, double x, double y, double z) {
    game_player_init(pl, NULL);
    pl->position[0] = x, pl->position[1] = y, pl->position[2] = z;
    pl->yaw = 0.0f;
    pl->on_ground = true;
}

#endif
