//! Derived fields on spectral-element meshes (seed 002's per-pixel evaluation, applied to a
//! function of the solution): the f64 reference at a reference point, the colour range, the
//! coefficient upload the device reads, and the run-time fragment shader.

use super::{physical_gradient, Expression, ExpressionError, InputErrors, Inputs, Slot};
use crate::spectral::{Shape, SpectralError, SpectralMesh};

/// An [`Expression`] over a spectral mesh's fields.
#[derive(Debug, Clone, PartialEq)]
pub struct DerivedField {
    /// The parsed expression.
    pub expression: Expression,
}

impl DerivedField {
    /// Parses `text` against `mesh`'s field names. Quadrilateral meshes only (planar or
    /// surfaces): the gradient of a hexahedral field on a cut plane is not built.
    pub fn new(mesh: &SpectralMesh, text: &str) -> Result<Self, SpectralError> {
        let names: Vec<String> = mesh.fields.iter().map(|f| f.name.clone()).collect();
        let expression = Expression::parse(text, &names)
            .map_err(|e: ExpressionError| SpectralError::Expression(e.to_string()))?;
        if mesh.shape == Shape::Hexahedron {
            return Err(SpectralError::Expression(format!(
                "--expr {text:?}: derived fields are drawn on quadrilateral meshes (planar or surfaces); \
                 this mesh is hexahedral (cut planes show its fields as they are)"
            )));
        }
        Ok(Self { expression })
    }

    /// The mesh's field index of every slot when `shown` is the field shown as `u`.
    pub fn fields(&self, shown: usize) -> Vec<usize> {
        self.expression
            .slots
            .iter()
            .map(|s| match s {
                Slot::Shown => shown,
                Slot::Named(k, _) => *k,
            })
            .collect()
    }

    /// Refuses a step that some field read by the expression does not have (naming it).
    pub fn check_step(&self, mesh: &SpectralMesh, shown: usize, step: usize) -> Result<(), SpectralError> {
        for f in self.fields(shown) {
            let field = mesh.fields.get(f).ok_or_else(|| SpectralError::Missing(format!("no field {f}")))?;
            if step >= field.steps.len() {
                return Err(SpectralError::Missing(format!(
                    "--expr {:?} reads field {:?}, which has {} time steps; step {step} does not exist",
                    self.expression.text,
                    field.name,
                    field.steps.len()
                )));
            }
        }
        Ok(())
    }

    /// The time `t` of `step`: the shown field's time there (0 when the file gives none).
    pub fn time(mesh: &SpectralMesh, shown: usize, step: usize) -> f64 {
        mesh.fields.get(shown).and_then(|f| f.times.get(step)).copied().unwrap_or(0.0)
    }

    /// The variables x, y, z, t ([`crate::expression::SPECTRAL_VARIABLES`]) as the
    /// interpreter reads them.
    fn variables(point: [f64; 3], time: f64) -> [[f64; 3]; 4] {
        [[point[0], 0.0, 0.0], [point[1], 0.0, 0.0], [point[2], 0.0, 0.0], [time, 0.0, 0.0]]
    }

    /// The derived value in quadrilateral `e` at reference point `r`, in f64: every slot's
    /// value and physical gradient ([`SpectralMesh::value_gradient`], [`physical_gradient`]
    /// with the geometry map's tangents), the mapped point and the step's time. Twin of
    /// `spectral_derived_value` (spectral_element.glsl).
    pub fn value_at(&self, mesh: &SpectralMesh, shown: usize, step: usize, e: usize, r: [f64; 2]) -> f64 {
        let (point, tangents) = mesh.map(e, r[0], r[1]);
        let fields = self.fields(shown);
        let mut values = Vec::with_capacity(fields.len());
        let mut gradients = Vec::with_capacity(fields.len());
        for f in fields {
            let (v, d) = mesh.value_gradient(f, step, e, r[0], r[1]);
            values.push(v);
            gradients.push(physical_gradient(tangents, d));
        }
        let variables = Self::variables(point, Self::time(mesh, shown, step));
        self.expression.eval(&Inputs { values: &values, gradients: &gradients, variables: &variables })
    }

