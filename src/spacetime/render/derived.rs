//! Derived fields on spacetime slices (`--expr`, [`SpacetimeExpression`]): the slice shader
//! with the expression spliced in, compiled at run time, and the colour range it maps.

use std::sync::Arc;

use super::{SpacetimeError, SpacetimeRenderer, SpacetimeView};
use crate::expression::spacetime::SpacetimeExpression;
use crate::render::{ColorFormat, DrawTarget, Pixels};

impl SpacetimeRenderer {
    /// Shows `expression` instead of U (None: U again), mapped linearly over `range` — or,
    /// without one, over the least and greatest value of each drawn slice's pixels (a data
    /// pass first, as for U_max). Compiles the slice shader (`runtime-shaderc`) and drops the
    /// pipelines made for the previous one.
    pub fn set_expression(
        &mut self,
        expression: Option<Arc<SpacetimeExpression>>,
        range: Option<(f64, f64)>,
    ) -> Result<(), SpacetimeError> {
        let same = match (&self.derived, &expression) {
            (Some(((a, _), _)), Some(b)) => a.expression.text == b.expression.text,
            (None, None) => true,
            _ => false,
        };
        if let Some((lo, hi)) = range {
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                return Err(SpacetimeError::Request(format!(
                    "the colour range [{lo}, {hi}] is not an interval"
                )));
            }
            // A host's draw (record_draw_into) resolves no range: the fixed one's low end
            // must be in place for it.
            self.derived_lo = lo;
        }
        if same {
            if let Some(d) = self.derived.as_mut() {
                d.0 .1 = range;
            }
            return Ok(());
        }
        self.derived = match expression {
            Some(e) => {
                let spirv = e.compile_fragment().map_err(SpacetimeError::Request)?;
                Some(((e, range), spirv))
            }
            None => None,
        };
        self.pipelines.clear();
        self.draw_sets.clear();
        Ok(())
    }

    /// The derived field shown, if any.
    pub fn expression(&self) -> Option<&SpacetimeExpression> {
        self.derived.as_ref().map(|d| &*d.0 .0)
    }

    /// The derived field's colour range (lo, hi) for `view` in a colour `target`: the fixed
    /// one, or the slice's own (a data pass). For callers that show it in a legend and then
    /// fix it ([`Self::set_expression`] with the range).
    pub fn derived_range_for<'a>(
        &mut self,
        target: impl Into<DrawTarget<'a>>,
        view: &SpacetimeView,
    ) -> Result<(f64, f64), SpacetimeError> {
        self.slice(view.time, view.subdivide)?;
        let hi = self.resolve_derived_range(&target.into(), view)?;
        Ok((self.derived_lo, hi))
    }

    /// Refuses what a derived field cannot be drawn with: per-vertex colour (the vertices
    /// carry U).
    pub(super) fn check_derived_view(&self, view: &SpacetimeView) -> Result<(), SpacetimeError> {
        match &self.derived {
            Some(((e, _), _)) if view.per_vertex => Err(SpacetimeError::Request(format!(
                "--expr {:?} is evaluated per pixel; it cannot be drawn per vertex",
                e.expression.text
            ))),
            _ => Ok(()),
        }
    }

    /// The derived field's colour range for `view`: the fixed one, or the least and greatest
    /// finite value over a data pass of the slice at the target's size (read back). Sets the
    /// low end for the draw and returns the high end. Data targets need none.
    pub(super) fn resolve_derived_range(
        &mut self,
        target: &DrawTarget<'_>,
        view: &SpacetimeView,
    ) -> Result<f64, SpacetimeError> {
        let Some(((_, range), _)) = &self.derived else { return Ok(1.0) };
        if let Some((lo, hi)) = *range {
            self.derived_lo = lo;
            return Ok(hi);
        }
        if target.format() == ColorFormat::Rgba32F {
            return Ok(1.0);
        }
        let data = self.data_pass_target(target)?;
        let data_view = SpacetimeView { u_max: Some(1.0), ..*view };
        let pixels = self.render(&data, &data_view);
        self.umax_target = Some(data);
        let Pixels::Rgba32F(v) = pixels? else {
            return Err(SpacetimeError::Request("a float target returned bytes".into()));
        };
        let (lo, hi) = v
            .chunks_exact(4)
            .map(|p| f64::from(p[0]))
            .filter(|u| u.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), u| (lo.min(u), hi.max(u)));
        let (lo, hi) = if lo <= hi { (lo, hi) } else { (0.0, 1.0) };
        self.derived_lo = lo;
        Ok(if hi > lo { hi } else { lo + 1.0 })
    }
}
