//! Dense tensors of any order, f32 or f64, row-major (last axis fastest), axis 0 the result.

use std::ops::{Add, AddAssign, Mul, Sub};

use super::error::TensorError;

/// The element types of tensors: f32 (GPU) and f64 (references).
pub trait Scalar:
    Copy
    + Default
    + PartialEq
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + AddAssign
    + bytemuck::Pod
    + std::fmt::Debug
    + Send
    + Sync
    + 'static
{
    /// Converts from f64 (rounding for f32).
    fn from_f64(v: f64) -> Self;
    /// Converts to f64 (exactly).
    fn to_f64(self) -> f64;
    /// Zero.
    fn zero() -> Self {
        Self::default()
    }
}

impl Scalar for f32 {
    fn from_f64(v: f64) -> Self {
        v as f32
    }
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
}

impl Scalar for f64 {
    fn from_f64(v: f64) -> Self {
        v
    }
    fn to_f64(self) -> f64 {
        self
    }
}

/// A dense tensor: `shape` and row-major `data`.
#[derive(Clone, Debug, PartialEq)]
pub struct Tensor<T: Scalar = f64> {
    shape: Vec<usize>,
    data: Vec<T>,
}

/// Row-major strides of `shape`.
pub(crate) fn strides(shape: &[usize]) -> Vec<usize> {
    let mut s = vec![1; shape.len()];
    for k in (0..shape.len().saturating_sub(1)).rev() {
        s[k] = s[k + 1] * shape[k + 1];
    }
    s
}

impl<T: Scalar> Tensor<T> {
    /// A tensor of zeros.
    pub fn zeros(shape: &[usize]) -> Self {
        Self { shape: shape.to_vec(), data: vec![T::zero(); shape.iter().product()] }
    }

    /// A tensor from row-major data; an error if the length disagrees with the shape.
    pub fn from_vec(shape: &[usize], data: Vec<T>) -> Result<Self, TensorError> {
        let expected: usize = shape.iter().product();
        if data.len() != expected {
            return Err(TensorError::DataLength {
                what: "tensor".into(),
                shape: shape.to_vec(),
                expected,
                found: data.len(),
            });
        }
        Ok(Self { shape: shape.to_vec(), data })
    }

    /// A vector (order 1).
    pub fn vector(data: Vec<T>) -> Self {
        Self { shape: vec![data.len()], data }
    }

    /// A `rows`×`cols` matrix from row-major data.
    pub fn matrix(rows: usize, cols: usize, data: Vec<T>) -> Result<Self, TensorError> {
        Self::from_vec(&[rows, cols], data)
    }

    /// The `n`×`n` identity.
    pub fn identity(n: usize) -> Self {
        let mut t = Self::zeros(&[n, n]);
        for i in 0..n {
            t.data[i * n + i] = T::from_f64(1.0);
        }
        t
    }

    /// Axis lengths.
    pub fn shape(&self) -> &[usize] {
        &self.shape
    }

    /// Number of axes.
    pub fn order(&self) -> usize {
        self.shape.len()
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.data.len()
    }

    /// True if the tensor holds no elements.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Row-major elements.
    pub fn data(&self) -> &[T] {
        &self.data
    }

    /// Mutable row-major elements.
    pub fn data_mut(&mut self) -> &mut [T] {
        &mut self.data
    }

    /// Consumes the tensor, returning its elements.
    pub fn into_data(self) -> Vec<T> {
        self.data
    }

    /// The element at a multi-index (panics if out of range: indices are the caller's).
    pub fn get(&self, index: &[usize]) -> T {
        self.data[self.offset(index)]
    }

    /// Sets the element at a multi-index.
    pub fn set(&mut self, index: &[usize], value: T) {
        let o = self.offset(index);
        self.data[o] = value;
    }

    fn offset(&self, index: &[usize]) -> usize {
        assert_eq!(
            index.len(),
            self.order(),
            "index of order {} into a tensor of order {}",
            index.len(),
            self.order()
        );
        index.iter().zip(&self.shape).zip(strides(&self.shape)).fold(0, |o, ((&i, &n), s)| {
            assert!(i < n, "index {i} out of range for axis length {n}");
            o + i * s
        })
    }

    /// Element type conversion.
    pub fn cast<U: Scalar>(&self) -> Tensor<U> {
        Tensor {
            shape: self.shape.clone(),
            data: self.data.iter().map(|v| U::from_f64(v.to_f64())).collect(),
        }
    }

    /// Largest |a − b| over all elements (shapes must match).
    pub fn max_abs_diff(&self, other: &Tensor<T>) -> f64 {
        assert_eq!(self.shape, other.shape, "max_abs_diff of different shapes");
        self.data.iter().zip(&other.data).fold(0.0, |m, (a, b)| m.max((a.to_f64() - b.to_f64()).abs()))
    }

