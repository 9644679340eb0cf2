// Data of the cluster-cull pass (src/passes/cluster_cull.rs, scalar block layout).
#ifndef CULLGRAPH_CLUSTER_COMMON_GLSL
#define CULLGRAPH_CLUSTER_COMMON_GLSL

// One cluster of a mesh level, in the mesh's local space (GpuCluster in
// src/passes/shared/cull_data.rs, 64 bytes).
struct Cluster {
    vec3 center;
    float radius;
    vec3 cone_apex;
    float cone_cutoff;   // 1 or more: the normals spread too wide to cull by
    vec3 cone_axis;
    uint first_index;
    uint index_count;
    uint pad0;
    uint pad1;
    uint pad2;
};

// Clusters tested by one workgroup of the test step: one instance's clusters
// [chunk * CLUSTER_CHUNK, +CLUSTER_CHUNK).
#define CLUSTER_CHUNK 64u

// Regions of a cluster list: the face culls (back, front, none), of the opaque instances' list
// and alike of the alpha-masked instances' (src/passes/cluster_cull.rs), whose commands are
// the face-cull regions CLUSTER_REGIONS to 2 * CLUSTER_REGIONS - 1 of the input list.
#define CLUSTER_REGIONS 3u

// One command of the input list whose level has clusters (written by the prepare step in
// command order): its tasks start at `first_task`, each instance taking `chunks` of them.
struct ClusteredCommand {
    uint first_task;
    uint chunks;
    uint first_cluster;
    uint cluster_count;
    uint command;        // its index in the input list
    uint region;         // its face-cull region
    uint pad0;
    uint pad1;
};

// The scratch buffer's header (words 2 to 7 unused), then the clustered commands.
#define SCRATCH_CLUSTERED 0u   // clustered commands
#define SCRATCH_TASKS 1u       // tasks in all
#define SCRATCH_HEADER_WORDS 8u

// Counters of one cluster pass (ClusterCounters in src/passes/cluster_cull.rs, 48 bytes).
#define STAT_TESTED 0u           // clusters tested
#define STAT_FRUSTUM 1u          // outside the frustum (or covering no sample position)
#define STAT_BACKFACING 2u       // facing away from the eye
#define STAT_OCCLUDED 3u         // behind the Hi-Z
#define STAT_DRAWN 4u            // clusters drawn
#define STAT_TRIANGLES_TESTED 5u // triangles of the clusters tested
#define STAT_TRIANGLES_DRAWN 6u  // triangles of the clusters drawn
#define STAT_WHOLE 7u            // commands passed on whole (levels without clusters)
#define STAT_WORDS 12u

#endif
