#version 450
// One patch per surface element (seed 002's artery and coil): no vertex data, the element is
// the patch (gl_PrimitiveID in the next stages).
void main() {
    gl_Position = vec4(0.0);
}
