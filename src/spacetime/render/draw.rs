//! The drawing half of [`SpacetimeRenderer`] (seed 003 §4.2.2–4.3): the fill and edge
//! pipelines, the colour ramp's U_max (a data pass reduced on the device), and the draws —
//! into a caller's render pass, an offscreen image, or a timed frame.

use crate::gpu::Recorder;
use ash::vk;

use super::*;

impl SpacetimeRenderer {
    /// Makes the fill and edge pipelines for `target`'s render pass on first use, and their
    /// bindings (the window, the colour map, the materials, the slice cubics) whenever they were
    /// dropped because the window was reallocated — rebinding, not recompiling.
    pub(super) fn pipelines_for(&mut self, target: &DrawTarget<'_>) -> Result<(), SpacetimeError> {
        let format = target.key();
        if !self.pipelines.contains_key(&format) {
            target.require_depth("a spacetime slice").map_err(dev("building the slice pipelines"))?;
            let make = |lines: bool| -> Result<GraphicsPipeline, SpacetimeError> {
                let fragment = match &self.derived {
                    Some((_, spirv)) => &spirv[..],
                    None => crate::spacetime::shaders::SLICE_FRAG,
                };
                let mut desc = GraphicsPipelineDesc::new(
                    if lines { "spacetime slice edges" } else { "spacetime slice" },
                    crate::spacetime::shaders::SLICE_VERT,
                    fragment,
                    target.render_pass(),
                );
                desc.bindings = &[
                    BindingKind::StorageBuffer,
                    BindingKind::Texture,
                    BindingKind::StorageBuffer,
                    BindingKind::StorageBuffer,
                ];
                desc.push = crate::gpu::PushLayout::of::<DrawPush>();
                desc.vertex_stride = std::mem::size_of::<SliceVertex>() as u32;
                desc.vertex_attributes = &[
                    (0, vk::Format::R32G32_SFLOAT, 0),
                    (1, vk::Format::R32_UINT, 8),
                    (2, vk::Format::R32_SFLOAT, 12),
                ];
                if lines {
                    desc.topology = vk::PrimitiveTopology::LINE_LIST;
                }
                GraphicsPipeline::new(&self.gpu, &desc).map_err(dev("building the slice pipelines"))
            };
            let pair = (make(false)?, make(true)?);
            self.pipelines.insert(format, pair);
        }
        if !self.draw_sets.contains_key(&format) {
            let window = self.window.as_ref().expect("made resident before drawing");
            let bindings = [
                Resource::Storage(window.buffer.binding().map_err(dev("binding elements"))?),
                self.colormap.resource(),
                Resource::Storage(self.materials.binding().map_err(dev("binding materials"))?),
                Resource::Storage(window.cubics.binding().map_err(dev("binding the slice cubics"))?),
            ];
            let (fill, edges) = &self.pipelines[&format];
            let bind = |p: &GraphicsPipeline| {
                p.bind(&self.gpu, &bindings).map_err(dev("binding the slice pipelines"))
            };
            let sets = (bind(fill)?, bind(edges)?);
            self.draw_sets.insert(format, sets);
        }
        Ok(())
    }

    /// The colour ramp's `U_max` for `view`: its own, or the largest U over the slice's
    /// pixels, from a data pass of the same view into a float target kept for the next frame
    /// of the same size, reduced on the device (on the host when the image exceeds one storage
    /// binding).
    pub(super) fn resolve_u_max(
        &mut self,
        target: &DrawTarget<'_>,
        view: &SpacetimeView,
    ) -> Result<f64, SpacetimeError> {
        if self.derived.is_some() {
            return self.resolve_derived_range(target, view);
        }
        match view.u_max {
            Some(u) => Ok(u),
            None if target.format() == ColorFormat::Rgba32F => Ok(1.0),
            None => {
                let data = self.data_pass_target(target)?;
                let data_view = SpacetimeView { u_max: Some(1.0), ..*view };
                self.slice(view.time, view.subdivide)?;
                let u_max = if data.readback_bytes() <= self.gpu.max_binding_bytes() {
                    self.data_pass_max_u(&data, &data_view)
                } else {
                    // Larger than one binding: read the pixels back and take the maximum here.
                    match self.render(&data, &data_view) {
                        Ok(Pixels::Rgba32F(v)) => Ok(v
                            .chunks_exact(4)
                            .map(|p| f64::from(p[0]))
                            .filter(|u| u.is_finite())
                            .fold(0.0, f64::max)),
                        Ok(Pixels::Rgba8(_)) => unreachable!("a float target"),
                        Err(e) => Err(e),
                    }
                };
                self.umax_target = Some(data);
                u_max
            }
        }
    }

