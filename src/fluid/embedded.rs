//! A box of fluid around an animated closed surface (seed 000 §6.1 and §7.2's eagle): the
//! base mesh is the box minus the surface at its base frame, stuffed with tetrahedra
//! ([`crate::mesh::stuffing`]); every later frame moves the mesh's surface vertices with the
//! animation and the interior harmonically ([`crate::mesh::deform`]).
//!
//! **Attaching.** Each vertex the stuffing put on the embedded surface, and each interior
//! vertex within [`ATTACH_SPACINGS`] lattice spacings of it, is attached to the nearest
//! triangle of the base frame: the barycentric weights of its closest point and its offset
//! from that point in the triangle's orthonormal frame (for surface vertices only the
//! stuffing's bisection error, so the base frame is reproduced exactly); at frame k it sits
//! at the same weights and offset on that triangle at frame k, so a part moving rigidly
//! carries the cells around it rigidly — also where the stuffing could not resolve a thin
//! part, which lattice edges then cross without a cut point. This is the seed's "deform the
//! base mesh so that the embedded surface matches the deformed surface model", with the
//! interior by harmonic rather than Laplacian deformation transfer.
//!
//! **Volume.** The fluid is incompressible and the box closed, so the domain's volume must
//! not change; an animation whose parts move rigidly but overlap (a wing root inside the
//! body) or whose stuffed approximation is not rigid does change it slightly. The box's lid
//! (its top face, z = hi) absorbs the difference: its vertices move by δ along z, and the
//! enclosed volume is affine in δ (a determinant with two equal translation columns
//! vanishes), so two evaluations give δ exactly. The lid moves by micrometres per unit of
//! box (reported by [`Embedded::lid_offset`]).

use crate::mesh::animation::SurfaceAnimation;
use crate::mesh::budget::CellBudget;
use crate::mesh::bvh::{closest_point_weights, Bvh};
use crate::mesh::deform::HarmonicDeformation;
use crate::mesh::sdf::{Cuboid, Difference, Sdf};
use crate::mesh::stuffing::stuff;
use crate::mesh::volume::enclosed_volume;
use crate::mesh::{MeshError, SimplexMesh, Topology};

/// The box and the stuffing of an embedded-surface domain.
#[derive(Clone, Debug, PartialEq)]
pub struct EmbeddedSpec {
    /// Lower corner of the box.
    pub lo: [f64; 3],
    /// Upper corner (the lid is the face z = `hi[2]`).
    pub hi: [f64; 3],
    /// Lattice spacing of the stuffing.
    pub spacing: f64,
    /// The animation frame the base mesh is built around.
    pub base_frame: usize,
}

/// A mesh vertex attached to a triangle of the animation: its closest point's barycentric
/// weights and its offset from that point in the triangle's own orthonormal frame.
#[derive(Clone, Copy, Debug)]
struct Attachment {
    vertex: u32,
    triangle: u32,
    weights: [f64; 3],
    offset: [f64; 3],
}

impl Attachment {
    /// Attaches `vertex` at `p` to `triangle` with corners `corners`.
    fn new(vertex: u32, triangle: u32, corners: &[[f64; 3]; 3], p: glam::DVec3) -> Self {
        let weights = closest_point_weights(p, &corners.map(glam::DVec3::from_array));
        let foot = foot_point(corners, weights);
        let offset = triangle_frame(corners).map(|e| (p - foot).dot(e));
        Self { vertex, triangle, weights, offset }
    }

    /// The vertex's position on its triangle with corners `corners` (the same triangle at
    /// another frame).
    fn position(&self, corners: &[[f64; 3]; 3]) -> glam::DVec3 {
        let axes = triangle_frame(corners);
        foot_point(corners, self.weights)
            + axes[0] * self.offset[0]
            + axes[1] * self.offset[1]
            + axes[2] * self.offset[2]
    }
}

/// The point of a triangle with barycentric `weights`.
fn foot_point(corners: &[[f64; 3]; 3], weights: [f64; 3]) -> glam::DVec3 {
    (0..3).map(|i| weights[i] * glam::DVec3::from_array(corners[i])).sum()
}

/// A triangle's orthonormal frame: the first edge's direction, the in-plane perpendicular
/// and the unit normal (rigid motions of the triangle move it rigidly).
fn triangle_frame(t: &[[f64; 3]; 3]) -> [glam::DVec3; 3] {
    let [a, b, c] = t.map(glam::DVec3::from_array);
    let e1 = (b - a).normalize_or_zero();
    let n = (b - a).cross(c - a).normalize_or_zero();
    [e1, n.cross(e1), n]
}

