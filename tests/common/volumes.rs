//! Comparing two f64 volume references of one view (`spectral::volume_reference`), for the
//! tests that show the reference converged.

use galerkin::spectral::volume_reference::VolumeSample;

/// The largest difference of a colour channel or the transmittance between `a` and `b` over
/// rays neither marks grazing, and how many rays either marks grazing (left out). Panics where
/// the two disagree on which rays meet the mesh.
pub fn reference_difference(a: &[Option<VolumeSample>], b: &[Option<VolumeSample>]) -> (f64, usize) {
    let (mut worst, mut grazing) = (0.0f64, 0);
    for (x, y) in a.iter().zip(b) {
        match (x, y) {
            (Some(x), Some(y)) if x.grazing || y.grazing => grazing += 1,
            (Some(x), Some(y)) => {
                for (p, q) in x.colour.iter().zip(&y.colour) {
                    worst = worst.max((p - q).abs());
                }
                worst = worst.max((x.transmittance - y.transmittance).abs());
            }
            (None, None) => {}
            _ => panic!("the two densities disagree on which rays meet the mesh"),
        }
    }
    (worst, grazing)
}
