//! The data sets of seed 003 §5 on tent-pitched meshes ([`super::tent`]): crack-tip
//! scattering (Figures 2, 4–6), a composite with circular inclusions (Figures 7–8) and a
//! sector of a solid rocket booster (Figures 1, 9).
//!
//! **The fields are analytic, not solved.** There is no spacetime DG solver here: each
//! scenario's displacement is a sum of travelling and reflected wave pulses written down in
//! closed form — plane waves (exact solutions of linear elastodynamics in a homogeneous
//! medium), and cylindrical waves with the far-field `1/√r` amplitude decay and reflections
//! with the sign their boundary condition dictates at normal incidence, which are
//! approximations (diffraction, mode conversion and the material contrast are not modelled
//! beyond that). Each field is L2-projected onto the cubic per element
//! ([`super::generate::project_element`]), so the data are discontinuous across faces as a DG
//! solution is. The materials only set the wave speeds of the mesher's causality bound and
//! the strain energy the renderer shows.
//!
//! Every pulse is a *shock*: a displacement step `A S(ξ)` smoothed over the width
//! [`WIDTH`], `S(ξ) = ½ (1 + tanh(ξ / WIDTH))`, with `ξ = c (t − t_start) − d(x)` the distance
//! the front centre has travelled past `x` (so the velocity and the strain are pulses of width
//! about `2 WIDTH`). At `t = 0` every front centre is [`LEAD`] outside the domain, so the
//! field starts (nearly) at rest. The wave fronts drive the mesher's local refinement: a slab
//! refines where some front centre passes within [`BAND`] plus the base cell size during the
//! slab ([`ScenarioModel`]'s [`TentProblem::near_front`]).

use std::fmt;
use std::str::FromStr;

use rayon::prelude::*;

use super::cubic::{CubicCoefficients, LocalFrame, Material};
use super::generate::project_element;
use super::mesh::SpacetimeMesh;
use super::tent::{count_tents, pitch_tents, tent_mesh, TentOptions, TentProblem, TentTet, Triangulation};

/// Displacement amplitude `A` of the main pulse (domains have unit size).
pub const AMPLITUDE: f64 = 0.01;
/// Smoothing width of every pulse's step.
pub const WIDTH: f64 = 0.03;
/// Distance of every front centre outside the domain at `t = 0` (`S(−LEAD) < 0.007`).
pub const LEAD: f64 = 2.5 * WIDTH;
/// Half width of the refined band around a front centre (beyond it `S` is within 0.7 % of 0
/// or 1).
pub const BAND: f64 = 2.5 * WIDTH;
/// Rounds of newest-vertex bisection near the fronts (two halve the edge lengths).
pub const REFINE_LEVELS: u32 = 2;
/// Slab duration in base cells crossed by the fastest wave.
pub const SLAB_CELLS: f64 = 4.0;
/// Largest element count [`Scenario::setup_for`] aims at (32-bit vertex indices).
pub const MAX_ELEMENTS: usize = 1_000_000_000;

/// A data set of seed 003 §5.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Scenario {
    /// Crack-tip scattering (seed 003 §5, Figures 4–6): the upper right quadrant of a plate
    /// under tensile shock loading, the crack along the left half of the bottom edge.
    Crack,
    /// A fibre composite (§5, Figures 7–8): stiff circular inclusions in a soft matrix.
    Inclusions,
    /// A sector of a solid rocket booster cross-section (§5, Figures 1, 9).
    Booster,
}

impl Scenario {
    /// Every scenario.
    pub const ALL: [Scenario; 3] = [Scenario::Crack, Scenario::Inclusions, Scenario::Booster];

