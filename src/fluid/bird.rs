//! The flying bird of seed 000 §7.2 (the paper's eagle: "266 frames of a triangle mesh
//! animation of a flying eagle flapping its wings and soaring left and right"), generated:
//! a body and two wings, each a closed triangulated ellipsoid, flapping about shoulder hinges
//! and banking and turning as a whole. No eagle model ships with this engine; this
//! procedural one has the same structure (closed parts moving rigidly, a base pose with the
//! wings fully extended) and can be written as an OBJ sequence
//! ([`SurfaceAnimation::write_sequence`]) for other tools.
//!
//! At frame k of n (s = k / n) the wings are at flap angle θ = A sin(2π · flaps · s) about
//! hinges parallel to the body axis (x) through (0, ±hinge, 0), the left wing (y > 0)
//! rotating by +θ and the right by −θ so both rise together; the whole bird then rolls by
//! φ = B sin(2π s) about x and turns by ψ = C sin(2π s) about z (soaring left, then right).
//! Frame 0 is the base pose: wings level, no bank.

use crate::mesh::animation::SurfaceAnimation;

/// The bird's shape and motion.
#[derive(Clone, Debug, PartialEq)]
pub struct BirdSpec {
    /// Wingtip to wingtip at rest.
    pub span: f64,
    /// Body length (along x, the flight direction; the head at +x).
    pub body_length: f64,
    /// Wing chord (front to back, at the widest).
    pub chord: f64,
    /// Wing thickness (top to bottom, at the thickest).
    pub thickness: f64,
    /// Flap amplitude A in degrees.
    pub flap_degrees: f64,
    /// Wingbeats over the animation.
    pub flaps: f64,
    /// Bank (roll) amplitude B in degrees.
    pub bank_degrees: f64,
    /// Turn (yaw) amplitude C in degrees.
    pub turn_degrees: f64,
    /// Frames of the animation (the paper: 266).
    pub frames: usize,
    /// Tessellation: rings per ellipsoid (twice as many segments around).
    pub rings: usize,
}

impl Default for BirdSpec {
    fn default() -> Self {
        Self {
            span: 2.4,
            body_length: 1.2,
            chord: 0.55,
            thickness: 0.2,
            flap_degrees: 25.0,
            flaps: 4.0,
            bank_degrees: 12.0,
            turn_degrees: 8.0,
            frames: 266,
            rings: 12,
        }
    }
}

/// An ellipsoid's triangulation: `rings` rings of latitude about the polar axis `axis`,
/// `2·rings` segments around; vertices first (two poles, then the rings), then triangles.
fn ellipsoid(
    centre: [f64; 3],
    semi: [f64; 3],
    axis: usize,
    rings: usize,
    offset: u32,
) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let segments = 2 * rings;
    let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
    let point = |polar: f64, around: f64| {
        let mut unit = [0.0; 3];
        unit[axis] = polar.cos();
        unit[a1] = polar.sin() * around.cos();
        unit[a2] = polar.sin() * around.sin();
        std::array::from_fn(|k| centre[k] + semi[k] * unit[k])
    };
    let pi = std::f64::consts::PI;
    let mut vertices = vec![point(0.0, 0.0), point(pi, 0.0)];
    for r in 1..rings {
        for s in 0..segments {
            vertices.push(point(pi * r as f64 / rings as f64, 2.0 * pi * s as f64 / segments as f64));
        }
    }
    let ring = |r: usize, s: usize| offset + 2 + ((r - 1) * segments + s % segments) as u32;
    let mut triangles = Vec::new();
    for s in 0..segments {
        triangles.push([offset, ring(1, s), ring(1, s + 1)]);
        triangles.push([offset + 1, ring(rings - 1, s + 1), ring(rings - 1, s)]);
        for r in 1..rings - 1 {
            triangles.push([ring(r, s), ring(r + 1, s), ring(r + 1, s + 1)]);
            triangles.push([ring(r, s), ring(r + 1, s + 1), ring(r, s + 1)]);
        }
    }
    (vertices, triangles)
}

fn rotate(p: [f64; 3], axis: usize, angle: f64) -> [f64; 3] {
    let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
    let (s, c) = angle.sin_cos();
    let mut q = p;
    q[a1] = c * p[a1] - s * p[a2];
    q[a2] = s * p[a1] + c * p[a2];
    q
}

impl BirdSpec {
    /// The y of the shoulder hinges (inside the body).
    fn hinge(&self) -> f64 {
        0.08 * self.body_length
    }