    /// Largest |element|.
    pub fn max_abs(&self) -> f64 {
        self.data.iter().fold(0.0, |m, v| m.max(v.to_f64().abs()))
    }

    /// Checks that axis `axis` exists and has length `n`; `what` names the operand in errors.
    pub fn expect_axis(&self, what: &str, axis: usize, n: usize) -> Result<(), TensorError> {
        match self.shape.get(axis) {
            None => Err(TensorError::NoSuchAxis { what: what.into(), axis, order: self.order() }),
            Some(&m) if m != n => Err(TensorError::Shape { what: what.into(), axis, expected: n, found: m }),
            Some(_) => Ok(()),
        }
    }

    /// `Q ⊗_k x`: contraction of axis `axis` with the vector `x` (the order drops by one).
    pub fn contract(&self, axis: usize, x: &[T]) -> Result<Tensor<T>, TensorError> {
        self.expect_axis("contraction", axis, x.len())?;
        let outer: usize = self.shape[..axis].iter().product();
        let n = self.shape[axis];
        let inner: usize = self.shape[axis + 1..].iter().product();
        let mut out = vec![T::zero(); outer * inner];
        if inner == 1 {
            // The last axis: one dot product per output element, over contiguous memory.
            for (o, row) in out.iter_mut().zip(self.data.chunks_exact(n.max(1))) {
                *o = row.iter().zip(x).fold(T::zero(), |acc, (&a, &b)| acc + a * b);
            }
        } else {
            for o in 0..outer {
                let dst = &mut out[o * inner..(o + 1) * inner];
                for (i, &xi) in x.iter().enumerate() {
                    let src = &self.data[(o * n + i) * inner..(o * n + i + 1) * inner];
                    for (d, &s) in dst.iter_mut().zip(src) {
                        *d += s * xi;
                    }
                }
            }
        }
        let mut shape = self.shape.clone();
        shape.remove(axis);
        Ok(Tensor { shape, data: out })
    }

    /// `Q ⊗_k M` for a matrix `M` (n×m): axis `axis` (length n) is replaced by an axis of
    /// length m, `out[…, j, …] = Σ_i Q[…, i, …] M[i, j]`. With `M = B`, this premultiplies one
    /// axis of `Q` by its basis (Eq. 2); with `axis = 0` it is the paper's `Bᵀ Q`.
    pub fn mode_product(&self, axis: usize, m: &Tensor<T>) -> Result<Tensor<T>, TensorError> {
        if m.order() != 2 {
            return Err(TensorError::NotSquare {
                what: "mode product with a non-matrix".into(),
                shape: m.shape.clone(),
            });
        }
        self.expect_axis("mode product", axis, m.shape[0])?;
        let (n, k) = (m.shape[0], m.shape[1]);
        let outer: usize = self.shape[..axis].iter().product();
        let inner: usize = self.shape[axis + 1..].iter().product();
        let mut out = vec![T::zero(); outer * k * inner];
        for o in 0..outer {
            for i in 0..n {
                let src = &self.data[(o * n + i) * inner..(o * n + i + 1) * inner];
                for j in 0..k {
                    let mij = m.data[i * k + j];
                    let dst = &mut out[(o * k + j) * inner..(o * k + j + 1) * inner];
                    for (d, &s) in dst.iter_mut().zip(src) {
                        *d += s * mij;
                    }
                }
            }
        }
        let mut shape = self.shape.clone();
        shape[axis] = k;
        Ok(Tensor { shape, data: out })
    }

    /// Contracts several axes of `self` (numbered as in `self`) with vectors:
    /// `Q ⊗_a x ⊗_b y …`.
    pub fn contract_axes(&self, args: &[(usize, &[T])]) -> Result<Tensor<T>, TensorError> {
        let mut order: Vec<&(usize, &[T])> = args.iter().collect();
        order.sort_by_key(|a| std::cmp::Reverse(a.0));
        for w in order.windows(2) {
            if w[0].0 == w[1].0 {
                return Err(TensorError::NoSuchAxis {
                    what: "axis contracted twice".into(),
                    axis: w[0].0,
                    order: self.order(),
                });
            }
        }
        let mut t: Option<Tensor<T>> = None;
        for (axis, x) in order {
            t = Some(match &t {
                None => self.contract(*axis, x)?,
                Some(t) => t.contract(*axis, x)?,
            });
        }
        Ok(t.unwrap_or_else(|| self.clone()))
    }

