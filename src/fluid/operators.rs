//! The full-space operators of seed 000 §5 on a simplicial mesh, two ways:
//!
//! - as the reduction core's sparse tensors ([`volume_tensor`], [`flux_to_momentum_tensor`],
//!   [`advection_tensor`], [`laplacian_tensor`], [`divergence_tensor`],
//!   [`boundary_selector_tensor`]): the definitions the reduced model will premultiply;
//! - evaluated directly per cell ([`CellOperators`]): what the full simulation runs, tested
//!   to agree with the tensors entry by entry.
//!
//! Conventions (fixed here, proved in the tests): velocities u and momenta p have `d`
//! components per cell (`u[d·c + k]`); a face's flux f is positive outward from its first cell
//! and each cell sees it with its sign σ; the geometry vector is g (`g[d·v + k]`).
//!
//! - Volume (Eq. 7): `V[(c,k), (c,k), g…g]`, a homogeneous polynomial of degree d in g: the
//!   cell volume `det[[1, x₀], …, [1, x_d]] / d!`.
//! - Flux to momentum (§5.3): `p_c = Σ_faces σ f (x_face − x_c)`, linear in g. For a uniform
//!   flow U (f = A n·U) this is `∫_∂c (U·n)(x − x_c) = vol·U` exactly.
//! - Advection (Eq. 6): `ṗ_c = −Σ_faces σ f (u_c + u_e)/2`, with `u_e = 0` across boundary
//!   faces. Then `uᵀ(A⊗f)u = −½ Σ_c |u_c|² (div f)_c`: skew (energy-neutral) whenever f is
//!   divergence-free, whatever the boundary fluxes. (The seed writes the sum without the
//!   minus sign; outward flux carries momentum out, so the sign is negative.)
//! - Diffusion (Eq. 9): the graph Laplacian `(Δu)_c = Σ_{e ∈ N_c} (u_e − u_c)` (periodic
//!   neighbours included) is negative semidefinite, so `u̇ = +μ V⁻¹ Δ u` dissipates; the seed's
//!   printed `−μV⁻¹Δ` would add energy.
//! - Divergence: `(div f)_c = Σ_faces σ f`; boundary selector D picks the boundary faces.

use rayon::prelude::*;

use crate::mesh::geometry::{face_area_normal, face_centroid, signed_volume};
use crate::mesh::{SimplexMesh, Topology};
use crate::tensor::SparseTensor;

pub use crate::mesh::volume::{volume_monomials, volume_tensor};

/// Weight of local vertex `v` in `x_face(k) − x_cell` (face k opposite vertex k).
fn lever_weight(dim: usize, k: usize, v: usize) -> f64 {
    let cell = 1.0 / (dim as f64 + 1.0);
    if v == k {
        -cell
    } else {
        1.0 / dim as f64 - cell
    }
}

/// The flux-to-momentum tensor P (§5.3): shape `[d·n_c, n_f, G]`, so that
/// `(P ⊗₂ g) f = p` with `p_c = Σ_faces σ f (x_face − x_c)`. Face centroids are taken from the
/// cell's own vertices, so periodic cells see their translated copy of a wrap face.
pub fn flux_to_momentum_tensor(mesh: &SimplexMesh, topo: &Topology) -> SparseTensor {
    let d = mesh.dim();
    let (nc, nv) = (mesh.cell_count(), mesh.vertex_count());
    let mut p = SparseTensor::new(&[d * nc, topo.face_count(), d * nv]);
    for c in 0..nc {
        let cell = mesh.cell(c);
        for l in 0..=d {
            let (face, sigma) = (topo.cell_face(c, l), topo.sign(c, l));
            for (v, &vertex) in cell.iter().enumerate() {
                for k in 0..d {
                    p.push(&[d * c + k, face, d * vertex as usize + k], sigma * lever_weight(d, l, v));
                }
            }
        }
    }
    p
}