    /// Flap θ, bank φ and turn ψ (radians) at `frame`.
    pub fn angles(&self, frame: usize) -> [f64; 3] {
        let s = frame as f64 / self.frames.max(1) as f64;
        let tau = 2.0 * std::f64::consts::PI;
        [
            self.flap_degrees.to_radians() * (tau * self.flaps * s).sin(),
            self.bank_degrees.to_radians() * (tau * s).sin(),
            self.turn_degrees.to_radians() * (tau * s).sin(),
        ]
    }

    /// The animation: parts `body`, `wing_left`, `wing_right`, `frames` frames.
    pub fn animation(&self) -> SurfaceAnimation {
        let (l, hinge) = (self.body_length, self.hinge());
        let rings = self.rings.max(3);
        // The body: an ellipsoid along x, slightly deeper than wide.
        let (mut rest, mut triangles) = ellipsoid([0.0; 3], [0.5 * l, 0.14 * l, 0.15 * l], 0, rings, 0);
        let mut parts = vec![("body".to_string(), 0..triangles.len())];
        let mut side = vec![0i8; rest.len()];
        // The wings: flat ellipsoids along y from just inside the body to the tip, swept back.
        let root = 0.04 * l;
        let half = 0.5 * (0.5 * self.span - root);
        for (name, sign) in [("wing_left", 1.0), ("wing_right", -1.0)] {
            let first = triangles.len();
            let (v, t) = ellipsoid(
                [0.0, sign * (root + half), 0.0],
                [0.5 * self.chord, half, 0.5 * self.thickness],
                1,
                rings,
                rest.len() as u32,
            );
            for p in v {
                let sweep = 0.25 * (p[1].abs() - root).max(0.0);
                rest.push([p[0] - sweep, p[1], p[2]]);
                side.push(sign as i8);
            }
            triangles.extend(t);
            parts.push((name.to_string(), first..triangles.len()));
        }
        let frames = (0..self.frames)
            .map(|k| {
                let [flap, bank, turn] = self.angles(k);
                rest.iter()
                    .zip(&side)
                    .map(|(&p, &s)| {
                        let mut q = p;
                        if s != 0 {
                            let h = f64::from(s) * hinge;
                            q = rotate([q[0], q[1] - h, q[2]], 0, f64::from(s) * flap);
                            q[1] += h;
                        }
                        rotate(rotate(q, 0, bank), 2, turn)
                    })
                    .collect()
            })
            .collect();
        SurfaceAnimation { triangles, parts, frames }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Volume enclosed by triangles `range` at `frame` (divergence theorem).
    fn part_volume(a: &SurfaceAnimation, frame: usize, range: std::ops::Range<usize>) -> f64 {
        range
            .map(|t| {
                let [p, q, r] = a.triangle_at(frame, t);
                (p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0])
                    + p[2] * (q[0] * r[1] - q[1] * r[0]))
                    / 6.0
            })
            .sum()
    }

    #[test]
    fn the_parts_are_closed_outward_ellipsoids_moving_rigidly() {
        let spec = BirdSpec { frames: 40, ..BirdSpec::default() };
        let a = spec.animation();
        assert_eq!(a.parts.len(), 3);
        assert_eq!(a.frame_count(), 40);
        for (name, range) in &a.parts {
            // Closed: every edge is used once in each direction.
            let mut edges = std::collections::HashMap::new();
            for t in range.clone() {
                let [x, y, z] = a.triangles[t];
                for (p, q) in [(x, y), (y, z), (z, x)] {
                    *edges.entry((p, q)).or_insert(0) += 1;
                }
            }
            for (&(p, q), &n) in &edges {
                assert_eq!((n, edges.get(&(q, p))), (1, Some(&1)), "{name}: edge {p}-{q}");
            }
            // Outward (positive volume) and rigid: the volume of every frame equals frame 0's.
            let v0 = part_volume(&a, 0, range.clone());
            assert!(v0 > 0.0, "{name}: volume {v0}");
            for k in 1..a.frame_count() {
                let v = part_volume(&a, k, range.clone());
                assert!((v - v0).abs() < 1e-12 * v0, "{name} frame {k}: {v} vs {v0}");
            }
        }
        // The wings rise together: at a quarter wingbeat both tips are above the body.
        let k = (spec.frames as f64 / spec.flaps / 4.0).round() as usize;
        let [flap, ..] = spec.angles(k);
        assert!(flap > 0.9 * spec.flap_degrees.to_radians());
        let tip_z = |range: &std::ops::Range<usize>| {
            range.clone().flat_map(|t| a.triangle_at(k, t)).map(|p| p[2]).fold(f64::MIN, f64::max)
        };
        assert!(tip_z(&a.parts[1].1) > 0.2 && tip_z(&a.parts[2].1) > 0.2);
    }
}
