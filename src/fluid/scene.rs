//! Fluid scenes (TOML): the 2D periodic tunnel of seed 000 §7.1, the 3D cavity and the flying
//! bird of §7.2, a user's OBJ animation in a box, and a user's Gmsh mesh.
//! For the tunnel the seed gives no
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
//! The 3D deforming cavity of §7.2 ([`super::cavity`]), in `scenes/fluid/cavity*.toml`: the
//! fluid starts at rest and is driven by the compression of the small cavities (one of the
//! 14 training runs), μ = 1e-3, Δt = 0.02, 60 frames (compress over 30, re-inflate over 30).
//!
//! ```toml
//! [cavity]            # crate::fluid::cavity::CavitySpec
//! central_radius = 1.0
//! small_radius = 0.45
//! small_distance = 1.9
//! tunnel_radius = 0.16
//! spacing = 0.09      # lattice spacing of the stuffing
//! run = 0             # training run, 0 to 13
//! [flow]
//! initial_velocity = [0.0, 0.0, 0.0]
//! viscosity = 1e-3
//! frame_time = 0.02
//! frames = 60
//! ```
//!
//! The flying bird of §7.2 (the paper's eagle; [`super::bird`], [`super::embedded`]) in
//! `scenes/fluid/bird*.toml`: a procedural bird flapping and banking in a closed box of still
//! air, the box minus the bird stuffed at the base frame (wings level), surface vertices
//! riding on the bird's triangles, the lid absorbing the volume change, the interior
//! harmonic; μ = 1e-3, Δt = 0.02. Every `[bird]` key is optional (defaults in
//! [`super::bird::BirdSpec`]):
//!
//! ```toml
//! [bird]
//! span = 2.4
//! flap_degrees = 25.0
//! flaps = 4.0          # wingbeats over the animation
//! bank_degrees = 12.0
//! turn_degrees = 8.0
//! frames = 266         # animation frames; flow.frames may be at most frames - 1
//! [box]
//! lo = [-1.4, -1.8, -1.3]
//! hi = [1.4, 1.8, 1.3]
//! spacing = 0.104      # lattice spacing of the stuffing (about 300,000 cells)
//! [flow]
//! initial_velocity = [0.0, 0.0, 0.0]
//! viscosity = 1e-3
//! frame_time = 0.02
//! frames = 265
//! ```
//!
//! A user's triangle-mesh animation instead of the bird: an OBJ sequence (one file per frame,
//! sorted by name, each with the same objects and faces; every object a closed surface, the
//! objects may overlap), the pattern relative to the scene file
//! (`galerkin fluid surface SCENE --out DIR` writes a scene's animation in this form):
//!
//! ```toml
//! [surface]
//! obj_sequence = "flapper/frame_*.obj"
//! base_frame = 0      # the frame the base mesh is built around
//! [box]
//! lo = [-2.0, -2.0, -2.0]
//! hi = [2.0, 2.0, 2.0]
//! spacing = 0.1
//! [flow]
//! initial_velocity = [0.0, 0.0, 0.0]
//! viscosity = 1e-3
//! frame_time = 0.02
//! frames = 100
//! ```
//!
//! A user's mesh (Gmsh MSH 4.1, ASCII or binary, triangles or tetrahedra; the path relative to
//! the scene file), static, optionally periodic along one axis (the two sides matched
//! geometrically):
//!
//! ```toml
//! [mesh]
//! file = "channel.msh"
//! periodic_axis = 0   # optional
//! [flow]
//! initial_velocity = [1.0, 0.0, 0.0]
//! viscosity = 1e-3
//! frame_time = 0.02
//! frames = 100
//! ```
//!
//! The tunnel:
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

use super::bird::BirdSpec;
use super::cavity::{training_run, Cavity, CavitySpec, TRAINING_RUNS};
use super::embedded::{Embedded, EmbeddedSpec};
use crate::mesh::animation::SurfaceAnimation;
use crate::mesh::budget::CellBudget;
use crate::mesh::deform::HarmonicDeformation;
use crate::mesh::gmsh::read_msh;
use crate::mesh::tunnel::{tunnel, TunnelSpec};
use crate::mesh::{Periodic, SimplexMesh, Topology};
use crate::scene_file;

