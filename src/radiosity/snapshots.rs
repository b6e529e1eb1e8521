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

use super::form_factor::{scaled_cosines, squared_distance, NearField};
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
    let (s, s_back) = scaled_cosines(g, i, j);
    let r = squared_distance(g, i, j, near);
    let (h, h_back) = (s / r, s_back / r);
    let c = h * h_back / (2.0 * PI);
    let v = f64::from(u8::from(conf.visible(n * i + j)));
    let d = c * v;
    // |nᵢ| = 2Aᵢ exactly (the areas are half the normals' lengths).
    [s, r, h, c, v, d, d / (2.0 * g.areas[i])]
}

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
    cache: Mutex<VecDeque<(Vec<usize>, Block)>>,
    /// Buffers of evicted blocks, reused: blocks are 100 MB and more, and returning them to
    /// the system each time costs page faults and TLB shootdowns on every core.
    spare: Mutex<Vec<Vec<f64>>>,
}

impl<'a> PairSnapshots<'a> {
    /// The snapshots of `configurations` (solved, one topology) with near-field `near`.
    pub fn new(configurations: &'a [Configuration], near: NearField) -> Self {
        let faces = configurations.first().map_or(0, |c| c.geometry.areas.len());
        Self {
            configurations,
            near,
            faces,
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
                for (c, conf) in self.configurations.iter().enumerate() {
                    for (row, &k) in tile.iter().enumerate() {
                        let values = pair_values(conf, k / n, k % n, self.near);
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
