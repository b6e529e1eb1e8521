//! Volume rendering of solid meshes (hexahedra and tetrahedra), per pixel: one triangle over the
//! viewport (`volume.vert`); each fragment integrates emission–absorption along its ray through
//! the elements its screen tile lists and composites them front to back (`volume.frag`). The
//! tiles are binned here on the host every frame: each element's box (of its Bernstein control
//! points) projected to the screen, and elements whose opacity is zero over their value bounds
//! ([`proxy::value_bounds`]) and that hold no sheet's value left out. Isosurfaces drawn here
//! (transparent ones, or any in a volume: [`SpectralView::uses_volume_pass`]) are sheets
//! composited where the ray crosses their value. The f64 reference is
//! [`crate::spectral::volume_reference`].

use std::collections::HashMap;

use ash::vk;
use glam::{DMat4, DVec4};

use super::*;
use crate::gpu::Recorder;
use crate::spectral::transfer::{Sheets, TransferFunction, MAX_SHEETS};

/// Screen tile edge in pixels.
pub const VOLUME_TILE: u32 = 16;

/// Words before the per-tile ranges in the tile buffer (`volume.frag`'s header).
const TILE_HEADER: usize = 8;

/// Bindings of the volume pipeline: geometry, coefficients, colour map, element boxes,
/// transfer function, tiles, element hulls.
const VOLUME_BINDINGS: [BindingKind; 7] = [
    BindingKind::StorageBuffer,
    BindingKind::StorageBuffer,
    BindingKind::Texture,
    BindingKind::StorageBuffer,
    BindingKind::StorageBuffer,
    BindingKind::StorageBuffer,
    BindingKind::StorageBuffer,
];

/// The volume pass's buffers and pipelines.
pub(super) struct VolumePass {
    /// Per element (lo, 0), (hi, 0): its box ([`super::element_boxes`]).
    boxes: Buffer<[f32; 4]>,
    corners: Vec<[f32; 4]>,
    /// [`TransferFunction::device_words`].
    transfer: Buffer<u32>,
    /// Per element its hull's [`super::HULL_PLANES`] half-spaces ([`super::element_hull_planes`]).
    hulls: Buffer<[f32; 4]>,
    /// The tile ranges and element lists of the last frame, one buffer per band (grown when a
    /// frame needs more).
    tiles: Vec<Buffer<u32>>,
    /// Per element its value bounds, for the (field, step) in `bounds_of`.
    bounds: Vec<[f64; 2]>,
    bounds_of: Option<(usize, usize)>,
    /// Per target: the pipeline and a set per band (bound anew when `tiles` changes).
    pub(super) pipelines: HashMap<PassKey, (GraphicsPipeline, Vec<DescriptorSet>)>,
}

