// Phong illumination with the diffuse and specular reflectances as multiples of the surface
// colour (seed 003 §4.2.3). Twin of src/render/phong.rs; tests check they agree.
#ifndef GALERKIN_PHONG_GLSL
#define GALERKIN_PHONG_GLSL

const float PHONG_AMBIENT = 0.3;
const float PHONG_DIFFUSE = 0.7;
const float PHONG_SPECULAR = 0.25;
const float PHONG_SHININESS = 24.0;

// Lit colour of `colour` at a point with unit normal `n`, unit direction to the light `l` and
// unit direction to the eye `v`. Two-sided: the normal is flipped to face the eye.
vec3 phong(vec3 colour, vec3 n, vec3 l, vec3 v) {
    if (dot(n, v) < 0.0) n = -n;
    float diffuse = max(dot(n, l), 0.0);
    vec3 r = 2.0 * dot(n, l) * n - l;
    float specular = diffuse > 0.0 ? pow(max(dot(r, v), 0.0), PHONG_SHININESS) : 0.0;
    return colour * (PHONG_AMBIENT + PHONG_DIFFUSE * diffuse + PHONG_SPECULAR * specular);
}

#endif
