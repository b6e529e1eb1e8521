//! Isosurfaces of solid meshes (hexahedra and tetrahedra), per pixel: each element's box is
//! drawn (`iso.vert`), and each fragment on the box's far side casts the pixel's ray through the
//! element (where the ray lies in its hull, [`super::element_hull_planes`]), finds the first root of f − c for the view's iso values and draws it at its own
//! depth with the exact normal (`iso.frag`). The f64 reference is
//! [`crate::spectral::reference::iso_reference`].

use std::collections::HashMap;

use ash::vk;

use super::*;
use crate::gpu::Recorder;

/// The most iso values one view can have.
pub const MAX_ISO_VALUES: usize = 8;

/// Bindings of the isosurface pipeline: geometry, coefficients, colour map, element boxes,
/// iso values, element hulls.
const ISO_BINDINGS: [BindingKind; 6] = [
    BindingKind::StorageBuffer,
    BindingKind::StorageBuffer,
    BindingKind::Texture,
    BindingKind::StorageBuffer,
    BindingKind::StorageBuffer,
    BindingKind::StorageBuffer,
];

/// The isosurface pass's buffers and pipelines.
pub(super) struct IsoPass {
    /// Per element its box's 12 triangles.
    vertices: Buffer<DrawVertex>,
    count: u32,
    /// Per element (lo, f_lo), (hi, f_hi): its box, and an interval holding its field's values
    /// ([`proxy::value_bounds`]) for the field and step in `bounds_of`.
    boxes: Buffer<[f32; 4]>,
    /// The box corners without the value bounds.
    corners: Vec<[f32; 4]>,
    /// The (field, step) whose value bounds `boxes` holds.
    bounds_of: Option<(usize, usize)>,
    /// The count, then up to [`MAX_ISO_VALUES`] values (f32 bits).
    values: Buffer<u32>,
    /// Per element its hull's [`super::HULL_PLANES`] half-spaces ([`super::element_hull_planes`]).
    hulls: Buffer<[f32; 4]>,
    /// Per target and whether it colours by a second field (`iso_colour.frag`).
    pub(super) pipelines: HashMap<(PassKey, bool), (GraphicsPipeline, DescriptorSet)>,
}

/// Per element of a solid mesh, the box of its Bernstein control points (which contains it),
/// grown by 8 f32 ulps of the coordinates' size: (lo, 0), (hi, 0) (the isosurface pass puts
/// the element's value bounds in the zeros).
pub fn element_boxes(mesh: &SpectralMesh) -> Result<Vec<[f32; 4]>> {
    let hull = proxy::bernstein_hull(mesh)?;
    let per = mesh.points_per_element();
    let mut out = Vec::with_capacity(2 * mesh.elements());
    for e in 0..mesh.elements() {
        let points: Vec<[f64; 3]> =
            hull[e * per..(e + 1) * per].iter().map(|p| [p[0], p[1], p[2]].map(f64::from)).collect();
        let (lo, hi) = super::super::mesh::bounds_of(&points);
        let size = lo.iter().chain(&hi).fold(0.0f64, |a, c| a.max(c.abs()));
        let slack = 8.0 * f64::from(f32::EPSILON) * size;
        out.push([(lo[0] - slack) as f32, (lo[1] - slack) as f32, (lo[2] - slack) as f32, 0.0]);
        out.push([(hi[0] + slack) as f32, (hi[1] + slack) as f32, (hi[2] + slack) as f32, 0.0]);
    }
    Ok(out)
}

/// The six faces of a box or hexahedron by corner (corner k at (k & 1, k >> 1 & 1, k >> 2 & 1)),
/// each around its boundary.
pub(super) const BOX_FACES: [[usize; 4]; 6] =
    [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]];