    /// The command-line name: `crack`, `inclusions`, `booster`.
    pub fn name(self) -> &'static str {
        match self {
            Scenario::Crack => "crack",
            Scenario::Inclusions => "inclusions",
            Scenario::Booster => "booster",
        }
    }

    /// The analytic model at base resolution `resolution` (which sets the refinement margin).
    pub fn model(self, resolution: usize) -> ScenarioModel {
        let n = resolution.max(1) as f64;
        match self {
            Scenario::Crack => crack(1.0 / n),
            Scenario::Inclusions => inclusions(1.0 / n),
            Scenario::Booster => booster((BOOSTER.outer - BOOSTER.inner) / n),
        }
    }

    /// Base triangulation, model and mesher options at base resolution `resolution` (at least
    /// 1): `resolution²` squares for the plates, `resolution` radial cells for the booster.
    pub fn setup(self, resolution: usize) -> ScenarioSetup {
        let n = resolution.max(1);
        let model = self.model(n);
        let base = match self {
            Scenario::Crack | Scenario::Inclusions => Triangulation::rectangle([0.0; 2], [1.0; 2], n, n),
            Scenario::Booster => {
                let b = BOOSTER;
                let arc = 0.5 * (b.inner + b.outer) * 2.0 * b.half_angle;
                let na = ((n as f64 * arc / (b.outer - b.inner)).round() as usize).max(1);
                Triangulation::mapped(n, na, |[u, v]| {
                    let a = b.half_angle * (2.0 * v - 1.0);
                    let r = b.radius(a) + u * (b.outer - b.radius(a));
                    [r * a.cos(), r * a.sin()]
                })
            }
        }
        .expect("the scenario grids are valid for every resolution");
        let c_max = model.materials.iter().map(Material::p_wave_speed).fold(0.0, f64::max);
        let slabs = (model.duration * c_max / (SLAB_CELLS * model.margin)).ceil().max(1.0) as usize;
        let options = TentOptions::slabs(0.0, model.duration, slabs, REFINE_LEVELS);
        ScenarioSetup { model, base, options, resolution: n }
    }

    /// The set-up whose mesh has about `elements` tetrahedra (clamped to `[1, MAX_ELEMENTS]`).
    ///
    /// The count scales like (base triangles) × (lifts per vertex): about `n³` in the base
    /// resolution `n` (the refined bands add a lower order term, since their margin shrinks
    /// with the cells), and like `1/s` in the safety factor `s`. Every count below is exact,
    /// from a dry run ([`count_tents`]: no projection, about 2·10⁷ elements per second, a small
    /// fraction of the generation time):
    ///
    /// 1. from `n = 4`, `n ← round(n (target / count)^{1/3})` until within 3 % or repeating
    ///    (at most 8 runs);
    /// 2. the finest `n` whose count (at `s = ½`) does not exceed the target;
    /// 3. `s ← s · count / target` (only ever lowered from the default ½, so the front stays
    ///    space-like: see [`super::tent`]), up to three times, until within 3 %.
    ///
    /// Step 3 only adds elements, so the count ends within the 3 % of step 3 or above the
    /// target by less than one resolution step would add: measured 0.97–1.07 times the request
    /// for every scenario from 3·10³ to 5·10⁶ elements. Requests below the coarsest mesh
    /// (`n = 2`: 1.5·10³ to 2.4·10³ elements) get the coarsest mesh.
    pub fn setup_for(self, elements: usize) -> ScenarioSetup {
        const MIN_RESOLUTION: usize = 2;
        let target = elements.clamp(1, MAX_ELEMENTS) as f64;
        let count = |s: &ScenarioSetup| {
            count_tents(&s.base, &s.model, &s.options).map_or(f64::INFINITY, |c| c.elements as f64)
        };
        let mut counts: std::collections::BTreeMap<usize, f64> = std::collections::BTreeMap::new();
        let mut count_at = |n: usize| *counts.entry(n).or_insert_with(|| count(&self.setup(n)));
        // 1. The cube law.
        let mut n = 4;
        let mut tried = Vec::new();
        for _ in 0..8 {
            let ratio = count_at(n) / target;
            tried.push(n);
            if ratio.ln().abs() < 0.03 {
                break;
            }
            let next = ((n as f64 * ratio.powf(-1.0 / 3.0)).round() as usize).max(MIN_RESOLUTION);
            if tried.contains(&next) {
                break;
            }
            n = next;
        }
        // 2. The finest resolution not above the target.
        while n > MIN_RESOLUTION && count_at(n) > target {
            n -= 1;
        }
        while count_at(n + 1) <= target {
            n += 1;
        }
        // 3. More lifts per vertex.
        let mut setup = self.setup(n);
        let mut c = count_at(n);
        for _ in 0..3 {
            if c > 0.97 * target {
                break;
            }
            setup.options.safety *= c / target;
            c = count(&setup);
        }
        setup
    }
}

impl fmt::Display for Scenario {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Scenario {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Scenario::ALL
            .into_iter()
            .find(|x| x.name() == s)
            .ok_or_else(|| format!("unknown scenario {s:?} (available: crack, inclusions, booster)"))
    }
}