/// The surface's size: the diagonal of its bounding box at `frame`.
fn surface_size(animation: &SurfaceAnimation, frame: usize) -> f64 {
    let (mut lo, mut hi) = (glam::DVec3::INFINITY, glam::DVec3::NEG_INFINITY);
    for &p in &animation.frames[frame] {
        lo = lo.min(glam::DVec3::from_array(p));
        hi = hi.max(glam::DVec3::from_array(p));
    }
    (hi - lo).length()
}

/// Attached vertices are also those within this fraction of the surface's size of it
/// (whichever of this and [`ATTACH_SPACINGS`] is larger): the harmonic interpolation bends
/// the mesh most right next to thin moving parts, so a shell moving rigidly with them leaves
/// the bending to cells further out, which are larger relative to it.
pub const ATTACH_SIZE: f64 = 0.06;

/// Attached vertices within this many lattice spacings of the surface: the stuffing resolves
/// a surface only where it is thicker than about a spacing, and lattice cells straddling a
/// thin part (a wing's trailing edge, its tip) must move with it.
pub const ATTACH_SPACINGS: f64 = 0.75;

/// The stuffed box around an animated surface, with its boundary motion and harmonic
/// interior.
#[derive(Debug)]
pub struct Embedded {
    /// The surface animation.
    pub animation: SurfaceAnimation,
    /// The box and stuffing.
    pub spec: EmbeddedSpec,
    /// The base mesh (the box minus the surface at the base frame).
    pub mesh: SimplexMesh,
    /// Its topology (no periodic axis).
    pub topology: Topology,
    /// Every boundary vertex (box and embedded surface).
    pub surface: Vec<u32>,
    attached: Vec<Attachment>,
    lid: Vec<u32>,
    rest_volume: f64,
    deform: HarmonicDeformation,
    lid_offset: f64,
}

impl Embedded {
    /// Stuffs the box minus the surface at `spec.base_frame` and attaches the surface
    /// vertices. Refused: a base frame past the animation, a box that does not hold the
    /// surface with a margin of two lattice spacings at every frame (naming the frame), a
    /// spacing too coarse to resolve the surface, a mesh past `budget`.
    pub fn new(
        animation: SurfaceAnimation,
        spec: &EmbeddedSpec,
        budget: &CellBudget,
    ) -> Result<Self, MeshError> {
        let n = animation.frame_count();
        if spec.base_frame >= n {
            return Err(MeshError::Generation(format!(
                "base frame {} of an animation with {n} frames",
                spec.base_frame
            )));
        }
        if !(spec.spacing.is_finite() && spec.spacing > 0.0) || (0..3).any(|k| spec.hi[k] <= spec.lo[k]) {
            return Err(MeshError::Generation("the box needs lo < hi and a positive spacing".into()));
        }
        let margin = 2.0 * spec.spacing;
        for (k, frame) in animation.frames.iter().enumerate() {
            if let Some(p) = frame
                .iter()
                .find(|p| (0..3).any(|a| p[a] < spec.lo[a] + margin || p[a] > spec.hi[a] - margin))
            {
                return Err(MeshError::Generation(format!(
                    "frame {k}: the surface reaches {p:?}, within two lattice spacings ({margin}) of the box or outside it"
                )));
            }
        }
        let boxed = Cuboid { lo: spec.lo, hi: spec.hi };
        let domain = Difference { outer: Box::new(boxed), hole: Box::new(animation.sdf(spec.base_frame)?) };
        let stuffed = stuff(&domain, spec.spacing, budget)?;
        let mesh = stuffed.mesh;
        let topology = Topology::new(&mesh, None)?;
        let base = spec.base_frame;
        // One hierarchy per part: a vertex near a junction follows each nearby part.
        let bvhs: Vec<Bvh> = animation
            .parts
            .iter()
            .map(|(_, range)| {
                Bvh::new(
                    range
                        .clone()
                        .map(|t| animation.triangle_at(base, t).map(glam::DVec3::from_array))
                        .collect(),
                )
            })
            .collect();
        let extent = (0..3).map(|k| spec.hi[k] - spec.lo[k]).fold(0.0, f64::max);
        let attach_radius =
            (ATTACH_SPACINGS * spec.spacing).max(ATTACH_SIZE * surface_size(&animation, base));
        let (mut attached, mut lid) = (Vec::new(), Vec::new());
        let mut on_surface = vec![false; mesh.vertex_count()];
        for &v in &stuffed.surface {
            on_surface[v as usize] = true;
        }
        for v in 0..mesh.vertex_count() as u32 {
            let p = mesh.point(v as usize);
            let p = [p[0], p[1], p[2]];
            let to_box = boxed.distance(p).abs();
            let q = glam::DVec3::from_array(p);
            // Per part: (distance, triangle index in the animation).
            let nearest: Vec<(f64, u32)> = bvhs
                .iter()
                .zip(&animation.parts)
                .map(|(bvh, (_, range))| {
                    bvh.nearest(q).map_or((f64::INFINITY, 0), |(d, t)| (d, t + range.start as u32))
                })
                .collect();
            let to_surface = nearest.iter().map(|n| n.0).fold(f64::INFINITY, f64::min);
            if on_surface[v as usize] && to_box <= to_surface {
                if (spec.hi[2] - p[2]).abs() <= 1e-9 * extent {
                    lid.push(v);
                }
                continue;
            }
            if !on_surface[v as usize] && to_surface > attach_radius {
                continue;
            }
            // Each attached vertex rides on its nearest part. An interior vertex near two
            // parts (where a wing's root meets the body) stays free: the parts' shells would
            // move into each other there, and the harmonic solve and smoothing do better.
            let near_parts = nearest.iter().filter(|n| n.0 <= 2.0 * attach_radius).count();
            if !on_surface[v as usize] && near_parts > 1 {
                continue;
            }
            let Some(&(_, t)) = nearest.iter().find(|n| n.0 == to_surface) else { continue };
            attached.push(Attachment::new(v, t, &animation.triangle_at(base, t as usize), q));
        }
        if attached.is_empty() {
            return Err(MeshError::Generation(format!(
                "spacing {}: the stuffing resolved none of the surface (make the spacing smaller)",
                spec.spacing
            )));
        }
        let rest_volume = enclosed_volume(&mesh, &topology, mesh.g());
        let mut prescribed = stuffed.surface.clone();
        prescribed.extend(attached.iter().map(|a| a.vertex).filter(|&v| !on_surface[v as usize]));
        let deform = HarmonicDeformation::new(&mesh, &prescribed)?;
        Ok(Self {
            animation,
            spec: spec.clone(),
            mesh,
            topology,
            surface: stuffed.surface,
            attached,
            lid,
            rest_volume,
            deform,
            lid_offset: 0.0,
        })
    }

