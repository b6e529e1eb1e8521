//! The units of a premultiplication, packed symmetric rows, and the cost-ordered plan.

use std::collections::{HashMap, HashSet};

use rayon::prelude::*;

use super::{PremultiplyPlan, Unit};
use crate::tensor::{SparseTensor, Tensor};

/// Sorted reduced index tuples of a symmetric group and their packed positions.
pub(crate) struct Packing {
    pub m: usize,
    pub tuples: Vec<Vec<u32>>,
    /// Packed index of every tuple of `m^g`, sorted or not.
    pub index: Vec<u32>,
}

impl Packing {
    pub fn new(m: usize, g: usize) -> Self {
        let mut tuples = Vec::new();
        let mut t = vec![0u32; g];
        loop {
            tuples.push(t.clone());
            // Next non-decreasing tuple.
            let Some(k) = (0..g).rev().find(|&k| (t[k] as usize) < m - 1) else { break };
            let v = t[k] + 1;
            for x in &mut t[k..] {
                *x = v;
            }
        }
        let total = m.pow(g as u32);
        let mut index = vec![0u32; total];
        for (flat, slot) in index.iter_mut().enumerate() {
            let mut c: Vec<u32> = (0..g).map(|l| ((flat / m.pow((g - 1 - l) as u32)) % m) as u32).collect();
            c.sort_unstable();
            *slot = tuples.binary_search(&c).expect("sorted tuple is listed") as u32;
        }
        Self { m, tuples, index }
    }

    pub fn len(&self) -> usize {
        self.tuples.len()
    }
}

/// The unit vector of an entry: a basis row (axis) or a packed symmetrised row (group).
pub(crate) fn unit_row(
    unit: &Unit,
    coords: &[u32],
    bases: &[&Tensor],
    packings: &HashMap<Vec<usize>, Packing>,
    out: &mut Vec<f64>,
) {
    out.clear();
    match unit {
        Unit::Axis(a) => {
            let b = bases[*a];
            let m = b.shape()[1];
            let r = coords[0] as usize;
            out.extend_from_slice(&b.data()[r * m..(r + 1) * m]);
        }
        Unit::Group(axes) => {
            let p = &packings[axes];
            let b = bases[axes[0]].data();
            let m = p.m;
            out.resize(p.len(), 0.0);
            // Walk the distinct permutations of the (sorted) coordinates in place.
            let g = coords.len();
            let mut perm = [0u32; 8];
            perm[..g].copy_from_slice(coords);
            loop {
                for (t, tuple) in p.tuples.iter().enumerate() {
                    let mut prod = 1.0;
                    for (l, &c) in tuple.iter().enumerate() {
                        prod *= b[perm[l] as usize * m + c as usize];
                    }
                    out[t] += prod;
                }
                let Some(i) = (1..g).rev().find(|&i| perm[i - 1] < perm[i]) else { break };
                let j = (i..g).rev().find(|&j| perm[j] > perm[i - 1]).expect("a larger element exists");
                perm.swap(i - 1, j);
                perm[i..g].reverse();
            }
        }
    }
}

pub(crate) fn unit_size(unit: &Unit, bases: &[&Tensor], packings: &HashMap<Vec<usize>, Packing>) -> usize {
    match unit {
        Unit::Axis(a) => bases[*a].shape()[1],
        Unit::Group(g) => packings[g].len(),
    }
}

/// Number of distinct projections of `q`'s coordinates onto `axes`.
fn distinct_on(q: &SparseTensor, axes: &[usize]) -> usize {
    if axes.is_empty() {
        return 1;
    }
    let order = q.order();
    if axes.len() <= 4 {
        let mut keys: Vec<u128> = q
            .coords()
            .par_chunks(order)
            .map(|c| axes.iter().fold(0u128, |k, &a| (k << 32) | u128::from(c[a])))
            .collect();
        keys.par_sort_unstable();
        keys.dedup();
        return keys.len();
    }
    let set: HashSet<Vec<u32>> =
        q.coords().par_chunks(order).map(|c| axes.iter().map(|&a| c[a]).collect::<Vec<u32>>()).collect();
    set.len()
}

