//! Sparse full-space tensors as coordinate lists: each nonzero keeps its index on every axis,
//! so locality survives (a fluid cell's entries touch its 4 faces and 4 vertices, a radiosity
//! pair's touch 2 faces). Duplicate coordinates add up.
//!
//! Groups of axes may be declared symmetric (the fluid volume tensor's three geometry axes):
//! the tensor then has the same value at every permutation of a group's indices, and only one
//! entry per multiset is stored, with the group's indices sorted. An entry at (…, 1, 1, 4, …)
//! in a symmetric group of three stands for the three full entries (1,1,4), (1,4,1), (4,1,1).

use super::dense::{strides, Tensor};
use super::error::TensorError;

/// A sparse tensor in coordinate (COO) form.
#[derive(Clone, Debug, PartialEq)]
pub struct SparseTensor {
    shape: Vec<usize>,
    /// `nnz × order` indices, entry-major; sorted within each symmetric group.
    coords: Vec<u32>,
    values: Vec<f64>,
    /// Disjoint groups of axes (ascending) whose indices may be permuted freely.
    symmetric: Vec<Vec<usize>>,
}

/// Every distinct permutation of `sorted` (ascending), in lexicographic order: each multiset
/// permutation exactly once (the classic next-permutation walk).
pub fn distinct_permutations(sorted: &[u32]) -> Vec<Vec<u32>> {
    let mut p = sorted.to_vec();
    let mut out = vec![p.clone()];
    loop {
        let Some(i) = (1..p.len()).rev().find(|&i| p[i - 1] < p[i]) else { return out };
        let j = (i..p.len()).rev().find(|&j| p[j] > p[i - 1]).expect("a larger element exists");
        p.swap(i - 1, j);
        p[i..].reverse();
        out.push(p.clone());
    }
}

impl SparseTensor {
    /// An empty tensor of `shape` (every axis shorter than 2³²).
    pub fn new(shape: &[usize]) -> Self {
        assert!(shape.iter().all(|&n| n <= u32::MAX as usize), "axis lengths must fit in u32");
        Self { shape: shape.to_vec(), coords: Vec::new(), values: Vec::new(), symmetric: Vec::new() }
    }

    /// Declares `axes` (two or more, equal lengths, not in another group) symmetric: existing
    /// and later entries have their indices on these axes sorted, and each stands for all its
    /// distinct permutations.
    pub fn with_symmetric_axes(mut self, axes: &[usize]) -> Result<Self, TensorError> {
        let what = "symmetric axes";
        let mut group = axes.to_vec();
        group.sort_unstable();
        group.dedup();
        if group.len() < 2 || group.len() > 6 {
            return Err(TensorError::NotFinite {
                what: what.into(),
                detail: format!("a group needs 2 to 6 distinct axes, got {axes:?}"),
            });
        }
        for &a in &group {
            if a >= self.order() {
                return Err(TensorError::NoSuchAxis { what: what.into(), axis: a, order: self.order() });
            }
            if self.shape[a] != self.shape[group[0]] {
                return Err(TensorError::Shape {
                    what: what.into(),
                    axis: a,
                    expected: self.shape[group[0]],
                    found: self.shape[a],
                });
            }
            if self.symmetric.iter().any(|g| g.contains(&a)) {
                return Err(TensorError::NotFinite {
                    what: what.into(),
                    detail: format!("axis {a} is already in a symmetric group"),
                });
            }
        }
        let order = self.order();
        for c in self.coords.chunks_mut(order.max(1)) {
            let mut v: Vec<u32> = group.iter().map(|&a| c[a]).collect();
            v.sort_unstable();
            for (&a, x) in group.iter().zip(v) {
                c[a] = x;
            }
        }
        self.symmetric.push(group);
        Ok(self)
    }

    /// The symmetric groups of axes.
    pub fn symmetric_groups(&self) -> &[Vec<usize>] {
        &self.symmetric
    }

    /// Every full coordinate entry `e` stands for (one, unless it lies in symmetric groups).
    pub fn expanded_coords(&self, e: usize) -> Vec<Vec<u32>> {
        let mut out = vec![self.coords_of(e).to_vec()];
        for g in &self.symmetric {
            let sorted: Vec<u32> = g.iter().map(|&a| self.coords_of(e)[a]).collect();
            let perms = distinct_permutations(&sorted);
            out = out
                .into_iter()
                .flat_map(|c| {
                    perms.iter().map(move |p| {
                        let mut c = c.clone();
                        for (&a, &x) in g.iter().zip(p) {
                            c[a] = x;
                        }
                        c
                    })
                })
                .collect();
        }
        out
    }