/// A scenario ready to mesh: the base triangulation, the model and the mesher's options.
#[derive(Clone, Debug)]
pub struct ScenarioSetup {
    /// The analytic field, materials and refinement marker.
    pub model: ScenarioModel,
    /// The base triangulation of the domain.
    pub base: Triangulation,
    /// Slabs (equal, each [`SLAB_CELLS`] base cells for the fastest wave), refinement levels
    /// and safety factor.
    pub options: TentOptions,
    /// The base resolution ([`Scenario::setup`]).
    pub resolution: usize,
}

/// How far a front has to travel to reach a point.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Path {
    /// A plane front: `d(x) = dir · x − offset`.
    Plane { dir: [f64; 2], offset: f64 },
    /// A cylindrical front from `centre`: `d(x) = √(r² + r0²) − r0` (regularised at the centre).
    Ring { centre: [f64; 2], r0: f64 },
    /// Outward from the booster's bore along rays: `d(x) = r − r_b(θ)`.
    Outward,
    /// Back from the booster's case: `d(x) = (R − r_b(θ)) + (R − r)`.
    Inward,
}

/// The direction of the displacement.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Polarization {
    /// A fixed unit vector.
    Fixed([f64; 2]),
    /// Away from the path's centre (longitudinal for a cylindrical P wave).
    Radial,
    /// Radial turned by +90° (transverse for a cylindrical S wave).
    Tangential,
}

/// A factor of the amplitude over space.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Modulation {
    /// 1.
    Uniform,
    /// `−tanh((x − split) / WIDTH)`: +1 left of `split`, −1 right of it.
    Split(f64),
    /// `sin(lobes θ)`: the slope of the booster's star bore.
    Lobes,
}

/// One travelling pulse: `u = A m(x) a(x) S(c (t − start) − d(x)) p(x)`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Wave {
    path: Path,
    start: f64,
    speed: f64,
    amplitude: f64,
    polarization: Polarization,
    modulation: Modulation,
}

/// The booster's geometry: a star-shaped bore `r_b(θ) = inner (1 + depth cos(lobes θ))`
/// inside a case of radius `outer`, the sector `|θ| ≤ half_angle`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Bore {
    inner: f64,
    outer: f64,
    depth: f64,
    lobes: f64,
    half_angle: f64,
}

impl Bore {
    fn radius(&self, angle: f64) -> f64 {
        self.inner * (1.0 + self.depth * (self.lobes * angle).cos())
    }
}

/// The booster sector: a 60° sector with one lobe of a six-pointed star bore.
const BOOSTER: Bore =
    Bore { inner: 0.4, outer: 1.0, depth: 0.12, lobes: 6.0, half_angle: std::f64::consts::FRAC_PI_6 };

/// A circular inclusion of the composite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inclusion {
    /// Centre (x, y).
    pub centre: [f64; 2],
    /// Radius.
    pub radius: f64,
    /// Index of its material.
    pub material: u32,
}

