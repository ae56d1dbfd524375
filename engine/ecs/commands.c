/* commands.c — command buffers: structural changes recorded now and applied later.
 *
 * A buffer belongs to one system invocation (or one batch of a parallel system), so recording
 * needs no lock: it touches only the buffer, and reads only component sizes, which do not
 * change while a phase runs.
 */
#include "ecs_internal.h"

#include <string.h>

static uint32_t next_serial(ecs_world *world) {
    /* Atomic because a job may create a buffer of its own while a phase runs. */
    return __atomic_add_fetch(&world->command_serial, 1, __ATOMIC_RELAXED) & ECS_GENERATION_MASK;
}

ecs_commands *ecs_commands_create(ecs_world *world) {
    ecs_commands *commands = core_calloc(1, sizeof *commands);
    commands->world = world;
    commands->serial = next_serial(world);
    return commands;
}

void ecs_commands_destroy(ecs_commands *commands) {
    if (!commands) return;
    core_free(commands->list, commands->capacity * sizeof *commands->list);
    core_free(commands->values, commands->values_capacity);
    core_free(commands->resolved, commands->resolved_capacity * sizeof *commands->resolved);
    core_free(commands, sizeof *commands);
}

void ecs_commands_reset(ecs_commands *commands) {
    commands->count = 0;
    commands->values_size = 0;
    commands->placeholder_count = 0;
    /* A new serial makes placeholders of the last round unusable by mistake. */
    commands->serial = next_serial(commands->world);
}

int ecs_commands_count(const ecs_commands *commands) { return (int)commands->count; }

/* ---- recording -------------------------------------------------------------------------- */

static void record(ecs_commands *commands, ecs_command command) {
    commands->list = ecs_grow(commands->list, &commands->capacity, commands->count + 1,
                              sizeof *commands->list);
    commands->list[commands->count++] = command;
}

static size_t store_value(ecs_commands *commands, const void *value, size_t size) {
    size_t offset = commands->values_size, needed = offset + size;
    commands->values = core_grow(commands->values, &commands->values_capacity, needed, 1);
    if (size) memcpy(commands->values + offset, value, size);
    commands->values_size = needed;
    return offset;
}

ecs_entity ecs_defer_entity_create(ecs_commands *commands) {
    uint32_t local = commands->placeholder_count++;
    ecs_entity placeholder = ECS_PLACEHOLDER_BIT | ecs_id_make(local, commands->serial);
    record(commands, (ecs_command){ .kind = ECS_COMMAND_CREATE, .entity = placeholder });
    return placeholder;
}

void ecs_defer_entity_destroy(ecs_commands *commands, ecs_entity entity) {
    record(commands, (ecs_command){ .kind = ECS_COMMAND_DESTROY, .entity = entity });
}

void ecs_defer_add(ecs_commands *commands, ecs_entity entity, ecs_component component) {
    ECS_ASSERT_COMPONENT(commands->world, component);
    record(commands, (ecs_command){ .kind = ECS_COMMAND_ADD, .entity = entity,
                                    .component = component });
}

void ecs_defer_set(ecs_commands *commands, ecs_entity entity, ecs_component component,
                   const void *value) {
    ECS_ASSERT_COMPONENT(commands->world, component);
    size_t size = commands->world->components[component].size;
    assert((value || size == 0) && "ecs_defer_set without a value");
    record(commands, (ecs_command){ .kind = ECS_COMMAND_SET, .entity = entity,
                                    .component = component,
                                    .value_offset = store_value(commands, value, size) });
}

void ecs_defer_remove(ecs_commands *commands, ecs_entity entity, ecs_component component) {
    ECS_ASSERT_COMPONENT(commands->world, component);
    record(commands, (ecs_command){ .kind = ECS_COMMAND_REMOVE, .entity = entity,
                                    .component = component });
}

/* ---- applying --------------------------------------------------------------------------- */

/* The real id behind `entity`: itself, or what its placeholder was created as. */
static ecs_entity resolve(const ecs_commands *commands, ecs_entity entity) {
    if (!ecs_id_is_placeholder(entity)) return entity;
    uint32_t local = ecs_id_index(entity);
    bool ours = (ecs_id_generation(entity) & ECS_GENERATION_MASK) == commands->serial &&
                local < commands->placeholder_count;
    assert(ours && "placeholder from another command buffer (or an applied one)");
    return ours ? commands->resolved[local] : 0;
}

static void apply_one(ecs_commands *commands, const ecs_command *command) {
    ecs_world *world = commands->world;
    if (command->kind == ECS_COMMAND_CREATE) {
        commands->resolved[ecs_id_index(command->entity)] = ecs_entity_create(world);
        return;
    }
    ecs_entity entity = resolve(commands, command->entity);
    switch (command->kind) {
    case ECS_COMMAND_CREATE:
        break;
    case ECS_COMMAND_DESTROY:
        ecs_entity_destroy(world, entity);
        break;
    case ECS_COMMAND_ADD:
        if (ecs_is_alive(world, entity)) ecs_add(world, entity, command->component);
        break;
    case ECS_COMMAND_SET:
        if (ecs_is_alive(world, entity))
            ecs_set(world, entity, command->component, commands->values + command->value_offset);
        break;
    case ECS_COMMAND_REMOVE:
        ecs_remove(world, entity, command->component);
        break;
    }
}

void ecs_commands_apply(ecs_commands *commands) {
    ECS_ASSERT_STRUCTURAL(commands->world);
    /* Most systems record nothing most frames: an empty buffer has no placeholders to retire,
     * so it keeps its serial. */
    if (commands->count == 0) return;
    commands->resolved = ecs_grow(commands->resolved, &commands->resolved_capacity,
                                  commands->placeholder_count, sizeof *commands->resolved);
    for (uint32_t i = 0; i < commands->count; i++) apply_one(commands, &commands->list[i]);
    ecs_commands_reset(commands);
}
