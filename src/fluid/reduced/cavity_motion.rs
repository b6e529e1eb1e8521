//! The cavity driven at run time (seed 000 §7.2 and its video: "not all deformations seen in
//! the video are part of the original training set"): the reduced geometry ĝ as a function
//! of the three compressions, for any combination — one cavity compressed while another
//! re-inflates, amounts never trained.
//!
//! **Why exact, not learned.** The cavity's map ([`crate::fluid::cavity`]) is linear in its
//! amounts: `g(a, λ) = g₀ + a₁D₁ + a₂D₂ + a₃D₃ + (λ − 1)D₀`, with λ the central inflation that
//! keeps the enclosed volume. So with `E = [g₀ D₁ D₂ D₃ D₀]` and `c = [1, a₁, a₂, a₃, λ − 1]`,
//! the reduced geometry is `ĝ = B_gᵀ E c`, a fixed m_g × 5 matrix times c — the projection of
//! the full deformation of the same parameters, exactly (and when the training runs move
//! every cavity and the centre, `B_g` spans E and nothing is lost: m_g = 5, Table 1's size).
//! The enclosed volume is a cubic form in the geometry, so in c it is a 5 × 5 × 5 symmetric
//! tensor T (polarized from the mesh's own [`enclosed_volume`] on E's columns), and λ solves
//! the scalar cubic `T(c, c, c) = V_rest` by Newton's method. Blending training frames (the
//! radiosity model's Eq. 17) would only interpolate the trained motions and need the volume
//! restored afterwards; a map learned by regression would recover this same linear map
//! without λ. Both cost more and are exact nowhere this is not.

use crate::fluid::cavity::Cavity;
use crate::fluid::FluidError;
use crate::mesh::volume::enclosed_volume;
use crate::reduce::Basis;
use crate::tensor::Tensor;

/// Newton steps on the volume cubic before bisection takes over.
const NEWTON_STEPS: usize = 30;

/// The cavity's reduced geometry as a function of its compressions (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct CavityMotion {
    /// `B_gᵀ E`: m_g × 5.
    pub map: Tensor,
    /// The enclosed volume as a symmetric cubic form in `c = [1, a₁, a₂, a₃, λ − 1]` (5 × 5 × 5).
    pub volume: Tensor,
    /// The rest volume the central inflation keeps.
    pub rest_volume: f64,
}

impl CavityMotion {
    /// The motion model of `cavity` with the geometry basis `b_g`.
    pub fn new(cavity: &Cavity, b_g: &Basis) -> Self {
        let fields = cavity.motion_fields();
        let m = b_g.reduced_dim();
        let mut map = vec![0.0; m * 5];
        for (p, field) in fields.iter().enumerate() {
            for (j, x) in b_g.project(field).into_iter().enumerate() {
                map[j * 5 + p] = x;
            }
        }
        // Polarization of the cubic V(E c): T(e_p, e_q, e_r) = (1/48) Σ_ε ε₁ε₂ε₃ V(E(ε₁e_p + ε₂e_q + ε₃e_r)).
        let volume_at = |c: [f64; 5]| {
            let g: Vec<f64> =
                (0..fields[0].len()).map(|i| (0..5).map(|p| c[p] * fields[p][i]).sum()).collect();
            enclosed_volume(&cavity.mesh, &cavity.topology, &g)
        };
        let mut t = vec![0.0; 125];
        for p in 0..5 {
            for q in p..5 {
                for r in q..5 {
                    let mut sum = 0.0;
                    for signs in 0..8 {
                        let e = |bit: usize| if signs >> bit & 1 == 1 { -1.0 } else { 1.0 };
                        let mut c = [0.0; 5];
                        c[p] += e(0);
                        c[q] += e(1);
                        c[r] += e(2);
                        sum += e(0) * e(1) * e(2) * volume_at(c);
                    }
                    let value = sum / 48.0;
                    for (i, j, k) in [(p, q, r), (p, r, q), (q, p, r), (q, r, p), (r, p, q), (r, q, p)] {
                        t[(i * 5 + j) * 5 + k] = value;
                    }
                }
            }
        }
        Self {
            map: Tensor::from_vec(&[m, 5], map).expect("m_g × 5"),
            volume: Tensor::from_vec(&[5, 5, 5], t).expect("5 × 5 × 5"),
            rest_volume: cavity.rest_volume(),
        }
    }