    /// The float target of a data pass at `target`'s size (for U_max or a derived field's
    /// range): the one kept from the last pass when the size is the same (give it back to
    /// `umax_target` when done).
    pub(super) fn data_pass_target(
        &mut self,
        target: &DrawTarget<'_>,
    ) -> Result<RenderTarget, SpacetimeError> {
        let extent = target.extent();
        Ok(match self.umax_target.take() {
            Some(d) if d.extent() == extent => d,
            _ => RenderTarget::new(
                &self.gpu,
                "spacetime data pass",
                extent.width,
                extent.height,
                ColorFormat::Rgba32F,
            )
            .map_err(dev("the data pass's target"))?,
        })
    }

    /// Draws the data pass of `view` into the float target `data` and reduces its U channel to
    /// the maximum on the device (`max_u.comp`); reads back 4 bytes.
    pub(super) fn data_pass_max_u(
        &mut self,
        data: &RenderTarget,
        view: &SpacetimeView,
    ) -> Result<f64, SpacetimeError> {
        let pixels = (data.extent().width as u64) * (data.extent().height as u64);
        if self.umax_pixels.as_ref().is_none_or(|b| b.len() != pixels) {
            self.umax_pixels = Some(
                Buffer::new(
                    &self.gpu,
                    "U_max pixels",
                    pixels,
                    vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                    MemoryKind::GpuOnly,
                )
                .map_err(dev("the U_max pass"))?,
            );
            self.umax_set = None;
        }
        if self.umax_set.is_none() {
            let pix =
                self.umax_pixels.as_ref().expect("made above").binding().map_err(dev("the U_max pass"))?;
            let res = self.umax_result.binding().map_err(dev("the U_max pass"))?;
            self.umax_set = Some(
                self.umax_reducer
                    .bind(&self.gpu, &[Resource::Storage(pix), Resource::Storage(res)])
                    .map_err(dev("the U_max pass"))?,
            );
        }
        let push = self.draw_push(&data.draw_target(), view, 1.0);
        let gpu = self.gpu.clone();
        self.pipelines_for(&data.draw_target())?;
        let draw = self.draw_commands(&data.draw_target(), view, &push);
        let pix = self.umax_pixels.as_ref().expect("made above");
        let (reducer, set, result) =
            (&self.umax_reducer, self.umax_set.as_ref().expect("bound above"), &self.umax_result);
        gpu.run(|rec| {
            data.record_begin(rec, [f32::NAN; 4]);
            draw(rec);
            data.record_end(rec);
            data.record_readback(rec, pix);
            rec.fill_buffer(result, 0);
            let n = pixels as u32;
            reducer.record_dispatch(rec, set, &MaxUPush { n }, [64, 1, 1]);
        })
        .map_err(dev("the U_max pass"))?;
        let bits = self.umax_result.download(&self.gpu).map_err(dev("reading U_max"))?;
        Ok(f64::from(f32::from_bits(bits[0])))
    }

    pub(super) fn draw_push(&self, target: &DrawTarget<'_>, view: &SpacetimeView, u_max: f64) -> DrawPush {
        let height_scale = view.height_scale.unwrap_or_else(|| self.default_height_scale());
        let eye = view.camera.eye.map(|x| x as f32);
        DrawPush {
            view_proj: view.camera.view_proj_f32(target.aspect()).to_cols_array(),
            eye_t: [eye[0], eye[1], eye[2], view.time as f32],
            light_scale: [LIGHT[0] as f32, LIGHT[1] as f32, LIGHT[2] as f32, height_scale as f32],
            ramp: [u_max as f32, self.colormap.texels() as f32, 0.0, self.derived_lo as f32],
            flags: [
                match (target.format(), view.unshaded) {
                    (ColorFormat::Rgba32F, _) => 1,
                    (_, true) => 2,
                    (_, false) => 0,
                },
                u32::from(view.height),
                u32::from(view.per_vertex),
                0,
            ],
        }
    }

