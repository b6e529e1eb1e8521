//! Cut planes through hexahedral meshes (the seed's future work, across many elements): the
//! pass that finds the crossed elements and draws a rectangle containing each section
//! (`cut.comp`), and the pipeline whose fragments pull their plane point back into the element
//! (`cut.vert`/`cut.frag`).

use crate::gpu::Recorder;
use std::collections::HashMap;

use ash::vk;

use super::*;

crate::push_constants! {
    /// `cut.comp`'s push constants.
    struct CutPush {
        elements: u32,
        points_per_element: u32,
    }
}

impl Cutter {
    pub(super) fn new(
        gpu: &Gpu,
        mesh: &SpectralMesh,
        points: &Buffer<[f32; 4]>,
        values: &Buffer<f32>,
        specialization: &[u32],
    ) -> Result<Self> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let hull = Buffer::from_slice(gpu, "spectral hulls", &proxy::bernstein_hull(mesh)?, storage)
            .map_err(dev("uploading"))?;
        let planes = Buffer::new(
            gpu,
            "spectral cut planes",
            MAX_CUT_PLANES as u64,
            storage | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryKind::GpuOnly,
        )
        .map_err(dev("the cut pass"))?;
        let draw = Buffer::new(
            gpu,
            "spectral cut draw",
            4,
            storage | vk::BufferUsageFlags::INDIRECT_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryKind::GpuOnly,
        )
        .map_err(dev("the cut pass"))?;
        let vertices = Buffer::new(
            gpu,
            "spectral cut rectangles",
            (mesh.elements() * MAX_CUT_PLANES * 6) as u64,
            storage | vk::BufferUsageFlags::VERTEX_BUFFER,
            MemoryKind::GpuOnly,
        )
        .map_err(dev("the cut pass"))?;
        let pass = ComputePipeline::new(
            gpu,
            &ComputePipelineDesc {
                name: "spectral cut",
                spirv: crate::spectral::shaders::CUT,
                bindings: &[BindingKind::StorageBuffer; 7],
                push: crate::gpu::PushLayout::of::<CutPush>(),
                specialization,
            },
        )
        .map_err(dev("building the cut pass"))?;
        let pass_set = Self::bind_pass(gpu, &pass, points, values, (&planes, &hull, &draw, &vertices))?;
        Ok(Self { pass, pass_set, planes, draw, vertices, _hull: hull, pipelines: HashMap::new() })
    }

    /// The cut pass's bindings: geometry, coefficients (read by the shared declarations of
    /// spectral_element.glsl), planes, hulls, the indirect draw and the rectangles.
    #[allow(clippy::type_complexity)]
    fn bind_pass(
        gpu: &Gpu,
        pass: &ComputePipeline,
        points: &Buffer<[f32; 4]>,
        values: &Buffer<f32>,
        (planes, hull, draw, vertices): (
            &Buffer<[f32; 4]>,
            &Buffer<[f32; 4]>,
            &Buffer<u32>,
            &Buffer<DrawVertex>,
        ),
    ) -> Result<DescriptorSet> {
        fn b(r: crate::gpu::GpuResult<crate::gpu::BufferBinding<'_>>) -> Result<Resource<'_>> {
            r.map(Resource::Storage).map_err(dev("binding"))
        }
        pass.bind(
            gpu,
            &[
                b(points.binding())?,
                b(values.binding())?,
                b(values.binding())?,
                b(planes.binding())?,
                b(hull.binding())?,
                b(draw.binding())?,
                b(vertices.binding())?,
            ],
        )
        .map_err(dev("binding the cut pass"))
    }

    /// Rebinds the cut pass to a new coefficient buffer (a derived field's, larger) and drops
    /// the draw pipelines' bindings with it.
    pub(super) fn rebind(
        &mut self,
        gpu: &Gpu,
        points: &Buffer<[f32; 4]>,
        values: &Buffer<f32>,
    ) -> Result<()> {
        let rest = (&self.planes, &self._hull, &self.draw, &self.vertices);
        self.pass_set = Self::bind_pass(gpu, &self.pass, points, values, rest)?;
        self.pipelines.clear();
        Ok(())
    }
}