    /// The enclosed volume at `c` and its derivative in λ.
    fn volume_and_slope(&self, c: &[f64; 5]) -> (f64, f64) {
        let t = self.volume.data();
        let (mut v, mut slope) = (0.0, 0.0);
        for p in 0..5 {
            for q in 0..5 {
                let cpq = c[p] * c[q];
                for r in 0..5 {
                    v += t[(p * 5 + q) * 5 + r] * cpq * c[r];
                }
                slope += 3.0 * t[(4 * 5 + p) * 5 + q] * cpq;
            }
        }
        (v, slope)
    }

    /// The central inflation λ that keeps the rest volume under compressions `a` (each in
    /// [0, 1): a cavity cannot shrink to its centre): Newton's method on the cubic, bisection
    /// in λ ∈ [0.5, 2] if it does not converge, to 1e-13 of the rest volume.
    pub fn inflation(&self, a: [f64; 3]) -> Result<f64, FluidError> {
        if let Some((i, x)) = a.iter().enumerate().find(|(_, x)| !(x.is_finite() && (0.0..1.0).contains(*x)))
        {
            return Err(FluidError::State(format!("cavity {i}: compression {x} outside [0, 1)")));
        }
        let target = self.rest_volume;
        let at = |lambda: f64| [1.0, a[0], a[1], a[2], lambda - 1.0];
        let mut lambda = 1.0;
        for _ in 0..NEWTON_STEPS {
            let (v, slope) = self.volume_and_slope(&at(lambda));
            if (v - target).abs() <= 1e-13 * target {
                return Ok(lambda);
            }
            if slope <= 0.0 {
                break;
            }
            lambda -= (v - target) / slope;
        }
        let (mut lo, mut hi) = (0.5, 2.0);
        let residual = |l: f64| self.volume_and_slope(&at(l)).0 - target;
        if residual(lo) > 0.0 || residual(hi) < 0.0 {
            return Err(FluidError::State(format!(
                "compressions {a:?}: no central inflation in [0.5, 2] restores the volume"
            )));
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if residual(mid) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Ok(0.5 * (lo + hi))
    }

    /// The reduced geometry ĝ for compressions `a`, the volume kept.
    pub fn geometry(&self, a: [f64; 3]) -> Result<Vec<f64>, FluidError> {
        let lambda = self.inflation(a)?;
        let c = [1.0, a[0], a[1], a[2], lambda - 1.0];
        Ok(self.map.data().chunks(5).map(|row| row.iter().zip(&c).map(|(m, x)| m * x).sum()).collect())
    }
}

impl CavityMotion {
    /// The compressions whose reduced geometry is `g`: the inverse of [`Self::geometry`], by
    /// least squares in `ĝ = M c` with `c₀ = 1` (the normal equations of M's last four
    /// columns). `None` where the geometry basis does not resolve the four motions (m_g < 5,
    /// or a training that never moved a cavity) or `g` has another length.
    pub fn compressions_of(&self, g: &[f64]) -> Option<[f64; 3]> {
        let m = self.map.shape()[0];
        if g.len() != m || m < 5 {
            return None;
        }
        let rows: Vec<&[f64]> = self.map.data().chunks(5).collect();
        let mut normal = vec![0.0; 16];
        let mut rhs = vec![0.0; 4];
        for (row, gj) in rows.iter().zip(g) {
            for p in 0..4 {
                rhs[p] += row[p + 1] * (gj - row[0]);
                for q in 0..4 {
                    normal[p * 4 + q] += row[p + 1] * row[q + 1];
                }
            }
        }
        let scale = (0..4).map(|p| normal[p * 5]).fold(0.0f64, f64::max);
        let normal = Tensor::from_vec(&[4, 4], normal).ok()?;
        let (values, _) = crate::tensor::symmetric_eigen("cavity motion", &normal).ok()?;
        let smallest = values.iter().copied().fold(f64::INFINITY, f64::min);
        if smallest.is_nan() || smallest <= 1e-10 * scale {
            return None;
        }
        let c = crate::tensor::solve("cavity motion", &normal, &rhs).ok()?;
        Some([c[0], c[1], c[2]])
    }

    /// The largest compression of each cavity over the reduced geometries `frames` (e.g. every
    /// frame of a model's training trajectories): what the model was trained on. `None` where
    /// [`Self::compressions_of`] cannot tell.
    pub fn trained_compressions<'a>(&self, frames: impl IntoIterator<Item = &'a [f64]>) -> Option<[f64; 3]> {
        let mut top = [0.0f64; 3];
        for g in frames {
            let a = self.compressions_of(g)?;
            for i in 0..3 {
                top[i] = top[i].max(a[i]);
            }
        }
        Some(top)
    }
}

