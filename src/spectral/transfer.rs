//! Transfer functions of volume rendering (`volume.frag`, [`super::volume_reference`]): the
//! emission colour of a field value is the view's colour map at that value; its opacity is a
//! piecewise-linear ramp α(f) over field values (constant beyond its ends), turned into an
//! extinction coefficient per unit length as ParaView's volume mappers do with their scalar
//! opacity unit distance D: a slab D thick of opacity α lets 1 − α through, so
//! σ(f) = −ln(1 − α(f)) / D. Emission–absorption along a ray then composites
//! C = ∫ c(f) σ(f) e^{−∫σ} dt, the light left over is T = e^{−∫σ dt}.
//!
//! Read from flags (`v:α,v:α,…`), from a text file of `value opacity` lines, or from a
//! ParaView colour-map preset (`.json`, as ParaView's "Save preset" writes it): its `Points`
//! (value, opacity, midpoint, sharpness quadruples; midpoint ½ and sharpness 0 — linear —
//! only) and, if present, its `RGBPoints` as the colour map.

use std::path::Path;

use crate::render::Colormap;

/// The most opacity points a transfer function may have (the device reads them from a fixed
/// buffer).
pub const MAX_TRANSFER_POINTS: usize = 64;

/// The largest opacity used in σ = −ln(1 − α) / D: α = 1 would be an infinite extinction; at
/// 1 − 2⁻²⁰ a slab of D lets 10⁻⁶ through.
pub const MAX_OPACITY: f64 = 1.0 - 1.0 / 1_048_576.0;

/// A volume-rendering transfer function: an opacity ramp over field values and its unit
/// distance (see the module's documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct TransferFunction {
    /// (field value, opacity α ∈ [0, 1]), values strictly increasing; α is linear between
    /// points and constant beyond the first and last.
    pub opacity: Vec<(f64, f64)>,
    /// The distance over which opacity α lets 1 − α through (world units, > 0).
    pub unit_distance: f64,
}

impl TransferFunction {
    /// Checks and makes a transfer function: 1 to [`MAX_TRANSFER_POINTS`] points of finite
    /// values, strictly increasing (a ramp whose values go down is "inverted"), opacities in
    /// [0, 1] not all zero (an "empty" ramp shows nothing), and a finite positive unit distance.
    pub fn new(opacity: Vec<(f64, f64)>, unit_distance: f64) -> Result<Self, String> {
        if opacity.is_empty() {
            return Err("the transfer function is empty: it has no opacity points".into());
        }
        if opacity.len() > MAX_TRANSFER_POINTS {
            return Err(format!(
                "the transfer function has {} opacity points; at most {MAX_TRANSFER_POINTS}",
                opacity.len()
            ));
        }
        for (k, &(v, a)) in opacity.iter().enumerate() {
            if !v.is_finite() || !a.is_finite() {
                return Err(format!("opacity point {k} ({v}, {a}) is not a pair of finite numbers"));
            }
            if !(0.0..=1.0).contains(&a) {
                return Err(format!("opacity point {k} (value {v}): opacity {a} is not in [0, 1]"));
            }
            if k > 0 && v <= opacity[k - 1].0 {
                return Err(format!(
                    "the transfer function is inverted: opacity point {k}'s value {v} does not follow point {}'s {} (values must increase)",
                    k - 1,
                    opacity[k - 1].0
                ));
            }
        }
        if opacity.iter().all(|p| p.1 == 0.0) {
            return Err("the transfer function is empty: every opacity is 0, nothing would show".into());
        }
        if !(unit_distance.is_finite() && unit_distance > 0.0) {
            return Err(format!("the opacity unit distance {unit_distance} is not a positive number"));
        }
        Ok(Self { opacity, unit_distance })
    }

    /// The default ramp over a field's range [lo, hi]: transparent at lo, opacity ½ at hi,
    /// over a unit distance of a tenth of `diagonal` (the mesh's).
    pub fn default_for(lo: f64, hi: f64, diagonal: f64) -> Result<Self, String> {
        let hi = if hi > lo { hi } else { lo + 1.0 };
        Self::new(vec![(lo, 0.0), (hi, 0.5)], 0.1 * diagonal.max(f64::MIN_POSITIVE))
    }

