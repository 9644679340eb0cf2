// Workgroups counted in a line, laid out over x and y where x alone cannot hold them
// (src/gpu/line_dispatch.rs). A shader leaves at once the workgroups past its line's end.
#ifndef CULLGRAPH_LINE_DISPATCH_GLSL
#define CULLGRAPH_LINE_DISPATCH_GLSL

uint line_workgroup() { return gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x; }

// One invocation per item in a line of workgroups of gl_WorkGroupSize.x invocations. A macro,
// so that gl_WorkGroupSize is read where it is used: in a function defined before the shader's
// local_size declaration, it would still be (1, 1, 1).
#define line_invocation() (line_workgroup() * gl_WorkGroupSize.x + gl_LocalInvocationIndex)

#endif
