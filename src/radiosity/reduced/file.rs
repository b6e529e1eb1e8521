//! Saving and loading a reduced radiosity ([`ReducedRadiosity::save`], [`ReducedRadiosity::load`]):
//! the core's reduced model in `model.safetensors`, the learned visibility, the emission, the
//! sky's visibility bits, the error estimate's series and the provenance in
//! `visibility.safetensors`.

use std::collections::HashMap;
use std::path::Path;

use safetensors::tensor::{Dtype, SafeTensors, TensorView};

use super::super::error::RadiosityError;
use super::super::form_factor::NearField;
use super::super::scene::{LightMode, Lights};
use super::super::visibility::LearnedVisibility;
use super::{ReducedRadiosity, SkyLight, TrainedNearField};
use crate::radiosity::estimate::CrossValidation;
use crate::reduce::provenance::Provenance;
use crate::reduce::ReducedModel;
use crate::tensor::Tensor;

/// The `format` metadata of a reduced radiosity's learned-visibility file.
pub const FORMAT: &str = "galerkin-reduced-radiosity";
/// Its version (2: the training's near field is recorded; a version-1 file carrying `Q` was
/// trained with the exact near field, one without it with centroid form factors. 3: the error
/// estimate's offline part, `left_out_error`, `basis_floor` and `sample_spacing`, when training
/// made it).
pub const VERSION: u32 = 3;

