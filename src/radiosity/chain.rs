//! Seed 000 Table 2: radiosity as a composition of tensor contractions, a diagonal inverse, a
//! diagonal inverse square root and a matrix inverse, written with the reduction core's
//! [`Expr`] so that [`Model::reduce`] premultiplies it like any other function.
//!
//! With `n` faces, `V` vertices and pairs `k = n·i + j` (the paper's unrolling of `F`), from
//! the geometry `g` (3V), the visibility `v` (n², §8.3) and the emission `e` (3n: the three
//! colour channels stacked, `e[c·n + i]`):
//!
//! | quantity | element form | tensor form | axes (bases) |
//! |---|---|---|---|
//! | normals | `nᵢ = (g_{i1} − g_{i0}) × (g_{i2} − g_{i0})` | `n = N ⊗₁ g ⊗₂ g` | N: n, g, g |
//! | scaled cosines | `s_k = nᵢ·(cⱼ − cᵢ)` | `s = S ⊗₁ n ⊗₂ g` | S: sh, n, g |
//! | squared distances | `r_k = |cᵢ − cⱼ|² (+ (Lᵢ + Lⱼ)/16π)` | `r = R ⊗₁ g ⊗₂ g` | R: r, g, g |
//! | half form factors | `h_k = s_k / r_k` | `h = (H ⊗₂ r)⁻¹ ⊗₁ s` | H: sh, sh, r |
//! | visibility-free form factors | `c_k = h_k h_{kᵀ} / 2π` | `c = C ⊗₁ h ⊗₂ h` | C: c, sh, sh |
//! | area-free form factors | `d_k = c_k v_k` | `d = D ⊗₁ c ⊗₂ v` | D: dp, c, v |
//! | squared areas | `aᵢ = nᵢ·nᵢ` | `a = A ⊗₁ n ⊗₂ n` | A: a, n, n |
//! | form factors | `p_k = d_k / √aᵢ` | `p = (P ⊗₂ a)^(−½) ⊗₁ d` | P: dp, dp, a |
//! | radiosity | `b = (I − ρF)⁻¹ e` | `b = (I − E ⊗₂ p)⁻¹ ⊗₁ e` | I: b, b; E: b, b, dp |
//! | corrected at the training configurations | `b = (I − ρF̂(x))⁻¹ e` | `b = (I − E ⊗₂ p − Q ⊗₂ x)⁻¹ ⊗₁ e` | Q: b, b, x |
//!
//! The bases carry the paper's constraints in their names: `B_s = B_h` ("sh"), `B_d = B_p`
//! ("dp"), `B_e = B_b` ("b") — §4's rule that an inverted or rooted matrix has one basis on
//! both axes. Two constants differ from the table as printed, to make `p` *equal* the form
//! factors of [`super::form_factor`]: `1/2π` in `C` (with `|nᵢ| = 2Aᵢ`, `s_ij s_ji / (r² · 2Aᵢ)`
//! is `2π F_ij`), and the near-field term in `R` ([`NearField`]; `Lᵢ` is quadratic in `g`, so
//! `r` stays `R ⊗ g ⊗ g`). Diagonal pairs (`i = j`) have no entries: `s`, `r`, `h` are 0 there
//! and the core's diagonal inverse maps 0/0 to 0.
//!
//! Sizes: `S` has 18 entries per pair and `R` (stored symmetric in its geometry axes) up to
//! 117 — 2.9·10⁹ entries at 5,000 faces — so the pair tensors are never built whole: they are
//! streamed, a few faces' rows of pairs at a time, and premultiplied chunk by chunk.

use std::f64::consts::PI;
use std::sync::Arc;

use super::form_factor::NearField;
use super::mesh::SceneMesh;
use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};
use rayon::prelude::*;

use crate::reduce::{AxisRows, Expr, Model, ReduceError, StreamedTensor, TensorChunks};
use crate::tensor::{SparseTensor, Tensor};

/// `n = N ⊗₁ g ⊗₂ g`.
pub fn normals() -> Expr {
    Expr::tensor("N").times(1, Expr::input("g")).times(2, Expr::input("g"))
}