    /// The draws of the current slice into `target` (making its pipelines first).
    pub(super) fn record_draw(
        &mut self,
        target: &DrawTarget<'_>,
        view: &SpacetimeView,
        push: &DrawPush,
    ) -> Result<impl FnOnce(&mut Recorder<'_>) + '_, SpacetimeError> {
        self.check_derived_view(view)?;
        self.pipelines_for(target)?;
        Ok(self.draw_commands(target, view, push))
    }

    /// The draws of the current slice (polygons, then edges if on) for a target whose pipelines
    /// exist ([`Self::pipelines_for`]).
    pub(super) fn draw_commands(
        &self,
        target: &DrawTarget<'_>,
        view: &SpacetimeView,
        push: &DrawPush,
    ) -> impl FnOnce(&mut Recorder<'_>) + '_ {
        let (tris, lines, draws) = (&self.tris, &self.lines, &self.draws);
        let extent = target.viewport();
        let edges_on = view.edges;
        let (push, edge_push) = (*push, push.for_edges());
        let (fill, edges) = &self.pipelines[&target.key()];
        let (fill_set, edges_set) = &self.draw_sets[&target.key()];
        move |rec| {
            fill.record_draw_indirect(
                rec,
                extent,
                fill_set,
                &push,
                Some(tris.whole()),
                draws.binding_range(crate::gpu::Chunk { first: 0, len: 4 }),
            );
            if edges_on {
                let bytes = &edge_push;
                let second = draws.binding_range(crate::gpu::Chunk { first: 4, len: 4 });
                edges.record_draw_indirect(rec, extent, edges_set, bytes, Some(lines.whole()), second);
            }
        }
    }

    /// The colour ramp's `U_max` for `view` in a colour `target`: the view's own, or the
    /// largest U over the slice's pixels (a data pass at the target's size). For callers that
    /// fix the ramp once, e.g. while animating t.
    pub fn u_max_for<'a>(
        &mut self,
        target: impl Into<DrawTarget<'a>>,
        view: &SpacetimeView,
    ) -> Result<f64, SpacetimeError> {
        self.slice(view.time, view.subdivide)?;
        self.resolve_u_max(&target.into(), view)
    }

    /// Records the draw of the current slice (see [`Self::slice`]; slice at `view.time` first)
    /// inside `target`'s render pass, begun and ended by the caller, in its viewport — an
    /// engine target ([`RenderTarget::draw_target`]) or a host's render pass
    /// ([`crate::gpu::RenderPass::from_host`]). It reads the slice's vertex streams (vertex
    /// input) and indirect commands, whose writes the slicing pass made visible to those
    /// stages, and writes only the colour and depth attachments of its viewport.
    pub fn record_draw_into(
        &mut self,
        rec: &mut Recorder<'_>,
        target: DrawTarget<'_>,
        view: &SpacetimeView,
        u_max: f64,
    ) -> Result<(), SpacetimeError> {
        let push = self.draw_push(&target, view, u_max);
        let draw = self.record_draw(&target, view, &push)?;
        draw(rec);
        Ok(())
    }

    /// Renders `view` into `target` (slicing first if needed) and returns the pixels: lit
    /// colours in an RGBA8 target, `(U, |v|, n_x, n_y)` in an RGBA32F target.
    pub fn render(&mut self, target: &RenderTarget, view: &SpacetimeView) -> Result<Pixels, SpacetimeError> {
        self.slice(view.time, view.subdivide)?;
        let u_max = self.resolve_u_max(&target.draw_target(), view)?;
        let push = self.draw_push(&target.draw_target(), view, u_max);
        let gpu = self.gpu.clone();
        let draw = self.record_draw(&target.draw_target(), view, &push)?;
        target.render(&gpu, clear_colour(target), |rec| draw(rec)).map_err(dev("drawing the slice"))
    }

    /// One frame as an interactive loop runs it: the slice (always redone, as when `t`
    /// advances) and the draw in one submission, without reading the image back; with a
    /// `profiler` (4 scopes), each stage's device time. `view.u_max` should be set (else a data
    /// pass runs first, as in [`Self::render`]).
    pub fn frame(
        &mut self,
        target: &RenderTarget,
        view: &SpacetimeView,
        mut profiler: Option<&mut Profiler>,
    ) -> Result<(SliceStats, Option<FrameTimes>), SpacetimeError> {
        let drawn = target.draw_target();
        let u_max = self.resolve_u_max(&drawn, view)?;
        self.sliced = None;
        let active = self.data.active_range(view.time);
        let streamed = self.make_resident(active.clone())?;
        let push = self.draw_push(&drawn, view, u_max);
        let gpu = self.gpu.clone();
        loop {
            self.bind_slicer()?;
            self.pipelines_for(&drawn)?;
            let slice_push = self.slice_push(view.time, view.subdivide, &active);
            let clear = clear_colour(target);
            {
                let mut profiler = profiler.as_deref_mut();
                let slicer = &*self;
                let commands = slicer.draw_commands(&drawn, view, &push);
                gpu.run(|rec| {
                    if let Some(p) = profiler.as_deref_mut() {
                        p.record_reset(rec);
                    }
                    slicer.record_slice(rec, &slice_push, profiler.as_deref_mut());
                    let draw = |rec: &mut Recorder<'_>| {
                        target.record_begin(rec, clear);
                        commands(rec);
                        target.record_end(rec);
                    };
                    match profiler {
                        Some(p) => p.scope(rec, "draw", draw),
                        None => draw(rec),
                    }
                })
                .map_err(dev("drawing a frame"))?;
            }
            if let Some(stats) = self.finish_slice(active.len(), streamed)? {
                self.sliced = Some((view.time, view.subdivide, stats));
                let times = match profiler {
                    Some(p) => {
                        let r = p.results().map_err(dev("reading timestamps"))?;
                        let get = |name: &str| r.iter().find(|(n, _)| n == name).map_or(0.0, |(_, ms)| *ms);
                        Some(FrameTimes {
                            slice_ms: get("slice"),
                            subdivide_ms: get("subdivide"),
                            draw_ms: get("draw"),
                        })
                    }
                    None => None,
                };
                return Ok((stats, times));
            }
        }
    }
}

