//! Surfaces in 3D and height fields: the bounds that set each element's tessellation level, the
//! compute pass that tessellates (`tessellate.comp`), and its counts checked against the CPU
//! twin of the level.

use ash::vk;

use super::*;

impl SpectralRenderer {
    /// The height scale `view` asks for (planar meshes), its automatic value resolved.
    pub fn height_scale(&mut self, view: &SpectralView) -> Option<f64> {
        let scale = view.height.filter(|_| self.planar)?;
        if scale != 0.0 {
            return Some(scale);
        }
        let (lo, hi) = self.range(view);
        let (a, b) = self.bounds;
        Some(0.25 * (b[0] - a[0]) / (hi - lo).max(1e-300))
    }

    /// Uploads the patches `view` needs: the height field's when it shows one.
    pub(super) fn patches_for_view(&mut self, view: &SpectralView) -> Result<()> {
        let want = self.height_scale(view).map(|s| (view.field, view.step, s.to_bits()));
        if want == self.patches_for || self.patch_bounds.is_empty() {
            return Ok(());
        }
        self.patch_bounds = match want {
            Some((f, step, s)) => proxy::height_patches(&self.mesh, f, step, f64::from_bits(s)),
            None => proxy::surface_patches(&self.mesh),
        };
        self._patches.upload(&self.gpu, 0, &self.patch_bounds).map_err(dev("uploading the patches"))?;
        self.patches_for = want;
        Ok(())
    }

    /// A camera that shows the height field of `view` (its box, z from the scaled range).
    pub(super) fn height_camera(&mut self, view: &SpectralView, scale: f64) -> Camera {
        let (lo, hi) = self.range(view);
        let (mut a, mut b) = self.bounds;
        a[2] = (scale * lo).min(scale * hi);
        b[2] = (scale * lo).max(scale * hi);
        camera_for_box(a, b)
    }

    /// The inputs of a tessellation for `push` with the current patches.
    pub(super) fn tessellation_key_of(&self, push: &SpectralPush) -> TessellationKey {
        let mut k = [0u32; 22];
        for (i, v) in push.view_proj.iter().enumerate() {
            k[i] = v.to_bits();
        }
        k[16] = push.pixel_to_world[3].to_bits();
        k[17] = push.misc[2].to_bits();
        k[18] = push.misc[3].to_bits();
        let (field, step, scale) = self.patches_for.unwrap_or((usize::MAX, usize::MAX, 0));
        k[19] = field as u32;
        k[20] = step as u32;
        k[21] = (scale ^ (scale >> 32)) as u32;
        k
    }

    /// Each element's tessellation level for `push` by the CPU twin of `tessellate.comp`.
    fn cpu_levels<'a>(&'a self, push: &'a SpectralPush) -> impl Iterator<Item = u32> + 'a {
        let view_proj = Mat4::from_cols_array(&push.view_proj);
        self.patch_bounds.iter().map(move |p| {
            proxy::tessellation_level(p, &view_proj, push.pixel_to_world[3], push.misc[2], push.misc[3])
        })
    }

    /// Forgets the tessellation the vertex stream holds, so the next frame tessellates again
    /// (benchmarks of a moving camera).
    pub fn invalidate_tessellation(&mut self) {
        self.tessellation_key.set(None);
    }

