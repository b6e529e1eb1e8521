#version 450
// Does nothing: the cost of one dispatch, submit and wait.
layout(local_size_x = 1) in;
layout(std430, set = 0, binding = 0) buffer Out { float sink[]; };
void main() {}
