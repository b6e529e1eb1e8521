//! The pair quantities of Table 2 — scaled cosines `s`, squared distances `r`, half form factors
//! `h`, visibility-free form factors `c`, visibility `v`, area-free form factors `d` and form
//! factors `p`, `n²` values each — of every training configuration, regenerated on demand from
//! each configuration's face geometry and visibility bits (seed 000 §9). At 5,000 faces and 540
//! configurations one quantity's snapshots are 107 GB, so they are never stored: the PCA's Gram
//! pass and the premultiplication's basis rows ask for blocks of pairs, and all seven quantities
//! of a block are made together (they share `s`, `r` and `Vis`) and kept for the next request.

use std::collections::VecDeque;
use std::f64::consts::PI;
use std::sync::{Arc, Mutex};

use rayon::prelude::*;

use glam::DVec3;

use super::form_factor::{scaled_cosines_of, NearField};
use super::train::{Configuration, Quantity};
use crate::reduce::{ReduceError, SnapshotRows};
use crate::tensor::Tensor;

/// The pair quantities in the order [`pair_values`] returns them.
pub const PAIR_QUANTITIES: [Quantity; 7] =
    [Quantity::S, Quantity::R, Quantity::H, Quantity::C, Quantity::V, Quantity::D, Quantity::P];

/// `[s, r, h, c, v, d, p]` of pair `(i, j)` in configuration `conf` (all 0 on the diagonal):
/// `h = s/r`, `c = h_ij h_ji / 2π`, `d = c·Vis`, `p = d / |nᵢ|` — Table 2 row by row.
pub fn pair_values(conf: &Configuration, i: usize, j: usize, near: NearField) -> [f64; 7] {
    if i == j {
        return [0.0; 7];
    }
    let g = &conf.geometry;
    let n = g.areas.len();
    let face = |f: usize| FaceAt {
        centroid: g.centroids[f],
        normal: g.normals[f],
        edge_squares: g.edge_squares[f],
        area: g.areas[f],
    };
    pair_formula(face(i), face(j), conf.visible(n * i + j), near)
}

/// What [`pair_formula`] needs of one face in one configuration.
#[derive(Clone, Copy)]
struct FaceAt {
    centroid: DVec3,
    normal: DVec3,
    edge_squares: f64,
    area: f64,
}

/// Table 2 row by row for faces `i ≠ j` (see [`pair_values`]): the one formula behind
/// [`pair_values`] and the blocks of [`PairSnapshots`].
#[inline(always)]
fn pair_formula(i: FaceAt, j: FaceAt, visible: bool, near: NearField) -> [f64; 7] {
    let between = j.centroid - i.centroid;
    let (s, s_back) = scaled_cosines_of(between, i.normal, j.normal);
    let r = near.squared_distance(between, i.edge_squares, j.edge_squares);
    let (h, h_back) = (s / r, s_back / r);
    let c = h * h_back / (2.0 * PI);
    let v = f64::from(u8::from(visible));
    let d = c * v;
    // |nᵢ| = 2Aᵢ exactly (the areas are half the normals' lengths).
    [s, r, h, c, v, d, d / (2.0 * i.area)]
}

/// Fields of a face kept per configuration in [`PairSnapshots`]: centroid, normal, sum of
/// squared edge lengths, area.
const FIELDS: usize = 8;

/// Blocks of pairs kept after they are made (the premultiplication asks for a block's rows
/// and, for `C`, its transposed rows, tensor after tensor).
const CACHED_BLOCKS: usize = 2;

/// Rows per parallel task while generating (its output stays in cache while the task walks
/// the configurations).
const TILE: usize = 32;

type Block = Arc<Vec<Arc<Tensor>>>;

/// Every pair quantity of `configurations`, regenerated a block of pairs at a time.
pub struct PairSnapshots<'a> {
    configurations: &'a [Configuration],
    near: NearField,
    faces: usize,
    /// Face geometry of every configuration, face-major: `series[(f·FIELDS + field)·T + c]`,
    /// so that a pair's values over the configurations read and write contiguous memory.
    series: Vec<f64>,
    cache: Mutex<VecDeque<(Vec<usize>, Block)>>,
    /// Buffers of evicted blocks, reused: blocks are 100 MB and more, and returning them to
    /// the system each time costs page faults and TLB shootdowns on every core.
    spare: Mutex<Vec<Vec<f64>>>,
}

