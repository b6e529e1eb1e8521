//! A radiosity scene file of either kind (seed 000 §9's design space): the generated two rooms
//! ([`SceneSpec`]) or a user's OBJ scene with named deformation targets ([`ObjScene`], a scene
//! file with a `base = "….obj"` key), behind one [`DesignSpace`] — what `radiosity render`,
//! `train`, `compare` and the viewer take.

use std::path::Path;

use super::obj::ObjScene;
use super::render::{camera_for, Viewpoint};
use super::scene::{LightMode, SceneSpec, PARAMETERS};
use super::train::DesignSpace;
use super::{RadiosityError, SceneMesh};
use crate::render::{camera_for_box, Camera};

/// A scene of either kind.
pub enum AnyScene {
    /// The generated two rooms (window, skylight, door and ceiling-tilt parameters).
    Rooms(Box<SceneSpec>),
    /// A user's OBJ scene: one parameter per deformation target.
    Obj(Box<ObjScene>),
}

impl AnyScene {
    /// Reads `path` (an OBJ scene if it has a `base = …` key, else the two rooms), its lighting
    /// replaced by `lights` if given. Errors name the file.
    pub fn load(path: &Path, lights: Option<LightMode>) -> Result<Self, RadiosityError> {
        let text = crate::scene_file::read(path)?;
        let mut scene = if is_obj_scene(&text) {
            AnyScene::Obj(Box::new(ObjScene::load(path)?))
        } else {
            AnyScene::Rooms(Box::new(SceneSpec::load(path)?))
        };
        if let Some(mode) = lights {
            scene.set_light_mode(mode);
        }
        Ok(scene)
    }

    /// Lights the scene by area lights in its openings or by the sky through them (§9).
    pub fn set_light_mode(&mut self, mode: LightMode) {
        match self {
            AnyScene::Rooms(s) => s.lights.mode = mode,
            AnyScene::Obj(s) => s.set_light_mode(mode),
        }
    }

    /// The scene as a design space: parameter ranges and defaults, the mesh at parameters, the
    /// lights.
    pub fn space(&self) -> &dyn DesignSpace {
        match self {
            AnyScene::Rooms(s) => s.as_ref(),
            AnyScene::Obj(s) => s.as_ref(),
        }
    }

    /// SHA-256 of the scene's content read from `path`: the scene file and, for an OBJ scene,
    /// every OBJ file it names ([`crate::reduce::provenance::files_sha256`]).
    pub fn content_sha256(&self, path: &Path) -> Result<String, RadiosityError> {
        let mut files: Vec<&Path> = vec![path];
        if let AnyScene::Obj(s) = self {
            files.extend(s.files().iter().map(|p| p.as_path()));
        }
        crate::reduce::provenance::files_sha256(&files)
            .map_err(|message| RadiosityError::File { path: path.to_path_buf(), message })
    }

    /// The provenance of a model of this scene (read from `path`) trained with `options` on
    /// the samples `params`.
    pub fn provenance(
        &self,
        path: &Path,
        options: String,
        params: &[Vec<f64>],
    ) -> Result<crate::reduce::provenance::Provenance, RadiosityError> {
        Ok(crate::reduce::provenance::Provenance::new(path, self.content_sha256(path)?, options, params))
    }

    /// The parameters' names, in the design space's order.
    pub fn names(&self) -> Vec<String> {
        match self {
            AnyScene::Rooms(_) => PARAMETERS.iter().map(|s| s.to_string()).collect(),
            AnyScene::Obj(s) => s.names().iter().map(|s| s.to_string()).collect(),
        }
    }

    /// Parameters from `name=value` pairs over the defaults; unknown names and values outside
    /// their ranges are refused, naming the parameter.
    pub fn parameters_from(&self, pairs: &[(String, f64)]) -> Result<Vec<f64>, RadiosityError> {
        if let AnyScene::Rooms(spec) = self {
            return Ok(spec.parameters_from(pairs)?.to_vec());
        }
        let names = self.names();
        let space = self.space();
        let mut p = space.defaults();
        for (name, v) in pairs {
            let Some(a) = names.iter().position(|n| n == name) else {
                return Err(RadiosityError::Parameter {
                    name: name.clone(),
                    message: format!("unknown (the scene has {})", names.join(", ")),
                });
            };
            p[a] = *v;
        }
        space.mesh(&p)?;
        Ok(p)
    }

    /// A camera for `mesh` (the scene at some parameters): the two rooms' `view`, or (an OBJ
    /// scene has no named viewpoints) one that shows the mesh's bounding box from outside.
    pub fn camera(&self, mesh: &SceneMesh, view: Viewpoint) -> Camera {
        match self {
            AnyScene::Rooms(spec) => camera_for(spec, view),
            AnyScene::Obj(_) => {
                let (lo, hi) = mesh.bounds();
                camera_for_box(lo.to_array(), hi.to_array())
            }
        }
    }
}

/// Whether a scene file's text describes an OBJ scene (a `base = "….obj"` key) rather than the
/// generated two rooms.
fn is_obj_scene(text: &str) -> bool {
    text.lines().any(|l| l.trim_start().starts_with("base") && l.contains('='))
}