/// `p = (P ⊗₂ a)^(−½) ⊗₁ d`, the form factors `F_ij` at `k = n·i + j`, through every row of
/// Table 2 above it.
pub fn form_factors() -> Expr {
    let g = || Expr::input("g");
    let s = Expr::tensor("S").times(1, normals()).times(2, g());
    let r = Expr::tensor("R").times(1, g()).times(2, g());
    let h = Expr::tensor("H").times(2, r).inverse().times(1, s);
    let c = Expr::tensor("C").times(1, h.clone()).times(2, h);
    let d = Expr::tensor("D").times(1, c).times(2, Expr::input("v"));
    let a = Expr::tensor("A").times(1, normals()).times(2, normals());
    Expr::tensor("P").times(2, a).inverse_sqrt().times(1, d)
}

/// The reflected part of Eq. 16's operator, `E ⊗₂ p` (axes b, b: `ρF` per channel).
pub fn reflection() -> Expr {
    Expr::tensor("E").times(2, form_factors())
}

/// The operator Eq. 16 inverts, `I − E ⊗₂ p` (axes b, b: `I − ρF` per channel), and with
/// `corrected` `I − E ⊗₂ p − Q ⊗₂ x` ([`super::operator_correction`]).
pub fn radiosity_operator(corrected: bool) -> Expr {
    let reflected = reflection();
    let reflected =
        if corrected { reflected.plus(Expr::tensor("Q").times(2, Expr::input("x"))) } else { reflected };
    Expr::tensor("I").minus(reflected)
}

/// `b = (I − E ⊗₂ p)⁻¹ ⊗₁ e` (Eq. 16), the three channels stacked.
pub fn radiosity() -> Expr {
    radiosity_operator(false).inverse().times(1, Expr::input("e"))
}

/// `b = (I − E ⊗₂ p − Q ⊗₂ x)⁻¹ ⊗₁ e`: Eq. 16 with the reduced operator corrected at the
/// training configurations, `Q` (axes b, b, x) blended by Eq. 17's weights `x`
/// ([`super::operator_correction`]).
pub fn radiosity_corrected() -> Expr {
    radiosity_operator(true).inverse().times(1, Expr::input("e"))
}

/// Table 2's tensors for `mesh`'s topology and albedo, as a model computing `output`
/// ([`form_factors`] or [`radiosity`]); inputs `g`, `v` and `e`. The per-face tensors (`N`,
/// `A`, `I`) are stored; the pair tensors (`S`, `R`, `H`, `C`, `D`, `P`, `E`) are streamed,
/// generated a few faces' rows of pairs at a time ([`PairTensor`]), so the model of a
/// 5,000-face scene is small until it is premultiplied.
pub fn table2_model(mesh: &SceneMesh, near: NearField, output: Expr) -> Model {
    let n = mesh.len();
    let (n3, g3) = (3 * n, 3 * mesh.vertices.len());
    let faces = &mesh.faces;

    let mut tn = SparseTensor::new(&[n3, g3, g3]);
    for (i, f) in faces.iter().enumerate() {
        let [v0, v1, v2] = f.map(|v| v as usize);
        for (p, q) in [(v1, v2), (v0, v1), (v2, v0)] {
            for a in 0..3 {
                let (b, c) = ((a + 1) % 3, (a + 2) % 3);
                tn.push(&[3 * i + a, 3 * p + b, 3 * q + c], 1.0);
                tn.push(&[3 * i + a, 3 * p + c, 3 * q + b], -1.0);
            }
        }
    }
    let mut ta = SparseTensor::new(&[n, n3, n3]);
    for i in 0..n {
        for a in 0..3 {
            ta.push(&[i, 3 * i + a, 3 * i + a], 1.0);
        }
    }
    let mut ti = SparseTensor::new(&[3 * n, 3 * n]);
    for c in 0..3 {
        for i in 0..n {
            ti.push(&[c * n + i, c * n + i], 1.0);
        }
    }
    let topology = Arc::new(PairTopology {
        faces: faces.clone(),
        albedo: mesh.albedo.clone(),
        vertices: mesh.vertices.len(),
        near,
    });
    let pair = |kind| StreamedTensor::new(Arc::new(PairTensor { kind, topology: topology.clone() }));
    Model::new(output)
        .with_tensor("N", &["n", "g", "g"], tn)
        .with_tensor("S", &["sh", "n", "g"], pair(PairKind::S))
        .with_tensor("R", &["r", "g", "g"], pair(PairKind::R))
        .with_tensor("H", &["sh", "sh", "r"], pair(PairKind::H))
        .with_tensor("C", &["c", "sh", "sh"], pair(PairKind::C))
        .with_tensor("D", &["dp", "c", "v"], pair(PairKind::D))
        .with_tensor("A", &["a", "n", "n"], ta)
        .with_tensor("P", &["dp", "dp", "a"], pair(PairKind::P))
        .with_tensor("E", &["b", "b", "dp"], pair(PairKind::E))
        .with_tensor("I", &["b", "b"], ti)
        .with_input("g", "g")
        .with_input("v", "v")
        .with_input("e", "b")
}