impl<'a> PairSnapshots<'a> {
    /// The snapshots of `configurations` (solved, one topology) with near-field `near`.
    pub fn new(configurations: &'a [Configuration], near: NearField) -> Self {
        let faces = configurations.first().map_or(0, |c| c.geometry.areas.len());
        let t = configurations.len();
        let mut series = vec![0.0; faces * FIELDS * t];
        series.par_chunks_mut(FIELDS * t).enumerate().for_each(|(f, out)| {
            for (c, conf) in configurations.iter().enumerate() {
                let g = &conf.geometry;
                let (centroid, normal) = (g.centroids[f], g.normals[f]);
                let fields = [
                    centroid.x,
                    centroid.y,
                    centroid.z,
                    normal.x,
                    normal.y,
                    normal.z,
                    g.edge_squares[f],
                    g.areas[f],
                ];
                for (k, v) in fields.into_iter().enumerate() {
                    out[k * t + c] = v;
                }
            }
        });
        Self {
            configurations,
            near,
            faces,
            series,
            cache: Mutex::new(VecDeque::new()),
            spare: Mutex::new(Vec::new()),
        }
    }

    /// The snapshot source of quantity `q` (one of [`PAIR_QUANTITIES`]).
    pub fn quantity(&self, q: Quantity) -> Option<PairQuantity<'_, 'a>> {
        PAIR_QUANTITIES.iter().position(|&p| p == q).map(|slot| PairQuantity { all: self, slot })
    }

    /// Rows `indices` (pairs `k = n·i + j`) of all seven quantities.
    fn block(&self, indices: &[usize]) -> Result<Block, ReduceError> {
        if let Some((_, b)) =
            self.cache.lock().expect("no panics while locked").iter().find(|(k, _)| k == indices)
        {
            return Ok(b.clone());
        }
        let (n, t) = (self.faces, self.configurations.len());
        if let Some(&k) = indices.iter().find(|&&k| k >= n * n) {
            return Err(ReduceError::BadBasis {
                basis: "pair snapshots".into(),
                detail: format!("pair {k} of {} faces", n),
            });
        }
        let mut out: Vec<Vec<f64>> = {
            let mut spare = self.spare.lock().expect("no panics while locked");
            (0..7)
                .map(|_| {
                    let mut v = spare.pop().unwrap_or_default();
                    v.resize(indices.len() * t, 0.0);
                    v
                })
                .collect()
        };
        let [o0, o1, o2, o3, o4, o5, o6] = &mut out[..] else { unreachable!("seven quantities") };
        let width = TILE * t;
        (
            o0.par_chunks_mut(width),
            o1.par_chunks_mut(width),
            o2.par_chunks_mut(width),
            o3.par_chunks_mut(width),
            o4.par_chunks_mut(width),
            o5.par_chunks_mut(width),
            o6.par_chunks_mut(width),
            indices.par_chunks(TILE),
        )
            .into_par_iter()
            .for_each(|(q0, q1, q2, q3, q4, q5, q6, tile)| {
                let mut outs = [q0, q1, q2, q3, q4, q5, q6];
                for (row, &k) in tile.iter().enumerate() {
                    let (i, j) = (k / n, k % n);
                    if i == j {
                        for o in outs.iter_mut() {
                            o[row * t..(row + 1) * t].fill(0.0);
                        }
                        continue;
                    }
                    let fi = &self.series[i * FIELDS * t..(i + 1) * FIELDS * t];
                    let fj = &self.series[j * FIELDS * t..(j + 1) * FIELDS * t];
                    let face = |f: &[f64], c: usize| FaceAt {
                        centroid: DVec3::new(f[c], f[t + c], f[2 * t + c]),
                        normal: DVec3::new(f[3 * t + c], f[4 * t + c], f[5 * t + c]),
                        edge_squares: f[6 * t + c],
                        area: f[7 * t + c],
                    };
                    for (c, conf) in self.configurations.iter().enumerate() {
                        let values = pair_formula(face(fi, c), face(fj, c), conf.visible(k), self.near);
                        for (o, v) in outs.iter_mut().zip(values) {
                            o[row * t + c] = v;
                        }
                    }
                }
            });
        let block: Block = Arc::new(
            out.into_iter()
                .map(|v| Arc::new(Tensor::from_vec(&[indices.len(), t], v).expect("rows × configurations")))
                .collect(),
        );
        let mut cache = self.cache.lock().expect("no panics while locked");
        if cache.len() == CACHED_BLOCKS {
            if let Some((_, old)) = cache.pop_front() {
                // Recycled if nobody holds it any more.
                if let Ok(tensors) = Arc::try_unwrap(old) {
                    let mut spare = self.spare.lock().expect("no panics while locked");
                    spare.extend(
                        tensors.into_iter().filter_map(|t| Arc::try_unwrap(t).ok()).map(Tensor::into_data),
                    );
                }
            }
        }
        cache.push_back((indices.to_vec(), block.clone()));
        Ok(block)
    }
}