impl ReducedRadiosity {
    /// Writes `dir/model.safetensors` (the core's reduced model: Table 2's premultiplied
    /// tensors and the bases of `g` and `b`) and `dir/visibility.safetensors` (`B_gᵀ G`,
    /// `B_vᵀ V`, `ê`, f64), each to a temporary name first.
    pub fn save(&self, dir: &Path) -> Result<(), RadiosityError> {
        let fail = |detail: String| RadiosityError::File { path: dir.to_path_buf(), message: detail };
        std::fs::create_dir_all(dir).map_err(|e| fail(e.to_string()))?;
        self.model.save(&dir.join("model.safetensors")).map_err(|e| fail(e.to_string()))?;
        let bytes = |t: &[f64]| t.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>();
        let mut entries = vec![
            (
                "geometry",
                Dtype::F64,
                bytes(self.visibility.geometry().data()),
                self.visibility.geometry().shape().to_vec(),
            ),
            (
                "visibility",
                Dtype::F64,
                bytes(self.visibility.visibility().data()),
                self.visibility.visibility().shape().to_vec(),
            ),
            ("emission", Dtype::F64, bytes(&self.emission_hat), vec![self.emission_hat.len()]),
        ];
        let mut meta: HashMap<String, String> = [
            ("format".to_string(), FORMAT.to_string()),
            ("version".to_string(), VERSION.to_string()),
            ("faces".to_string(), self.faces.to_string()),
            ("trained_near_field".to_string(), format!("{:?}", self.trained_near)),
        ]
        .into();
        if let Some(p) = &self.provenance {
            meta.insert("provenance".into(), p.to_json());
        }
        if let Some(v) = &self.validation {
            for (name, series) in
                [("left_out_error", &v.left_out), ("basis_floor", &v.floor), ("sample_spacing", &v.spacing)]
            {
                entries.push((name, Dtype::F64, bytes(series), vec![series.len()]));
            }
        }
        if let Some(sky) = &self.sky {
            let openings: Vec<f64> = sky.openings.iter().map(|&o| f64::from(o)).collect();
            entries.push(("sky_openings", Dtype::F64, bytes(&openings), vec![openings.len()]));
            let words = sky.bits.first().map_or(0, Vec::len);
            let raw: Vec<u8> = sky.bits.iter().flatten().flat_map(|w| w.to_le_bytes()).collect();
            entries.push(("sky_visibility_bits", Dtype::U8, raw, vec![sky.bits.len(), 8 * words]));
            let l = &sky.lights;
            meta.insert(
                "sky_zenith".into(),
                format!("{} {} {}", l.sky_zenith[0], l.sky_zenith[1], l.sky_zenith[2]),
            );
            meta.insert("ground_albedo".into(), l.ground_albedo.to_string());
            meta.insert("near_field".into(), format!("{:?}", sky.near));
        }
        let views = entries
            .iter()
            .map(|(n, d, b, s)| TensorView::new(*d, s.clone(), b).map(|v| (n.to_string(), v)))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| fail(e.to_string()))?;
        let buffer = crate::reduce::serialize(views, meta).map_err(fail)?;
        let path = dir.join("visibility.safetensors");
        crate::atomic_file::write(&path, &buffer).map_err(|e| fail(e.to_string()))
    }

    /// Reads what [`ReducedRadiosity::save`] wrote; errors name the file and what is wrong.
    pub fn load(dir: &Path) -> Result<Self, RadiosityError> {
        let model = ReducedModel::load(&dir.join("model.safetensors")).map_err(|e| RadiosityError::File {
            path: dir.join("model.safetensors"),
            message: e.to_string(),
        })?;
        let path = dir.join("visibility.safetensors");
        let fail = |m: String| RadiosityError::File { path: path.clone(), message: m };
        let bytes = std::fs::read(&path).map_err(|e| fail(e.to_string()))?;
        let (_, meta) = SafeTensors::read_metadata(&bytes).map_err(|e| fail(e.to_string()))?;
        let meta = meta.metadata().clone().unwrap_or_default();
        if meta.get("format").map(String::as_str) != Some(FORMAT) {
            return Err(fail(format!("not a {FORMAT} file")));
        }
        if meta.get("version").and_then(|v| v.parse::<u32>().ok()).is_none_or(|v| v > VERSION) {
            return Err(fail(format!(
                "version {:?} is not one this build reads (≤ {VERSION})",
                meta.get("version")
            )));
        }
        let faces: usize = match meta.get("faces") {
            None => return Err(fail("its metadata has no \"faces\" entry (the scene's face count)".into())),
            Some(v) => v.parse().ok().filter(|&n| n > 0 && n as u64 <= crate::limits::MAX_COUNT).ok_or_else(
                || {
                    fail(format!(
                        "metadata \"faces\" is {v:?}, not a face count from 1 to {}",
                        crate::limits::MAX_COUNT
                    ))
                },
            )?,
        };
        let file = SafeTensors::deserialize(&bytes).map_err(|e| fail(e.to_string()))?;
        let read = |name: &str| -> Result<Tensor, RadiosityError> {
            let v = file.tensor(name).map_err(|e| fail(format!("{name}: {e}")))?;
            if v.dtype() != Dtype::F64 {
                return Err(fail(format!("{name}: expected f64")));
            }
            let data = v
                .data()
                .chunks_exact(8)
                .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")))
                .collect::<Vec<f64>>();
            if let Some((i, x)) = crate::limits::first_out_of_range(&data) {
                return Err(fail(format!("{name}: entry {i} is {}", crate::limits::out_of_range_reason(x))));
            }
            Tensor::from_vec(v.shape(), data).map_err(|e| fail(format!("{name}: {e}")))
        };
        let learned = LearnedVisibility::new(read("geometry")?, read("visibility")?)
            .map_err(|e| fail(e.to_string()))?;
        let emission = read("emission")?.into_data();
        let sky = match meta.get("sky_zenith") {
            None => None,
            Some(z) => {
                let z: Vec<f64> = z.split_whitespace().filter_map(|v| v.parse().ok()).collect();
                let ground = meta.get("ground_albedo").and_then(|v| v.parse().ok());
                let (Ok(zenith), Some(ground_albedo)) = (<[f64; 3]>::try_from(z), ground) else {
                    return Err(fail("bad sky metadata".into()));
                };
                let near = match meta.get("near_field").map(String::as_str) {
                    Some("Eq15") => NearField::Eq15,
                    _ => NearField::Regularised,
                };
                let openings = read("sky_openings")?.into_data().into_iter().map(|v| v as u32).collect();
                let v = file
                    .tensor("sky_visibility_bits")
                    .map_err(|e| fail(format!("sky_visibility_bits: {e}")))?;
                let per = v.shape().get(1).copied().unwrap_or(0);
                if v.dtype() != Dtype::U8 || per % 8 != 0 {
                    return Err(fail("sky_visibility_bits: expected u8 rows of whole 64-bit words".into()));
                }
                let bits = v
                    .data()
                    .chunks_exact(per.max(1))
                    .map(|row| {
                        row.chunks_exact(8)
                            .map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")))
                            .collect()
                    })
                    .collect();
                let lights = Lights {
                    mode: LightMode::Sky,
                    window_exitance: [0.0; 3],
                    sky_zenith: zenith,
                    ground_albedo,
                };
                Some(SkyLight { lights, openings, bits, near })
            }
        };
        let trained_near = match meta.get("trained_near_field").map(String::as_str) {
            Some("Exact") => TrainedNearField::Exact,
            Some("Centroid") => TrainedNearField::Centroid,
            Some(other) => return Err(fail(format!("unknown trained_near_field {other:?}"))),
            // Version 1: the near-field correction was the only Q.
            None if model.tensor("Q").is_some() => TrainedNearField::Exact,
            None => TrainedNearField::Centroid,
        };
        let loaded =
            Self::new(model, learned, emission, faces, sky, trained_near).map_err(|e| fail(e.to_string()))?;
        let loaded = match meta.get("provenance") {
            Some(text) => {
                let provenance = Provenance::from_json(text).map_err(&fail)?;
                provenance.check_engine().map_err(&fail)?;
                loaded.with_provenance(provenance)
            }
            None => loaded,
        };
        if file.names().iter().all(|n| *n != "left_out_error") {
            return Ok(loaded);
        }
        let validation = CrossValidation::new(
            read("left_out_error")?.into_data(),
            read("basis_floor")?.into_data(),
            read("sample_spacing")?.into_data(),
        )
        .map_err(&fail)?;
        loaded.with_estimate(validation).map_err(|e| fail(e.to_string()))
    }
}
