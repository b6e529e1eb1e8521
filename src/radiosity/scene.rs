//! The radiosity scene file (TOML, e.g. `scenes/radiosity/two_rooms.toml`): the rooms'
//! dimensions, the mesh resolution, the design parameters of seed 000 §9 (window, skylight and
//! door sizes, the living-room ceiling tilt) each with a default and a range, the materials
//! (RGB albedo per part) and the lights. Errors name the file and the line.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Deserialize;

use super::error::RadiosityError;
use crate::scene_file;

/// The design parameters of the two-room scene, in the order of a parameter vector.
pub const PARAMETERS: [&str; 4] = ["window_width", "skylight_size", "door_width", "ceiling_tilt"];

/// Dimensions of the two rooms (metres).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rooms {
    /// Living room: length along x, depth along y, height at the south wall.
    pub living: [f64; 3],
    /// Bedroom: length along x, depth along y (must equal the living room's), height.
    pub bedroom: [f64; 3],
    /// Thickness of the wall between the rooms (the door passes through it).
    pub wall_thickness: f64,
    /// Height of the door.
    pub door_height: f64,
    /// Height of the window sills above the floor.
    pub window_sill: f64,
    /// Height of the windows.
    pub window_height: f64,
    /// Width of the bedroom's window as a fraction of the living room's.
    pub bedroom_window_ratio: f64,
}

/// Mesh resolution.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Resolution {
    /// Target edge length of the wall cells (metres) at the default parameters; every cell
    /// is split into two triangles. 0.3 gives about 5,000 faces.
    pub cell: f64,
}

/// One design parameter: its default and its range.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParameterSpec {
    /// Value used when none is given (and to fix the mesh topology).
    pub default: f64,
    /// Closed range `[lo, hi]` of valid values.
    pub range: [f64; 2],
}

/// RGB albedo of each part of the scene.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Materials {
    /// Living-room walls (light).
    pub living_walls: [f64; 3],
    /// Living-room floor.
    pub living_floor: [f64; 3],
    /// Living-room ceiling.
    pub living_ceiling: [f64; 3],
    /// Bedroom walls (darker).
    pub bedroom_walls: [f64; 3],
    /// Bedroom floor.
    pub bedroom_floor: [f64; 3],
    /// Bedroom ceiling.
    pub bedroom_ceiling: [f64; 3],
    /// The door's reveal (jambs, lintel, threshold).
    pub door_frame: [f64; 3],
    /// The cubes in the living room.
    pub furniture: [f64; 3],
    /// The bed.
    pub bed: [f64; 3],
}

/// How the scene is lit (seed 000 §9: both ways).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LightMode {
    /// Area lights in the windows and the skylight: their faces emit, inside the model.
    Area,
    /// An overcast sky outside: direct light through the openings, computed at run time.
    Sky,
}

/// The lights. Every key is optional: the defaults are the two-room scene's (area mode,
/// window exitance [10, 10, 10.5] W/m², zenith radiance [4, 4, 4.3] W/m²/sr, ground albedo
/// 0.2), so an area-lit scene need not give the sky's keys and the other way round.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Lights {
    /// `area` or `sky`.
    pub mode: LightMode,
    /// Area mode: exitance (radiosity, W/m²) of the window and skylight faces, RGB.
    pub window_exitance: [f64; 3],
    /// Sky mode: zenith radiance of the CIE overcast sky, RGB (W/m²/sr).
    pub sky_zenith: [f64; 3],
    /// Sky mode: albedo of the ground outside (light from below the horizon).
    pub ground_albedo: f64,
}

impl Default for Lights {
    fn default() -> Self {
        Self {
            mode: LightMode::Area,
            window_exitance: [10.0, 10.0, 10.5],
            sky_zenith: [4.0, 4.0, 4.3],
            ground_albedo: 0.2,
        }
    }
}

impl Lights {
    /// Refuses a negative or non-finite exitance or zenith radiance (naming the key and the
    /// channel) and a ground albedo outside [0, 1): light a scene cannot emit.
    pub fn check(&self) -> Result<(), String> {
        for (key, rgb) in [("window_exitance", self.window_exitance), ("sky_zenith", self.sky_zenith)] {
            if let Some(c) = rgb.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
                return Err(format!(
                    "{key} = {rgb:?}: channel {} ({}) must be finite and ≥ 0",
                    c,
                    ["red", "green", "blue"][c]
                ));
            }
        }
        if !(self.ground_albedo.is_finite() && (0.0..1.0).contains(&self.ground_albedo)) {
            return Err(format!("ground_albedo = {}: must be in [0, 1)", self.ground_albedo));
        }
        Ok(())
    }
}

/// A whole radiosity scene.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    /// Room dimensions.
    pub rooms: Rooms,
    /// Mesh resolution.
    pub resolution: Resolution,
    /// The design parameters by name ([`PARAMETERS`]).
    pub parameters: BTreeMap<String, ParameterSpec>,
    /// Albedos.
    pub materials: Materials,
    /// Lights.
    pub lights: Lights,
}

/// The most faces a scene file may ask for (estimated from its rooms and resolution before the
/// mesh is built): the full solve stores a form factor for every pair, 20 GB at this size.
pub const MAX_FACES: usize = 50_000;

/// A point of the parameter space, in the order of [`PARAMETERS`].
pub type Parameters = [f64; 4];

impl SceneSpec {
    /// Reads and validates a scene file.
    pub fn load(path: &Path) -> Result<Self, RadiosityError> {
        Self::parse(&scene_file::read(path)?, path)
    }