/// One pair quantity's snapshots (a view of [`PairSnapshots`]).
pub struct PairQuantity<'s, 'a> {
    all: &'s PairSnapshots<'a>,
    slot: usize,
}

impl SnapshotRows for PairQuantity<'_, '_> {
    fn dim(&self) -> usize {
        self.all.faces * self.all.faces
    }
    fn count(&self) -> usize {
        self.all.configurations.len()
    }
    fn rows_at(&self, indices: &[usize]) -> Result<Arc<Tensor>, ReduceError> {
        Ok(self.all.block(indices)?[self.slot].clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::radiosity::SceneMesh;

    /// The blocks (face-major, every configuration of a pair at once) hold exactly
    /// [`pair_values`] of every pair, diagonal and both near-field treatments included, also
    /// when a recycled buffer is reused for a later block.
    #[test]
    fn blocks_hold_the_pair_values_of_every_configuration() {
        let mut mesh = SceneMesh::parallelogram(DVec3::ZERO, DVec3::X, DVec3::Y, 2, [0.5; 3], "floor");
        mesh.append(&SceneMesh::parallelogram(
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::Y,
            DVec3::X,
            2,
            [0.5; 3],
            "ceiling",
        ));
        let n = mesh.len();
        let configurations: Vec<Configuration> = (0..5)
            .map(|c| {
                let g: Vec<f64> = mesh
                    .vertices
                    .iter()
                    .flat_map(|v| [v.x, v.y * (1.0 + 0.1 * c as f64), v.z + 0.05 * (c as f64 * v.x).sin()])
                    .collect();
                let geometry = mesh.with_g(&g).unwrap().geometry();
                let visibility = (0..(n * n).div_ceil(64))
                    .map(|w| 0x9E37_79B9_7F4A_7C15u64.rotate_left((w + c) as u32))
                    .collect();
                Configuration {
                    params: vec![c as f64],
                    g,
                    geometry,
                    visibility,
                    emission: vec![[0.0; 3]; n],
                    radiosity: vec![[0.0; 3]; n],
                    near_correction: Vec::new().into(),
                }
            })
            .collect();
        for near in [NearField::Regularised, NearField::Eq15] {
            let snapshots = PairSnapshots::new(&configurations, near);
            // Three blocks (more than are cached), the last two overlapping the first.
            for indices in [(0..n * n).collect::<Vec<_>>(), (3..40).collect(), (0..n * n).rev().collect()] {
                for (slot, &q) in PAIR_QUANTITIES.iter().enumerate() {
                    let rows = snapshots.quantity(q).unwrap().rows_at(&indices).unwrap();
                    for (r, &k) in indices.iter().enumerate() {
                        for (c, conf) in configurations.iter().enumerate() {
                            let want = pair_values(conf, k / n, k % n, near)[slot];
                            assert_eq!(
                                rows.data()[r * configurations.len() + c],
                                want,
                                "{q:?} pair {k} conf {c}"
                            );
                        }
                    }
                }
            }
        }
    }
}
