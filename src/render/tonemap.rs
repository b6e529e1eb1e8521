//! Exposure tone mapping of radiance to display colour, the CPU twin of
//! `shaders-glsl/include/tonemap.glsl`: `c = 1 − exp(−exposure · L)` per channel (a radiance of
//! `1/exposure` shows at 63 % of white, nothing clips), then the sRGB transfer function.

/// The sRGB transfer function (IEC 61966-2-1) of a linear value in [0, 1].
pub fn srgb_encode(c: f64) -> f64 {
    if c <= 0.0031308 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// Display colour (sRGB values in [0, 1]) of `radiance` at `exposure`.
pub fn tone_map(radiance: [f64; 3], exposure: f64) -> [f64; 3] {
    radiance.map(|l| srgb_encode(1.0 - (-exposure * l.max(0.0)).exp()))
}

/// An exposure that shows the `quantile` (e.g. 0.9) of `luminances` (weighted by `weights`)
/// at `1 − e^{-1.5}` ≈ 78 % of white: `1.5 / L_q`. 1 when every luminance is zero.
pub fn auto_exposure(luminances: &[f64], weights: &[f64], quantile: f64) -> f64 {
    let mut pairs: Vec<(f64, f64)> = luminances
        .iter()
        .zip(weights)
        .filter(|(l, w)| l.is_finite() && **w > 0.0)
        .map(|(l, w)| (*l, *w))
        .collect();
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = pairs.iter().map(|p| p.1).sum();
    let mut acc = 0.0;
    for (l, w) in &pairs {
        acc += w;
        if acc >= quantile * total && *l > 0.0 {
            return 1.5 / l;
        }
    }
    1.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tone_map_is_monotone_and_bounded() {
        let mut last = -1.0;
        for k in 0..100 {
            let c = tone_map([k as f64 * 0.1; 3], 1.0)[0];
            assert!(c > last && (0.0..1.0).contains(&c));
            last = c;
        }
        assert_eq!(tone_map([0.0; 3], 2.0), [0.0; 3]);
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-12);
        assert!((auto_exposure(&[1.0, 2.0, 3.0, 4.0], &[1.0; 4], 0.5) - 0.75).abs() < 1e-12);
    }
}
