//! Where the spectral renderer looks from: the 2D view of planar meshes (pixel centres in world
//! coordinates, for the per-pixel check), cameras fitted to meshes and boxes, and the options of
//! a view.

use glam::Mat4;

use crate::render::{camera_for_box, Camera};
use crate::spectral::SpectralMesh;

/// A camera that shows all of `mesh` (its bounding sphere) from above the x–y diagonal.
pub fn fit_camera(mesh: &SpectralMesh) -> Camera {
    let (lo, hi) = mesh.bounds();
    camera_for_box(lo, hi)
}

/// A 2D view of a planar mesh: the world point at the image centre and the world size of a
/// pixel (square pixels, y up).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct View2d {
    /// World (x, y) at the centre of the image.
    pub centre: [f64; 2],
    /// World units per pixel.
    pub pixel_size: f64,
}

impl View2d {
    /// The view that fits `mesh`'s geometry points (with a 4 % margin) into `width` × `height`.
    pub fn fit(mesh: &SpectralMesh, width: u32, height: u32) -> Self {
        let (lo, hi) = mesh.bounds();
        Self::fit_box(lo, hi, width, height)
    }

    /// The view that fits the box [`lo`, `hi`] (x and y; with a 4 % margin) into `width` ×
    /// `height`.
    pub fn fit_box(lo: [f64; 3], hi: [f64; 3], width: u32, height: u32) -> Self {
        let size = ((hi[0] - lo[0]) / f64::from(width)).max((hi[1] - lo[1]) / f64::from(height));
        Self { centre: [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])], pixel_size: 1.04 * size.max(1e-30) }
    }

    /// The world point at the centre of pixel (`px`, `py`) (row 0 at the top) of a
    /// `width` × `height` image — the point each pixel shows.
    pub fn pixel_centre(&self, px: u32, py: u32, width: u32, height: u32) -> [f64; 2] {
        [
            self.centre[0] + (f64::from(px) + 0.5 - 0.5 * f64::from(width)) * self.pixel_size,
            self.centre[1] - (f64::from(py) + 0.5 - 0.5 * f64::from(height)) * self.pixel_size,
        ]
    }

    /// The orthographic projection of this view (Vulkan clip space, y down).
    pub(super) fn view_proj(&self, width: u32, height: u32) -> Mat4 {
        let (sx, sy) =
            (2.0 / (self.pixel_size * f64::from(width)), 2.0 / (self.pixel_size * f64::from(height)));
        Mat4::from_cols_array(&[
            sx as f32,
            0.0,
            0.0,
            0.0,
            0.0,
            -sy as f32,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            0.0,
            (-sx * self.centre[0]) as f32,
            (sy * self.centre[1]) as f32,
            0.0,
            1.0,
        ])
    }

    /// World (x, y) of framebuffer coordinate (0, 0) and the world step per framebuffer unit.
    pub(super) fn pixel_to_world(&self, width: u32, height: u32) -> [f32; 4] {
        [
            (self.centre[0] - 0.5 * f64::from(width) * self.pixel_size) as f32,
            (self.centre[1] + 0.5 * f64::from(height) * self.pixel_size) as f32,
            self.pixel_size as f32,
            -self.pixel_size as f32,
        ]
    }
}