/// Parses a cut plane as the command line gives it: `x=V`, `y=V`, `z=V` (the axis plane
/// through V) or `A,B,C,D` (the plane A x + B y + C z = D, normal not zero); the error names
/// the text and what is wrong.
pub fn parse_plane(s: &str) -> std::result::Result<[f64; 4], String> {
    let num = |v: &str| v.trim().parse::<f64>().ok().filter(|v| v.is_finite());
    if let Some((axis, v)) = s.split_once('=') {
        let v = num(v).ok_or_else(|| format!("{s:?}: {v:?} is not a number"))?;
        return match axis.trim() {
            "x" => Ok([1.0, 0.0, 0.0, v]),
            "y" => Ok([0.0, 1.0, 0.0, v]),
            "z" => Ok([0.0, 0.0, 1.0, v]),
            other => Err(format!("{s:?}: axis {other:?} is not x, y or z")),
        };
    }
    let parts: Vec<f64> =
        s.split(',').map(num).collect::<Option<_>>().ok_or_else(|| format!("{s:?}: not A,B,C,D"))?;
    match parts[..] {
        [a, b, c, d] if a != 0.0 || b != 0.0 || c != 0.0 => Ok([a, b, c, d]),
        [_, _, _, _] => Err(format!("{s:?}: the normal (A, B, C) is zero")),
        _ => Err(format!("{s:?}: expected x=V, y=V, z=V or A,B,C,D")),
    }
}

/// The offsets `d` (for the unit normal of plane `c` = (n, d)) between which a cut plane can
/// meet `mesh`: the range of n·x over the control points, widened by a twentieth of the data
/// set's size (a curved Lagrange element can bulge past its nodes; Bernstein ones cannot).
pub fn plane_span(mesh: &crate::spectral::SpectralMesh, c: [f64; 4]) -> (f64, f64) {
    let n = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
    let (lo, hi) = mesh.points.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
        let d = (c[0] * p[0] + c[1] * p[1] + c[2] * p[2]) / n;
        (a.min(d), b.max(d))
    });
    let (blo, bhi) = mesh.bounds();
    let margin = 0.05 * (0..3).map(|a| bhi[a] - blo[a]).fold(0.0, f64::max);
    (lo - margin, hi + margin)
}

impl SpectralRenderer {
    /// The cut planes of `view`, unit normals, as `cut.comp` reads them (default: z through the
    /// middle of the mesh).
    pub(super) fn cut_planes(&self, view: &SpectralView) -> Result<Vec<[f32; 4]>> {
        if view.cuts.len() > MAX_CUT_PLANES {
            return Err(SpectralError::Missing(format!(
                "{} cut planes; at most {MAX_CUT_PLANES}",
                view.cuts.len()
            )));
        }
        let (lo, hi) = self.bounds;
        let default = vec![[0.0, 0.0, 1.0, 0.5 * (lo[2] + hi[2])]];
        let cuts = if view.cuts.is_empty() { &default } else { &view.cuts };
        cuts.iter()
            .enumerate()
            .map(|(k, c)| {
                let n = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
                if !(n.is_finite() && n > 0.0 && c[3].is_finite()) {
                    return Err(SpectralError::Missing(format!("cut plane {k}: {c:?} has no direction")));
                }
                // A plane that misses every element would draw nothing: refused.
                let (lo_d, hi_d) = plane_span(&self.mesh, *c);
                let d = c[3] / n;
                if d < lo_d || d > hi_d {
                    return Err(SpectralError::Missing(format!(
                        "cut plane {k} ({}x + {}y + {}z = {}) misses the mesh: along its normal the mesh spans {lo_d:.6} to {hi_d:.6}",
                        c[0], c[1], c[2], c[3]
                    )));
                }
                Ok([(c[0] / n) as f32, (c[1] / n) as f32, (c[2] / n) as f32, (c[3] / n) as f32])
            })
            .collect()
    }

