//! A user's scene from OBJ files (seed 000 §9's design space, for any architecture): a base
//! OBJ and one OBJ per design parameter with the same vertices and faces moved — named
//! deformation targets (blend shapes). The geometry at parameters `p` is
//! `g(p) = g₀ + Σ_a p_a (g_a − g₀)`, so the topology never changes, as Table 2 needs.
//!
//! The scene file (TOML) names the OBJ files (relative to itself), each target's range and
//! default, the albedo per OBJ object (`o`/`g` name; a default for the rest), which objects
//! are openings (windows, skylights), and the lights as in the two-room scene:
//!
//! ```toml
//! base = "room.obj"
//! [[targets]]
//! name = "window"
//! file = "room_window_wide.obj"
//! range = [0.0, 1.0]
//! default = 0.0
//! [materials]
//! default = [0.7, 0.7, 0.7]
//! by_object = { floor = [0.5, 0.4, 0.3] }
//! [openings]
//! windows = ["window"]
//! skylights = []
//! [lights]                 # optional, as is each key (defaults: the two-room scene's)
//! mode = "area"
//! window_exitance = [10.0, 10.0, 10.0]
//! sky_zenith = [4.0, 4.0, 4.0]
//! ground_albedo = 0.2
//! ```
//!
//! Light enters only through the openings: a scene without window or skylight objects is
//! dark (every radiosity 0), and loading it warns.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use glam::DVec3;
use serde::Deserialize;

use super::error::RadiosityError;
use super::mesh::{FaceKind, SceneMesh};
use super::scene::Lights;
use super::train::DesignSpace;
use crate::scene_file;

/// One deformation target.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TargetSpec {
    /// The parameter's name.
    pub name: String,
    /// The OBJ file with the target positions (same vertices and faces as the base).
    pub file: PathBuf,
    /// Range of the blend weight.
    pub range: [f64; 2],
    /// Default weight.
    #[serde(default)]
    pub default: f64,
}

/// Albedo by object name.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjMaterials {
    /// Albedo of objects not listed.
    pub default: [f64; 3],
    /// Albedo per object name.
    #[serde(default)]
    pub by_object: BTreeMap<String, [f64; 3]>,
}

/// Objects through which light enters.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjOpenings {
    /// Window objects.
    #[serde(default)]
    pub windows: Vec<String>,
    /// Skylight objects.
    #[serde(default)]
    pub skylights: Vec<String>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjSceneFile {
    base: PathBuf,
    #[serde(default)]
    targets: Vec<TargetSpec>,
    materials: ObjMaterials,
    #[serde(default)]
    openings: ObjOpenings,
    #[serde(default)]
    lights: Lights,
}

/// A loaded OBJ scene: the base mesh (with materials and kinds) and the targets' positions.
#[derive(Clone, Debug)]
pub struct ObjScene {
    base: SceneMesh,
    targets: Vec<(TargetSpec, Vec<DVec3>)>,
    lights: Lights,
    /// The OBJ files read: the base, then each target's.
    files: Vec<PathBuf>,
}

fn read_obj(path: &Path) -> Result<Vec<tobj::Model>, RadiosityError> {
    crate::mesh::obj::load(path).map_err(|message| RadiosityError::File { path: path.to_path_buf(), message })
}

fn positions(models: &[tobj::Model]) -> Vec<DVec3> {
    models
        .iter()
        .flat_map(|m| m.mesh.positions.chunks_exact(3).map(|p| DVec3::new(p[0], p[1], p[2])))
        .collect()
}

