//! A row-major f64 matrix read a few rows at a time at random — the reduced particles' `B_f`
//! and `B_g` (seed 000 §6.5: a particle evaluates only its cell's face and vertex rows) — kept
//! in transparent huge pages where the system offers them (Linux's `madvise(MADV_HUGEPAGE)`
//! through `memmap2`, on an anonymous mapping advised before it is written).
//!
//! The bird's `B_f` is 615,998 rows of 70 values (345 MB): with 4 KiB pages nearly every row a
//! particle reads is on a page the processor's address cache (TLB) does not hold, and the walk
//! through the page tables costs as much as the row. With 2 MiB pages the whole basis needs 165
//! entries. Where huge pages are not available (another system, THP disabled) the advice is
//! ignored and the table is an ordinary copy.

use memmap2::{Mmap, MmapMut};

use super::{Tensor, TensorError};

/// A row-major `rows × cols` f64 matrix in memory advised for huge pages (see the module docs).
pub struct RowTable {
    map: Mmap,
    rows: usize,
    cols: usize,
}

impl std::fmt::Debug for RowTable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "RowTable({} × {})", self.rows, self.cols)
    }
}

impl RowTable {
    /// A copy of the order-2 tensor `t`; refuses another order, or memory the system will not
    /// map (named `what`).
    pub fn from_tensor(t: &Tensor, what: &str) -> Result<Self, TensorError> {
        let &[rows, cols] = t.shape() else {
            let detail = format!("a row table needs an order-2 tensor, not shape {:?}", t.shape());
            return Err(TensorError::Storage { what: what.into(), detail });
        };
        let bytes = std::mem::size_of_val(t.data());
        // An empty mapping is refused by the system: map one value's worth.
        let mut map = MmapMut::map_anon(bytes.max(8)).map_err(|e| TensorError::Storage {
            what: what.into(),
            detail: format!("{bytes} bytes could not be mapped: {e}"),
        })?;
        #[cfg(target_os = "linux")]
        {
            // Advice only: a system without transparent huge pages keeps 4 KiB pages.
            let _ = map.advise(memmap2::Advice::HugePage);
        }
        map[..bytes].copy_from_slice(bytemuck::cast_slice(t.data()));
        let map = map.make_read_only().map_err(|e| TensorError::Storage {
            what: what.into(),
            detail: format!("could not be made read-only: {e}"),
        })?;
        Ok(Self { map, rows, cols })
    }

    /// Rows and columns.
    pub fn shape(&self) -> [usize; 2] {
        [self.rows, self.cols]
    }

    /// All values, row-major.
    pub fn data(&self) -> &[f64] {
        // A mapping starts on a page boundary, so it is aligned for f64.
        bytemuck::cast_slice(&self.map[..self.rows * self.cols * std::mem::size_of::<f64>()])
    }

    /// Row `i`.
    pub fn row(&self, i: usize) -> &[f64] {
        &self.data()[i * self.cols..(i + 1) * self.cols]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_row_table_holds_the_tensor_row_by_row_and_refuses_another_order() {
        let t = Tensor::from_vec(&[3, 2], vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]).unwrap();
        let table = RowTable::from_tensor(&t, "B").unwrap();
        assert_eq!(table.shape(), [3, 2]);
        assert_eq!(table.data(), t.data());
        assert_eq!(table.row(1), &[3.0, 4.0]);
        let empty = RowTable::from_tensor(&Tensor::from_vec(&[0, 4], vec![]).unwrap(), "B").unwrap();
        assert!(empty.data().is_empty());
        let cube = Tensor::from_vec(&[1, 1, 1], vec![1.0]).unwrap();
        let err = RowTable::from_tensor(&cube, "B_f").unwrap_err().to_string();
        assert!(err.contains("B_f") && err.contains("order-2"), "{err}");
    }
}
