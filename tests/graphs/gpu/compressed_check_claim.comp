#version 460
// compressed_check.comp for the claim variant: also checks the claimed samples (error 64).
#define SAMPLE_CLAIM 1
#include "compressed_check.glsl"