impl ObjScene {
    /// Reads the scene file and its OBJ files; errors name the file (and the line of the
    /// scene file, or the object and face).
    pub fn load(path: &Path) -> Result<Self, RadiosityError> {
        let text = scene_file::read(path)?;
        let spec: ObjSceneFile = scene_file::parse(&text, path)?;
        let fail = |key: &str, message: String| {
            RadiosityError::from(scene_file::error_at(&text, path, key, message))
        };
        spec.lights.check().map_err(|e| fail("[lights]", e))?;
        let albedos = std::iter::once(("default", &spec.materials.default))
            .chain(spec.materials.by_object.iter().map(|(k, v)| (k.as_str(), v)));
        for (name, albedo) in albedos {
            if albedo.iter().any(|a| !(a.is_finite() && (0.0..1.0).contains(a))) {
                return Err(fail(
                    name,
                    format!("albedo {name} = {albedo:?}: every channel must be in [0, 1)"),
                ));
            }
        }
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let base_path = dir.join(&spec.base);
        let models = read_obj(&base_path)?;
        let known: Vec<&str> = models.iter().map(|m| m.name.as_str()).collect();
        for name in
            spec.materials.by_object.keys().chain(&spec.openings.windows).chain(&spec.openings.skylights)
        {
            if !known.contains(&name.as_str()) {
                return Err(fail(
                    name,
                    format!("no object {name:?} in {} (it has {known:?})", base_path.display()),
                ));
            }
        }
        let mut base = SceneMesh {
            vertices: positions(&models),
            faces: Vec::new(),
            albedo: Vec::new(),
            kind: Vec::new(),
            part: Vec::new(),
            part_names: Vec::new(),
        };
        let mut offset = 0u32;
        for (part, m) in models.iter().enumerate() {
            let kind = if spec.openings.windows.contains(&m.name) {
                FaceKind::Window
            } else if spec.openings.skylights.contains(&m.name) {
                FaceKind::Skylight
            } else {
                FaceKind::Surface
            };
            let albedo = match kind {
                FaceKind::Surface => {
                    *spec.materials.by_object.get(&m.name).unwrap_or(&spec.materials.default)
                }
                _ => [0.0; 3],
            };
            base.part_names.push(m.name.clone());
            for f in m.mesh.indices.chunks_exact(3) {
                base.faces.push([f[0] + offset, f[1] + offset, f[2] + offset]);
                base.albedo.push(albedo);
                base.kind.push(kind);
                base.part.push(part as u16);
            }
            offset += (m.mesh.positions.len() / 3) as u32;
        }
        base.validate()
            .map_err(|e| RadiosityError::File { path: base_path.clone(), message: e.to_string() })?;
        if !base.kind.iter().any(|k| *k != FaceKind::Surface) {
            tracing::warn!(
                "{}: no window or skylight objects, so no light enters and every face's radiosity is 0: name the objects light comes through under [openings] (windows = [\"…\"], skylights = [\"…\"])",
                path.display()
            );
        }
        let mut targets = Vec::new();
        let mut files = vec![base_path.clone()];
        for t in spec.targets {
            let [lo, hi] = t.range;
            if !(lo.is_finite() && hi.is_finite() && lo <= hi && (lo..=hi).contains(&t.default)) {
                return Err(fail(
                    &t.name,
                    format!(
                        "target {}: needs lo <= default <= hi, got {:?} and {}",
                        t.name, t.range, t.default
                    ),
                ));
            }
            let target_path = dir.join(&t.file);
            let m = read_obj(&target_path)?;
            let faces: Vec<u32> = m
                .iter()
                .scan(0u32, |off, m| {
                    let f: Vec<u32> = m.mesh.indices.iter().map(|i| i + *off).collect();
                    *off += (m.mesh.positions.len() / 3) as u32;
                    Some(f)
                })
                .flatten()
                .collect();
            let p = positions(&m);
            let base_faces: Vec<u32> = base.faces.iter().flatten().copied().collect();
            if p.len() != base.vertices.len() || faces != base_faces {
                return Err(RadiosityError::File {
                    path: target_path,
                    message: format!(
                        "target {} must have the base's vertices and faces ({} vertices, {} faces), found {} and {}",
                        t.name,
                        base.vertices.len(),
                        base.faces.len(),
                        p.len(),
                        faces.len() / 3
                    ),
                });
            }
            files.push(target_path);
            targets.push((t, p));
        }
        Ok(Self { base, targets, lights: spec.lights, files })
    }

    /// Lights the scene by area lights in its openings or by the sky through them.
    pub fn set_light_mode(&mut self, mode: super::scene::LightMode) {
        self.lights.mode = mode;
    }

    /// The OBJ files the scene was read from: the base, then each target's.
    pub fn files(&self) -> &[PathBuf] {
        &self.files
    }

    /// The parameters' names.
    pub fn names(&self) -> Vec<&str> {
        self.targets.iter().map(|(t, _)| t.name.as_str()).collect()
    }
}

impl DesignSpace for ObjScene {
    fn ranges(&self) -> Vec<[f64; 2]> {
        self.targets.iter().map(|(t, _)| t.range).collect()
    }

    fn defaults(&self) -> Vec<f64> {
        self.targets.iter().map(|(t, _)| t.default).collect()
    }

    fn mesh(&self, p: &[f64]) -> Result<SceneMesh, RadiosityError> {
        if p.len() != self.targets.len() {
            return Err(RadiosityError::Parameter {
                name: "parameters".into(),
                message: format!("{} values for {} targets", p.len(), self.targets.len()),
            });
        }
        let mut mesh = self.base.clone();
        for ((t, target), &w) in self.targets.iter().zip(p) {
            let [lo, hi] = t.range;
            if !w.is_finite() || w < lo || w > hi {
                return Err(RadiosityError::Parameter {
                    name: t.name.clone(),
                    message: format!("{w} is outside its range [{lo}, {hi}]"),
                });
            }
            for (v, (b, q)) in mesh.vertices.iter_mut().zip(self.base.vertices.iter().zip(target)) {
                *v += w * (*q - *b);
            }
        }
        mesh.validate()?;
        Ok(mesh)
    }

    fn lights(&self) -> &Lights {
        &self.lights
    }
}