/// What a spacetime slice is drawn with ([`crate::render::Draw`] for [`SpacetimeRenderer`]):
/// the view and the colour ramp's `U_max` (from [`SpacetimeRenderer::u_max_for`], or fixed).
/// The trait's prepass records nothing: the slice is recorded by
/// [`SpacetimeRenderer::record_slice_into`], which needs the engine's transfers first
/// ([`SpacetimeRenderer::prepare_slice`]), or made by [`SpacetimeRenderer::slice`].
#[derive(Clone, Copy, Debug)]
pub struct SpacetimeDraw {
    /// How the slice is shown.
    pub view: SpacetimeView,
    /// The colour ramp's top.
    pub u_max: f64,
}

impl crate::render::Draw for SpacetimeRenderer {
    type View<'v> = SpacetimeDraw;
    type Error = SpacetimeError;

    fn device_error(context: &'static str, cause: crate::gpu::GpuError) -> SpacetimeError {
        SpacetimeError::device(context)(cause)
    }

    /// [`SpacetimeRenderer::record_draw_into`] of the current slice.
    fn record_draw_into(
        &mut self,
        rec: &mut Recorder<'_>,
        target: DrawTarget<'_>,
        draw: &SpacetimeDraw,
    ) -> Result<(), SpacetimeError> {
        SpacetimeRenderer::record_draw_into(self, rec, target, &draw.view, draw.u_max)
    }
}