/// The tile buffers of a `width` × `height` viewport whose corner is (`x`, `y`) in the
/// framebuffer, for elements whose boxes (lo, hi pairs) `view_proj` projects, in bands of
/// whole tile rows each at most `budget` words long (a device binds at most
/// `maxStorageBufferRange` bytes of one buffer: a picture whose lists need more is drawn band
/// by band). Each band: the header (tiles across and down, tile size, corner, its first row and
/// the row after its last, padding), (first, count) per tile of its rows, then their element
/// lists. An element is listed in every tile its box's projected rectangle (one pixel wider
/// each side) touches; a box reaching behind the eye is listed everywhere; `keep` selects the
/// elements at all. An error when one row of tiles alone is over the budget.
pub fn tile_bands(
    boxes: &[[f32; 4]],
    view_proj: &DMat4,
    (x, y, width, height): (u32, u32, u32, u32),
    keep: impl Fn(usize) -> bool,
    budget: u64,
) -> std::result::Result<Vec<Vec<u32>>, String> {
    let (tx, ty) = (width.div_ceil(VOLUME_TILE).max(1), height.div_ceil(VOLUME_TILE).max(1));
    let mut lists: Vec<Vec<u32>> = vec![Vec::new(); (tx * ty) as usize];
    for (e, b) in boxes.chunks_exact(2).enumerate() {
        if !keep(e) {
            continue;
        }
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        let (mut behind, mut all_behind) = (false, true);
        for k in 0..8 {
            let c = std::array::from_fn::<f64, 3, _>(|a| {
                f64::from(if k >> a & 1 == 1 { b[1][a] } else { b[0][a] })
            });
            let clip = *view_proj * DVec4::new(c[0], c[1], c[2], 1.0);
            if clip.w <= 1e-9 {
                behind = true;
                continue;
            }
            all_behind = false;
            let px = [
                (clip.x / clip.w + 1.0) * 0.5 * f64::from(width),
                (clip.y / clip.w + 1.0) * 0.5 * f64::from(height),
            ];
            for a in 0..2 {
                lo[a] = lo[a].min(px[a]);
                hi[a] = hi[a].max(px[a]);
            }
        }
        if all_behind {
            continue;
        }
        let (x0, x1, y0, y1) = if behind {
            (0, tx - 1, 0, ty - 1)
        } else {
            if hi[0] < -1.0
                || hi[1] < -1.0
                || lo[0] > f64::from(width) + 1.0
                || lo[1] > f64::from(height) + 1.0
            {
                continue;
            }
            let tile =
                |v: f64, n: u32| (v / f64::from(VOLUME_TILE)).floor().clamp(0.0, f64::from(n - 1)) as u32;
            (tile(lo[0] - 1.0, tx), tile(hi[0] + 1.0, tx), tile(lo[1] - 1.0, ty), tile(hi[1] + 1.0, ty))
        };
        for j in y0..=y1 {
            for i in x0..=x1 {
                lists[(j * tx + i) as usize].push(e as u32);
            }
        }
    }
    // Rows into bands, greedily.
    let row_words = |j: u32| -> u64 {
        let row = &lists[(j * tx) as usize..((j + 1) * tx) as usize];
        2 * u64::from(tx) + row.iter().map(|l| l.len() as u64).sum::<u64>()
    };
    let mut bands = Vec::new();
    let mut row0 = 0;
    while row0 < ty {
        let mut words = TILE_HEADER as u64 + row_words(row0);
        if words > budget {
            return Err(format!(
                "one row of {tx} screen tiles lists {words} words of elements, over the {budget} one buffer may hold; draw a smaller picture"
            ));
        }
        let mut row1 = row0 + 1;
        while row1 < ty && words + row_words(row1) <= budget {
            words += row_words(row1);
            row1 += 1;
        }
        let band = &lists[(row0 * tx) as usize..(row1 * tx) as usize];
        let mut out = Vec::with_capacity(words as usize);
        out.extend([tx, ty, VOLUME_TILE, x, y, row0, row1, 0]);
        let mut first = (TILE_HEADER + 2 * band.len()) as u32;
        for l in band {
            out.extend([first, l.len() as u32]);
            first += l.len() as u32;
        }
        for l in band {
            out.extend_from_slice(l);
        }
        bands.push(out);
        row0 = row1;
    }
    Ok(bands)
}

/// Whether an element whose field lies in [lo, hi] shows: the transfer function is not clear
/// there, or a sheet's value lies in it.
fn shows_between(tf: &TransferFunction, sheets: &Sheets, lo: f64, hi: f64) -> bool {
    max_alpha(tf, lo, hi) > 0.0 || sheets.values.iter().any(|&c| c >= lo && c <= hi)
}

/// The largest opacity `tf` takes over [lo, hi] (at the ends or a point between).
fn max_alpha(tf: &TransferFunction, lo: f64, hi: f64) -> f64 {
    let inner = tf.opacity.iter().filter(|p| p.0 > lo && p.0 < hi).map(|p| p.1);
    inner.fold(tf.alpha(lo).max(tf.alpha(hi)), f64::max)
}

