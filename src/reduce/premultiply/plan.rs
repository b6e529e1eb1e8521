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

/// The cheapest order to contract the units `rem` one after another, starting from `entries`
/// entries of `block` values: (multiply–adds, order). Contracting unit `u` costs its entries ×
/// block × `sizes[u]` and leaves one entry per distinct coordinate on the units still to come
/// (`distinct`), so the order matters: `P[k, k, i]` of Table 2 costs `n·m²` per face row by
/// its two pair axes first and `n²·m²·m_a` by its face axis first. Exhaustive over the `u!`
/// orders of `u` units (the distinct counts are cached per set of axes): the tensors here have
/// at most five units.
fn best_order(
    rem: &[usize],
    entries: f64,
    block: f64,
    sizes: &[usize],
    distinct: &mut dyn FnMut(&[usize]) -> usize,
) -> (f64, Vec<usize>) {
    if let [u] = rem {
        return (entries * block * sizes[*u] as f64, vec![*u]);
    }
    let mut best = (f64::INFINITY, Vec::new());
    for (k, &u) in rem.iter().enumerate() {
        let mut rest = rem.to_vec();
        rest.remove(k);
        let s = sizes[u] as f64;
        let d = distinct(&rest) as f64;
        let (tail, order) = best_order(&rest, d, block * s, sizes, distinct);
        let cost = entries * block * s + tail;
        if cost < best.0 {
            best = (cost, std::iter::once(u).chain(order).collect());
        }
    }
    best
}

/// Plans the stages (see the module docs). Each step is a single unit (an intermediate
/// materialised whole) or finishing every remaining unit in one streamed stage; either way the
/// units after it are costed in their best order ([`best_order`]), so finishing is chosen
/// whenever its final block fits the budget, and a finishing stage lists its units in the
/// order [`Partial::finish`](super::cpu::Partial::finish) contracts them last-to-first.
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
        let (finish_cost, chain) = best_order(&remaining, entries as f64, block as f64, sizes, &mut distinct);
        // The finishing stage's first unit is contracted last.
        let finish: Vec<usize> = chain.into_iter().rev().collect();
        let mut best: (bool, f64, Vec<usize>, usize) =
            (block as f64 * all <= budget_values, finish_cost, finish, 1);
        if remaining.len() > 1 {
            for (k, &u) in remaining.iter().enumerate() {
                let mut rest = remaining.clone();
                rest.remove(k);
                let d = distinct(&rest);
                let s = sizes[u] as f64;
                let (tail, _) = best_order(&rest, d as f64, block as f64 * s, sizes, &mut distinct);
                let cost = entries as f64 * block as f64 * s + tail;
                let fits = d as f64 * block as f64 * s <= budget_values;
                if (fits, -cost) > (best.0, -best.1) {
                    best = (fits, cost, vec![u], d);
                }
            }
        }
        let (_, cost, chosen, d) = best;
        let s: f64 = chosen.iter().map(|&u| sizes[u] as f64).product();
        let finishing = chosen.len() == remaining.len();
        plan.flops.push(if finishing { cost } else { entries as f64 * block as f64 * s });
        plan.stages.push(chosen.iter().map(|&u| units[u].clone()).collect());
        remaining.retain(|u| !chosen.contains(u));
        entries = if remaining.is_empty() { 1 } else { d };
        block *= s as usize;
        plan.entries.push(entries);
    }
    plan
}

/// Entry order sorted by the coordinates at positions `key_pos`, then those at `unit_pos`
/// (`coords` is entry-major with `s` coordinates per entry). The coordinates and the entry's
/// index are packed into one integer key where they fit in 128 bits (always, for a chunk's
/// local coordinates): sorting plain integers is several times faster than comparing
/// coordinate lists.
pub(crate) fn sorted_entries(coords: &[u32], s: usize, key_pos: &[usize], unit_pos: &[usize]) -> Vec<usize> {
    let n = coords.len().checked_div(s).unwrap_or(0);
    let positions: Vec<usize> = key_pos.iter().chain(unit_pos).copied().collect();
    let bits = |v: u64| (u64::BITS - v.leading_zeros()) as usize;
    let mut widths = vec![0usize; positions.len()];
    for e in coords.chunks_exact(s.max(1)) {
        for (w, &p) in widths.iter_mut().zip(&positions) {
            *w = (*w).max(bits(u64::from(e[p])));
        }
    }
    let index_bits = bits(n as u64);
    let total: usize = widths.iter().sum::<usize>() + index_bits;
    let pack = |e: usize| {
        let mut k = 0u128;
        for (w, &p) in widths.iter().zip(&positions) {
            k = (k << w) | u128::from(coords[e * s + p]);
        }
        (k << index_bits) | e as u128
    };
    let mask = (1u128 << index_bits) - 1;
    if total <= 64 {
        let mut keys: Vec<u64> = (0..n).into_par_iter().map(|e| pack(e) as u64).collect();
        keys.par_sort_unstable();
        return keys.into_par_iter().map(|k| (u128::from(k) & mask) as usize).collect();
    }
    if total <= 128 {
        let mut keys: Vec<u128> = (0..n).into_par_iter().map(pack).collect();
        keys.par_sort_unstable();
        return keys.into_par_iter().map(|k| (k & mask) as usize).collect();
    }
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
