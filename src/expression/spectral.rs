//! Derived fields on spectral-element meshes (seed 002's per-pixel evaluation, applied to a
//! function of the solution): the f64 reference at a reference point, the colour range, the
//! coefficient upload the device reads, and the run-time fragment shader.

use super::{physical_gradient, Expression, ExpressionError, Inputs, Slot};
use crate::spectral::{Shape, SpectralError, SpectralMesh};

/// Which fragment shader a derived field is spliced into.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DerivedShader {
    /// `element_planar.frag`: planar meshes, with the ownership rule at element edges.
    Planar,
    /// `element.frag`: surfaces in 3D.
    Surface,
    /// `cut.frag`: cut planes through hexahedra.
    CutPlanes,
}

/// An [`Expression`] over a spectral mesh's fields.
#[derive(Debug, Clone, PartialEq)]
pub struct DerivedField {
    /// The parsed expression.
    pub expression: Expression,
}

impl DerivedField {
    /// Parses `text` against `mesh`'s field names.
    pub fn new(mesh: &SpectralMesh, text: &str) -> Result<Self, SpectralError> {
        let names: Vec<String> = mesh.fields.iter().map(|f| f.name.clone()).collect();
        let expression = Expression::parse(text, &names)
            .map_err(|e: ExpressionError| SpectralError::Expression(e.to_string()))?;
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
    pub(super) fn variables(point: [f64; 3], time: f64) -> [[f64; 3]; 4] {
        [[point[0], 0.0, 0.0], [point[1], 0.0, 0.0], [point[2], 0.0, 0.0], [time, 0.0, 0.0]]
    }

    /// The derived value in quadrilateral `e` at reference point `r`, in f64: every slot's
    /// value and physical gradient ([`SpectralMesh::value_gradient`], [`physical_gradient`]
    /// with the geometry map's tangents), the mapped point and the step's time. Twin of
    /// `spectral_derived_value` (spectral_element.glsl).
    pub fn value_at(&self, mesh: &SpectralMesh, shown: usize, step: usize, e: usize, r: [f64; 2]) -> f64 {
        self.value_at_n(mesh, shown, step, e, r)
    }

    /// [`Self::value_at`] in hexahedron `e` at r = (ξ, η, ζ) (the gradient J⁻ᵀ ∇_r f). Twin
    /// of `spectral_derived_value_hex` (spectral_element.glsl).
    pub fn value_at_hex(&self, mesh: &SpectralMesh, shown: usize, step: usize, e: usize, r: [f64; 3]) -> f64 {
        self.value_at_n(mesh, shown, step, e, r)
    }

    fn value_at_n<const D: usize>(
        &self,
        mesh: &SpectralMesh,
        shown: usize,
        step: usize,
        e: usize,
        r: [f64; D],
    ) -> f64 {
        let (point, tangents) = geometry(mesh, e, r);
        let fields = self.fields(shown);
        let mut values = Vec::with_capacity(fields.len());
        let mut gradients = Vec::with_capacity(fields.len());
        for f in fields {
            let (v, d) = mesh.value_gradient_at(f, step, e, r);
            values.push(v);
            gradients.push(gradient(&tangents, &d));
        }
        let variables = Self::variables(point, Self::time(mesh, shown, step));
        self.expression.eval(&Inputs { values: &values, gradients: &gradients, variables: &variables })
    }

    /// The least and greatest finite derived value, sampled on a (2n + 1)ᴰ grid per element
    /// (as [`SpectralMesh::value_range`] samples a field): the colour range's "auto". `None`
    /// when no sample is finite.
    pub fn range(&self, mesh: &SpectralMesh, shown: usize, step: usize) -> Option<(f64, f64)> {
        let mut range: Option<(f64, f64)> = None;
        mesh.for_each_sample(|e, r| {
            let v = match mesh.shape {
                Shape::Quadrilateral | Shape::Triangle => self.value_at(mesh, shown, step, e, [r[0], r[1]]),
                Shape::Hexahedron | Shape::Tetrahedron => self.value_at_hex(mesh, shown, step, e, r),
            };
            if v.is_finite() {
                range = Some(range.map_or((v, v), |(lo, hi)| (lo.min(v), hi.max(v))));
            }
        });
        range
    }

    /// The coefficients the derived-field shader reads: per element, every slot's padded f32
    /// run (as [`crate::spectral::render::padded_values`] pads one field), then one vec4
    /// holding the time.
    pub fn padded_values(&self, mesh: &SpectralMesh, shown: usize, step: usize) -> Vec<f32> {
        let mut out = crate::spectral::render::padded_slots(mesh, &self.fields(shown), step);
        out.extend_from_slice(&[Self::time(mesh, shown, step) as f32, 0.0, 0.0, 0.0]);
        out
    }

    /// The GLSL source of the derived-field fragment shader of `kind` for a mesh of
    /// `elements` elements, with this expression spliced in. The time follows the last
    /// element's coefficients ([`Self::padded_values`]).
    pub fn fragment_source(&self, kind: DerivedShader, elements: usize) -> String {
        let (defines, body) = match kind {
            DerivedShader::Planar => ("#define SPECTRAL_EDGE_OWNERSHIP\n", "spectral_element_frag.glsl"),
            DerivedShader::Surface => ("", "spectral_element_frag.glsl"),
            DerivedShader::CutPlanes => ("", "spectral_cut_frag.glsl"),
        };
        let slots = self.expression.slots.len();
        let gradients: Vec<&str> =
            (0..slots).map(|k| if self.expression.reads_gradient(k) { "true" } else { "false" }).collect();
        format!(
            "#version 450\n#define SPECTRAL_FIELDS {slots}u\n#define SPECTRAL_ELEMENTS {elements}u\n#define SPECTRAL_EXPRESSION\n\
             #define SPECTRAL_SLOT_GRADIENTS bool[{slots}]({})\n{defines}{}#include \"{body}\"\n",
            gradients.join(", "),
            self.expression.glsl("spectral_expression")
        )
    }

    /// Compiles [`Self::fragment_source`] to SPIR-V through the `shaderc` crate. Without the
    /// `runtime-shaderc` feature: an error saying how to build with it.
    pub fn compile_fragment(&self, kind: DerivedShader, elements: usize) -> Result<Vec<u32>, SpectralError> {
        #[cfg(feature = "runtime-shaderc")]
        {
            crate::gpu::shaders::compile_glsl(
                &self.fragment_source(kind, elements),
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
            let _ = (kind, elements);
            Err(SpectralError::Expression(format!(
                "--expr {:?} needs run-time shader compilation: build with `--features runtime-shaderc` \
                 (scripts/install-deps.sh --shaderc installs the system's shaderc and glslang)",
                self.expression.text
            )))
        }
    }
}

/// The geometry map of element `e` at `r` (D = 2: quadrilateral, 3: hexahedron): the point and
/// its derivatives along each reference axis.
pub(super) fn geometry<const D: usize>(
    mesh: &SpectralMesh,
    e: usize,
    r: [f64; D],
) -> ([f64; 3], [[f64; 3]; D]) {
    let mut tangents = [[0.0; 3]; D];
    let point = if D == 3 {
        let (x, t) = mesh.map_hex(e, [r[0], r[1], r[2]]);
        tangents.copy_from_slice(&t[..D]);
        x
    } else {
        let (x, t) = mesh.map(e, r[0], r[1]);
        tangents.copy_from_slice(&t[..D]);
        x
    };
    (point, tangents)
}

/// The physical gradient from reference derivatives `d` and the map's `tangents`:
/// [`physical_gradient`] on quadrilaterals, J⁻ᵀ d on hexahedra (twin of
/// `spectral_physical_gradient_hex`).
pub(super) fn gradient<const D: usize>(tangents: &[[f64; 3]; D], d: &[f64; D]) -> [f64; 3] {
    if D == 3 {
        let j = glam::DMat3::from_cols(tangents[0].into(), tangents[1].into(), tangents[2].into());
        (j.inverse().transpose() * glam::DVec3::new(d[0], d[1], d[2])).to_array()
    } else {
        physical_gradient([tangents[0], tangents[1]], [d[0], d[1]])
    }
}