impl SpectralRenderer {
    /// Caps the words one of the volume's tile buffers may hold (default: what the device binds
    /// at once, `maxStorageBufferRange`): a frame whose tile lists need more is drawn in bands
    /// of tile rows, one buffer and one draw each. For embedders that share a memory budget,
    /// and for the tests, which draw a picture in bands and whole and compare.
    pub fn set_volume_tile_budget(&mut self, words: u64) {
        self.volume_budget = words;
    }

    /// Checks a view the volume pass draws: a solid mesh, no derived field or cut planes; its
    /// isosurfaces (sheets) as the isosurface pass checks them, at an opacity in (0, 1], neither
    /// coloured by another field nor edged.
    fn check_volume_view(&self, view: &SpectralView) -> Result<()> {
        if !self.mesh.shape.is_volume() {
            return Err(SpectralError::Missing(format!(
                "volume rendering and transparent isosurfaces are for hexahedral and tetrahedral meshes; this one is of {:?}s",
                self.mesh.shape
            )));
        }
        if view.expression.is_some() || !view.cuts.is_empty() {
            return Err(SpectralError::Missing(
                "volume rendering or transparent isosurfaces together with cut planes or a derived field are not drawn yet"
                    .into(),
            ));
        }
        if !view.iso.is_empty() {
            self.check_iso_view(view)?;
            Sheets::check_opacity(view.iso_opacity).map_err(SpectralError::Missing)?;
            if view.colour_by.is_some() || view.edges {
                return Err(SpectralError::Missing(
                    "transparent isosurfaces, and isosurfaces in a volume, are coloured by their values and drawn without element edges (--colour-by and --edges go with opaque isosurfaces)"
                        .into(),
                ));
            }
        }
        Ok(())
    }

    fn volume_pipeline_for(&mut self, target: &DrawTarget<'_>) -> Result<()> {
        if self.volume.is_none() {
            let corners = element_boxes(&self.mesh)?;
            let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
            let boxes = Buffer::from_slice(&self.gpu, "spectral volume boxes", &corners, storage)
                .map_err(dev("uploading"))?;
            let words = 8 + 2 * crate::spectral::transfer::MAX_TRANSFER_POINTS as u64 + MAX_SHEETS as u64;
            let transfer =
                Buffer::new(&self.gpu, "spectral transfer function", words, storage, MemoryKind::GpuOnly)
                    .map_err(dev("the volume pass"))?;
            let planes = super::element_hull_planes(&self.mesh)?;
            let hulls = Buffer::from_slice(&self.gpu, "spectral element hulls", &planes, storage)
                .map_err(dev("uploading the element hulls"))?;
            self.volume = Some(VolumePass {
                boxes,
                corners,
                transfer,
                hulls,
                tiles: Vec::new(),
                bounds: Vec::new(),
                bounds_of: None,
                pipelines: HashMap::new(),
            });
        }
        let key = target.key();
        if self.volume.as_ref().is_some_and(|v| v.pipelines.contains_key(&key)) {
            return Ok(());
        }
        target.require_depth("volume rendering").map_err(dev("building the volume pipeline"))?;
        let mut desc = GraphicsPipelineDesc::new(
            "spectral volume",
            crate::spectral::shaders::VOLUME_VERT,
            crate::spectral::shaders::VOLUME_FRAG,
            target.render_pass(),
        );
        desc.bindings = &VOLUME_BINDINGS;
        desc.specialization = &self.specialization;
        desc.push = crate::gpu::PushLayout::of::<SpectralPush>();
        let pipeline =
            GraphicsPipeline::new(&self.gpu, &desc).map_err(dev("building the volume pipeline"))?;
        if let Some(v) = self.volume.as_mut() {
            v.pipelines.insert(key, (pipeline, Vec::new()));
        }
        Ok(())
    }

