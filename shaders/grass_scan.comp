#version 450 core
// grass_scan.comp — the per-triangle tuft counts of grass_place.comp become each triangle's first
// tuft (an exclusive prefix sum, in place) in one work group: each invocation sums a contiguous
// run of triangles, the 256 sums are scanned in shared memory (Hillis and Steele), and each run
// is then rewritten as offsets. The total is what the CPU reads back to size the patch.

layout(local_size_x = 256) in;

layout(std430, binding = 2) buffer Counts { uint counts[]; };
layout(std430, binding = 5) writeonly buffer Total { uint total_tufts; };

uniform uint u_triangle_count;

shared uint sums[256];

void main() {
    uint lane = gl_LocalInvocationID.x;
    uint run = (u_triangle_count + 255u) / 256u;
    uint begin = min(lane * run, u_triangle_count), end = min(begin + run, u_triangle_count);
    uint total = 0u;
    for (uint t = begin; t < end; t++) total += counts[t];
    sums[lane] = total;
    barrier();
    for (uint step = 1u; step < 256u; step <<= 1) {
        uint before = lane >= step ? sums[lane - step] : 0u;
        barrier();
        sums[lane] += before;
        barrier();
    }
    uint offset = sums[lane] - total;
    for (uint t = begin; t < end; t++) {
        uint count = counts[t];
        counts[t] = offset;
        offset += count;
    }
    if (lane == 255u) total_tufts = sums[255];
}