    /// Makes room for this frame's surface tessellation (the CPU bound of the device's levels,
    /// one level of slack per element against f32 rounding) and binds the pass.
    pub(super) fn tessellator_for(&mut self, push: &SpectralPush) -> Result<()> {
        if self.tessellator.is_none() {
            let bindings = [BindingKind::StorageBuffer; 6];
            let pipeline = ComputePipeline::new(
                &self.gpu,
                &ComputePipelineDesc {
                    name: "spectral tessellation",
                    spirv: crate::spectral::shaders::TESSELLATE,
                    bindings: &bindings,
                    push: crate::gpu::PushLayout::of::<SpectralPush>(),
                    specialization: &self.specialization,
                },
            )
            .map_err(dev("building the tessellation pass"))?;
            let draw = Buffer::new(
                &self.gpu,
                "spectral tessellation draw",
                6,
                vk::BufferUsageFlags::STORAGE_BUFFER
                    | vk::BufferUsageFlags::INDIRECT_BUFFER
                    | vk::BufferUsageFlags::TRANSFER_DST
                    | vk::BufferUsageFlags::TRANSFER_SRC,
                MemoryKind::GpuOnly,
            )
            .map_err(dev("the tessellation pass"))?;
            self.tessellator = Some(Tessellator { pipeline, draw, vertices: None, set: None });
        }
        let shape = self.mesh.shape;
        // One level of slack against f32 rounding differences with the device.
        let need: u64 = self
            .cpu_levels(push)
            .map(|l| if l == 0 { 0 } else { tessellated_vertices(shape, l + 1) })
            .sum::<u64>()
            .max(6);
        let max = self.gpu.max_binding_bytes() / std::mem::size_of::<DrawVertex>() as u64;
        let need = need.min(max);
        self.tessellated = need;
        let mut t = self.tessellator.take().expect("made above");
        let grown = self.grow_tessellation(&mut t, need, max);
        let bound = grown.and_then(|()| self.bind_tessellation(&mut t));
        self.tessellator = Some(t);
        bound
    }

    /// Makes room for `need` tessellated vertices (at most `max`).
    fn grow_tessellation(&mut self, t: &mut Tessellator, need: u64, max: u64) -> Result<()> {
        if t.vertices.as_ref().is_none_or(|v| v.len() < need) {
            // Grow by half again, so a slowly moving camera does not reallocate every frame.
            let len = (need + need / 2).min(max);
            self.tessellation_key.set(None);
            t.set = None;
            t.vertices = None;
            t.vertices = Some(
                Buffer::new(
                    &self.gpu,
                    "spectral tessellated vertices",
                    len,
                    vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::VERTEX_BUFFER,
                    MemoryKind::GpuOnly,
                )
                .map_err(dev("the tessellation pass"))?,
            );
        }
        Ok(())
    }

    /// Binds the tessellation pass's resources, if not bound yet.
    fn bind_tessellation(&self, t: &mut Tessellator) -> Result<()> {
        if t.set.is_none() {
            let vertices = t.vertices.as_ref().expect("made above");
            let mut resources = self.resources()?;
            // Binding 2 (the colour map in the draws) is unused by the pass: bind the values.
            resources[2] = Resource::Storage(self.values.binding().map_err(dev("binding"))?);
            resources.push(Resource::Storage(t.draw.binding().map_err(dev("binding"))?));
            resources.push(Resource::Storage(vertices.binding().map_err(dev("binding"))?));
            t.set =
                Some(t.pipeline.bind(&self.gpu, &resources).map_err(dev("binding the tessellation pass"))?);
        }
        Ok(())
    }

    /// The last surface tessellation as the device did it: vertices written and elements
    /// skipped for want of room (0 unless the frame needed more than one storage binding);
    /// `None` before the first surface frame.
    pub fn last_tessellation(&self) -> Result<Option<(u32, u32)>> {
        let Some(t) = &self.tessellator else { return Ok(None) };
        let d = t.draw.download(&self.gpu).map_err(dev("reading the tessellation's counts"))?;
        Ok(Some((d[0], d[5])))
    }

    /// The vertices the CPU twin of the tessellation levels ([`proxy::tessellation_level`])
    /// gives `view` in `target`: [`tessellated_vertices`] per element.
    pub fn expected_tessellation(&mut self, target: &RenderTarget, view: &SpectralView) -> u64 {
        let push = self.push(&target.draw_target(), view);
        let shape = self.mesh.shape;
        self.cpu_levels(&push).map(|l| tessellated_vertices(shape, l)).sum()
    }
}

/// The vertices `tessellate.comp` writes for an element of `shape` at level `l`: 6 L² for a
/// quadrilateral (L² cells of two triangles), 3 L² for a triangle (L² triangles in L rows).
pub fn tessellated_vertices(shape: crate::spectral::Shape, l: u32) -> u64 {
    let per = if shape == crate::spectral::Shape::Triangle { 3 } else { 6 };
    per * u64::from(l) * u64::from(l)
}