    /// From coordinates (`nnz × order`, entry-major) and values, checking every index.
    pub fn from_coords(
        what: &str,
        shape: &[usize],
        coords: Vec<u32>,
        values: Vec<f64>,
    ) -> Result<Self, TensorError> {
        let order = shape.len();
        if coords.len() != values.len() * order {
            return Err(TensorError::DataLength {
                what: what.into(),
                shape: shape.to_vec(),
                expected: values.len() * order,
                found: coords.len(),
            });
        }
        for (entry, c) in coords.chunks(order.max(1)).enumerate() {
            for (axis, (&i, &n)) in c.iter().zip(shape).enumerate() {
                if i as usize >= n {
                    return Err(TensorError::IndexOutOfRange {
                        what: what.into(),
                        entry,
                        axis,
                        index: i as usize,
                        size: n,
                    });
                }
            }
        }
        if let Some(entry) = values.iter().position(|v| !v.is_finite()) {
            return Err(TensorError::NotFinite {
                what: what.into(),
                detail: format!("entry {entry} is not finite"),
            });
        }
        Ok(Self { shape: shape.to_vec(), coords, values, symmetric: Vec::new() })
    }

    /// Adds `value` at `index` (panics on a bad index: use [`SparseTensor::from_coords`] for
    /// data that comes from users).
    pub fn push(&mut self, index: &[usize], value: f64) {
        assert_eq!(index.len(), self.order(), "index order");
        let start = self.coords.len();
        for (&i, &n) in index.iter().zip(&self.shape) {
            assert!(i < n, "index {i} out of range for axis length {n}");
            self.coords.push(i as u32);
        }
        for g in &self.symmetric {
            // Groups have at most 6 axes: sorted on the stack (a pair tensor pushes millions).
            let c = &mut self.coords[start..];
            let mut v = [0u32; 6];
            for (x, &a) in v.iter_mut().zip(g) {
                *x = c[a];
            }
            let v = &mut v[..g.len()];
            v.sort_unstable();
            for (&a, &x) in g.iter().zip(v.iter()) {
                c[a] = x;
            }
        }
        self.values.push(value);
    }

    /// Axis lengths.
    pub fn shape(&self) -> &[usize] {
        &self.shape
    }

    /// Number of axes.
    pub fn order(&self) -> usize {
        self.shape.len()
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.values.len()
    }

    /// Entry `e`'s index on every axis.
    pub fn coords_of(&self, e: usize) -> &[u32] {
        &self.coords[e * self.order()..(e + 1) * self.order()]
    }

    /// All coordinates, entry-major.
    pub fn coords(&self) -> &[u32] {
        &self.coords
    }

    /// All values.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Stored entries `range` (clamped to the entries there are) as a tensor of the same
    /// shape and symmetric groups: the tensor is the sum of its entry ranges — what a rank
    /// premultiplies of a tensor shared over ranks.
    pub fn entries(&self, range: std::ops::Range<usize>) -> SparseTensor {
        let end = range.end.min(self.nnz());
        let start = range.start.min(end);
        let o = self.order();
        SparseTensor {
            shape: self.shape.clone(),
            coords: self.coords[start * o..end * o].to_vec(),
            values: self.values[start..end].to_vec(),
            symmetric: self.symmetric.clone(),
        }
    }

    /// The dense equivalent (duplicates summed, symmetric groups expanded).
    pub fn to_dense(&self) -> Tensor {
        let mut t = Tensor::zeros(&self.shape);
        let s = strides(&self.shape);
        for e in 0..self.nnz() {
            for c in self.expanded_coords(e) {
                let o: usize = c.iter().zip(&s).map(|(&i, &st)| i as usize * st).sum();
                t.data_mut()[o] += self.values[e];
            }
        }
        t
    }

    /// `Q ⊗_a x ⊗_b y …` straight from the nonzeros: each entry's value times the vectors'
    /// components at its indices on the contracted axes, added at its remaining indices.
    pub fn contract_axes(&self, what: &str, args: &[(usize, &[f64])]) -> Result<Tensor, TensorError> {
        let contracted = self.contracted_axes(what, args)?;
        let kept: Vec<usize> = (0..self.order()).filter(|&a| contracted[a].is_none()).collect();
        let out_shape: Vec<usize> = kept.iter().map(|&a| self.shape[a]).collect();
        let out_strides = strides(&out_shape);
        let mut out = Tensor::zeros(&out_shape);
        self.for_each_contracted(&contracted, |c, v| {
            let o: usize = kept.iter().zip(&out_strides).map(|(&a, &s)| c[a] as usize * s).sum();
            out.data_mut()[o] += v;
        });
        Ok(out)
    }
}

