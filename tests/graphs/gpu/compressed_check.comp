#version 460
// The compressed G-buffer's lists checked against the MSAA depth (compressed_check.glsl).
#include "compressed_check.glsl"