impl Inclusion {
    /// Whether the triangle meets the disc (distance from the centre to the triangle at most
    /// the radius).
    fn meets(&self, t: &[[f64; 2]; 3]) -> bool {
        let c = self.centre;
        let side = |a: [f64; 2], b: [f64; 2]| (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        if (0..3).all(|k| side(t[k], t[(k + 1) % 3]) >= 0.0) {
            return true;
        }
        (0..3).any(|k| {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let s = (((c[0] - a[0]) * dx + (c[1] - a[1]) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
            (a[0] + s * dx - c[0]).hypot(a[1] + s * dy - c[1]) <= self.radius
        })
    }
}

/// Polar coordinates of a point about the booster's axis, and the bore radius at its angle.
#[derive(Clone, Copy, Debug)]
struct Polar {
    r: f64,
    angle: f64,
    radial: [f64; 2],
    bore: f64,
}

/// What the pulses at one point share: the polar coordinates and the last ring's geometry (a P
/// and an S pulse from the same centre follow each other).
#[derive(Default)]
struct PointCache {
    polar: Option<Polar>,
    ring: Option<([f64; 2], f64, RingGeometry)>,
}

/// A ring's distance travelled, amplitude decay and radial direction at a point.
type RingGeometry = (f64, f64, [f64; 2]);

/// A scenario's analytic field, materials, inclusions and refinement marker; the
/// [`TentProblem`] the mesher works on.
#[derive(Clone, Debug)]
pub struct ScenarioModel {
    scenario: Scenario,
    waves: Vec<Wave>,
    materials: Vec<Material>,
    inclusions: Vec<Inclusion>,
    duration: f64,
    margin: f64,
}

impl ScenarioModel {
    /// The scenario.
    pub fn scenario(&self) -> Scenario {
        self.scenario
    }

    /// The time span `[0, duration]`.
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// The materials (index 0 is the matrix or the only material).
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// The inclusions (composite only).
    pub fn inclusions(&self) -> &[Inclusion] {
        &self.inclusions
    }

    /// Distance travelled to `x`, amplitude factor, and polarisation of a wave.
    fn geometry(&self, w: &Wave, x: [f64; 2], cache: &mut PointCache) -> (f64, f64, [f64; 2]) {
        let mut polar = || {
            *cache.polar.get_or_insert_with(|| {
                let r = x[0].hypot(x[1]).max(1e-300);
                let angle = x[1].atan2(x[0]);
                Polar { r, angle, radial: [x[0] / r, x[1] / r], bore: BOOSTER.radius(angle) }
            })
        };
        let (d, decay, radial) = match w.path {
            Path::Plane { dir, offset } => (dir[0] * x[0] + dir[1] * x[1] - offset, 1.0, [0.0, 0.0]),
            Path::Ring { centre, r0 } => match cache.ring {
                Some((c, r, g)) if c == centre && r == r0 => g,
                _ => {
                    let (dx, dy) = (x[0] - centre[0], x[1] - centre[1]);
                    let rho = (dx * dx + dy * dy + r0 * r0).sqrt();
                    let g = (rho - r0, (r0 / rho).sqrt(), [dx / rho, dy / rho]);
                    cache.ring = Some((centre, r0, g));
                    g
                }
            },
            Path::Outward => {
                let p = polar();
                (p.r - p.bore, (BOOSTER.inner / p.r).sqrt(), p.radial)
            }
            Path::Inward => {
                let p = polar();
                (2.0 * BOOSTER.outer - p.bore - p.r, (BOOSTER.inner / p.r).sqrt(), p.radial)
            }
        };
        let m = match w.modulation {
            Modulation::Uniform => 1.0,
            Modulation::Split(s) => -((x[0] - s) / WIDTH).tanh(),
            Modulation::Lobes => (BOOSTER.lobes * polar().angle).sin(),
        };
        let p = match w.polarization {
            Polarization::Fixed(p) => p,
            Polarization::Radial => radial,
            Polarization::Tangential => [-radial[1], radial[0]],
        };
        (d, m * decay, p)
    }

    /// The analytic displacement at `(x, y, t)`: the sum of the scenario's pulses. A pulse
    /// whose step is below `e^{−36}` (its front centre more than 18 widths away, ahead) is
    /// skipped: an error below `3·10⁻¹⁶ A` per pulse.
    pub fn displacement(&self, p: [f64; 3]) -> [f64; 2] {
        const CUTOFF: f64 = 18.0 * WIDTH;
        let x = [p[0], p[1]];
        let mut cache = PointCache::default();
        let mut u = [0.0; 2];
        for w in &self.waves {
            let run = w.speed * (p[2] - w.start);
            // A ring's distance is non-negative: nothing of it has arrived anywhere yet.
            if matches!(w.path, Path::Ring { .. }) && run < -CUTOFF {
                continue;
            }
            let (d, a, pol) = self.geometry(w, x, &mut cache);
            let xi = run - d;
            if xi < -CUTOFF {
                continue;
            }
            // S(ξ) = ½ (1 + tanh(ξ / WIDTH)) = 1 / (1 + e^{−2ξ/WIDTH}).
            let s = w.amplitude * a / (1.0 + (-2.0 * xi / WIDTH).exp());
            u[0] += s * pol[0];
            u[1] += s * pol[1];
        }
        u
    }

    /// The times at which the front centres of the pulses pass `x`, with their speeds.
    pub fn arrivals(&self, x: [f64; 2]) -> Vec<(f64, f64)> {
        let mut cache = PointCache::default();
        self.waves.iter().map(|w| (w.start + self.geometry(w, x, &mut cache).0 / w.speed, w.speed)).collect()
    }
}

impl TentProblem for ScenarioModel {
    /// The largest P-wave speed of the materials on the triangle (for the composite: of the
    /// matrix and of every inclusion the triangle meets).
    fn wave_speed(&self, triangle: &[[f64; 2]; 3]) -> f64 {
        let matrix = self.materials[0].p_wave_speed();
        self.inclusions
            .iter()
            .filter(|i| i.meets(triangle))
            .map(|i| self.materials[i.material as usize].p_wave_speed())
            .fold(matrix, f64::max)
    }

    /// Whether a front centre passes within `BAND` plus the base cell size of `point` during
    /// the slab.
    fn near_front(&self, slab_start: f64, slab_end: f64, point: [f64; 2]) -> bool {
        let mut cache = PointCache::default();
        self.waves.iter().any(|w| {
            let arrival = w.start + self.geometry(w, point, &mut cache).0 / w.speed;
            let half = (BAND + self.margin) / w.speed;
            arrival - half <= slab_end && arrival + half >= slab_start
        })
    }

    /// The inclusion containing the centroid's (x, y), else the matrix (0).
    fn material(&self, centroid: [f64; 3]) -> u32 {
        self.inclusions
            .iter()
            .find(|i| (centroid[0] - i.centre[0]).hypot(centroid[1] - i.centre[1]) < i.radius)
            .map_or(0, |i| i.material)
    }
}

/// A plane pulse along `dir` with `d(x) = dir · x − offset`, starting [`LEAD`] outside.
fn plane(
    dir: [f64; 2],
    offset: f64,
    speed: f64,
    amplitude: f64,
    polarization: [f64; 2],
    m: Modulation,
) -> Wave {
    Wave {
        path: Path::Plane { dir, offset },
        start: LEAD / speed,
        speed,
        amplitude,
        polarization: Polarization::Fixed(polarization),
        modulation: m,
    }
}

/// A cylindrical pulse from `centre`, its front centre there at time `start`.
fn ring(
    centre: [f64; 2],
    r0: f64,
    start: f64,
    speed: f64,
    amplitude: f64,
    polarization: Polarization,
) -> Wave {
    Wave {
        path: Path::Ring { centre, r0 },
        start,
        speed,
        amplitude,
        polarization,
        modulation: Modulation::Uniform,
    }
}

/// Crack-tip scattering in the unit square, the upper right quadrant of a plate (seed 003
/// §5): a tensile shock applied to the top edge (`y = 1`) runs down as a plane P wave
/// (`u_y = A S`, upward: tension). The bottom edge `y = 0` is the crack face for `x < ½`
/// (traction free: the reflection has the same displacement, `u_y` doubles, the stress
/// cancels) and the symmetry plane of the uncracked ligament for `x > ½` (`u_y = 0`: the
/// reflection has the opposite displacement and the stress doubles). The two halves of the
/// reflected plane wave are joined smoothly over `WIDTH` at the tip `(½, 0)`, and the tip
/// scatters a cylindrical P wave and a slower S wave (amplitudes `A/2` and `0.35 A`, decaying
/// like `1/√r`) that start when the incident front reaches it. The reflected wave reflects
/// again at the loaded top edge, whose traction is prescribed, like a free surface (same
/// displacement). Reflections of the scattered waves and at the side edges are left out. One
/// material (λ = 2, μ = 1, ρ = 1: `c_p = 2`, `c_s = 1`); time span `[0, 1.25]`: the plane wave
/// goes down, back up and a quarter down again.
fn crack(margin: f64) -> ScenarioModel {
    let m = Material { lambda: 2.0, mu: 1.0, density: 1.0 };
    let (cp, cs) = (m.p_wave_speed(), m.s_wave_speed());
    let a = AMPLITUDE;
    let up = [0.0, 1.0];
    let tip = [0.5, 0.0];
    let t_tip = (LEAD + 1.0) / cp;
    ScenarioModel {
        scenario: Scenario::Crack,
        waves: vec![
            plane([0.0, -1.0], -1.0, cp, a, up, Modulation::Uniform),
            plane([0.0, 1.0], -1.0, cp, a, up, Modulation::Split(tip[0])),
            plane([0.0, -1.0], -3.0, cp, a, up, Modulation::Split(tip[0])),
            ring(tip, WIDTH, t_tip, cp, 0.5 * a, Polarization::Radial),
            ring(tip, WIDTH, t_tip, cs, 0.35 * a, Polarization::Tangential),
        ],
        materials: vec![m],
        inclusions: Vec::new(),
        duration: 1.25,
        margin,
    }
}

/// A fibre composite in the unit square (seed 003 §5, a representative volume element): a
/// soft matrix (λ = 2, μ = 1, ρ = 1: `c_p = 2`) with four fibres (λ = 8, μ = 4: `c_p = 4`)
/// and a stiffer central one (λ = 12, μ = 6: `c_p ≈ 4.9`); an element belongs to a fibre when
/// its centroid lies in the circle (three materials). A compressive plane P shock enters
/// from the top edge (`u_y = −A S`) and reflects from the free bottom edge (same
/// displacement). When its front passes an inclusion's centre, the inclusion scatters a
/// cylindrical P and S wave (amplitudes `A κ` and `0.6 A κ`, `κ = (c_f − c_m)/(c_f + c_m)`,
/// decaying like `1/√r` beyond the fibre radius). Waves inside the fibres travel at the
/// matrix speed in this approximation. Time span `[0, 0.8]`.
fn inclusions(margin: f64) -> ScenarioModel {
    let matrix = Material { lambda: 2.0, mu: 1.0, density: 1.0 };
    let fibre = Material { lambda: 8.0, mu: 4.0, density: 1.0 };
    let core = Material { lambda: 12.0, mu: 6.0, density: 1.0 };
    let materials = vec![matrix, fibre, core];
    let inclusions = vec![
        Inclusion { centre: [0.5, 0.5], radius: 0.13, material: 2 },
        Inclusion { centre: [0.2, 0.28], radius: 0.08, material: 1 },
        Inclusion { centre: [0.78, 0.22], radius: 0.09, material: 1 },
        Inclusion { centre: [0.24, 0.76], radius: 0.09, material: 1 },
        Inclusion { centre: [0.8, 0.74], radius: 0.08, material: 1 },
    ];
    let (cp, cs) = (matrix.p_wave_speed(), matrix.s_wave_speed());
    let a = AMPLITUDE;
    let down = [0.0, -1.0];
    let mut waves = vec![
        plane([0.0, -1.0], -1.0, cp, a, down, Modulation::Uniform),
        plane([0.0, 1.0], -1.0, cp, a, down, Modulation::Uniform),
    ];
    for i in &inclusions {
        let cf = materials[i.material as usize].p_wave_speed();
        let kappa = (cf - cp) / (cf + cp);
        let start = (LEAD + 1.0 - i.centre[1]) / cp;
        waves.push(ring(i.centre, i.radius, start, cp, a * kappa, Polarization::Radial));
        waves.push(ring(i.centre, i.radius, start, cs, 0.6 * a * kappa, Polarization::Tangential));
    }
    ScenarioModel { scenario: Scenario::Inclusions, waves, materials, inclusions, duration: 0.8, margin }
}

/// A 60° sector of a solid rocket booster cross-section (seed 003 §5, Figure 9): propellant
/// (λ = 4, μ = 1, ρ = 1: `c_p = √6`, `c_s = 1`) between a six-pointed star bore `r_b(θ) = 0.4
/// (1 + 0.12 cos 6θ)` on the left (towards the rocket's axis, where combustion has begun) and
/// the case at `r = 1`. A compressive pressure shock leaves the bore radially (`u = A √(0.4/r)
/// S e_r`, its front at distance `r − r_b(θ)` from the bore along each ray: an approximation
/// of the front of a non-circular source) and reflects at the case, taken as rigid (opposite
/// displacement, so `u = 0` at `r = 1`). The bore's slopes also launch a slower shear pulse
/// (`0.5 A sin(6θ)`, tangential). The sector's straight sides are symmetry lines, which radial
/// waves satisfy. Time span: the P front crosses the propellant and comes back 60 % of the way.
fn booster(margin: f64) -> ScenarioModel {
    let m = Material { lambda: 4.0, mu: 1.0, density: 1.0 };
    let (cp, cs) = (m.p_wave_speed(), m.s_wave_speed());
    let a = AMPLITUDE;
    let wave = |path, speed: f64, amplitude, polarization, modulation| Wave {
        path,
        start: LEAD / speed,
        speed,
        amplitude,
        polarization,
        modulation,
    };
    ScenarioModel {
        scenario: Scenario::Booster,
        waves: vec![
            wave(Path::Outward, cp, a, Polarization::Radial, Modulation::Uniform),
            wave(Path::Inward, cp, -a, Polarization::Radial, Modulation::Uniform),
            wave(Path::Outward, cs, 0.5 * a, Polarization::Tangential, Modulation::Lobes),
        ],
        materials: vec![m],
        inclusions: Vec::new(),
        duration: (LEAD + 1.6 * (BOOSTER.outer - BOOSTER.inner)) / cp,
        margin,
    }
}

/// The materials of a scenario (index 0 is the matrix or the only material).
pub fn materials(scenario: Scenario) -> Vec<Material> {
    scenario.model(1).materials
}

/// The scenario's data set with about `elements` tetrahedra ([`Scenario::setup_for`]):
/// tent-pitched, sorted by lowest time, every element the L2 projection of the analytic field.
/// The whole mesh is held in memory (about 400 bytes per element); see [`generate_streaming`]
/// for large counts.
pub fn generate(scenario: Scenario, elements: usize) -> SpacetimeMesh {
    let s = scenario.setup_for(elements);
    let field = |p: [f64; 3]| s.model.displacement(p);
    tent_mesh(&s.base, &s.model, &s.options, s.model.materials.clone(), &field)
        .expect("the scenario set-ups are valid by construction")
}

/// One element of a streamed data set.
#[derive(Clone, Debug, PartialEq)]
pub struct GeneratedElement {
    /// Corners (x, y, t), in the mesher's order `(a, b, v_old, v_new)`.
    pub corners: [[f64; 3]; 4],
    /// The local frame of its polynomial (the corners' bounding box).
    pub frame: LocalFrame,
    /// Index into [`materials`].
    pub material: u32,
    /// The displacement's 20 coefficient 2-vectors.
    pub coefficients: CubicCoefficients,
}

/// What [`generate_streaming`] produced.
#[derive(Clone, Debug, PartialEq)]
pub struct GenerationSummary {
    /// Elements handed to the sink.
    pub elements: usize,
    /// Distinct vertices of the mesh (shared within a slab).
    pub vertices: usize,
    /// Base resolution chosen.
    pub resolution: usize,
    /// Safety factor chosen (at most [`super::tent::DEFAULT_SAFETY`]).
    pub safety: f64,
    /// Number of slabs.
    pub slabs: usize,
    /// Time span `[0, duration]`.
    pub duration: f64,
    /// Area of the (polygonal) domain.
    pub area: f64,
}

/// Elements projected per parallel batch by [`generate_streaming`].
const CHUNK: usize = 16_384;

/// The data set of [`generate`] without holding it: every element, with corners, frame,
/// material and coefficients, is handed to `sink` in order of non-decreasing lowest time (so a
/// writer can stream it to disk in the order the renderer wants). Memory stays bounded: the
/// mesher holds one slab's front and triangulation, and elements are projected in parallel
/// batches of 16384 before being handed on in order.
pub fn generate_streaming(
    scenario: Scenario,
    elements: usize,
    sink: &mut dyn FnMut(&GeneratedElement),
) -> GenerationSummary {
    let s = scenario.setup_for(elements);
    let field = |p: [f64; 3]| s.model.displacement(p);
    let flush = |batch: &mut Vec<TentTet>, sink: &mut dyn FnMut(&GeneratedElement)| {
        let records: Vec<GeneratedElement> = batch
            .par_iter()
            .with_min_len(64)
            .map(|t| {
                let (frame, coefficients) = project_element(t.corners, &field);
                GeneratedElement { corners: t.corners, frame, material: t.material, coefficients }
            })
            .collect();
        for r in &records {
            sink(r);
        }
        batch.clear();
    };
    let mut batch = Vec::with_capacity(CHUNK);
    let stats = pitch_tents(&s.base, &s.model, &s.options, &mut |t| {
        batch.push(*t);
        if batch.len() == CHUNK {
            flush(&mut batch, sink);
        }
    })
    .expect("the scenario set-ups are valid by construction");
    flush(&mut batch, sink);
    GenerationSummary {
        elements: stats.elements,
        vertices: stats.vertices,
        resolution: s.resolution,
        safety: s.options.safety,
        slabs: s.options.slab_times.len() - 1,
        duration: s.model.duration,
        area: s.base.area(),
    }
}