impl SparseTensor {
    /// `Q ⊗_a x ⊗_b y …` kept sparse: the remaining axes' entries, duplicates summed and
    /// symmetric groups expanded, zeros dropped. What a full-space evaluation needs when the
    /// result is itself large and sparse (seed 000 Table 2: `H ⊗₂ r` is an `n² × n²`
    /// diagonal).
    pub fn contract_axes_sparse(
        &self,
        what: &str,
        args: &[(usize, &[f64])],
    ) -> Result<SparseTensor, TensorError> {
        let contracted = self.contracted_axes(what, args)?;
        let kept: Vec<usize> = (0..self.order()).filter(|&a| contracted[a].is_none()).collect();
        let mut acc: std::collections::HashMap<Vec<u32>, f64> = std::collections::HashMap::new();
        self.for_each_contracted(&contracted, |c, v| {
            if v != 0.0 {
                *acc.entry(kept.iter().map(|&a| c[a]).collect()).or_insert(0.0) += v;
            }
        });
        let mut entries: Vec<(Vec<u32>, f64)> = acc.into_iter().filter(|(_, v)| *v != 0.0).collect();
        entries.sort_unstable_by(|a, b| a.0.cmp(&b.0));
        let shape: Vec<usize> = kept.iter().map(|&a| self.shape[a]).collect();
        let mut coords = Vec::with_capacity(entries.len() * kept.len());
        let mut values = Vec::with_capacity(entries.len());
        for (c, v) in entries {
            coords.extend(c);
            values.push(v);
        }
        Ok(SparseTensor { shape, coords, values, symmetric: Vec::new() })
    }

    /// Every full entry (symmetric groups expanded) with its value times the contracted
    /// vectors' components at its indices.
    fn for_each_contracted(&self, contracted: &[Option<&[f64]>], mut f: impl FnMut(&[u32], f64)) {
        for e in 0..self.nnz() {
            for c in self.expanded_coords(e) {
                let mut v = self.values[e];
                for (axis, x) in contracted.iter().enumerate() {
                    if let Some(x) = x {
                        v *= x[c[axis] as usize];
                    }
                }
                f(&c, v);
            }
        }
    }

    /// The vector each axis is contracted with (`None`: kept), checking the axes and lengths.
    fn contracted_axes<'a>(
        &self,
        what: &str,
        args: &[(usize, &'a [f64])],
    ) -> Result<Vec<Option<&'a [f64]>>, TensorError> {
        let mut contracted: Vec<Option<&[f64]>> = vec![None; self.order()];
        for &(axis, x) in args {
            match self.shape.get(axis) {
                None => return Err(TensorError::NoSuchAxis { what: what.into(), axis, order: self.order() }),
                Some(&n) if n != x.len() => {
                    return Err(TensorError::Shape { what: what.into(), axis, expected: n, found: x.len() })
                }
                Some(_) if contracted[axis].is_some() => {
                    return Err(TensorError::NoSuchAxis {
                        what: format!("{what} (axis contracted twice)"),
                        axis,
                        order: self.order(),
                    })
                }
                Some(_) => contracted[axis] = Some(x),
            }
        }
        Ok(contracted)
    }

    /// The diagonal of a square matrix whose every entry lies on it; `None` otherwise.
    pub fn diagonal(&self) -> Option<Vec<f64>> {
        if self.order() != 2 || self.shape[0] != self.shape[1] {
            return None;
        }
        let mut d = vec![0.0; self.shape[0]];
        for e in 0..self.nnz() {
            let c = self.coords_of(e);
            if c[0] != c[1] {
                return None;
            }
            d[c[0] as usize] += self.values[e];
        }
        Some(d)
    }

    /// The diagonal matrix with `d` on its diagonal.
    pub fn from_diagonal(d: &[f64]) -> Self {
        let coords = (0..d.len() as u32).flat_map(|i| [i, i]).collect();
        Self { shape: vec![d.len(), d.len()], coords, values: d.to_vec(), symmetric: Vec::new() }
    }