    /// Parses `v:α,v:α,…` (the flags' form).
    pub fn parse_points(text: &str) -> Result<Vec<(f64, f64)>, String> {
        text.split(',')
            .enumerate()
            .map(|(k, p)| {
                let (v, a) = p
                    .split_once(':')
                    .ok_or_else(|| format!("opacity point {k} {p:?} is not VALUE:OPACITY"))?;
                let num = |s: &str| {
                    s.trim()
                        .parse::<f64>()
                        .map_err(|_| format!("opacity point {k} {p:?}: {s:?} is not a number"))
                };
                Ok((num(v)?, num(a)?))
            })
            .collect()
    }

    /// α(f): linear between the points, constant beyond.
    pub fn alpha(&self, f: f64) -> f64 {
        let p = &self.opacity;
        if f <= p[0].0 {
            return p[0].1;
        }
        for w in p.windows(2) {
            if f <= w[1].0 {
                let s = (f - w[0].0) / (w[1].0 - w[0].0);
                return w[0].1 + s * (w[1].1 - w[0].1);
            }
        }
        p[p.len() - 1].1
    }

    /// σ(f) = −ln(1 − min(α(f), [`MAX_OPACITY`])) / D, the extinction per unit length.
    pub fn sigma(&self, f: f64) -> f64 {
        -(1.0 - self.alpha(f).min(MAX_OPACITY)).ln() / self.unit_distance
    }

    /// A clear medium: opacity 0 everywhere (σ = 0). Not a ramp a user gives
    /// ([`Self::new`] refuses it as empty); the medium of transparent isosurfaces drawn without
    /// a volume, where only the sheets ([`Sheets`]) absorb and emit.
    pub fn clear() -> Self {
        Self { opacity: vec![(0.0, 0.0)], unit_distance: 1.0 }
    }

    /// Whether the ramp is 0 everywhere (only sheets show).
    pub fn is_clear(&self) -> bool {
        self.opacity.iter().all(|p| p.1 == 0.0)
    }

    /// The words `volume.frag` reads (binding 4; `spectral_transfer.glsl`): the point count, the
    /// unit distance, the background colour (f32 bits), the sheets' count and opacity, 1 when
    /// the medium is clear ([`Self::is_clear`]); then [`MAX_TRANSFER_POINTS`] (value, opacity) pairs, then
    /// [`MAX_SHEETS`] iso values of the sheets.
    pub fn device_words(&self, background: [f32; 3], sheets: &Sheets) -> Vec<u32> {
        let mut w = vec![0u32; 8 + 2 * MAX_TRANSFER_POINTS + MAX_SHEETS];
        w[0] = self.opacity.len() as u32;
        w[1] = (self.unit_distance as f32).to_bits();
        for (o, c) in w[2..5].iter_mut().zip(background) {
            *o = c.to_bits();
        }
        let count = sheets.values.len().min(MAX_SHEETS);
        w[5] = count as u32;
        w[6] = (sheets.opacity as f32).to_bits();
        w[7] = u32::from(self.is_clear());
        for (k, &(v, a)) in self.opacity.iter().enumerate() {
            w[8 + 2 * k] = (v as f32).to_bits();
            w[9 + 2 * k] = (a as f32).to_bits();
        }
        for (k, &c) in sheets.values[..count].iter().enumerate() {
            w[8 + 2 * MAX_TRANSFER_POINTS + k] = (c as f32).to_bits();
        }
        w
    }
}

/// The most isosurface sheets a volume carries (as many as opaque isosurfaces,
/// [`crate::spectral::render::MAX_ISO_VALUES`]).
pub const MAX_SHEETS: usize = 8;

/// Isosurfaces composited inside the volume pass (transparent isosurfaces, or opaque ones in a
/// volume): wherever the field crosses one of `values` along a ray, a sheet of opacity
/// `opacity` coloured by the colour map at that value and lit with the exact normal
/// (`volume.frag`, [`super::volume_reference`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sheets {
    /// The iso values (at most [`MAX_SHEETS`]).
    pub values: Vec<f64>,
    /// Each sheet's opacity α ∈ (0, 1]: it lets 1 − α of the light behind it through.
    pub opacity: f64,
}

impl Sheets {
    /// No sheets.
    pub fn none() -> Self {
        Self { values: Vec::new(), opacity: 0.0 }
    }