/// A warning when compressions `a` go beyond the trained ones (by more than 1e-6): the bases
/// hold no snapshot of that geometry, so the reduced flow extrapolates (the geometry itself
/// stays exact, [`CavityMotion`]).
pub fn beyond_training(trained: [f64; 3], a: [f64; 3]) -> Option<String> {
    let over: Vec<String> = (0..3)
        .filter(|&i| a[i] > trained[i] + 1e-6)
        .map(|i| format!("cavity {} at {:.3} (trained up to {:.3})", i + 1, a[i], trained[i]))
        .collect();
    (!over.is_empty()).then(|| {
        format!("compressions beyond the training: {}; the reduced flow extrapolates there", over.join(", "))
    })
}

/// The cavity's compressions over time: keyframes `(frame, [a₁, a₂, a₃])`, linearly
/// interpolated between them and held after the last. Written `FRAME=A1/A2/A3,…`, e.g.
/// `0=0/0/0,30=0.5/0/0,60=0.5/0/0.4,90=0/0/0.4` (cavity 1 compresses, then cavity 3 while 1
/// stays compressed, then 1 re-inflates while 3 stays: a motion no training run makes).
#[derive(Clone, Debug, PartialEq)]
pub struct CompressionSchedule {
    keys: Vec<(usize, [f64; 3])>,
}

/// Most keyframes a schedule may have.
pub const MAX_KEYFRAMES: usize = 10_000;

impl CompressionSchedule {
    /// A schedule from keyframes (frames strictly increasing, amounts in [0, 1)).
    pub fn new(keys: Vec<(usize, [f64; 3])>) -> Result<Self, String> {
        if keys.is_empty() || keys.len() > MAX_KEYFRAMES {
            return Err(format!("{} keyframes: give 1 to {MAX_KEYFRAMES}", keys.len()));
        }
        for (k, (frame, a)) in keys.iter().enumerate() {
            if k > 0 && *frame <= keys[k - 1].0 {
                return Err(format!(
                    "keyframe {k}: frame {frame} does not come after frame {}",
                    keys[k - 1].0
                ));
            }
            if let Some(x) = a.iter().find(|x| !(x.is_finite() && (0.0..1.0).contains(*x))) {
                return Err(format!("keyframe {k} (frame {frame}): compression {x} outside [0, 1)"));
            }
        }
        Ok(Self { keys })
    }

    /// The compressions at `frame`.
    pub fn at(&self, frame: usize) -> [f64; 3] {
        let k = self.keys.partition_point(|(f, _)| *f <= frame);
        if k == 0 {
            return self.keys[0].1;
        }
        let (f0, a0) = self.keys[k - 1];
        match self.keys.get(k) {
            None => a0,
            Some(&(f1, a1)) => {
                let t = (frame - f0) as f64 / (f1 - f0) as f64;
                std::array::from_fn(|i| a0[i] + t * (a1[i] - a0[i]))
            }
        }
    }

    /// The last keyframe's frame.
    pub fn last_frame(&self) -> usize {
        self.keys.last().map_or(0, |k| k.0)
    }

    /// Each cavity's largest compression over the schedule (a keyframe's: linear between).
    pub fn largest(&self) -> [f64; 3] {
        let mut top = [0.0f64; 3];
        for (_, a) in &self.keys {
            for i in 0..3 {
                top[i] = top[i].max(a[i]);
            }
        }
        top
    }
}

impl std::str::FromStr for CompressionSchedule {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let mut keys = Vec::new();
        for (k, part) in s.split(',').enumerate() {
            if k >= MAX_KEYFRAMES {
                return Err(format!("more than {MAX_KEYFRAMES} keyframes"));
            }
            let (frame, amounts) = part
                .split_once('=')
                .ok_or_else(|| format!("keyframe {k} `{part}`: expected FRAME=A1/A2/A3"))?;
            let frame: usize =
                frame.trim().parse().map_err(|e| format!("keyframe {k} `{part}`: frame: {e}"))?;
            let a: Vec<f64> = amounts
                .split('/')
                .map(|x| x.trim().parse::<f64>().map_err(|e| format!("keyframe {k} `{part}`: {e}")))
                .collect::<Result<_, _>>()?;
            let a: [f64; 3] = a
                .try_into()
                .map_err(|_| format!("keyframe {k} `{part}`: three compressions, one per cavity"))?;
            keys.push((frame, a));
        }
        Self::new(keys)
    }
}