    /// Number of mesh vertices attached to the embedded surface (on it, or within
    /// [`ATTACH_SPACINGS`] spacings of it).
    pub fn attached_count(&self) -> usize {
        self.attached.len()
    }

    /// The fluid's volume at the base frame (kept at every frame).
    pub fn rest_volume(&self) -> f64 {
        self.rest_volume
    }

    /// Numerical factorisations of the harmonic deformation so far (one, plus one per
    /// stiffened solve).
    pub fn factorisations(&self) -> usize {
        self.deform.factorisations()
    }

    /// The lid's displacement δ (along z) of the last frame computed.
    pub fn lid_offset(&self) -> f64 {
        self.lid_offset
    }

    /// The boundary positions at `frame`: attached vertices on their triangles, the lid
    /// raised by δ so that the enclosed volume is the rest volume; returns them and δ.
    pub fn boundary(&self, frame: usize) -> Result<(Vec<f64>, f64), MeshError> {
        if frame >= self.animation.frame_count() {
            return Err(MeshError::Generation(format!(
                "frame {frame}: the surface animation has frames 0 to {}",
                self.animation.frame_count() - 1
            )));
        }
        let mut g = self.mesh.g().to_vec();
        for a in &self.attached {
            let p = a.position(&self.animation.triangle_at(frame, a.triangle as usize));
            g[3 * a.vertex as usize..3 * a.vertex as usize + 3].copy_from_slice(&p.to_array());
        }
        let volume = |g: &[f64]| enclosed_volume(&self.mesh, &self.topology, g);
        let v0 = volume(&g);
        let mut lifted = g.clone();
        for &v in &self.lid {
            lifted[3 * v as usize + 2] += 1.0;
        }
        let slope = volume(&lifted) - v0;
        let delta = if slope > 0.0 { (self.rest_volume - v0) / slope } else { 0.0 };
        for &v in &self.lid {
            g[3 * v as usize + 2] += delta;
        }
        Ok((g, delta))
    }

    /// The whole mesh's geometry at `frame` (boundary, then harmonic interior); a frame with
    /// an inverted cell is refused naming it and the cell.
    pub fn geometry(&mut self, frame: usize) -> Result<Vec<f64>, MeshError> {
        let (target, delta) = self.boundary(frame)?;
        self.lid_offset = delta;
        self.deform.deform(&target, frame)
    }
}