    /// Bins this frame's tiles, uploads them (growing the buffer, which rebinds every set) and
    /// the transfer function, and binds the target's pipeline.
    fn volume_upload(
        &mut self,
        target: &DrawTarget<'_>,
        view: &SpectralView,
        tf: &TransferFunction,
        sheets: &Sheets,
    ) -> Result<()> {
        let (field, step) = (view.field, view.step);
        if self.volume.as_ref().is_some_and(|v| v.bounds_of != Some((field, step))) {
            let bounds = proxy::value_bounds(&self.mesh, field, step)?;
            if let Some(v) = self.volume.as_mut() {
                v.bounds = bounds;
                v.bounds_of = Some((field, step));
            }
        }
        let e = target.extent();
        let camera = match self.picture_view(view, e.width, e.height) {
            PictureView::Camera(c) => c,
            PictureView::Plane(_) => return Err(SpectralError::Missing("a volume needs a camera".into())),
        };
        let vp = camera.view_proj(target.aspect());
        let port = target.viewport();
        let Some(v) = self.volume.as_mut() else { return Ok(()) };
        let bounds = &v.bounds;
        let limit = (self.gpu.caps().max_storage_buffer_range / 4).min(self.volume_budget);
        let bands = tile_bands(
            &v.corners,
            &vp,
            (port.x, port.y, e.width, e.height),
            |k| bounds.get(k).is_none_or(|b| shows_between(tf, sheets, b[0], b[1])),
            limit,
        )
        .map_err(SpectralError::Missing)?;
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let mut rebind = bands.len() != v.tiles.len();
        v.tiles.truncate(bands.len());
        for (k, words) in bands.iter().enumerate() {
            if v.tiles.get(k).is_none_or(|b| (words.len() as u64) > b.len()) {
                // Room to grow (a power of two, at least 4,096 words), within the budget.
                let need = words.len() as u64;
                let len = need.next_power_of_two().max(4096).min(limit).max(need);
                let buffer =
                    Buffer::new(&self.gpu, "spectral volume tiles", len, storage, MemoryKind::GpuOnly)
                        .map_err(dev("the volume's tile lists"))?;
                if k < v.tiles.len() {
                    v.tiles[k] = buffer;
                } else {
                    v.tiles.push(buffer);
                }
                rebind = true;
            }
            v.tiles[k].upload(&self.gpu, 0, words).map_err(dev("uploading the volume's tiles"))?;
        }
        if rebind {
            for p in v.pipelines.values_mut() {
                p.1.clear();
            }
        }
        let bg = crate::render::BACKGROUND;
        v.transfer
            .upload(&self.gpu, 0, &tf.device_words([bg[0], bg[1], bg[2]], sheets))
            .map_err(dev("uploading the transfer function"))?;
        let key = target.key();
        if self.volume.as_ref().is_some_and(|v| v.pipelines.get(&key).is_some_and(|p| p.1.is_empty())) {
            let r = self.resources()?;
            let Some(v) = self.volume.as_ref() else { return Ok(()) };
            let mut sets = Vec::with_capacity(v.tiles.len());
            for tiles in &v.tiles {
                let resources = [
                    r[0],
                    r[1],
                    r[2],
                    Resource::Storage(v.boxes.binding().map_err(dev("binding"))?),
                    Resource::Storage(v.transfer.binding().map_err(dev("binding"))?),
                    Resource::Storage(tiles.binding().map_err(dev("binding"))?),
                    Resource::Storage(v.hulls.binding().map_err(dev("binding"))?),
                ];
                sets.push(
                    v.pipelines[&key]
                        .0
                        .bind(&self.gpu, &resources)
                        .map_err(dev("binding the volume pipeline"))?,
                );
            }
            if let Some(p) = self.volume.as_mut().and_then(|v| v.pipelines.get_mut(&key)) {
                p.1 = sets;
            }
        }
        Ok(())
    }

