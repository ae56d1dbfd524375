/* resource.c — the world's singletons (ecs.h, RESOURCES). A resource takes an id from the
 * component id space, with size 0 so that no table ever gets a column for it, and keeps its
 * storage here. */
#include "ecs_internal.h"

#include <string.h>

const ecs_resource_slot *ecs_resource_slot_of(const ecs_world *world, ecs_component id) {
    for (uint32_t i = 0; i < world->resource_count; i++)
        if (world->resources[i].id == id) return &world->resources[i];
    return NULL;
}

bool ecs_is_resource(const ecs_world *world, ecs_component id) {
    return ecs_resource_slot_of(world, id) != NULL;
}

ecs_component ecs_resource_register(ecs_world *world, const ecs_resource_desc *desc) {
    ECS_ASSERT_STRUCTURAL(world);
    assert(desc && desc->name && "a resource needs a name");
    assert(!(desc->size && desc->object) && "a resource is a value (size) or an object, not both");
    size_t align = desc->align ? desc->align : alignof(max_align_t);
    assert((align & (align - 1)) == 0);
    ecs_component id = ecs_component_lookup(world, desc->name);
    if (id) {
        ecs_resource_slot *slot = (ecs_resource_slot *)ecs_resource_slot_of(world, id);
        assert(slot && "the name belongs to a component");
        assert(slot->size == desc->size && "registered again with another size");
        if (slot && !slot->size) slot->data = desc->object;
        return id;
    }
    /* The id: a size-0 component, which no entity may hold (ecs_add asserts). */
    id = ecs_component_register(world, &(ecs_component_desc){ .name = desc->name });
    world->resources = ecs_grow(world->resources, &world->resource_capacity,
                                world->resource_count + 1, sizeof *world->resources);
    ecs_resource_slot *slot = &world->resources[world->resource_count++];
    *slot = (ecs_resource_slot){ .id = id, .size = desc->size, .data = desc->object };
    if (desc->size) {
        slot->allocated = (desc->size + align - 1) / align * align;
        slot->data = core_alloc_aligned(slot->allocated, align < sizeof(void *) ? sizeof(void *) : align);
        memset(slot->data, 0, slot->allocated);
    }
    return id;
}

void *ecs_resource_get(const ecs_world *world, ecs_component resource) {
    const ecs_resource_slot *slot = ecs_resource_slot_of(world, resource);
    assert(slot && "ecs_resource_get: not a resource");
    if (!slot) return NULL;
    ecs_access_check(world, resource, false, "ecs_resource_get");
    return slot->data;
}

void ecs_resource_set(ecs_world *world, ecs_component resource, const void *value) {
    const ecs_resource_slot *slot = ecs_resource_slot_of(world, resource);
    assert(slot && slot->size && "ecs_resource_set: not a value resource");
    if (!slot || !slot->size) return;
    ecs_access_check(world, resource, true, "ecs_resource_set");
    memcpy(slot->data, value, slot->size);
}

void ecs_resources_free(ecs_world *world) {
    for (uint32_t i = 0; i < world->resource_count; i++) {
        ecs_resource_slot *slot = &world->resources[i];
        if (slot->allocated) core_free(slot->data, slot->allocated);
    }
    core_free(world->resources, world->resource_capacity * sizeof *world->resources);
}