    /// Checks and makes sheets: at most [`MAX_SHEETS`] finite values and an opacity in (0, 1].
    pub fn new(values: Vec<f64>, opacity: f64) -> Result<Self, String> {
        if values.len() > MAX_SHEETS {
            return Err(format!("{} iso values; at most {MAX_SHEETS}", values.len()));
        }
        if let Some(v) = values.iter().find(|v| !v.is_finite()) {
            return Err(format!("iso value {v} is not a finite number"));
        }
        Self::check_opacity(opacity)?;
        Ok(Self { values, opacity })
    }

    /// Checks a sheet opacity: a number in (0, 1].
    pub fn check_opacity(opacity: f64) -> Result<(), String> {
        if opacity > 0.0 && opacity <= 1.0 {
            Ok(())
        } else {
            Err(format!("the isosurfaces' opacity {opacity} is not in (0, 1]"))
        }
    }
}

/// The transfer function of `galerkin spectral render --volume`: the opacity points of
/// `points` (`v:α,…`) or of `file` ([`read_transfer_file`]; not both), else
/// [`TransferFunction::default_for`] the field's `range`; the unit distance given, else a tenth
/// of `diagonal`. With the file's colours when it had them.
pub fn transfer_for_view(
    points: Option<&str>,
    file: Option<&Path>,
    unit_distance: Option<f64>,
    range: (f64, f64),
    diagonal: f64,
) -> Result<(TransferFunction, Option<Colormap>), String> {
    let unit = unit_distance.unwrap_or(0.1 * diagonal);
    let (opacity, colormap) = match (points, file) {
        (Some(_), Some(_)) => {
            return Err("give the opacity points or a transfer function file, not both".into())
        }
        (Some(p), None) => (TransferFunction::parse_points(p)?, None),
        (None, Some(f)) => {
            let t = read_transfer_file(f)?;
            let tf = TransferFunction::new(t.opacity, unit).map_err(|e| format!("{}: {e}", f.display()))?;
            return Ok((tf, t.colormap));
        }
        (None, None) => {
            let mut tf = TransferFunction::default_for(range.0, range.1, diagonal)?;
            if let Some(u) = unit_distance {
                tf = TransferFunction::new(tf.opacity, u)?;
            }
            return Ok((tf, None));
        }
    };
    Ok((TransferFunction::new(opacity, unit)?, colormap))
}

/// A transfer function file read: its opacity ramp, and the colour map when the file had one
/// (a ParaView preset's `RGBPoints`).
#[derive(Clone, Debug)]
pub struct TransferFile {
    /// The opacity points.
    pub opacity: Vec<(f64, f64)>,
    /// The colours, if the file gave them.
    pub colormap: Option<Colormap>,
}

/// Reads a transfer function file: a ParaView preset (`.json`: an object, or an array whose
/// first object is used, with `Points` and optionally `RGBPoints`) or text lines
/// `value opacity` (`#` starts a comment). Errors name the file and the line or array.
pub fn read_transfer_file(path: &Path) -> Result<TransferFile, String> {
    let name = path.display();
    let meta = std::fs::metadata(path).map_err(|e| format!("{name}: {e}"))?;
    // A transfer function is a few dozen numbers; anything past 16 MiB is not one.
    if meta.len() > 16 << 20 {
        return Err(format!("{name}: {} bytes is too large for a transfer function", meta.len()));
    }
    let text = std::fs::read_to_string(path).map_err(|e| format!("{name}: {e}"))?;
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("json")) {
        return read_preset(&text).map_err(|e| format!("{name}: {e}"));
    }
    let mut opacity = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let nums: Vec<f64> = line
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty())
            .map(|s| s.parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("{name}:{}: {line:?} is not `value opacity`", k + 1))?;
        let [v, a] = nums[..] else {
            return Err(format!("{name}:{}: {line:?} is not `value opacity` (two numbers)", k + 1));
        };
        if opacity.len() == MAX_TRANSFER_POINTS {
            return Err(format!("{name}:{}: more than {MAX_TRANSFER_POINTS} opacity points", k + 1));
        }
        opacity.push((v, a));
    }
    Ok(TransferFile { opacity, colormap: None })
}