/// Plans the stages (see the module docs).
pub(crate) fn plan(q: &SparseTensor, units: &[Unit], sizes: &[usize], budget: u64) -> PremultiplyPlan {
    let mut remaining: Vec<usize> = (0..units.len()).collect();
    let mut cache: HashMap<Vec<usize>, usize> = HashMap::new();
    let mut distinct = |rem: &[usize]| -> usize {
        let mut axes: Vec<usize> = rem.iter().flat_map(|&u| units[u].axes().iter().copied()).collect();
        axes.sort_unstable();
        *cache.entry(axes.clone()).or_insert_with(|| distinct_on(q, &axes))
    };
    let mut plan = PremultiplyPlan { stages: Vec::new(), entries: Vec::new(), flops: Vec::new() };
    let mut entries = q.nnz();
    let mut block = 1usize;
    let budget_values = (budget / 8) as f64;
    while !remaining.is_empty() {
        let all: f64 = remaining.iter().map(|&u| sizes[u] as f64).product();
        let finish_cost = entries as f64 * block as f64 * all;
        let mut best: (bool, f64, Vec<usize>, usize) =
            (block as f64 * all <= budget_values, finish_cost, remaining.clone(), 1);
        if remaining.len() > 1 {
            for (k, &u) in remaining.iter().enumerate() {
                let mut rest = remaining.clone();
                rest.remove(k);
                let d = distinct(&rest);
                let s = sizes[u] as f64;
                let rest_all: f64 = rest.iter().map(|&v| sizes[v] as f64).product();
                let cost = entries as f64 * block as f64 * s + d as f64 * block as f64 * s * rest_all;
                let fits = d as f64 * block as f64 * s <= budget_values;
                if (fits, -cost) > (best.0, -best.1) {
                    best = (fits, cost, vec![u], d);
                }
            }
        }
        let (_, _, chosen, d) = best;
        let s: f64 = chosen.iter().map(|&u| sizes[u] as f64).product();
        plan.flops.push(entries as f64 * block as f64 * s);
        plan.stages.push(chosen.iter().map(|&u| units[u].clone()).collect());
        remaining.retain(|u| !chosen.contains(u));
        entries = if remaining.is_empty() { 1 } else { d };
        block *= s as usize;
        plan.entries.push(entries);
    }
    plan
}

/// Entry order sorted by the coordinates at positions `key_pos`, then those at `unit_pos`
/// (`coords` is entry-major with `s` coordinates per entry).
pub(crate) fn sorted_entries(coords: &[u32], s: usize, key_pos: &[usize], unit_pos: &[usize]) -> Vec<usize> {
    let n = coords.len().checked_div(s).unwrap_or(0);
    let mut idx: Vec<usize> = (0..n).collect();
    idx.par_sort_unstable_by(|&a, &b| {
        let ka = key_pos.iter().map(|&i| coords[a * s + i]);
        let kb = key_pos.iter().map(|&i| coords[b * s + i]);
        ka.cmp(kb).then_with(|| {
            unit_pos.iter().map(|&i| coords[a * s + i]).cmp(unit_pos.iter().map(|&i| coords[b * s + i]))
        })
    });
    idx
}

/// Splits `idx` (sorted by the first unit's coordinates, `first_of`) into consecutive ranges of
/// whole first-unit groups, at most `per_chunk` groups each (at least one).
pub(crate) fn chunks_of_groups(
    idx: &[usize],
    first_of: impl Fn(usize) -> Vec<u32>,
    per_chunk: usize,
) -> Vec<std::ops::Range<usize>> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < idx.len() {
        let mut j = i;
        let mut distinct = 0;
        while j < idx.len() && (distinct < per_chunk.max(1) || first_of(idx[j]) == first_of(idx[j - 1])) {
            if j == i || first_of(idx[j]) != first_of(idx[j - 1]) {
                distinct += 1;
            }
            j += 1;
        }
        out.push(i..j);
        i = j;
    }
    out
}

/// Positions, among `sparse_axes`, of `unit`'s axes (in the unit's order).
pub(crate) fn unit_positions(sparse_axes: &[usize], unit: &Unit) -> Vec<usize> {
    unit.axes()
        .iter()
        .map(|a| sparse_axes.iter().position(|x| x == a).expect("the unit's axes are sparse"))
        .collect()
}

/// Positions, among `sparse_axes`, of `unit`'s axes and of every other axis (the grouping key).
pub(crate) fn unit_and_key_positions(sparse_axes: &[usize], unit: &Unit) -> (Vec<usize>, Vec<usize>) {
    let unit_pos = unit_positions(sparse_axes, unit);
    let key_pos = (0..sparse_axes.len()).filter(|i| !unit_pos.contains(i)).collect();
    (unit_pos, key_pos)
}
