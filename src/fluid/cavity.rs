//! The deforming cavity of seed 000 §7.2: a large central cavity and three smaller ones,
//! joined to it by thin tunnels, designed from level-set primitives (spheres and capsules)
//! and stuffed with tetrahedra ([`crate::mesh::stuffing`]). Each small cavity is compressed
//! and re-inflated analytically (seed 000 §7.2: "by analytically compressing the outer
//! cavities while renormalizing the volume"); the central cavity inflates to keep the total
//! volume constant (renormalised exactly, so the fluid stays incompressible).
//!
//! **The map.** A point p near small cavity i (weight `w_i(p)`: 1 within the cavity's radius
//! of its centre c_i, falling smoothly to 0 halfway along its tunnel) moves to
//! `c_i + (1 − a_i(t) w_i(p))(p − c_i)`, where `a_i(t)` is the compression (0 at rest, up to
//! `amount` at the frame of deepest compression, a raised-cosine pulse in time). A point near
//! the central cavity (weight w₀) moves to `c₀ + (1 + (λ − 1) w₀(p))(p − c₀)`, with λ found by
//! the secant method so that the enclosed volume (a sum over boundary faces) equals the rest
//! volume to 1e-12. The map moves **every** vertex, the interior too: it is a radial scaling
//! about each centre whose radial derivative `1 − a w − a w′ |p − c|` and tangential factor
//! `1 − a w` stay positive for a < 1 (w decreases, and the small and central transition bands
//! are disjoint), so it is orientation preserving and no cell inverts. (A harmonic interior,
//! this module's first form, flattened cells at the tunnel mouths under the deeper training
//! compressions — 0.45 and more — until the projection could not converge.)
//!
//! **The 14 training runs** ([`training_run`]): each small cavity alone at two amounts (6),
//! each pair of small cavities at two amounts (6), and each of two cavities alone at a third,
//! deeper amount (2); every run compresses over the first half of its frames and re-inflates
//! over the second.

use crate::mesh::budget::CellBudget;
use crate::mesh::sdf::{Capsule, Sdf, Sphere, Union};
use crate::mesh::stuffing::stuff;
use crate::mesh::volume::enclosed_volume;
use crate::mesh::{MeshError, SimplexMesh, Topology};

/// The cavity's shape.
#[derive(Clone, Debug, PartialEq)]
pub struct CavitySpec {
    /// Radius of the central cavity (at the origin).
    pub central_radius: f64,
    /// Radius of the three small cavities.
    pub small_radius: f64,
    /// Distance of the small cavities' centres from the origin (in the z = 0 plane, at 0°,
    /// 120° and 240°).
    pub small_distance: f64,
    /// Radius of the tunnels.
    pub tunnel_radius: f64,
    /// Lattice spacing of the stuffing.
    pub spacing: f64,
}

impl Default for CavitySpec {
    fn default() -> Self {
        Self {
            central_radius: 1.0,
            small_radius: 0.45,
            small_distance: 1.9,
            tunnel_radius: 0.16,
            spacing: 0.09,
        }
    }
}

impl CavitySpec {
    /// Centres of the three small cavities.
    pub fn small_centres(&self) -> [[f64; 3]; 3] {
        [0.0f64, 120.0, 240.0].map(|deg| {
            let a = deg.to_radians();
            [self.small_distance * a.cos(), self.small_distance * a.sin(), 0.0]
        })
    }

    /// The signed distance function of the cavity.
    pub fn sdf(&self) -> Union {
        let mut parts: Vec<Box<dyn Sdf>> =
            vec![Box::new(Sphere { centre: [0.0; 3], radius: self.central_radius })];
        for c in self.small_centres() {
            parts.push(Box::new(Sphere { centre: c, radius: self.small_radius }));
            parts.push(Box::new(Capsule { a: [0.0; 3], b: c, radius: self.tunnel_radius }));
        }
        Union(parts)
    }
}

/// One training run: compression amounts of the three small cavities at the deepest frame.
pub fn training_run(run: usize) -> Option<[f64; 3]> {
    let single = |i: usize, a: f64| {
        let mut v = [0.0; 3];
        v[i] = a;
        v
    };
    let pair = |i: usize, j: usize, a: f64| {
        let mut v = [0.0; 3];
        v[i] = a;
        v[j] = a;
        v
    };
    Some(match run {
        0..=2 => single(run, 0.3),
        3..=5 => single(run - 3, 0.5),
        6..=8 => pair(run - 6, (run - 5) % 3, 0.3),
        9..=11 => pair(run - 9, (run - 8) % 3, 0.45),
        12 => single(0, 0.6),
        13 => single(1, 0.6),
        _ => return None,
    })
}

/// Number of training runs.
pub const TRAINING_RUNS: usize = 14;

fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// A stuffed cavity with its analytic motion.
#[derive(Debug)]
pub struct Cavity {
    spec: CavitySpec,
    /// The rest mesh.
    pub mesh: SimplexMesh,
    /// Its topology (no periodic axis).
    pub topology: Topology,
    /// The surface vertices.
    pub surface: Vec<u32>,
    rest_volume: f64,
}

impl Cavity {
    /// Stuffs the cavity of `spec` (refused past `budget`).
    pub fn new(spec: &CavitySpec, budget: &CellBudget) -> Result<Self, MeshError> {
        let stuffed = stuff(&spec.sdf(), spec.spacing, budget)?;
        let topology = Topology::new(&stuffed.mesh, None)?;
        let rest_volume = enclosed_volume(&stuffed.mesh, &topology, stuffed.mesh.g());
        Ok(Self { spec: spec.clone(), mesh: stuffed.mesh, topology, surface: stuffed.surface, rest_volume })
    }