    /// `self + s·other` (same shape), as concatenated entries.
    pub fn add_scaled(&self, other: &SparseTensor, s: f64) -> Result<SparseTensor, TensorError> {
        if let Some(axis) =
            (0..self.order().max(other.order())).find(|&a| self.shape.get(a) != other.shape.get(a))
        {
            return Err(TensorError::Shape {
                what: "sparse sum".into(),
                axis,
                expected: self.shape.get(axis).copied().unwrap_or(0),
                found: other.shape.get(axis).copied().unwrap_or(0),
            });
        }
        let expand = |t: &SparseTensor| -> (Vec<u32>, Vec<f64>) {
            let mut coords = Vec::new();
            let mut values = Vec::new();
            for e in 0..t.nnz() {
                for c in t.expanded_coords(e) {
                    coords.extend(c);
                    values.push(t.values[e]);
                }
            }
            (coords, values)
        };
        let (mut coords, mut values) = expand(self);
        let (c2, v2) = expand(other);
        coords.extend(c2);
        values.extend(v2.into_iter().map(|v| s * v));
        Ok(SparseTensor { shape: self.shape.clone(), coords, values, symmetric: Vec::new() })
    }

    /// `c · self`.
    pub fn scale(&self, c: f64) -> SparseTensor {
        let mut t = self.clone();
        t.values.iter_mut().for_each(|v| *v *= c);
        t
    }

    /// Number of values the dense equivalent holds (saturating).
    pub fn dense_len(&self) -> usize {
        self.shape.iter().fold(1usize, |a, &n| a.saturating_mul(n))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sparse_contraction_matches_dense() {
        let mut q = SparseTensor::new(&[3, 4, 2]);
        q.push(&[0, 1, 1], 2.0);
        q.push(&[2, 3, 0], -1.5);
        q.push(&[2, 3, 0], 0.5);
        q.push(&[1, 0, 1], 4.0);
        let d = q.to_dense();
        assert_eq!(d.get(&[2, 3, 0]), -1.0);
        let x = [0.5, -1.0, 2.0, 3.0];
        let y = [1.5, -0.25];
        let s = q.contract_axes("Q", &[(1, &x), (2, &y)]).unwrap();
        let r = d.contract_axes(&[(1, &x), (2, &y)]).unwrap();
        assert!(s.max_abs_diff(&r) < 1e-15);
        assert!(SparseTensor::from_coords("Q", &[2, 2], vec![0, 2], vec![1.0]).is_err());
        // Kept sparse: the same values.
        let k = q.contract_axes_sparse("Q", &[(2, &y)]).unwrap();
        assert!(k.to_dense().max_abs_diff(&d.contract_axes(&[(2, &y)]).unwrap()) < 1e-15);
        let diag = SparseTensor::from_diagonal(&[1.0, 2.0]);
        assert_eq!(diag.diagonal(), Some(vec![1.0, 2.0]));
        assert_eq!(k.diagonal(), None);
        let sum = diag.add_scaled(&diag.scale(2.0), -1.0).unwrap();
        assert_eq!(sum.to_dense().data(), &[-1.0, 0.0, 0.0, -2.0]);
    }

    #[test]
    fn distinct_permutations_of_multisets() {
        assert_eq!(distinct_permutations(&[1, 1, 4]), vec![vec![1, 1, 4], vec![1, 4, 1], vec![4, 1, 1]]);
        assert_eq!(distinct_permutations(&[0, 1, 2]).len(), 6);
        assert_eq!(distinct_permutations(&[3, 3, 3]), vec![vec![3, 3, 3]]);
    }

    #[test]
    fn a_symmetric_entry_stands_for_its_permutations() {
        let mut q = SparseTensor::new(&[2, 5, 5, 5]).with_symmetric_axes(&[1, 2, 3]).unwrap();
        q.push(&[1, 4, 1, 1], 2.0); // stored as (1, 1, 1, 4)
        assert_eq!(q.coords_of(0), &[1, 1, 1, 4]);
        let d = q.to_dense();
        for idx in [[1, 1, 1, 4], [1, 1, 4, 1], [1, 4, 1, 1]] {
            assert_eq!(d.get(&idx), 2.0);
        }
        assert_eq!(d.data().iter().filter(|&&v| v != 0.0).count(), 3);
        let x = [0.5, -1.0, 2.0, 3.0, 0.25];
        let s = q.contract_axes("Q", &[(1, &x), (2, &x), (3, &x)]).unwrap();
        let r = d.contract_axes(&[(1, &x), (2, &x), (3, &x)]).unwrap();
        assert!(s.max_abs_diff(&r) < 1e-15);
        assert!(SparseTensor::new(&[2, 3]).with_symmetric_axes(&[0, 1]).is_err(), "unequal lengths");
    }
}