/// What to show and how (`galerkin spectral render` options).
#[derive(Clone, Debug, PartialEq)]
pub struct SpectralView {
    /// The field (index into the mesh's fields).
    pub field: usize,
    /// Its time step.
    pub step: usize,
    /// Colour range; `None`: the field's sampled range at this step.
    pub range: Option<(f64, f64)>,
    /// Logarithmic colour scale (positive ranges).
    pub log: bool,
    /// Iso-lines per colour range (0: none).
    pub isolines: u32,
    /// Draw the element edges in front, dark (the mesh).
    pub edges: bool,
    /// Edge overdraw behind the faces (fills cracks between discontinuous elements).
    pub overdraw: bool,
    /// The seed's baseline: colour at the nodes, interpolated (node grids).
    pub per_vertex: bool,
    /// With `per_vertex` on a surface: colour at the vertices of the per-pixel path's own
    /// tessellation instead of the node grids — the same triangles, so the difference to per
    /// pixel is the cost of the per-fragment evaluation alone.
    pub per_vertex_on_tessellation: bool,
    /// The 2D view of a planar mesh; `None`: fit the mesh.
    pub view: Option<View2d>,
    /// The camera of a surface mesh; `None`: [`fit_camera`].
    pub camera: Option<Camera>,
    /// The surface tessellation's screen-space error budget in pixels.
    pub max_error_px: f64,
    /// Planar meshes: show the field as a height field z = scale · f (lit with its exact
    /// normals, seen through `camera`) instead of flat. `Some(0.0)`: a scale that makes the
    /// field's range a quarter of the mesh's size.
    pub height: Option<f64>,
    /// Cut planes (n_x, n_y, n_z, d): the points with n · x = d, through hexahedral meshes
    /// (at most [`super::MAX_CUT_PLANES`]; the normal need not be unit). Empty: one plane z = the
    /// middle of the mesh.
    pub cuts: Vec<[f64; 4]>,
    /// A derived field to show instead of the field itself (`--expr`; the field is its `u`),
    /// evaluated per pixel by a fragment shader compiled at run time.
    pub expression: Option<std::sync::Arc<crate::expression::spectral::DerivedField>>,
    /// Isosurfaces of solid meshes (hexahedra, tetrahedra): the field's values whose surfaces
    /// are drawn per pixel instead of cut planes (at most [`super::MAX_ISO_VALUES`]; empty:
    /// none). See `iso.frag`.
    pub iso: Vec<f64>,
    /// Isosurfaces coloured by this field's value at each surface point instead of by their
    /// iso values (`--colour-by`; `iso_colour.frag`).
    pub colour_by: Option<usize>,
    /// Volume rendering of a solid mesh (hexahedra, tetrahedra) with this transfer function
    /// instead of cut planes: emission–absorption along each pixel's ray (`volume.frag`).
    pub volume: Option<crate::spectral::transfer::TransferFunction>,
    /// The isosurfaces' opacity α ∈ (0, 1] (`--iso-opacity`). Below 1 they are transparent:
    /// drawn by the volume pass as sheets composited front to back along each ray (each lets
    /// 1 − α of the light behind it through), every crossing of every value. With
    /// [`Self::volume`] the isosurfaces are always such sheets inside the volume, at this
    /// opacity. 1 without a volume: the opaque isosurface pass (`iso.frag`).
    pub iso_opacity: f64,
}

impl SpectralView {
    /// The derived field's text, which keys its shader, pipelines, ranges and uploads
    /// (`None`: the field itself).
    pub(crate) fn expression_key(&self) -> Option<String> {
        self.expression.as_ref().map(|d| d.expression.text.clone())
    }

    /// Whether the volume pass draws this view: a volume, or transparent isosurfaces.
    pub fn uses_volume_pass(&self) -> bool {
        self.volume.is_some() || (!self.iso.is_empty() && self.iso_opacity < 1.0)
    }

    /// The volume pass's sheets: the isosurfaces at their opacity when the volume pass draws
    /// them ([`Self::uses_volume_pass`]), none otherwise.
    pub fn sheets(&self) -> crate::spectral::transfer::Sheets {
        if self.iso.is_empty() || !self.uses_volume_pass() {
            return crate::spectral::transfer::Sheets::none();
        }
        crate::spectral::transfer::Sheets { values: self.iso.clone(), opacity: self.iso_opacity }
    }
}

impl Default for SpectralView {
    fn default() -> Self {
        Self {
            field: 0,
            step: 0,
            range: None,
            log: false,
            isolines: 0,
            edges: false,
            overdraw: true,
            per_vertex: false,
            per_vertex_on_tessellation: false,
            view: None,
            camera: None,
            max_error_px: 0.5,
            height: None,
            cuts: Vec::new(),
            expression: None,
            iso: Vec::new(),
            colour_by: None,
            volume: None,
            iso_opacity: 1.0,
        }
    }
}