/// The 12 triangles of each element's box, every vertex tagged with its element.
fn box_triangles(boxes: &[[f32; 4]]) -> Vec<DrawVertex> {
    let mut out = Vec::with_capacity(boxes.len() / 2 * 36);
    for (e, b) in boxes.chunks_exact(2).enumerate() {
        let corner = |k: usize| -> [f32; 3] {
            std::array::from_fn(|a| if k >> a & 1 == 1 { b[1][a] } else { b[0][a] })
        };
        for f in BOX_FACES {
            for k in [f[0], f[1], f[2], f[0], f[2], f[3]] {
                out.push(DrawVertex { position: corner(k), reference: [0.0; 2], element: e as u32 });
            }
        }
    }
    out
}

impl SpectralRenderer {
    /// Checks an isosurface view: a solid mesh, 1 to [`MAX_ISO_VALUES`] finite values, no
    /// derived field, no cut planes.
    pub(super) fn check_iso_view(&self, view: &SpectralView) -> Result<()> {
        if !self.mesh.shape.is_volume() {
            return Err(SpectralError::Missing(format!(
                "isosurfaces are drawn for hexahedral and tetrahedral meshes; this one is of {:?}s",
                self.mesh.shape
            )));
        }
        if view.iso.len() > MAX_ISO_VALUES {
            return Err(SpectralError::Missing(format!(
                "{} iso values; at most {MAX_ISO_VALUES}",
                view.iso.len()
            )));
        }
        if let Some(v) = view.iso.iter().find(|v| !v.is_finite()) {
            return Err(SpectralError::Missing(format!("iso value {v} is not a finite number")));
        }
        if let Some(k) = view.colour_by {
            if k >= self.mesh.fields.len() || view.step >= self.mesh.fields[k].steps.len() {
                return Err(SpectralError::Missing(format!(
                    "isosurfaces coloured by field {k}: there is no such field with step {}",
                    view.step
                )));
            }
        }
        if view.expression.is_some() || !view.cuts.is_empty() {
            return Err(SpectralError::Missing(
                "isosurfaces of derived fields, and isosurfaces together with cut planes, are not drawn yet"
                    .into(),
            ));
        }
        Ok(())
    }

    fn iso_pipeline_for(&mut self, target: &DrawTarget<'_>, coloured: bool) -> Result<()> {
        if self.iso.is_none() {
            let boxes = element_boxes(&self.mesh)?;
            let triangles = box_triangles(&boxes);
            let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
            let vertices = Buffer::from_slice(
                &self.gpu,
                "spectral iso boxes",
                &triangles,
                vk::BufferUsageFlags::VERTEX_BUFFER,
            )
            .map_err(dev("uploading the element boxes"))?;
            let box_buffer =
                Buffer::from_slice(&self.gpu, "spectral boxes", &boxes, storage).map_err(dev("uploading"))?;
            let planes = super::element_hull_planes(&self.mesh)?;
            let hulls = Buffer::from_slice(&self.gpu, "spectral element hulls", &planes, storage)
                .map_err(dev("uploading the element hulls"))?;
            let values = Buffer::new(
                &self.gpu,
                "spectral iso values",
                (1 + MAX_ISO_VALUES) as u64,
                storage | vk::BufferUsageFlags::TRANSFER_DST,
                MemoryKind::GpuOnly,
            )
            .map_err(dev("the isosurface pass"))?;
            self.iso = Some(IsoPass {
                vertices,
                count: triangles.len() as u32,
                boxes: box_buffer,
                corners: boxes,
                bounds_of: None,
                values,
                hulls,
                pipelines: HashMap::new(),
            });
        }
        let key = (target.key(), coloured);
        if self.iso.as_ref().is_some_and(|i| i.pipelines.contains_key(&key)) {
            return Ok(());
        }
        target.require_depth("isosurfaces").map_err(dev("building the isosurface pipeline"))?;
        let mut desc = self.draw_desc(
            "spectral isosurfaces",
            crate::spectral::shaders::ISO_VERT,
            if coloured {
                crate::spectral::shaders::ISO_COLOUR_FRAG
            } else {
                crate::spectral::shaders::ISO_FRAG
            },
            target,
        );
        desc.bindings = &ISO_BINDINGS;
        // Both sides: the fragment stage keeps the box's far side itself (eye inside a box too).
        desc.cull_mode = vk::CullModeFlags::NONE;
        let pipeline =
            GraphicsPipeline::new(&self.gpu, &desc).map_err(dev("building the isosurface pipeline"))?;
        let r = self.resources()?;
        let Some(iso) = self.iso.as_ref() else { return Ok(()) };
        let resources = [
            r[0],
            r[1],
            r[2],
            Resource::Storage(iso.boxes.binding().map_err(dev("binding"))?),
            Resource::Storage(iso.values.binding().map_err(dev("binding"))?),
            Resource::Storage(iso.hulls.binding().map_err(dev("binding"))?),
        ];
        let set = pipeline.bind(&self.gpu, &resources).map_err(dev("binding the isosurface pipeline"))?;
        if let Some(iso) = self.iso.as_mut() {
            iso.pipelines.insert(key, (pipeline, set));
        }
        Ok(())
    }