/// What the pair tensors are made of: the scene's faces and albedo.
struct PairTopology {
    faces: Vec<[u32; 3]>,
    albedo: Vec<[f64; 3]>,
    vertices: usize,
    near: NearField,
}

/// Which of Table 2's pair tensors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum PairKind {
    S,
    R,
    H,
    C,
    D,
    P,
    E,
}

/// Pairs per chunk a pair tensor aims for (a whole number of faces' rows, at least one).
const PAIRS_PER_CHUNK: usize = 1 << 14;

/// One of Table 2's pair tensors, a chunk of whole rows `i` of pairs `k = n·i + j` at a time.
pub struct PairTensor {
    kind: PairKind,
    topology: Arc<PairTopology>,
}

impl PairTensor {
    fn faces_per_chunk(&self) -> usize {
        (PAIRS_PER_CHUNK / self.topology.faces.len().max(1)).max(1)
    }

    /// The faces `i` whose rows of pairs chunk `chunk` holds.
    fn face_rows(&self, chunk: usize) -> std::ops::Range<usize> {
        let per = self.faces_per_chunk();
        chunk * per..((chunk + 1) * per).min(self.topology.faces.len())
    }
}

impl TensorChunks for PairTensor {
    fn shape(&self) -> Vec<usize> {
        let n = self.topology.faces.len();
        let (pairs, n3, g3) = (n * n, 3 * n, 3 * self.topology.vertices);
        match self.kind {
            PairKind::S => vec![pairs, n3, g3],
            PairKind::R => vec![pairs, g3, g3],
            PairKind::H | PairKind::C | PairKind::D => vec![pairs; 3],
            PairKind::P => vec![pairs, pairs, n],
            PairKind::E => vec![n3, n3, pairs],
        }
    }

    fn chunks(&self) -> usize {
        self.topology.faces.len().div_ceil(self.faces_per_chunk())
    }

    /// Pair axes name the chunk's whole rows of pairs (`C`'s last axis: their transposes), so
    /// every pair tensor asks the pair bases for the same rows and the snapshots of a block of
    /// pairs are made once for all of them.
    fn chunk_rows(&self, chunk: usize, axis: usize) -> Option<Vec<usize>> {
        let n = self.topology.faces.len();
        let rows = self.face_rows(chunk);
        let pair_axis = match self.kind {
            PairKind::S | PairKind::R => axis == 0,
            PairKind::H | PairKind::D => true,
            PairKind::C => axis <= 1,
            PairKind::P => axis <= 1,
            PairKind::E => axis == 2,
        };
        if pair_axis {
            Some((n * rows.start..n * rows.end).collect())
        } else if self.kind == PairKind::C && axis == 2 {
            Some((0..n).flat_map(|j| rows.clone().map(move |i| n * j + i)).collect())
        } else {
            None
        }
    }