    pub(super) fn cut_pipeline_for(&mut self, target: &DrawTarget<'_>, view: &SpectralView) -> Result<()> {
        let format = (target.key(), view.expression_key());
        if self.cutter.as_ref().is_none_or(|c| c.pipelines.contains_key(&format)) {
            return Ok(());
        }
        if let Some(d) = &view.expression {
            self.derived_shader(d)?;
        }
        let Some(c) = self.cutter.as_ref() else { return Ok(()) };
        target.require_depth("cut planes").map_err(dev("building the cut pipeline"))?;
        let planes = Resource::Storage(c.planes.binding().map_err(dev("binding"))?);
        let fragment = match &format.1 {
            Some(text) => &self.derived_shaders[text][..],
            None => crate::spectral::shaders::CUT_FRAG,
        };
        let desc =
            self.draw_desc("spectral cut planes", crate::spectral::shaders::CUT_VERT, fragment, target);
        let pipeline = GraphicsPipeline::new(&self.gpu, &desc).map_err(dev("building the cut pipeline"))?;
        let r = self.resources()?;
        let resources = [r[0], r[1], r[2], planes];
        let set = pipeline.bind(&self.gpu, &resources).map_err(dev("binding the cut pipeline"))?;
        let c = self.cutter.as_mut().expect("checked above");
        c.pipelines.insert(format, (pipeline, set));
        Ok(())
    }

    #[allow(clippy::type_complexity)]
    pub(super) fn prepare_cuts(
        &mut self,
        target: &DrawTarget<'_>,
        view: &SpectralView,
    ) -> Result<(Box<dyn FnOnce(&mut Recorder<'_>) + '_>, Box<dyn FnOnce(&mut Recorder<'_>) + '_>)> {
        self.check_derived_view(view)?;
        self.show(view)?;
        self.cut_pipeline_for(target, view)?;
        let planes = self.cut_planes(view)?;
        let push = self.push(target, view);
        let c = self.cutter.as_ref().expect("a hexahedral mesh has a cutter");
        let (pipeline, set) = &c.pipelines[&(target.key(), view.expression_key())];
        let extent = target.viewport();
        let cut_push = CutPush {
            elements: self.mesh.elements() as u32,
            points_per_element: self.mesh.points_per_element() as u32,
        };
        let pre = move |rec: &mut Recorder<'_>| {
            // The updates wait for the last frame's reads (declared accesses).
            let header: [u32; 4] = [0, 1, 0, 0];
            rec.update_buffer(&c.draw, 0, &header);
            // At most MAX_CUT_PLANES planes (checked in cut_planes): inside the buffer.
            rec.update_buffer(&c.planes, 0, &planes);
            let groups = (cut_push.elements.div_ceil(c.pass.local_size()[0]), planes.len() as u32, 1);
            c.pass.record_dispatch(rec, &c.pass_set, &cut_push, [groups.0, groups.1, groups.2]);
            // The draw's reads, declared before its render pass.
            pipeline.declare_draw(rec, set, Some(c.vertices.whole()), Some(c.draw.whole()));
        };
        let draw = move |rec: &mut Recorder<'_>| {
            let bytes = &push;
            pipeline.record_draw_indirect(rec, extent, set, bytes, Some(c.vertices.whole()), c.draw.whole());
        };
        Ok((Box::new(pre), Box::new(draw)))
    }
}

#[cfg(test)]
mod tests {
    use super::parse_plane;

    #[test]
    fn planes_parse_as_axis_planes_or_coefficients_and_bad_ones_say_why() {
        assert_eq!(parse_plane("z=0.5"), Ok([0.0, 0.0, 1.0, 0.5]));
        assert_eq!(parse_plane(" x = -2"), Ok([1.0, 0.0, 0.0, -2.0]));
        assert_eq!(parse_plane("1,0.7,2,0.9"), Ok([1.0, 0.7, 2.0, 0.9]));
        for (bad, why) in [
            ("w=1", "axis \"w\""),
            ("z=nan", "not a number"),
            ("0,0,0,1", "normal (A, B, C) is zero"),
            ("1,2,3", "expected x=V"),
            ("1,a,3,4", "not A,B,C,D"),
        ] {
            let err = parse_plane(bad).expect_err(bad);
            assert!(err.contains(why) && err.contains(bad), "{bad}: {err}");
        }
    }
}
