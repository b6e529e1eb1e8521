//! Boxes of Kuhn (Freudenthal) simplices: each unit square split into 2 triangles, each cube
//! into 6 tetrahedra along the paths 0 → … → 7 of its corners. Conforming, of any size, with
//! exactly known volumes: the meshes of tests, scaling benchmarks and synthetic tensors.

use super::{MeshError, SimplexMesh};

/// The 2 Kuhn triangles of a square and the 6 tetrahedra of a cube, as corner indices (bit 0
/// = x, bit 1 = y, bit 2 = z).
const KUHN2: [[usize; 3]; 2] = [[0, 1, 3], [0, 2, 3]];
const KUHN3: [[usize; 4]; 6] =
    [[0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7], [0, 2, 6, 7], [0, 4, 5, 7], [0, 4, 6, 7]];

/// A box `[0, size_k]` per axis of `counts[k]` boxes per axis (only the first `dim` entries
/// are used), each split into Kuhn simplices.
pub fn kuhn_box(dim: usize, counts: [usize; 3], size: [f64; 3]) -> Result<SimplexMesh, MeshError> {
    if !(2..=3).contains(&dim)
        || counts[..dim].contains(&0)
        || size[..dim].iter().any(|&s| s.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater))
    {
        return Err(MeshError::Generation(format!(
            "a Kuhn box needs dimension 2 or 3, positive counts and sizes (got {dim}, {counts:?}, {size:?})"
        )));
    }
    let n = [counts[0], counts[1], if dim == 3 { counts[2] } else { 1 }];
    let vid = |x: usize, y: usize, z: usize| (z * (n[1] + 1) + y) * (n[0] + 1) + x;
    let mut g = Vec::new();
    for z in 0..=(if dim == 3 { n[2] } else { 0 }) {
        for y in 0..=n[1] {
            for x in 0..=n[0] {
                g.push(size[0] * x as f64 / n[0] as f64);
                g.push(size[1] * y as f64 / n[1] as f64);
                if dim == 3 {
                    g.push(size[2] * z as f64 / n[2] as f64);
                }
            }
        }
    }
    let mut cells = Vec::new();
    for z in 0..(if dim == 3 { n[2] } else { 1 }) {
        for y in 0..n[1] {
            for x in 0..n[0] {
                let corner = |c: usize| vid(x + (c & 1), y + ((c >> 1) & 1), z + ((c >> 2) & 1)) as u32;
                if dim == 2 {
                    for t in KUHN2 {
                        cells.extend(t.map(corner));
                    }
                } else {
                    for t in KUHN3 {
                        cells.extend(t.map(corner));
                    }
                }
            }
        }
    }
    SimplexMesh::new(dim, g, cells)
}

/// A 3D Kuhn box of at least `cells` tetrahedra, near-cubic, truncated to exactly `cells`
/// (cells are numbered cube by cube, so truncation keeps locality): the synthetic volume
/// tensors of the reduction benchmarks.
pub fn kuhn_tets_with_cells(cells: usize) -> Result<SimplexMesh, MeshError> {
    let cubes = cells.div_ceil(6).max(1);
    let mut n = (cubes as f64).cbrt().floor().max(1.0) as usize;
    while n * n * n < cubes {
        n += 1;
    }
    let nz = cubes.div_ceil(n * n);
    let full = kuhn_box(3, [n, n, nz], [n as f64, n as f64, nz as f64])?;
    let keep = cells.max(1).min(full.cell_count());
    let used = full.cells()[..4 * keep].to_vec();
    // Keep the vertex numbering (unused vertices stay: the geometry vector is the box's).
    SimplexMesh::new(3, full.g().to_vec(), used)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kuhn_boxes_fill_their_box_with_positive_cells() {
        let m2 = kuhn_box(2, [3, 2, 0], [3.0, 1.0, 0.0]).expect("2D box");
        assert_eq!(m2.cell_count(), 12);
        assert!((m2.volumes().iter().sum::<f64>() - 3.0).abs() < 1e-14);
        let m3 = kuhn_box(3, [2, 2, 3], [1.0, 2.0, 3.0]).expect("3D box");
        assert_eq!(m3.cell_count(), 72);
        assert!((m3.volumes().iter().sum::<f64>() - 6.0).abs() < 1e-13);
        assert!(m3.volumes().iter().all(|&v| v > 0.0));
        assert!(kuhn_box(2, [0, 1, 1], [1.0; 3]).is_err());
    }
}