/// The advection tensor A (Eq. 6): shape `[d·n_c, d·n_c, n_f]`, `ṗ = (A ⊗₂ f) u` with
/// `ṗ_c = −Σ_faces σ f (u_c + u_e)/2` (`u_e = 0` across boundary faces).
pub fn advection_tensor(topo: &Topology) -> SparseTensor {
    let d = topo.dim();
    let nc = cell_count(topo);
    let mut a = SparseTensor::new(&[d * nc, d * nc, topo.face_count()]);
    for c in 0..nc {
        for l in 0..=d {
            let (face, sigma) = (topo.cell_face(c, l), topo.sign(c, l));
            for k in 0..d {
                a.push(&[d * c + k, d * c + k, face], -0.5 * sigma);
                if let Some(e) = topo.neighbour(c, l) {
                    a.push(&[d * c + k, d * e + k, face], -0.5 * sigma);
                }
            }
        }
    }
    a
}

/// The graph Laplacian Δ (Eq. 9): shape `[d·n_c, d·n_c]`, `(Δu)_c = Σ_{e ∈ N_c} (u_e − u_c)`.
pub fn laplacian_tensor(topo: &Topology) -> SparseTensor {
    let d = topo.dim();
    let nc = cell_count(topo);
    let mut t = SparseTensor::new(&[d * nc, d * nc]);
    for c in 0..nc {
        for l in 0..=d {
            if let Some(e) = topo.neighbour(c, l) {
                for k in 0..d {
                    t.push(&[d * c + k, d * e + k], 1.0);
                    t.push(&[d * c + k, d * c + k], -1.0);
                }
            }
        }
    }
    t
}

/// The divergence: shape `[n_c, n_f]`, `(div f)_c = Σ_faces σ f`.
pub fn divergence_tensor(topo: &Topology) -> SparseTensor {
    let d = topo.dim();
    let nc = cell_count(topo);
    let mut t = SparseTensor::new(&[nc, topo.face_count()]);
    for c in 0..nc {
        for l in 0..=d {
            t.push(&[c, topo.cell_face(c, l)], topo.sign(c, l));
        }
    }
    t
}

/// The boundary selector D (§5.4): shape `[n_b, n_f]`, row b picks boundary face b.
pub fn boundary_selector_tensor(topo: &Topology) -> SparseTensor {
    let b = topo.boundary_faces();
    let mut t = SparseTensor::new(&[b.len(), topo.face_count()]);
    for (row, &f) in b.iter().enumerate() {
        t.push(&[row, f as usize], 1.0);
    }
    t
}

fn cell_count(topo: &Topology) -> usize {
    topo.cell_count()
}

/// The operators evaluated at one geometry g, per cell: what the full simulation runs.
#[derive(Clone, Debug)]
pub struct CellOperators {
    dim: usize,
    /// Cell volumes (the diagonal of V(g)).
    pub volumes: Vec<f64>,
    /// `lever[(c·(d+1) + l)·d + k]`: σ (x_face − x_c)_k of local face l: the entries of P ⊗₂ g.
    lever: Vec<f64>,
}

impl CellOperators {
    /// Evaluates V(g) and P ⊗₂ g for `mesh`'s topology at geometry `g`.
    pub fn new(mesh: &SimplexMesh, topo: &Topology, g: &[f64]) -> Self {
        let d = mesh.dim();
        let nc = mesh.cell_count();
        let mut volumes = Vec::with_capacity(nc);
        let mut lever = Vec::with_capacity(nc * (d + 1) * d);
        for c in 0..nc {
            let p = mesh.cell_points_at(g, c);
            volumes.push(signed_volume(d, &p));
            let xc = crate::mesh::geometry::centroid(&p);
            for l in 0..=d {
                let xf = face_centroid(&p, l);
                let sigma = topo.sign(c, l);
                for k in 0..d {
                    lever.push(sigma * (xf[k] - xc[k]));
                }
            }
        }
        Self { dim: d, volumes, lever }
    }

    /// The spatial dimension.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Entry of P ⊗₂ g: component k of cell c's momentum per unit flux through its local face l.
    pub fn lever(&self, c: usize, l: usize, k: usize) -> f64 {
        self.lever[(c * (self.dim + 1) + l) * self.dim + k]
    }