    /// Writes the value bounds of `field` at `step` into the element boxes' fourth components
    /// (when another field or step was drawn last), each widened outward by two f32 ulps of
    /// its size: `iso.vert` drops the boxes of elements whose bounds hold no iso value.
    fn iso_value_bounds(&mut self, field: usize, step: usize) -> Result<()> {
        if self.iso.as_ref().is_none_or(|i| i.bounds_of == Some((field, step))) {
            return Ok(());
        }
        let bounds = proxy::value_bounds(&self.mesh, field, step)?;
        let Some(iso) = self.iso.as_mut() else { return Ok(()) };
        let widen = |v: f64, side: f64| {
            (v + side * 2.0 * f64::from(f32::EPSILON) * v.abs().max(f64::from(f32::MIN_POSITIVE))) as f32
        };
        let mut boxes = iso.corners.clone();
        for (e, b) in bounds.iter().enumerate() {
            boxes[2 * e][3] = widen(b[0], -1.0);
            boxes[2 * e + 1][3] = widen(b[1], 1.0);
        }
        iso.boxes.upload(&self.gpu, 0, &boxes).map_err(dev("uploading the element value bounds"))?;
        iso.bounds_of = Some((field, step));
        Ok(())
    }

    #[allow(clippy::type_complexity)]
    pub(super) fn prepare_iso(
        &mut self,
        target: &DrawTarget<'_>,
        view: &SpectralView,
    ) -> Result<(Box<dyn FnOnce(&mut Recorder<'_>) + '_>, Box<dyn FnOnce(&mut Recorder<'_>) + '_>)> {
        self.check_iso_view(view)?;
        self.show(view)?;
        let coloured = view.colour_by.is_some();
        self.iso_pipeline_for(target, coloured)?;
        self.iso_value_bounds(view.field, view.step)?;
        let mut push = self.push(target, view);
        // The mode word is the isosurfaces' element-edge switch (spectral_iso_frag.glsl).
        push.flags[2] = u32::from(view.edges);
        let mut values = vec![0u32; 1 + MAX_ISO_VALUES];
        values[0] = view.iso.len() as u32;
        for (v, &c) in values[1..].iter_mut().zip(&view.iso) {
            *v = (c as f32).to_bits();
        }
        let extent = target.viewport();
        let Some(iso) = self.iso.as_ref() else {
            return Err(SpectralError::Missing("the isosurface pass was not made".into()));
        };
        let (pipeline, set) = &iso.pipelines[&(target.key(), coloured)];
        let pre = move |rec: &mut Recorder<'_>| {
            rec.update_buffer(&iso.values, 0, &values);
            pipeline.declare_draw(rec, set, Some(iso.vertices.whole()), None);
        };
        let draw = move |rec: &mut Recorder<'_>| {
            pipeline.record_draw(rec, extent, set, &push, Some(iso.vertices.whole()), iso.count);
        };
        Ok((Box::new(pre), Box::new(draw)))
    }
}