    /// Moves axes: `out` axis `i` is `self` axis `perm[i]`.
    pub fn permute(&self, perm: &[usize]) -> Tensor<T> {
        assert_eq!(perm.len(), self.order(), "permutation length");
        let shape: Vec<usize> = perm.iter().map(|&p| self.shape[p]).collect();
        let src_strides = strides(&self.shape);
        let mut out = vec![T::zero(); self.len()];
        let mut index = vec![0usize; self.order()];
        for v in out.iter_mut() {
            let o: usize = index.iter().zip(perm).map(|(&i, &p)| i * src_strides[p]).sum();
            *v = self.data[o];
            for a in (0..index.len()).rev() {
                index[a] += 1;
                if index[a] < shape[a] {
                    break;
                }
                index[a] = 0;
            }
        }
        Tensor { shape, data: out }
    }

    /// Elementwise `self + s·other` (same shapes).
    pub fn add_scaled(&self, other: &Tensor<T>, s: T) -> Result<Tensor<T>, TensorError> {
        if self.shape != other.shape {
            let axis = self.shape.iter().zip(&other.shape).position(|(a, b)| a != b).unwrap_or(0);
            return Err(TensorError::Shape {
                what: "sum".into(),
                axis,
                expected: self.shape.get(axis).copied().unwrap_or(0),
                found: other.shape.get(axis).copied().unwrap_or(0),
            });
        }
        let data = self.data.iter().zip(&other.data).map(|(&a, &b)| a + s * b).collect();
        Ok(Tensor { shape: self.shape.clone(), data })
    }

    /// Every element times `s`.
    pub fn scale(&self, s: T) -> Tensor<T> {
        Tensor { shape: self.shape.clone(), data: self.data.iter().map(|&v| v * s).collect() }
    }

    /// The leading block `[0..lens[0], 0..lens[1], …]` (each `lens[k]` at most the axis
    /// length): a reduced tensor of nested bases cut to their first columns.
    pub fn leading(&self, lens: &[usize]) -> Result<Tensor<T>, TensorError> {
        if lens.len() != self.order() {
            return Err(TensorError::NoSuchAxis {
                what: "leading block".into(),
                axis: lens.len(),
                order: self.order(),
            });
        }
        for (axis, (&l, &n)) in lens.iter().zip(&self.shape).enumerate() {
            if l > n {
                return Err(TensorError::Shape { what: "leading block".into(), axis, expected: n, found: l });
            }
        }
        let total: usize = lens.iter().product();
        let mut data = Vec::with_capacity(total);
        let mut index = vec![0usize; lens.len()];
        let stride = strides(&self.shape);
        if total > 0 {
            'outer: loop {
                let offset = index.iter().zip(&stride).map(|(i, s)| i * s).sum::<usize>();
                data.push(self.data[offset]);
                for k in (0..lens.len()).rev() {
                    index[k] += 1;
                    if index[k] < lens[k] {
                        continue 'outer;
                    }
                    index[k] = 0;
                }
                break;
            }
        }
        Ok(Tensor { shape: lens.to_vec(), data })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t3() -> Tensor {
        Tensor::from_vec(&[2, 3, 4], (0..24).map(f64::from).collect()).unwrap()
    }

    #[test]
    fn contraction_sums_along_one_axis() {
        let q = t3();
        let x = [1.0, -2.0, 0.5];
        let r = q.contract(1, &x).unwrap();
        assert_eq!(r.shape(), &[2, 4]);
        for i in 0..2 {
            for k in 0..4 {
                let want: f64 = (0..3).map(|j| q.get(&[i, j, k]) * x[j]).sum();
                assert_eq!(r.get(&[i, k]), want);
            }
        }
        assert!(q.contract(1, &[1.0]).is_err());
        assert!(q.contract(3, &[1.0]).is_err());
    }

    #[test]
    fn mode_product_replaces_an_axis() {
        let q = t3();
        let m = Tensor::matrix(4, 2, vec![1.0, 0.0, 0.0, 1.0, 2.0, -1.0, 0.5, 0.25]).unwrap();
        let r = q.mode_product(2, &m).unwrap();
        assert_eq!(r.shape(), &[2, 3, 2]);
        for (i, j, l) in [(0, 0, 0), (1, 2, 1), (1, 1, 0)] {
            let want: f64 = (0..4).map(|k| q.get(&[i, j, k]) * m.get(&[k, l])).sum();
            assert_eq!(r.get(&[i, j, l]), want);
        }
        // Contracting the product's new axis with y equals contracting the old axis with M y.
        let y = [0.3, -0.7];
        let my: Vec<f64> = (0..4).map(|k| m.get(&[k, 0]) * y[0] + m.get(&[k, 1]) * y[1]).collect();
        assert!(r.contract(2, &y).unwrap().max_abs_diff(&q.contract(2, &my).unwrap()) < 1e-12);
    }

    #[test]
    fn permute_moves_axes() {
        let q = t3();
        let p = q.permute(&[2, 0, 1]);
        assert_eq!(p.shape(), &[4, 2, 3]);
        assert_eq!(p.get(&[3, 1, 2]), q.get(&[1, 2, 3]));
    }
}