use super::{FluidError, FluidParams};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneSpec {
    tunnel: Option<TunnelKeys>,
    cavity: Option<CavityKeys>,
    mesh: Option<MeshKeys>,
    bird: Option<BirdKeys>,
    surface: Option<SurfaceKeys>,
    #[serde(rename = "box")]
    domain_box: Option<BoxKeys>,
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
struct MeshKeys {
    file: String,
    #[serde(default)]
    periodic_axis: Option<usize>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct BirdKeys {
    span: Option<f64>,
    body_length: Option<f64>,
    chord: Option<f64>,
    thickness: Option<f64>,
    flap_degrees: Option<f64>,
    flaps: Option<f64>,
    bank_degrees: Option<f64>,
    turn_degrees: Option<f64>,
    frames: Option<usize>,
    rings: Option<usize>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SurfaceKeys {
    obj_sequence: String,
    #[serde(default)]
    base_frame: usize,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxKeys {
    lo: [f64; 3],
    hi: [f64; 3],
    spacing: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CavityKeys {
    central_radius: f64,
    small_radius: f64,
    small_distance: f64,
    tunnel_radius: f64,
    spacing: f64,
    #[serde(default)]
    run: usize,
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
    initial_velocity: Vec<f64>,
    #[serde(default)]
    forcing: Vec<f64>,
    viscosity: f64,
    frame_time: f64,
    frames: usize,
}

/// How a scene's boundary moves.
#[derive(Debug)]
pub enum Motion {
    /// A fixed mesh (the tunnel).
    Static,
    /// The cavity's compressions (seed 000 §7.2).
    Cavity {
        /// The stuffed cavity with its deformation.
        cavity: Box<Cavity>,
        /// Deepest compression of each small cavity (the training run's).
        amounts: [f64; 3],
        /// The training run.
        run: usize,
    },
    /// A box around an animated surface (the flying bird, or a user's OBJ sequence).
    Embedded(Box<Embedded>),
}

/// A loaded fluid scene: the mesh at its simulation geometry, topology, parameters, the
/// initial velocity and the boundary motion.
#[derive(Debug)]
pub struct FluidScene {
    /// The base mesh (the tunnel's obstacle at the spec's radius; the cavity at rest).
    pub base: SimplexMesh,
    /// The mesh at frame 0 (the tunnel deformed to its obstacle scale).
    pub mesh: SimplexMesh,
    /// Its topology.
    pub topology: Topology,
    /// Solver parameters.
    pub params: FluidParams,
    /// Initial velocity (before projection), per cell.
    pub initial_velocity: Vec<f64>,
    /// Frames to simulate by default.
    pub frames: usize,
    /// Obstacle scale relative to the base mesh (the tunnel; 1 otherwise).
    pub obstacle_scale: f64,
    /// The periodic axis (the tunnel's x), if any.
    pub periodic_axis: Option<usize>,
    /// The boundary motion.
    pub motion: Motion,
    /// One line describing the scene.
    pub description: String,
}

/// The most frames a scene runs (each a full solve): `frames = 2^40`, a typo, is refused where
/// it is read rather than run until someone stops it (the command line's `--frames` has the
/// same cap).
pub const MAX_FRAMES: usize = 1_000_000;

/// The most frames a bird's generated animation has, and the most rings of its body (each
/// frame is a surface of rings × segments triangles, all kept in memory).
pub const MAX_BIRD_FRAMES: usize = 100_000;
/// See [`MAX_BIRD_FRAMES`].
pub const MAX_BIRD_RINGS: usize = 10_000;

type Fail<'a> = Box<dyn Fn(&str, String) -> FluidError + 'a>;

/// What each kind of scene builds; [`FluidScene::parse`] adds the `[flow]` keys.
struct Built {
    base: SimplexMesh,
    mesh: SimplexMesh,
    topology: Topology,
    obstacle_scale: f64,
    periodic_axis: Option<usize>,
    motion: Motion,
    description: String,
}

fn cavity_description(run: usize, amounts: [f64; 3]) -> String {
    format!("deforming cavity, training run {run} (deepest compressions {amounts:?})")
}

/// Refuses the first key whose value is not positive and finite, naming its line.
fn require_positive(fail: &Fail, keys: &[(&str, f64)]) -> Result<(), FluidError> {
    match keys.iter().find(|(_, v)| !(v.is_finite() && *v > 0.0)) {
        Some((key, v)) => Err(fail(key, format!("{key} = {v}: must be positive"))),
        None => Ok(()),
    }
}

impl FluidScene {
    /// Reads and builds the scene in `path`; errors name the file and line of the bad key.
    pub fn load(path: &Path) -> Result<Self, FluidError> {
        Self::parse(&scene_file::read(path)?, path)
    }

    /// Builds the scene from TOML `text` (`path` names it in errors), its mesh within what this
    /// machine can simulate ([`CellBudget::machine`]).
    pub fn parse(text: &str, path: &Path) -> Result<Self, FluidError> {
        Self::parse_within(text, path, &CellBudget::machine())
    }

    /// [`Self::parse`] with a generated mesh (tunnel, cavity, bird or surface) refused past
    /// `budget` before it is built.
    pub fn parse_within(text: &str, path: &Path, budget: &CellBudget) -> Result<Self, FluidError> {
        let spec: SceneSpec = scene_file::parse(text, path)?;
        let fail: Fail =
            Box::new(|key: &str, message: String| scene_file::error_at(text, path, key, message).into());
        require_positive(&fail, &[("frame_time", spec.flow.frame_time)])?;
        if spec.flow.frames > MAX_FRAMES {
            return Err(fail("frames", format!("frames = {}: at most {MAX_FRAMES}", spec.flow.frames)));
        }
        if !(spec.flow.viscosity.is_finite() && spec.flow.viscosity >= 0.0) {
            return Err(fail("viscosity", format!("viscosity = {}: must be ≥ 0", spec.flow.viscosity)));
        }
        if spec.flow.initial_velocity.iter().chain(&spec.flow.forcing).any(|v| !v.is_finite()) {
            return Err(fail("initial_velocity", "velocities and forcing must be finite".into()));
        }
        let user_mesh = match &spec.mesh {
            Some(m) => {
                let file = path.parent().unwrap_or(Path::new(".")).join(&m.file);
                Some(read_msh(&file).map_err(|e| fail("file", e.to_string()))?)
            }
            None => None,
        };
        let dim = match &user_mesh {
            Some(m) => m.dim(),
            None if spec.cavity.is_some() || spec.bird.is_some() || spec.surface.is_some() => 3,
            None => 2,
        };
        if spec.flow.initial_velocity.len() != dim {
            return Err(fail(
                "initial_velocity",
                format!("initial_velocity needs {dim} components in a {dim}D scene"),
            ));
        }
        if !spec.flow.forcing.is_empty() && spec.flow.forcing.len() != dim {
            return Err(fail("forcing", format!("forcing needs {dim} components in a {dim}D scene")));
        }
        let mut forcing = [0.0; 3];
        forcing[..spec.flow.forcing.len()].copy_from_slice(&spec.flow.forcing);
        let params =
            FluidParams { viscosity: spec.flow.viscosity, forcing, frame_time: spec.flow.frame_time };
        let kinds = usize::from(spec.tunnel.is_some())
            + usize::from(spec.cavity.is_some())
            + usize::from(user_mesh.is_some())
            + usize::from(spec.bird.is_some())
            + usize::from(spec.surface.is_some());
        if kinds != 1 {
            return Err(fail(
                "flow",
                "a scene needs exactly one of [tunnel], [cavity], [mesh], [bird] and [surface]".into(),
            ));
        }
        let built = if spec.bird.is_some() || spec.surface.is_some() {
            Self::embedded(&spec, path, &fail, budget)?
        } else if let (Some(mesh), Some(keys)) = (user_mesh, &spec.mesh) {
            if keys.periodic_axis.is_some_and(|a| a >= mesh.dim()) {
                return Err(fail(
                    "periodic_axis",
                    format!("periodic_axis in a {}D mesh must be below {}", mesh.dim(), mesh.dim()),
                ));
            }
            let topology = Topology::new(&mesh, keys.periodic_axis.map(|axis| Periodic { axis }))
                .map_err(|e| fail("file", e.to_string()))?;
            Built {
                base: mesh.clone(),
                description: format!("{} ({}D, {} cells)", keys.file, mesh.dim(), mesh.cell_count()),
                mesh,
                topology,
                obstacle_scale: 1.0,
                periodic_axis: keys.periodic_axis,
                motion: Motion::Static,
            }
        } else {
            match (&spec.tunnel, &spec.cavity) {
                (Some(t), _) => Self::tunnel(t, &spec, &fail, budget)?,
                (_, Some(c)) => Self::cavity(c, &fail, budget)?,
                (None, None) => unreachable!("one kind, checked above"),
            }
        };
        let initial_velocity =
            (0..built.mesh.cell_count()).flat_map(|_| spec.flow.initial_velocity.iter().copied()).collect();
        Ok(Self {
            base: built.base,
            mesh: built.mesh,
            topology: built.topology,
            params,
            initial_velocity,
            frames: spec.flow.frames,
            obstacle_scale: built.obstacle_scale,
            periodic_axis: built.periodic_axis,
            motion: built.motion,
            description: built.description,
        })
    }

    fn tunnel(
        t: &TunnelKeys,
        spec: &SceneSpec,
        fail: &Fail,
        budget: &CellBudget,
    ) -> Result<Built, FluidError> {
        require_positive(
            fail,
            &[
                ("length", t.length),
                ("height", t.height),
                ("radius", t.radius),
                ("cell", t.cell),
                ("obstacle_refinement", t.obstacle_refinement),
            ],
        )?;
        let s = spec.obstacle.scale;
        if !(s.is_finite() && s > 0.0 && s < 2.5) {
            return Err(fail("scale", format!("scale = {s}: must be in (0, 2.5)")));
        }
        let tunnel_spec = TunnelSpec {
            length: t.length,
            height: t.height,
            centre: t.centre,
            radius: t.radius,
            cell: t.cell,
            obstacle_refinement: t.obstacle_refinement,
        };
        let meshed = tunnel(&tunnel_spec, budget).map_err(|e| fail("tunnel", e.to_string()))?;
        let mesh = if s != 1.0 {
            let prescribed: Vec<u32> = meshed.obstacle.iter().chain(&meshed.outer).copied().collect();
            let mut deform = HarmonicDeformation::new(&meshed.mesh, &prescribed)?;
            let mut target = meshed.mesh.g().to_vec();
            for &v in &meshed.obstacle {
                for k in 0..2 {
                    let i = 2 * v as usize + k;
                    target[i] = t.centre[k] + s * (target[i] - t.centre[k]);
                }
            }
            let g = deform.deform(&target, 0).map_err(|e| fail("scale", format!("scale = {s}: {e}")))?;
            meshed.mesh.with_g(g, None)?
        } else {
            meshed.mesh.clone()
        };
        let topology = Topology::new(&mesh, Some(Periodic { axis: 0 }))?;
        Ok(Built {
            base: meshed.mesh,
            mesh,
            topology,
            obstacle_scale: s,
            periodic_axis: Some(0),
            motion: Motion::Static,
            description: format!("periodic tunnel, obstacle scale {s}"),
        })
    }

    fn cavity(c: &CavityKeys, fail: &Fail, budget: &CellBudget) -> Result<Built, FluidError> {
        require_positive(
            fail,
            &[
                ("central_radius", c.central_radius),
                ("small_radius", c.small_radius),
                ("small_distance", c.small_distance),
                ("tunnel_radius", c.tunnel_radius),
                ("spacing", c.spacing),
            ],
        )?;
        if c.small_distance <= c.central_radius + c.small_radius {
            return Err(fail("small_distance", "the small cavities must not overlap the central one".into()));
        }
        if c.tunnel_radius >= c.small_radius {
            return Err(fail("tunnel_radius", "tunnels must be thinner than the small cavities".into()));
        }
        let amounts = training_run(c.run).ok_or_else(|| {
            fail("run", format!("run = {}: the training runs are 0 to {}", c.run, TRAINING_RUNS - 1))
        })?;
        let cavity_spec = CavitySpec {
            central_radius: c.central_radius,
            small_radius: c.small_radius,
            small_distance: c.small_distance,
            tunnel_radius: c.tunnel_radius,
            spacing: c.spacing,
        };
        let cavity = Cavity::new(&cavity_spec, budget).map_err(|e| fail("cavity", e.to_string()))?;
        Ok(Built {
            base: cavity.mesh.clone(),
            mesh: cavity.mesh.clone(),
            topology: cavity.topology.clone(),
            obstacle_scale: 1.0,
            periodic_axis: None,
            description: cavity_description(c.run, amounts),
            motion: Motion::Cavity { cavity: Box::new(cavity), amounts, run: c.run },
        })
    }

    fn embedded(
        spec: &SceneSpec,
        path: &Path,
        fail: &Fail,
        budget: &CellBudget,
    ) -> Result<Built, FluidError> {
        let Some(b) = &spec.domain_box else {
            return Err(fail("flow", "[bird] and [surface] scenes need a [box] (lo, hi, spacing)".into()));
        };
        require_positive(fail, &[("spacing", b.spacing)])?;
        if (0..3).any(|k| !(b.lo[k].is_finite() && b.hi[k].is_finite() && b.lo[k] < b.hi[k])) {
            return Err(fail("lo", "the box needs finite lo < hi on every axis".into()));
        }
        let (animation, base_frame, what) = if let Some(keys) = &spec.bird {
            let d = BirdSpec::default();
            let bird = BirdSpec {
                span: keys.span.unwrap_or(d.span),
                body_length: keys.body_length.unwrap_or(d.body_length),
                chord: keys.chord.unwrap_or(d.chord),
                thickness: keys.thickness.unwrap_or(d.thickness),
                flap_degrees: keys.flap_degrees.unwrap_or(d.flap_degrees),
                flaps: keys.flaps.unwrap_or(d.flaps),
                bank_degrees: keys.bank_degrees.unwrap_or(d.bank_degrees),
                turn_degrees: keys.turn_degrees.unwrap_or(d.turn_degrees),
                frames: keys.frames.unwrap_or(d.frames),
                rings: keys.rings.unwrap_or(d.rings),
            };
            require_positive(
                fail,
                &[
                    ("span", bird.span),
                    ("body_length", bird.body_length),
                    ("chord", bird.chord),
                    ("thickness", bird.thickness),
                ],
            )?;
            if bird.span <= 0.2 * bird.body_length {
                return Err(fail("span", "span must exceed a fifth of body_length".into()));
            }
            if bird.frames < 2 || bird.rings < 3 {
                return Err(fail("frames", "a bird needs at least 2 frames and 3 rings".into()));
            }
            if bird.frames > MAX_BIRD_FRAMES {
                return Err(fail("frames", format!("frames = {}: at most {MAX_BIRD_FRAMES}", bird.frames)));
            }
            if bird.rings > MAX_BIRD_RINGS {
                return Err(fail("rings", format!("rings = {}: at most {MAX_BIRD_RINGS}", bird.rings)));
            }
            let what = format!("flying bird ({} frames, {} wingbeats)", bird.frames, bird.flaps);
            (bird.animation(), 0, what)
        } else {
            let keys = spec.surface.as_ref().expect("one kind, checked by the caller");
            let pattern = path.parent().unwrap_or(Path::new(".")).join(&keys.obj_sequence);
            let files = SurfaceAnimation::sequence_files(&pattern)
                .map_err(|e| fail("obj_sequence", e.to_string()))?;
            let animation =
                SurfaceAnimation::read_sequence(&files).map_err(|e| fail("obj_sequence", e.to_string()))?;
            let what = format!("{} ({} frames)", keys.obj_sequence, files.len());
            (animation, keys.base_frame, what)
        };
        let available = animation.frame_count() - 1;
        if spec.flow.frames > available {
            return Err(fail(
                "frames",
                format!(
                    "frames = {}: the surface animation allows at most {available} steps",
                    spec.flow.frames
                ),
            ));
        }
        let embedded_spec = EmbeddedSpec { lo: b.lo, hi: b.hi, spacing: b.spacing, base_frame };
        let mut domain =
            Embedded::new(animation, &embedded_spec, budget).map_err(|e| fail("box", e.to_string()))?;
        let base = domain.mesh.clone();
        let g0 = domain.geometry(0)?;
        let mesh = base.with_g(g0, Some(0))?;
        Ok(Built {
            description: format!("{what} in a box, {} surface vertices attached", domain.attached_count()),
            base,
            mesh,
            topology: domain.topology.clone(),
            obstacle_scale: 1.0,
            periodic_axis: None,
            motion: Motion::Embedded(Box::new(domain)),
        })
    }

    /// The surface animation of a `[bird]` or `[surface]` scene.
    pub fn animation(&self) -> Option<&SurfaceAnimation> {
        match &self.motion {
            Motion::Embedded(domain) => Some(&domain.animation),
            _ => None,
        }
    }

    /// The most frames the scene can run: [`MAX_FRAMES`], and for a surface animation (the
    /// bird, an OBJ sequence) one less than its frame count — every step moves to the next
    /// animation frame.
    pub fn max_frames(&self) -> usize {
        self.animation().map_or(MAX_FRAMES, |a| a.frame_count().saturating_sub(1).min(MAX_FRAMES))
    }

    /// Refuses `frames` beyond [`Self::max_frames`] before any step is taken, naming the
    /// scene and the limit (a `--frames` over an animation's length used to run every frame
    /// the animation has, then fail).
    pub fn check_frames(&self, frames: usize) -> Result<(), FluidError> {
        let most = self.max_frames();
        if frames <= most {
            return Ok(());
        }
        Err(FluidError::State(match self.animation() {
            Some(a) => format!(
                "{frames} frames asked of {}: its surface animation has {} frames, so at most {most} steps",
                self.description,
                a.frame_count()
            ),
            None => format!("{frames} frames asked of {}: at most {most}", self.description),
        }))
    }

    /// Chooses the cavity's training run (0 to 13); refused for other scenes.
    pub fn set_run(&mut self, run: usize) -> Result<(), FluidError> {
        let Motion::Cavity { amounts, run: current, .. } = &mut self.motion else {
            return Err(FluidError::State("--run applies to cavity scenes only".into()));
        };
        *amounts = training_run(run).ok_or_else(|| {
            FluidError::State(format!("run {run}: the training runs are 0 to {}", TRAINING_RUNS - 1))
        })?;
        *current = run;
        self.description = cavity_description(run, *amounts);
        Ok(())
    }

    /// The geometry vector of frame `frame` (the tunnel and a user's mesh: fixed; the cavity:
    /// its compressions at that frame, volume renormalised; the bird or a user's animation:
    /// the surface at that frame, the lid keeping the volume; interiors harmonic). An
    /// inverted frame is refused naming it.
    pub fn geometry(&mut self, frame: usize) -> Result<Vec<f64>, FluidError> {
        match &mut self.motion {
            Motion::Static => Ok(self.mesh.g().to_vec()),
            Motion::Cavity { cavity, amounts, .. } => {
                let a = Cavity::compression(*amounts, frame, self.frames);
                Ok(cavity.geometry(a, frame)?)
            }
            Motion::Embedded(domain) => Ok(domain.geometry(frame)?),
        }
    }
}
