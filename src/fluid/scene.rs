//! Fluid scenes (TOML). Today: the 2D periodic tunnel of seed 000 §7.1. The seed gives no
//! domain, forcing, viscosity or time step; ours, in `scenes/fluid/tunnel*.toml`:
//!
//! - domain `[0, 4] × [0, 1]`, periodic in x, free-slip walls at y = 0 and 1 (no flux
//!   through them; the graph-Laplacian diffusion has no wall term), an equilateral
//!   triangular obstacle of circumradius 0.2 at (1, 0.5) pointing upstream;
//! - the obstacle's size is set by deforming this one base mesh (`obstacle.scale`: 0.6
//!   small, 1.0 medium, 1.4 large), the interior following harmonically;
//! - the flow starts uniform, u = (1, 0), projected to be divergence-free around the
//!   obstacle; no forcing; μ = 1e-3; 50 frames per time unit (Δt = 0.02), RK4 substeps from
//!   the stability bound.
//!
//! ```toml
//! [tunnel]            # the base mesh (crate::mesh::tunnel)
//! length = 4.0
//! height = 1.0
//! centre = [1.0, 0.5]
//! radius = 0.2
//! cell = 0.05
//! obstacle_refinement = 0.5
//! [obstacle]
//! scale = 1.0         # obstacle size relative to the base mesh, in (0, 2.5)
//! [flow]
//! initial_velocity = [1.0, 0.0]
//! forcing = [0.0, 0.0]
//! viscosity = 1e-3
//! frame_time = 0.02
//! frames = 100
//! ```

use std::path::Path;

use serde::Deserialize;

use crate::mesh::deform::HarmonicDeformation;
use crate::mesh::tunnel::{tunnel, TunnelSpec};
use crate::mesh::{Periodic, SimplexMesh, Topology};
use crate::scene_file;

use super::{FluidError, FluidParams};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneSpec {
    tunnel: TunnelKeys,
    #[serde(default)]
    obstacle: ObstacleKeys,
    flow: FlowKeys,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TunnelKeys {
    length: f64,
    height: f64,
    centre: [f64; 2],
    radius: f64,
    cell: f64,
    #[serde(default = "half")]
    obstacle_refinement: f64,
}

fn half() -> f64 {
    0.5
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ObstacleKeys {
    #[serde(default = "one")]
    scale: f64,
}

impl Default for ObstacleKeys {
    fn default() -> Self {
        Self { scale: 1.0 }
    }
}

fn one() -> f64 {
    1.0
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FlowKeys {
    initial_velocity: [f64; 2],
    #[serde(default)]
    forcing: [f64; 2],
    viscosity: f64,
    frame_time: f64,
    frames: usize,
}

/// A loaded fluid scene: the mesh at its simulation geometry, topology, parameters and the
/// initial velocity.
#[derive(Debug)]
pub struct FluidScene {
    /// The base mesh (obstacle at the spec's radius).
    pub base: SimplexMesh,
    /// The mesh deformed to the scene's obstacle scale (the simulation's geometry).
    pub mesh: SimplexMesh,
    /// Its topology (periodic in x).
    pub topology: Topology,
    /// Solver parameters.
    pub params: FluidParams,
    /// Initial velocity (before projection), per cell.
    pub initial_velocity: Vec<f64>,
    /// Frames to simulate by default.
    pub frames: usize,
    /// Obstacle scale relative to the base mesh.
    pub obstacle_scale: f64,
}

impl FluidScene {
    /// Reads and builds the scene in `path`; errors name the file and line of the bad key.
    pub fn load(path: &Path) -> Result<Self, FluidError> {
        Self::parse(&scene_file::read(path)?, path)
    }

    /// Builds the scene from TOML `text` (`path` names it in errors).
    pub fn parse(text: &str, path: &Path) -> Result<Self, FluidError> {
        let spec: SceneSpec = scene_file::parse(text, path)?;
        let fail = |key: &str, message: String| -> FluidError {
            scene_file::error_at(text, path, key, message).into()
        };
        let positive = |key: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(fail(key, format!("{key} = {v}: must be positive")))
            }
        };
        let t = &spec.tunnel;
        positive("length", t.length)?;
        positive("height", t.height)?;
        positive("radius", t.radius)?;
        positive("cell", t.cell)?;
        positive("obstacle_refinement", t.obstacle_refinement)?;
        positive("frame_time", spec.flow.frame_time)?;
        let s = spec.obstacle.scale;
        if !(s.is_finite() && s > 0.0 && s < 2.5) {
            return Err(fail("scale", format!("scale = {s}: must be in (0, 2.5)")));
        }
        if !(spec.flow.viscosity.is_finite() && spec.flow.viscosity >= 0.0) {
            return Err(fail("viscosity", format!("viscosity = {}: must be ≥ 0", spec.flow.viscosity)));
        }
        if spec.flow.initial_velocity.iter().chain(&spec.flow.forcing).any(|v| !v.is_finite()) {
            return Err(fail("initial_velocity", "velocities and forcing must be finite".into()));
        }
        let tunnel_spec = TunnelSpec {
            length: t.length,
            height: t.height,
            centre: t.centre,
            radius: t.radius,
            cell: t.cell,
            obstacle_refinement: t.obstacle_refinement,
        };
        let meshed = tunnel(&tunnel_spec).map_err(|e| fail("tunnel", e.to_string()))?;
        let mesh = if (s - 1.0).abs() > 0.0 {
            let prescribed: Vec<u32> = meshed.obstacle.iter().chain(&meshed.outer).copied().collect();
            let mut deform = HarmonicDeformation::new(&meshed.mesh, &prescribed)?;
            let mut target = meshed.mesh.g().to_vec();
            for &v in &meshed.obstacle {
                for k in 0..2 {
                    let i = 2 * v as usize + k;
                    target[i] = t.centre[k] + s * (target[i] - t.centre[k]);
                }
            }
            deform.deform(&target, 0).map_err(|e| fail("scale", format!("scale = {s}: {e}")))?
        } else {
            meshed.mesh.clone()
        };
        let topology = Topology::new(&mesh, Some(Periodic { axis: 0 }))?;
        let [ux, uy] = spec.flow.initial_velocity;
        let initial_velocity = (0..mesh.cell_count()).flat_map(|_| [ux, uy]).collect();
        let [fx, fy] = spec.flow.forcing;
        Ok(Self {
            base: meshed.mesh,
            mesh,
            topology,
            params: FluidParams {
                viscosity: spec.flow.viscosity,
                forcing: [fx, fy, 0.0],
                frame_time: spec.flow.frame_time,
            },
            initial_velocity,
            frames: spec.flow.frames,
            obstacle_scale: s,
        })
    }
}