    /// Parses and validates scene text; `path` names it in errors. The geometry is built at
    /// every corner of the parameter box and checked, so a range that would fold a wall or
    /// close an opening is refused here, naming the parameter.
    pub fn parse(text: &str, path: &Path) -> Result<Self, RadiosityError> {
        let spec: SceneSpec = scene_file::parse(text, path)?;
        let fail = |key: &str, message: String| Err(scene_file::error_at(text, path, key, message).into());
        for name in spec.parameters.keys() {
            if !PARAMETERS.contains(&name.as_str()) {
                return fail(
                    &format!("[parameters.{name}]"),
                    format!("unknown parameter {name} (the scene has {})", PARAMETERS.join(", ")),
                );
            }
        }
        for name in PARAMETERS {
            let Some(p) = spec.parameters.get(name) else {
                return fail("[parameters", format!("parameter {name} is missing"));
            };
            let [lo, hi] = p.range;
            if !(lo.is_finite() && hi.is_finite() && lo <= hi && (lo..=hi).contains(&p.default)) {
                return fail(
                    &format!("[parameters.{name}]"),
                    format!(
                        "{name}: needs a finite range lo <= default <= hi, got [{lo}, {hi}] and {}",
                        p.default
                    ),
                );
            }
        }
        let r = &spec.rooms;
        let lengths = [r.living, r.bedroom].concat();
        if lengths.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return fail("living", "room dimensions must be positive".into());
        }
        if (r.living[1] - r.bedroom[1]).abs() > 1e-9 {
            return fail("bedroom", "the bedroom's depth must equal the living room's".into());
        }
        let positive =
            [r.wall_thickness, r.door_height, r.window_sill, r.window_height, r.bedroom_window_ratio];
        if positive.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return fail("wall_thickness", "wall thickness, door height, window sill and height and the bedroom window ratio must be positive".into());
        }
        if r.door_height >= r.living[2].min(r.bedroom[2])
            || r.window_sill + r.window_height >= r.living[2].min(r.bedroom[2])
        {
            return fail("door_height", "the door and the windows must end below the ceilings".into());
        }
        if !(spec.resolution.cell.is_finite() && (0.02..=10.0).contains(&spec.resolution.cell)) {
            return fail(
                "cell",
                format!("resolution.cell must be 0.02 to 10 m, got {}", spec.resolution.cell),
            );
        }
        // The mesh the resolution asks for, estimated before it is built: two triangles per
        // cell² of the rooms' surfaces. The full solve stores every pair's form factor.
        let area: f64 =
            [r.living, r.bedroom].iter().map(|d| 2.0 * (d[0] * d[1] + d[1] * d[2] + d[2] * d[0])).sum();
        let faces = 2.0 * area / (spec.resolution.cell * spec.resolution.cell);
        if faces > MAX_FACES as f64 {
            return fail(
                "cell",
                format!(
                    "rooms of {area:.0} m² at resolution.cell = {} m make about {faces:.0} faces; at most {MAX_FACES} (raise the cell size)",
                    spec.resolution.cell
                ),
            );
        }
        let m = &spec.materials;
        let albedos = [
            m.living_walls,
            m.living_floor,
            m.living_ceiling,
            m.bedroom_walls,
            m.bedroom_floor,
            m.bedroom_ceiling,
            m.door_frame,
            m.furniture,
            m.bed,
        ];
        if albedos.iter().flatten().any(|a| !(a.is_finite() && (0.0..1.0).contains(a))) {
            return fail("[materials]", "every albedo must be in [0, 1)".into());
        }
        if let Err(e) = spec.lights.check() {
            return fail("[lights]", e);
        }
        // Every corner of the parameter box must give a valid mesh.
        for corner in 0..16u32 {
            let mut p = spec.defaults();
            for (a, name) in PARAMETERS.iter().enumerate() {
                p[a] = spec.parameters[*name].range[((corner >> a) & 1) as usize];
            }
            if let Err(e) = super::architecture::check_layout(&spec, &p) {
                let name = e.0;
                return fail(&format!("[parameters.{name}]"), format!("{name}: {} (at {p:?})", e.1));
            }
            let mesh = super::architecture::build(&spec, &p).and_then(|m| m.validate().map(|_| m));
            if let Err(e) = mesh {
                return fail("[parameters", format!("the range corner {p:?} gives a bad mesh: {e}"));
            }
        }
        Ok(spec)
    }

    /// The default parameter vector.
    pub fn defaults(&self) -> Parameters {
        PARAMETERS.map(|n| self.parameters.get(n).map_or(0.0, |p| p.default))
    }

    /// The ranges, in the order of [`PARAMETERS`].
    pub fn ranges(&self) -> [[f64; 2]; 4] {
        PARAMETERS.map(|n| self.parameters.get(n).map_or([0.0, 0.0], |p| p.range))
    }

    /// Checks a parameter vector against the ranges, naming the first one outside.
    pub fn check(&self, p: &Parameters) -> Result<(), RadiosityError> {
        for ((name, v), [lo, hi]) in PARAMETERS.iter().zip(p).zip(self.ranges()) {
            if !v.is_finite() || *v < lo || *v > hi {
                return Err(RadiosityError::Parameter {
                    name: name.to_string(),
                    message: format!("{v} is outside its range [{lo}, {hi}]"),
                });
            }
        }
        Ok(())
    }

    /// Parameters from `name=value` pairs over the defaults; unknown names are refused.
    pub fn parameters_from(&self, pairs: &[(String, f64)]) -> Result<Parameters, RadiosityError> {
        let mut p = self.defaults();
        for (name, v) in pairs {
            let Some(a) = PARAMETERS.iter().position(|n| n == name) else {
                return Err(RadiosityError::Parameter {
                    name: name.clone(),
                    message: format!("unknown (the scene has {})", PARAMETERS.join(", ")),
                });
            };
            p[a] = *v;
        }
        self.check(&p)?;
        Ok(p)
    }
}
