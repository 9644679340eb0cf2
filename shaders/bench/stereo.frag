#version 460
// The stereo draws' fragment: the world normal, as a G-buffer's normal target holds it. Cheap on
// purpose: what is measured is the geometry and raster work that multiview shares.
layout(location = 0) in vec3 in_normal;
layout(location = 0) out vec4 out_color;

void main() {
    out_color = vec4(clamp(in_normal * 0.5 + 0.5, 0.0, 1.0), 1.0);
}
