// Push constants shared by the fluid cell and particle pipelines (src/fluid/render.rs Push).
layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 range;    // x: lo, y: hi, z: colour-map texels, w: 1 for a log scale
    vec4 sprite;   // x, y: particle half-size in clip units; z: cells plain (0), coloured (1),
                   // or a shaded surface (2);
                   // w: particles coloured by speed (0) or white (1)
} pc;