    /// A bound on |device − exact| of the derived value at reference point `r` of element
    /// `e` ([`Expression::rounding_bound`]) from bounds on what it reads, each times 4 as
    /// [`crate::spectral::reference::rounding_bound`]:
    /// - a value: that function's bound (its f32 sum and the f32 reference point);
    /// - a gradient g = J⁺ d: ‖J⁺‖ e_d (the derivative sum's rounding, 8m ε Σ(|ℓ'ℓ F| +
    ///   |ℓℓ' F|)), ‖J⁺‖ ‖g‖ e_J (the tangents' rounding, 8(g + 1) ε Σ(|γ'γ| + |γγ'|)|X|),
    ///   8 κ(J)² ε ‖g‖ (the metric G = JᵀJ and its inverse in f32), and the gradient's change
    ///   over the reference-point error δr = ‖J⁺‖ (2|x| + 8(g + 1) Σ|γγ X|) ε (central
    ///   differences in f64);
    /// - the point: (2|x| + 8(g + 1) Σ|γγ X|) ε.
    ///
    /// Polynomial cells (rational ones carry weights in every sum; not derived here: the
    /// bound is then an estimate).
    pub fn rounding_bound(
        &self,
        mesh: &SpectralMesh,
        shown: usize,
        step: usize,
        e: usize,
        r: [f64; 2],
    ) -> f64 {
        let eps = f64::from(f32::EPSILON);
        let (fb, gb) = (&mesh.basis, &mesh.geometry);
        let (m, gm) = (fb.len(), gb.len());
        let (mut a, mut da, mut b, mut db) = ([0.0; 16], [0.0; 16], [0.0; 16], [0.0; 16]);
        fb.eval(r[0], &mut a, Some(&mut da));
        fb.eval(r[1], &mut b, Some(&mut db));
        let (mut ga, mut gda, mut gbv, mut gdb) = ([0.0; 16], [0.0; 16], [0.0; 16], [0.0; 16]);
        gb.eval(r[0], &mut ga, Some(&mut gda));
        gb.eval(r[1], &mut gbv, Some(&mut gdb));
        let (point, tangents) = mesh.map(e, r[0], r[1]);
        let (mut sum_x, mut sum_j) = (0.0, 0.0);
        for (k, p) in mesh.element_points(e).iter().enumerate() {
            let (i, j) = (k % gm, k / gm);
            let size = p.iter().fold(0.0f64, |s, c| s.max(c.abs()));
            sum_x += (ga[i] * gbv[j]).abs() * size;
            sum_j += ((gda[i] * gbv[j]).abs() + (ga[i] * gdb[j]).abs()) * size;
        }
        let xmax = point.iter().fold(0.0f64, |s, c| s.max(c.abs()));
        let position = (2.0 * xmax + 8.0 * gm as f64 * sum_x) * eps;
        let dot = |u: [f64; 3], v: [f64; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
        let (g11, g12, g22) =
            (dot(tangents[0], tangents[0]), dot(tangents[0], tangents[1]), dot(tangents[1], tangents[1]));
        let det = g11 * g22 - g12 * g12;
        // ‖J⁺‖ ≤ √trace(G⁻¹), ‖J‖ ≤ √trace(G).
        let pinv = ((g11 + g22) / det).sqrt();
        let kappa = (g11 + g22).sqrt() * pinv;
        let e_tangent = 8.0 * gm as f64 * eps * sum_j;
        let dr = pinv * position;
        let fields = self.fields(shown);
        let mut values = Vec::with_capacity(fields.len());
        let mut gradients = Vec::with_capacity(fields.len());
        let mut value_errors = Vec::with_capacity(fields.len());
        let mut gradient_errors = Vec::with_capacity(fields.len());
        let gradient_at = |f: usize, r: [f64; 2]| {
            let (_, t) = mesh.map(e, r[0], r[1]);
            physical_gradient(t, mesh.value_gradient(f, step, e, r[0], r[1]).1)
        };
        for f in fields {
            let (v, d) = mesh.value_gradient(f, step, e, r[0], r[1]);
            let g = physical_gradient(tangents, d);
            let coefficients = mesh.element_values(f, step, e);
            let mut sum_d = 0.0;
            for (k, c) in coefficients.iter().enumerate() {
                let (i, j) = (k % m, k / m);
                sum_d += ((da[i] * b[j]).abs() + (a[i] * db[j]).abs()) * c.abs();
            }
            let gnorm = dot(g, g).sqrt();
            let h = 1e-6;
            let mut change = 0.0f64;
            for axis in 0..2 {
                let mut lo = r;
                let mut hi = r;
                lo[axis] = (r[axis] - h).max(0.0);
                hi[axis] = (r[axis] + h).min(1.0);
                let (gl, gh) = (gradient_at(f, lo), gradient_at(f, hi));
                let diff = [gh[0] - gl[0], gh[1] - gl[1], gh[2] - gl[2]];
                change += dot(diff, diff).sqrt() / (hi[axis] - lo[axis]);
            }
            let e_d = 8.0 * m as f64 * eps * sum_d;
            values.push(v);
            gradients.push(g);
            value_errors.push(crate::spectral::reference::rounding_bound(mesh, f, step, e, r));
            gradient_errors.push(
                4.0 * (pinv * e_d
                    + pinv * gnorm * e_tangent
                    + 8.0 * kappa * kappa * eps * gnorm
                    + change * dr),
            );
        }
        let time = Self::time(mesh, shown, step);
        let variables = Self::variables(point, time);
        let inputs = Inputs { values: &values, gradients: &gradients, variables: &variables };
        let p = 4.0 * position;
        let errors = InputErrors {
            values: &value_errors,
            gradients: &gradient_errors,
            variables: &[p, p, p, eps * time.abs()],
        };
        self.expression.rounding_bound(&inputs, &errors)
    }

    /// The least and greatest finite derived value, sampled on a (2n + 1)² grid per element
    /// (as [`SpectralMesh::value_range`] samples a field): the colour range's "auto". `None`
    /// when no sample is finite.
    pub fn range(&self, mesh: &SpectralMesh, shown: usize, step: usize) -> Option<(f64, f64)> {
        let s = 2 * mesh.basis.order.max(1);
        let mut range: Option<(f64, f64)> = None;
        for e in 0..mesh.elements() {
            for j in 0..=s {
                for i in 0..=s {
                    let v = self.value_at(mesh, shown, step, e, [i as f64 / s as f64, j as f64 / s as f64]);
                    if v.is_finite() {
                        range = Some(range.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))));
                    }
                }
            }
        }
        range
    }

    /// The coefficients the derived-field shader reads: per element, every slot's padded f32
    /// run (as [`crate::spectral::render::padded_values`] pads one field), then one vec4
    /// holding the time.
    pub fn padded_values(&self, mesh: &SpectralMesh, shown: usize, step: usize) -> Vec<f32> {
        let runs: Vec<Vec<f32>> = self
            .fields(shown)
            .iter()
            .map(|&f| crate::spectral::render::padded_values(mesh, f, step))
            .collect();
        let stride = mesh.values_per_element().div_ceil(4) * 4;
        let mut out = Vec::with_capacity(runs.len() * stride * mesh.elements() + 4);
        for e in 0..mesh.elements() {
            for run in &runs {
                out.extend_from_slice(&run[e * stride..(e + 1) * stride]);
            }
        }
        out.extend_from_slice(&[Self::time(mesh, shown, step) as f32, 0.0, 0.0, 0.0]);
        out
    }

    /// The GLSL source of the derived-field fragment shader for a mesh of `elements`
    /// elements: `element_planar.frag` (planar meshes, with the edge ownership rule) or
    /// `element.frag` with this expression spliced in. The time follows the last element's
    /// coefficients ([`Self::padded_values`]).
    pub fn fragment_source(&self, planar: bool, elements: usize) -> String {
        format!(
            "#version 450\n#define SPECTRAL_FIELDS {}u\n#define SPECTRAL_ELEMENTS {elements}u\n#define SPECTRAL_EXPRESSION\n{}{}#include \"spectral_element_frag.glsl\"\n",
            self.expression.slots.len(),
            if planar { "#define SPECTRAL_EDGE_OWNERSHIP\n" } else { "" },
            self.expression.glsl("spectral_expression")
        )
    }

    /// Compiles [`Self::fragment_source`] to SPIR-V through the `shaderc` crate. Without the
    /// `runtime-shaderc` feature: an error saying how to build with it.
    pub fn compile_fragment(&self, planar: bool, elements: usize) -> Result<Vec<u32>, SpectralError> {
        #[cfg(feature = "runtime-shaderc")]
        {
            crate::gpu::shaders::compile_glsl(
                &self.fragment_source(planar, elements),
                "derived_field.frag",
                shaderc::ShaderKind::Fragment,
            )
            .map_err(|e| {
                SpectralError::Expression(format!(
                    "--expr {:?}: the shader compiler refused the derived field: {e}",
                    self.expression.text
                ))
            })
        }
        #[cfg(not(feature = "runtime-shaderc"))]
        {
            let _ = (planar, elements);
            Err(SpectralError::Expression(format!(
                "--expr {:?} needs run-time shader compilation: build with `--features runtime-shaderc` \
                 (scripts/install-deps.sh --shaderc installs the system's shaderc and glslang)",
                self.expression.text
            )))
        }
    }
}