    /// The spec.
    pub fn spec(&self) -> &CavitySpec {
        &self.spec
    }

    /// The compression of each small cavity at `frame` of `frames` for a run with deepest
    /// compressions `amounts`: a raised-cosine pulse, 0 at the first and last frames.
    pub fn compression(amounts: [f64; 3], frame: usize, frames: usize) -> [f64; 3] {
        let s = frame as f64 / frames.max(1) as f64;
        let pulse = 0.5 * (1.0 - (2.0 * std::f64::consts::PI * s).cos());
        amounts.map(|a| a * pulse)
    }

    /// Every vertex mapped for compressions `a` with the central cavity's factor λ (see the
    /// module docs).
    fn mapped(&self, a: [f64; 3], lambda: f64) -> Vec<f64> {
        let g0 = self.mesh.g();
        let mut g = g0.to_vec();
        let centres = self.spec.small_centres();
        let (r0, rs, dist) = (self.spec.central_radius, self.spec.small_radius, self.spec.small_distance);
        for v in 0..self.mesh.vertex_count() {
            let p = [g0[3 * v], g0[3 * v + 1], g0[3 * v + 2]];
            let mut q = p;
            for (i, c) in centres.iter().enumerate() {
                let d = norm([p[0] - c[0], p[1] - c[1], p[2] - c[2]]);
                let w = 1.0 - smoothstep(rs * 1.02, rs + 0.5 * (dist - rs - r0), d);
                let s = a[i] * w;
                for k in 0..3 {
                    q[k] -= s * (p[k] - c[k]);
                }
            }
            let d0 = norm(p);
            let w0 = 1.0 - smoothstep(r0 * 1.02, r0 + 0.5 * (dist - rs - r0), d0);
            for k in 0..3 {
                q[k] += (lambda - 1.0) * w0 * p[k];
            }
            g[3 * v..3 * v + 3].copy_from_slice(&q);
        }
        g
    }

    /// The geometry for compressions `a`, the central cavity inflated so that the enclosed
    /// volume is the rest volume: λ by the secant method on the volume (a cubic in λ) to
    /// 1e-13 relative, bisecting whenever the secant step leaves the bracket.
    pub fn mapped_for(&self, a: [f64; 3]) -> Vec<f64> {
        self.mapped(a, self.inflation_for(a))
    }

    /// The central cavity's factor λ that restores the rest volume under compressions `a`
    /// (see [`Self::mapped_for`]; 1 when no factor in [1, 2] brackets it).
    pub fn inflation_for(&self, a: [f64; 3]) -> f64 {
        let target = self.rest_volume;
        let residual =
            |lambda: f64| enclosed_volume(&self.mesh, &self.topology, &self.mapped(a, lambda)) - target;
        let (mut lo, mut hi) = (1.0, 2.0);
        let (r_lo, r_hi) = (residual(lo), residual(hi));
        if r_lo >= 0.0 || r_hi <= 0.0 {
            return 1.0;
        }
        let (mut x0, mut x1, mut r0, mut r1) = (lo, hi, r_lo, r_hi);
        for _ in 0..100 {
            let mut x = x1 - r1 * (x1 - x0) / (r1 - r0);
            if !(x > lo && x < hi) {
                x = 0.5 * (lo + hi);
            }
            let r = residual(x);
            if r.abs() <= 1e-13 * target || hi - lo < 1e-15 {
                return x;
            }
            if r < 0.0 {
                lo = x;
            } else {
                hi = x;
            }
            (x0, r0, x1, r1) = (x1, r1, x, r);
        }
        0.5 * (lo + hi)
    }

    /// The map's motion fields: the geometry is exactly
    /// `g₀ + a₁D₁ + a₂D₂ + a₃D₃ + (λ − 1)D₀` (every displacement is linear in its amount, see
    /// the module docs); returns `[g₀, D₁, D₂, D₃, D₀]`.
    pub fn motion_fields(&self) -> [Vec<f64>; 5] {
        let g0 = self.mapped([0.0; 3], 1.0);
        let field = |a: [f64; 3], lambda: f64| -> Vec<f64> {
            self.mapped(a, lambda).iter().zip(&g0).map(|(x, x0)| x - x0).collect()
        };
        let (d1, d2, d3) =
            (field([1.0, 0.0, 0.0], 1.0), field([0.0, 1.0, 0.0], 1.0), field([0.0, 0.0, 1.0], 1.0));
        let d0 = field([0.0; 3], 2.0);
        [g0, d1, d2, d3, d0]
    }

    /// The whole mesh's geometry for compressions `a` at `frame` (the map of the module docs);
    /// an inverted cell — which the map cannot make unless the mesh is too coarse for its
    /// transition bands — is refused naming the frame.
    pub fn geometry(&mut self, a: [f64; 3], frame: usize) -> Result<Vec<f64>, MeshError> {
        let g = self.mapped_for(a);
        crate::mesh::refuse_inverted(&self.mesh.volumes_at(&g), Some(frame))?;
        Ok(g)
    }

    /// The rest volume of the fluid.
    pub fn rest_volume(&self) -> f64 {
        self.rest_volume
    }
}