    #[allow(clippy::type_complexity)]
    pub(super) fn prepare_volume(
        &mut self,
        target: &DrawTarget<'_>,
        view: &SpectralView,
    ) -> Result<(Box<dyn FnOnce(&mut Recorder<'_>) + '_>, Box<dyn FnOnce(&mut Recorder<'_>) + '_>)> {
        self.check_volume_view(view)?;
        self.show(view)?;
        self.volume_pipeline_for(target)?;
        // Transparent isosurfaces alone: a clear medium, only the sheets show.
        let tf = view.volume.clone().unwrap_or_else(TransferFunction::clear);
        self.volume_upload(target, view, &tf, &view.sheets())?;
        let push = self.push(target, view);
        let extent = target.viewport();
        let Some(v) = self.volume.as_ref() else {
            return Err(SpectralError::Missing("the volume pass was not made".into()));
        };
        let (pipeline, sets) = &v.pipelines[&target.key()];
        if sets.is_empty() {
            return Err(SpectralError::Missing("the volume pipeline was not bound".into()));
        }
        let pre = move |rec: &mut Recorder<'_>| {
            for set in sets {
                pipeline.declare_draw(rec, set, None, None);
            }
        };
        // One triangle over the viewport per band; each band's fragments outside its rows
        // return at once.
        let draw = move |rec: &mut Recorder<'_>| {
            for set in sets {
                pipeline.record_draw(rec, extent, set, &push, None, 3);
            }
        };
        Ok((Box::new(pre), Box::new(draw)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box in front of the camera is listed in the tiles its projection covers and no
    /// others; one behind the eye nowhere; one reaching behind the eye everywhere.
    #[test]
    fn tiles_list_the_boxes_they_see() {
        let camera = crate::render::Camera {
            eye: [0.0, 0.0, 5.0],
            target: [0.0, 0.0, 0.0],
            up: [0.0, 1.0, 0.0],
            fov_y_degrees: 45.0,
            near: 0.1,
            far: 100.0,
        };
        let vp = camera.view_proj(1.0);
        let boxes = [
            [-0.1, -0.1, -0.1, 0.0],
            [0.1, 0.1, 0.1, 0.0],
            [-0.1, -0.1, 6.0, 0.0],
            [0.1, 0.1, 7.0, 0.0],
            [-0.1, -0.1, 4.0, 0.0],
            [0.1, 0.1, 6.0, 0.0],
        ];
        let bands = tile_bands(&boxes, &vp, (0, 0, 64, 64), |_| true, u64::MAX).expect("binned");
        assert_eq!(bands.len(), 1);
        let w = &bands[0];
        assert_eq!(&w[..7], &[4, 4, VOLUME_TILE, 0, 0, 0, 4]);
        let listed = |tile: usize| -> Vec<u32> {
            let (first, count) = (w[TILE_HEADER + 2 * tile] as usize, w[TILE_HEADER + 2 * tile + 1] as usize);
            w[first..first + count].to_vec()
        };
        // The small box sits at the centre: the four middle tiles; the straddling one: all.
        for tile in 0..16 {
            let centre = matches!(tile, 5 | 6 | 9 | 10);
            assert_eq!(listed(tile), if centre { vec![0, 2] } else { vec![2] }, "tile {tile}");
        }
        let none = tile_bands(&boxes, &vp, (0, 0, 64, 64), |_| false, u64::MAX).expect("binned");
        assert!((0..16).all(|t| none[0][TILE_HEADER + 2 * t + 1] == 0));
        // A budget of two rows' worth: two bands of two rows, the same lists; one row over
        // the budget is an error.
        let row = TILE_HEADER as u64 + 2 * 4 + 4 + 2;
        let split = tile_bands(&boxes, &vp, (0, 0, 64, 64), |_| true, row + 2 * 4 + 4 + 2).expect("binned");
        assert_eq!(split.len(), 2);
        assert_eq!((split[0][5], split[0][6], split[1][5], split[1][6]), (0, 2, 2, 4));
        let rows: Vec<u32> = split
            .iter()
            .flat_map(|b| b[TILE_HEADER..TILE_HEADER + 16].iter().skip(1).step_by(2).copied())
            .collect();
        let whole: Vec<u32> = w[TILE_HEADER..TILE_HEADER + 32].iter().skip(1).step_by(2).copied().collect();
        assert_eq!(rows, whole, "the same counts per tile");
        assert!(tile_bands(&boxes, &vp, (0, 0, 64, 64), |_| true, row - 1).is_err());
    }
}
