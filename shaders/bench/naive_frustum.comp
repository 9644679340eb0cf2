#version 460
// The naive peer the culling pass is measured against: one thread per instance reads a 64-byte
// record (world sphere in the first 16 bytes, the rest what a typical instance carries), tests
// the sphere against the six frustum planes, and appends survivors through one global atomic
// (order varies; no per-group compaction, no draw commands).
layout(local_size_x = 256) in;

struct NaiveRecord {
    vec4 center_radius;   // world center, radius
    vec4 payload[3];      // transform rows / material: read, as a real instance record would be
};

layout(set = 0, binding = 0) readonly buffer Records { NaiveRecord records[]; };
layout(set = 0, binding = 1) buffer Counter { uint survivors; };
layout(set = 0, binding = 2) writeonly buffer Out { uint survivor_ids[]; };

layout(push_constant) uniform Push {
    vec4 planes[6];       // inward normals and distances, world space
    uint count;
} pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) return;
    NaiveRecord r = records[i];
    // Touch the payload so the whole record is read (a real kernel would use it).
    float keep = r.payload[0].x + r.payload[1].y + r.payload[2].z;
    bool visible = keep == keep;   // false only for NaN payloads, which the bench never writes
    for (int p = 0; p < 6; ++p) {
        visible = visible && dot(pc.planes[p].xyz, r.center_radius.xyz) + pc.planes[p].w > -r.center_radius.w;
    }
    if (visible) survivor_ids[atomicAdd(survivors, 1u)] = i;
}
