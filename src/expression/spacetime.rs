//! Derived fields on spacetime slices (seed 003 §4.2.3's per-pixel evaluation, applied to a
//! function of the slice's fields): `speed` (|v|, with its exact gradient `grad(speed)`), `U`,
//! the velocity `v` and displacement `disp` (vectors), the strain `eps_xx`, `eps_yy`,
//! `eps_xy`, the point `x`, `y` and the slice time `t`.

use super::{Expression, ExpressionError, Inputs, Scope, Type};
use crate::spacetime::cubic::PointFields;

/// The spacetime renderer's variables, in the order `spacetime_derived_value`
/// (spacetime_slice_frag.glsl) passes them.
pub const SPACETIME_VARIABLES: [(&str, Type); 9] = [
    ("x", Type::Scalar),
    ("y", Type::Scalar),
    ("t", Type::Scalar),
    ("U", Type::Scalar),
    ("v", Type::Vector),
    ("disp", Type::Vector),
    ("eps_xx", Type::Scalar),
    ("eps_yy", Type::Scalar),
    ("eps_xy", Type::Scalar),
];

/// An [`Expression`] over a spacetime slice's fields.
#[derive(Debug, Clone, PartialEq)]
pub struct SpacetimeExpression {
    /// The parsed expression.
    pub expression: Expression,
}

impl SpacetimeExpression {
    /// Parses `text` in the spacetime scope (errors name the column).
    pub fn new(text: &str) -> Result<Self, ExpressionError> {
        let scope = Scope { shown: "speed", fields: &[], variables: &SPACETIME_VARIABLES };
        Ok(Self { expression: Expression::parse_in(text, &scope)? })
    }

    /// The derived value from the fields at slice point (x, y) and time t, in f64. Twin of
    /// `spacetime_derived_value` (spacetime_slice_frag.glsl).
    pub fn value_at(&self, f: &PointFields, x: f64, y: f64, t: f64) -> f64 {
        let s = |v: f64| [v, 0.0, 0.0];
        let variables = [
            s(x),
            s(y),
            s(t),
            s(f.strain_energy_density),
            [f.velocity[0], f.velocity[1], 0.0],
            [f.displacement[0], f.displacement[1], 0.0],
            s(f.strain[0]),
            s(f.strain[1]),
            s(f.strain[2]),
        ];
        let gradients = [[f.speed_gradient[0], f.speed_gradient[1], 0.0]];
        self.expression.eval(&Inputs { values: &[f.speed], gradients: &gradients, variables: &variables })
    }

    /// The GLSL source of the derived-field slice shader: `slice.frag` with this expression
    /// spliced in.
    pub fn fragment_source(&self) -> String {
        format!(
            "#version 450\n#define SPACETIME_EXPRESSION\n{}#include \"spacetime_slice_frag.glsl\"\n",
            self.expression.glsl("spacetime_expression")
        )
    }

    /// Compiles [`Self::fragment_source`] to SPIR-V through the `shaderc` crate; without the
    /// `runtime-shaderc` feature, an error saying how to build with it.
    pub fn compile_fragment(&self) -> Result<Vec<u32>, String> {
        #[cfg(feature = "runtime-shaderc")]
        {
            crate::gpu::shaders::compile_glsl(
                &self.fragment_source(),
                "derived_slice.frag",
                shaderc::ShaderKind::Fragment,
            )
            .map_err(|e| {
                format!(
                    "--expr {:?}: the shader compiler refused the derived field: {e}",
                    self.expression.text
                )
            })
        }
        #[cfg(not(feature = "runtime-shaderc"))]
        {
            Err(format!(
                "--expr {:?} needs run-time shader compilation: build with `--features runtime-shaderc` \
                 (scripts/install-deps.sh --shaderc installs the system's shaderc and glslang)",
                self.expression.text
            ))
        }
    }
}