    /// p = (P ⊗₂ g) f.
    pub fn flux_to_momentum(&self, topo: &Topology, f: &[f64]) -> Vec<f64> {
        let d = self.dim;
        let nc = self.volumes.len();
        let mut p = vec![0.0; d * nc];
        for c in 0..nc {
            for l in 0..=d {
                let flux = f[topo.cell_face(c, l)];
                for k in 0..d {
                    p[d * c + k] += self.lever(c, l, k) * flux;
                }
            }
        }
        p
    }

    /// u = V⁻¹(g) (P ⊗₂ g) f: the velocity of a divergence-free flux (§5.3, Fig. 2).
    pub fn flux_to_velocity(&self, topo: &Topology, f: &[f64]) -> Vec<f64> {
        let mut u = self.flux_to_momentum(topo, f);
        self.divide_by_volume(&mut u);
        u
    }

    /// Multiplies a per-cell d-vector field by V⁻¹.
    pub fn divide_by_volume(&self, x: &mut [f64]) {
        let d = self.dim;
        for (c, v) in self.volumes.iter().enumerate() {
            for k in 0..d {
                x[d * c + k] /= v;
            }
        }
    }

    /// (P ⊗₂ g)ᵀ p.
    pub fn momentum_to_flux_transpose(&self, topo: &Topology, p: &[f64]) -> Vec<f64> {
        let d = self.dim;
        let mut out = vec![0.0; topo.face_count()];
        for c in 0..self.volumes.len() {
            for l in 0..=d {
                let face = topo.cell_face(c, l);
                for k in 0..d {
                    out[face] += self.lever(c, l, k) * p[d * c + k];
                }
            }
        }
        out
    }
}

/// ṗ = (A ⊗₂ f) u (Eq. 6), evaluated per cell (cells in parallel).
pub fn advect(topo: &Topology, f: &[f64], u: &[f64], out: &mut [f64]) {
    let d = topo.dim();
    out.par_chunks_mut(d).enumerate().for_each(|(c, o)| {
        o.fill(0.0);
        for l in 0..=d {
            let flux = -0.5 * topo.sign(c, l) * f[topo.cell_face(c, l)];
            let e = topo.neighbour(c, l);
            for k in 0..d {
                let ue = e.map_or(0.0, |e| u[d * e + k]);
                o[k] += flux * (u[d * c + k] + ue);
            }
        }
    });
}

/// out += s·Δu (Eq. 9's graph Laplacian), evaluated per cell (cells in parallel).
pub fn add_laplacian(topo: &Topology, u: &[f64], s: f64, out: &mut [f64]) {
    let d = topo.dim();
    out.par_chunks_mut(d).enumerate().for_each(|(c, o)| {
        for l in 0..=d {
            if let Some(e) = topo.neighbour(c, l) {
                for k in 0..d {
                    o[k] += s * (u[d * e + k] - u[d * c + k]);
                }
            }
        }
    });
}

/// (div f)_c = Σ_faces σ f.
pub fn divergence(topo: &Topology, f: &[f64]) -> Vec<f64> {
    let d = topo.dim();
    (0..topo.cell_count()).map(|c| (0..=d).map(|l| topo.sign(c, l) * f[topo.cell_face(c, l)]).sum()).collect()
}

/// The flux of a uniform velocity `velocity` through every face (`A n · U`, oriented): the
/// exactness test's input and a uniform initial state.
pub fn uniform_flux(mesh: &SimplexMesh, topo: &Topology, velocity: [f64; 3]) -> Vec<f64> {
    let d = mesh.dim();
    (0..topo.face_count())
        .map(|f| {
            let [c, _] = topo.face_cells(f);
            let l = topo.face_local(f)[0] as usize;
            let n = face_area_normal(d, &mesh.cell_points(c as usize), l);
            (0..d).map(|k| n[k] * velocity[k]).sum()
        })
        .collect()
}
