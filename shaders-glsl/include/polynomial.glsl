// The bivariate cubic of the demo field pass.
// Twin of src/demo/polynomial.rs (BivariateCubic::eval); the field test checks they agree.
#ifndef GALERKIN_POLYNOMIAL_GLSL
#define GALERKIN_POLYNOMIAL_GLSL

// p(x, y) = sum_{i+j<=3} c_ij x^i y^j with coefficients in graded order
// c00 c10 c01 c20 c11 c02 c30 c21 c12 c03, by Horner in x over polynomials in y.
float bivariate_cubic(float c[10], vec2 q) {
    float a0 = c[0] + q.y * (c[2] + q.y * (c[5] + q.y * c[9]));
    float a1 = c[1] + q.y * (c[4] + q.y * c[8]);
    float a2 = c[3] + q.y * c[7];
    float a3 = c[6];
    return a0 + q.x * (a1 + q.x * (a2 + q.x * a3));
}

#endif