    /// `R` from its structure ([`PairTensor::premultiply_r`]); the others through their entries.
    fn premultiply_chunk(
        &self,
        chunk: usize,
        rows: &mut AxisRows<'_>,
    ) -> Option<Result<Tensor, ReduceError>> {
        (self.kind == PairKind::R).then(|| self.premultiply_r(chunk, rows))
    }

    fn chunk(&self, chunk: usize) -> SparseTensor {
        let t = &self.topology;
        let (faces, n) = (&t.faces, t.faces.len());
        let rows = self.face_rows(chunk);
        let mut out = SparseTensor::new(&self.shape());
        if self.kind == PairKind::R {
            // R is symmetric in its two geometry axes: one entry per unordered pair of indices.
            out = out.with_symmetric_axes(&[1, 2]).expect("two equal axes");
        }
        let near_c = 1.0 / (16.0 * PI);
        for i in rows {
            for j in 0..n {
                let k = n * i + j;
                match self.kind {
                    PairKind::P => out.push(&[k, k, i], 1.0),
                    _ if i == j => {}
                    PairKind::H | PairKind::D => out.push(&[k, k, k], 1.0),
                    PairKind::C => out.push(&[k, k, n * j + i], 1.0 / (2.0 * PI)),
                    PairKind::E => {
                        for c in 0..3 {
                            let rho = t.albedo[i][c];
                            if rho != 0.0 {
                                out.push(&[c * n + i, c * n + j, k], rho);
                            }
                        }
                    }
                    PairKind::S | PairKind::R => {
                        // c_j − c_i = Σ_v w_v g_v.
                        let mut w: Vec<(usize, f64)> = Vec::with_capacity(6);
                        for (face, sign) in [(j, 1.0 / 3.0), (i, -1.0 / 3.0)] {
                            for &v in &faces[face] {
                                match w.iter_mut().find(|(u, _)| *u == v as usize) {
                                    Some(e) => e.1 += sign,
                                    None => w.push((v as usize, sign)),
                                }
                            }
                        }
                        for a in 0..3 {
                            for &(v, wv) in &w {
                                if wv == 0.0 {
                                    continue;
                                }
                                if self.kind == PairKind::S {
                                    out.push(&[k, 3 * i + a, 3 * v + a], wv);
                                    continue;
                                }
                                for &(u, wu) in &w {
                                    if wu != 0.0 && u >= v {
                                        out.push(&[k, 3 * v + a, 3 * u + a], wv * wu);
                                    }
                                }
                            }
                            if self.kind == PairKind::R && t.near == NearField::Regularised {
                                for face in [i, j] {
                                    let [v0, v1, v2] = faces[face].map(|v| v as usize);
                                    for (p, q) in [(v0, v1), (v1, v2), (v2, v0)] {
                                        out.push(&[k, 3 * p + a, 3 * p + a], near_c);
                                        out.push(&[k, 3 * q + a, 3 * q + a], near_c);
                                        out.push(&[k, 3 * p + a, 3 * q + a], -near_c);
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
        out
    }
}

impl PairTensor {
    /// Chunk `chunk` of `R̂ = R ⊗₀ B_r ⊗₁ B_g ⊗₂ B_g` from the structure of `R`'s entries rather
    /// than the entries: row `k = (i, j)` of `R` is the quadratic form of
    /// `r_k = Σ_a (c_{j,a} − c_{i,a})²` (+ the near-field term `Σ_{f ∈ {i, j}} Σ_edges
    /// |g_p − g_q|² / 16π`), so with `δ_{k,a} = C[j, a] − C[i, a]` from the centroid rows
    /// `C[f, a] = ⅓ Σ_{v ∈ f} B_g[3v + a, :]` and the per-face near-field matrices
    /// `L_f = Σ_{edges pq} Σ_a e eᵀ`, `e = B_g[3p + a, :] − B_g[3q + a, :]`:
    /// `R̂ = Σ_k B_r[k, :] ⊗ (Σ_a δ_{k,a} δ_{k,a}ᵀ + (L_i + L_j) / 16π)` — one GEMM over the
    /// chunk's pairs, against 117 entries per pair through the generic premultiplication.
    fn premultiply_r(&self, chunk: usize, rows: &mut AxisRows<'_>) -> Result<Tensor, ReduceError> {
        let t = &self.topology;
        let (faces, n) = (&t.faces, t.faces.len());
        let face_rows = self.face_rows(chunk);
        let pairs: Vec<usize> = (n * face_rows.start..n * face_rows.end).collect();
        let br = rows(0, &pairs)?;
        let everything: Vec<usize> = (0..3 * t.vertices).collect();
        let bg = rows(1, &everything)?;
        let (mr, mg) = (br.shape()[1], bg.shape()[1]);
        let g = bg.data();
        let row = |v: u32, a: usize| &g[(3 * v as usize + a) * mg..(3 * v as usize + a + 1) * mg];
        let mut centroids = vec![0.0; n * 3 * mg];
        for (f, face) in faces.iter().enumerate() {
            for a in 0..3 {
                let out = &mut centroids[(3 * f + a) * mg..(3 * f + a + 1) * mg];
                for &v in face {
                    for (o, x) in out.iter_mut().zip(row(v, a)) {
                        *o += x / 3.0;
                    }
                }
            }
        }
        let mg2 = mg * mg;
        let near: Option<Vec<f64>> = (t.near == NearField::Regularised).then(|| {
            let mut l = vec![0.0; n * mg2];
            let mut e = vec![0.0; mg];
            for (f, face) in faces.iter().enumerate() {
                let lf = &mut l[f * mg2..(f + 1) * mg2];
                let [v0, v1, v2] = *face;
                for (p, q) in [(v0, v1), (v1, v2), (v2, v0)] {
                    for a in 0..3 {
                        for ((x, gp), gq) in e.iter_mut().zip(row(p, a)).zip(row(q, a)) {
                            *x = gp - gq;
                        }
                        for (b, &eb) in e.iter().enumerate() {
                            for (o, &ec) in lf[b * mg..(b + 1) * mg].iter_mut().zip(&e) {
                                *o += eb * ec;
                            }
                        }
                    }
                }
            }
            l
        });
        let near_c = 1.0 / (16.0 * PI);
        // Q: one m_g × m_g block per pair of the chunk (zero on the diagonal i = j).
        let mut q = vec![0.0; pairs.len() * mg2];
        q.par_chunks_mut(mg2).zip(&pairs).for_each_init(
            || vec![0.0; mg],
            |delta, (qk, &k)| {
                let (i, j) = (k / n, k % n);
                if i == j {
                    return;
                }
                for a in 0..3 {
                    let (ci, cj) = (&centroids[(3 * i + a) * mg..], &centroids[(3 * j + a) * mg..]);
                    for (c, d) in delta.iter_mut().enumerate() {
                        *d = cj[c] - ci[c];
                    }
                    for (b, &db) in delta.iter().enumerate() {
                        for (o, &dc) in qk[b * mg..(b + 1) * mg].iter_mut().zip(delta.iter()) {
                            *o += db * dc;
                        }
                    }
                }
                if let Some(l) = &near {
                    for ((o, li), lj) in
                        qk.iter_mut().zip(&l[i * mg2..(i + 1) * mg2]).zip(&l[j * mg2..(j + 1) * mg2])
                    {
                        *o += near_c * (li + lj);
                    }
                }
            },
        );
        let mut out = vec![0.0; mr * mg2];
        matmul(
            MatMut::from_row_major_slice_mut(&mut out, mr, mg2),
            Accum::Replace,
            MatRef::from_row_major_slice(br.data(), pairs.len(), mr).transpose(),
            MatRef::from_row_major_slice(&q, pairs.len(), mg2),
            1.0,
            Par::rayon(0),
        );
        Ok(Tensor::from_vec(&[mr, mg, mg], out).expect("shape matches"))
    }
}

/// The emission stacked by channel (`e[c·n + i]`), the layout of [`radiosity`]'s `e` and `b`.
pub fn stack_channels(per_face: &[[f64; 3]]) -> Vec<f64> {
    (0..3).flat_map(|c| per_face.iter().map(move |v| v[c])).collect()
}