/// A ParaView preset's `Points` and `RGBPoints`.
fn read_preset(text: &str) -> Result<TransferFile, String> {
    let json: serde_json::Value = serde_json::from_str(text).map_err(|e| format!("not JSON: {e}"))?;
    let preset = match &json {
        serde_json::Value::Array(a) => a.first().ok_or("an empty array of presets")?,
        other => other,
    };
    let numbers = |key: &str, per: usize| -> Result<Option<Vec<f64>>, String> {
        let Some(v) = preset.get(key) else { return Ok(None) };
        let a = v.as_array().ok_or_else(|| format!("`{key}` is not an array"))?;
        if a.len() % per != 0 || a.len() > per * MAX_TRANSFER_POINTS.max(1024) {
            return Err(format!(
                "`{key}` has {} numbers: not groups of {per} (at most {})",
                a.len(),
                per * 1024
            ));
        }
        a.iter()
            .enumerate()
            .map(|(k, x)| x.as_f64().ok_or_else(|| format!("`{key}`[{k}] is not a number")))
            .collect::<Result<Vec<_>, _>>()
            .map(Some)
    };
    let points = numbers("Points", 4)?.ok_or("no `Points` (the opacity ramp) in the preset")?;
    let mut opacity = Vec::new();
    for (k, q) in points.chunks_exact(4).enumerate() {
        if (q[2] - 0.5).abs() > 1e-12 || q[3] != 0.0 {
            return Err(format!(
                "`Points` point {k}: midpoint {} and sharpness {} (only linear ramps, midpoint 0.5 and sharpness 0, are read)",
                q[2], q[3]
            ));
        }
        opacity.push((q[0], q[1]));
    }
    let colormap = match numbers("RGBPoints", 4)? {
        None => None,
        Some(rgb) => {
            let points: Vec<(f64, [f64; 3])> =
                rgb.chunks_exact(4).map(|q| (q[0], [q[1], q[2], q[3]])).collect();
            let name = preset.get("Name").and_then(|n| n.as_str()).unwrap_or("preset");
            Some(Colormap::from_points(name, &points).map_err(|e| format!("`RGBPoints`: {e}"))?)
        }
    };
    Ok(TransferFile { opacity, colormap })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramps_are_checked_and_evaluated() {
        let t = TransferFunction::new(vec![(0.0, 0.0), (1.0, 0.5), (2.0, 0.5)], 2.0).expect("valid");
        assert_eq!(t.alpha(-1.0), 0.0);
        assert_eq!(t.alpha(0.5), 0.25);
        assert_eq!(t.alpha(3.0), 0.5);
        // A slab of D = 2 at α = ½ lets ½ through.
        assert!(((-t.sigma(1.5) * 2.0).exp() - 0.5).abs() < 1e-15);
        for (points, what) in [
            (vec![], "empty"),
            (vec![(0.0, 0.0), (1.0, 0.0)], "empty"),
            (vec![(1.0, 0.1), (0.0, 0.2)], "inverted"),
            (vec![(0.0, 1.5)], "not in [0, 1]"),
            (vec![(f64::NAN, 0.5)], "finite"),
        ] {
            let e = TransferFunction::new(points, 1.0).expect_err("refused");
            assert!(e.contains(what), "{e}");
        }
        assert!(TransferFunction::new(vec![(0.0, 0.5)], 0.0).is_err());
        assert_eq!(
            TransferFunction::parse_points("0:0, 1.5:0.25").expect("parsed"),
            vec![(0.0, 0.0), (1.5, 0.25)]
        );
        assert!(TransferFunction::parse_points("0;1").expect_err("refused").contains("VALUE:OPACITY"));
    }

    #[test]
    fn paraview_presets_and_text_files_are_read() {
        let dir = tempfile::tempdir().expect("temp dir");
        let json = dir.path().join("tf.json");
        std::fs::write(
            &json,
            r#"[{"ColorSpace":"RGB","Name":"two","Points":[0,0,0.5,0, 1,0.8,0.5,0],"RGBPoints":[0,0,0,1, 1,1,0,0]}]"#,
        )
        .expect("written");
        let f = read_transfer_file(&json).expect("read");
        assert_eq!(f.opacity, vec![(0.0, 0.0), (1.0, 0.8)]);
        let c = f.colormap.expect("colours");
        assert!((c.sample(0.0)[2] - 1.0).abs() < 1e-12 && (c.sample(1.0)[0] - 1.0).abs() < 1e-12);
        std::fs::write(&json, r#"{"Points":[0,0,0.3,0]}"#).expect("written");
        assert!(read_transfer_file(&json).expect_err("refused").contains("midpoint"));
        let txt = dir.path().join("tf.txt");
        std::fs::write(&txt, "# value opacity\n0 0\n1 0.5\nx y\n").expect("written");
        let e = read_transfer_file(&txt).expect_err("refused");
        assert!(e.contains("tf.txt:4"), "{e}");
    }
}
